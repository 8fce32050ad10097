"""Chi-square quantiles without scipy at import (trackfuse/chi2.py)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

from trackfuse.chi2 import chi2_quantile


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 6, 10, 40])
def test_equals_scipy_stats_bit_for_bit(dof):
    for p in np.concatenate([np.linspace(0.5, 0.999999, 501), [0.99, 0.999, 0.9973]]):
        assert chi2_quantile(float(p), dof) == stats.chi2.ppf(p, dof)


def test_array_of_dof_equals_scipy_stats_bit_for_bit():
    dof = np.array([1.0, 2.0, 7.0, 50.0, 800.0])
    for p in (0.025, 0.5, 0.975):
        got = chi2_quantile(p, dof)
        assert got.shape == dof.shape
        assert np.array_equal(got, stats.chi2.ppf(p, dof))


def test_building_the_paper_experiments_imports_no_scipy_or_numba():
    code = ("import sys, trackfuse.experiments.twin_sensor, trackfuse.experiments.esm_radar, "
            "trackfuse.experiments.passive_assoc; print(sorted(m for m in sys.modules "
            "if m.split('.')[0] in ('scipy', 'pandas', 'matplotlib', 'numba')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"
