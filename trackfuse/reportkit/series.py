"""Curves over time drawn from per-trial series (one value per scan), in the kit's style: the
mean over trials with its 95 % Student-t band, one colour per setting of a sweep, the
settings named in the legend when few and on a colour bar beside the panels when more
(:data:`MAX_KEYED`)."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from trackfuse.reportkit.render import BAND_ALPHA
from trackfuse.stats import t_interval

#: The most settings named in a legend; more go on a colour bar (:func:`settings_bar`).
MAX_KEYED = 3


def mean_band(ax: Axes, t: np.ndarray, values: np.ndarray, label: str, colour: str,
              shade: bool) -> None:
    """Mean over trials of ``values`` (N, K) against ``t`` (K,) with its 95 % t band when
    ``shade`` (scans where every trial is defined)."""
    ok = np.isfinite(values).all(axis=0)
    v = values[:, ok]
    mean = v.mean(axis=0)
    ax.plot(t[ok], mean, label=label, color=colour)
    if shade and len(v) > 1:
        lo, hi = t_interval(mean, v.std(axis=0, ddof=1), len(v))
        ax.fill_between(t[ok], lo, hi, color=colour, alpha=BAND_ALPHA, linewidth=0)


def setting_colours(n: int) -> list:
    """One colour per setting of ``n``: dark grey for one, else viridis, light end cut."""
    if n == 1:
        return ["0.2"]
    return [matplotlib.colormaps["viridis"](i / (n - 1) * 0.9) for i in range(n)]


def settings_bar(fig: Figure, axes: Sequence[Axes], words: Sequence[str]) -> None:
    """A colour bar beside ``axes`` naming each setting's colour
    (:func:`setting_colours`; ``words``, in order)."""
    steps = matplotlib.colors.BoundaryNorm(np.arange(len(words) + 1) - 0.5, len(words))
    colours = matplotlib.colors.ListedColormap(setting_colours(len(words)))
    bar = fig.colorbar(matplotlib.cm.ScalarMappable(steps, colours), ax=list(axes),
                       ticks=range(len(words)), aspect=30)
    bar.ax.set_yticklabels(words)
