"""Chi-square quantiles, with scipy imported on first use.

Gates, loss rules and manoeuvre detectors need ``chi2.ppf`` while an experiment is built;
importing ``scipy.stats`` for it at module load would cost every ``trackfuse list`` and
``trackfuse validate`` about a second. :func:`chi2_quantile` computes the same number as
``scipy.stats.chi2.ppf`` (``2 gammaincinv(dof / 2, p)``, bit for bit).
"""

from __future__ import annotations


def chi2_quantile(p: float, dof: float) -> float:
    """The ``p`` quantile of the chi-square distribution with ``dof`` degrees of freedom."""
    from scipy.special import gammaincinv  # on first use: see the module docstring

    return float(2.0 * gammaincinv(dof / 2.0, p))
