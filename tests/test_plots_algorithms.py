"""The algorithms' looks (trackfuse/plots/algorithms.py)."""

import pytest

from trackfuse.plots.algorithms import BLACK, LOOKS, Look
from trackfuse.reportkit.looks import ROLES


def test_a_look_takes_only_a_known_role():
    assert {look.role for look in LOOKS.values()} == set(ROLES)
    with pytest.raises(ValueError, match="role 'papers' is not one of"):
        Look("typo", BLACK, "o", "papers")
