"""Chi-square quantiles, with scipy imported on first use.

Gates, loss rules and manoeuvre detectors need ``chi2.ppf`` while an experiment is built;
importing ``scipy.stats`` for it at module load would cost every ``trackfuse list`` and
``trackfuse validate`` about a second. :func:`chi2_quantile` computes the same number as
``scipy.stats.chi2.ppf`` (``2 gammaincinv(dof / 2, p)``, bit for bit).
"""

from __future__ import annotations

import numpy as np


def chi2_quantile(p: float, dof: float | np.ndarray) -> float | np.ndarray:
    """The ``p`` quantile of the chi-square distribution with ``dof`` degrees of freedom: a
    float for a number ``dof``, an array of ``dof``'s shape for an array."""
    from scipy.special import gammaincinv  # on first use: see the module docstring

    quantile = 2.0 * gammaincinv(np.asarray(dof, dtype=float) / 2.0, p)
    return float(quantile) if quantile.ndim == 0 else quantile
