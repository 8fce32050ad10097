"""The algorithms' looks (trackfuse/reportkit/looks.py)."""

import pytest

from trackfuse.reportkit.looks import BLACK, Look


def test_a_look_takes_only_a_known_role():
    with pytest.raises(ValueError, match="role 'papers' is not one of"):
        Look("typo", BLACK, "o", "papers")
