"""The one renderer: draws a declared :class:`~trackfuse.reportkit.spec.Plot` from a
finished run's ``summary.csv`` (no trial is recomputed).

Labels come from the experiment's declaration (``Param.label``, ``Metric.label``,
``Experiment.row_labels``) in print typography (:mod:`.typography`); each algorithm takes
its declared look (:mod:`.looks`); rates and fractions are drawn in %. A curve that would
hide another (the same means at every x) is shifted sideways by a small offset.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from trackfuse.reportkit import axes as kit_axes
from trackfuse.reportkit.looks import Look, look_of
from trackfuse.reportkit.spec import MAX_ENTRIES, Plot, Reference
from trackfuse.reportkit.style import context, legend_below, panels
from trackfuse.reportkit.typography import number, plain, unit_text

if TYPE_CHECKING:
    from trackfuse.experiments.base import Experiment
    from trackfuse.rundata import RunData

#: Shading of an interval band, and of a reference's (lighter, behind every band).
BAND_ALPHA, REFERENCE_BAND = 0.18, {"color": "k", "alpha": 0.07, "linewidth": 0, "zorder": 0.5}
#: Sideways shift of a curve that coincides with one drawn before it, as a fraction of the
#: x span on the axis's scale; of the points of one category, the spread of the methods.
COINCIDING_SHIFT, CATEGORY_SPREAD = 0.012, 0.28
#: Mean width (in) of a character of an 8 pt axis label and of an 8.5 pt title: when to
#: break them over two lines.
LABEL_CHAR_IN, TITLE_CHAR_IN = 0.066, 0.072


@dataclass(frozen=True)
class Quantity:
    """How a column is shown: ``label``, printed ``unit``, drawn in % (``percent``),
    counted (``count``: integer ticks)."""

    label: str
    unit: str
    percent: bool = False
    count: bool = False
    symbol: str = ""
    bounds: tuple[float, float] | None = None
    words: tuple[tuple[Any, str], ...] = ()

    def axis(self, scale: str = "", room: float = float("inf")) -> str:
        """Its axis label, naming a log or symlog scale, over two lines when longer than
        ``room`` inches."""
        shown = "%" if self.percent else self.unit
        inside = ", ".join(p for p in (shown, f"{scale} scale" if scale else "") if p)
        if not inside:
            return self.label
        one_line = f"{self.label} ({inside})"
        return one_line if len(one_line) * LABEL_CHAR_IN <= room else f"{self.label}\n({inside})"

    def shown(self, values: np.ndarray) -> tuple[float, Quantity]:
        """``(factor, quantity)`` that ``values`` are drawn in: % for a rate, ms for times
        in seconds all below 0.1 s."""
        if self.percent:
            return 100.0, self
        largest = np.nanmax(np.abs(values), initial=0.0)
        if self.unit == "s" and largest < 0.1:
            return 1e3, replace(self, unit="ms")
        if self.unit == "m" and largest >= 1e3:
            return 1e-3, replace(self, unit="km")
        return 1.0, self

    def word(self, v: Any) -> str:
        """``v`` as a tick or category label: its declared word, else :meth:`value`."""
        return next((w for value, w in self.words if value == v), None) or self.value(v)

    def title(self, v: Any) -> str:
        """A panel's setting: the value's declared word, else ``symbol = value``."""
        if words := [w for value, w in self.words if value == v]:
            return words[0]
        return f"{self.symbol or self.label} = {self.value(v)}"

    def value(self, v: Any) -> str:
        """``v`` with its unit: ``5``, ``0.2``, ``0.005 rad``."""
        text = number(v) if isinstance(v, int | float) and not isinstance(v, bool) else str(v)
        return f"{text} {self.unit}" if self.unit and not self.count else text


def quantity(experiment: Experiment, key: str) -> Quantity:
    """How ``key`` (a parameter, metric or row key) of ``experiment`` is shown."""
    if key in experiment.schema:
        p = experiment.schema[key]
        count = p.kind is int or p.item_kind is int and p.kind is list
        return Quantity(p.label or key, unit_text(p.unit), count=count,
                        symbol=p.symbol or p.label or key, words=p.words)
    metric = next((m for m in experiment.metrics if m.name == key), None)
    if metric is not None:
        return Quantity(metric.label or key, unit_text(metric.unit), metric.percent,
                        bounds=metric.bounds or ((0.0, 1.0) if metric.binary else None))
    label, unit = experiment.row_labels.get(key, (key, ""))
    return Quantity(label, unit_text(unit), count=unit == "count")


def y_quantity(experiment: Experiment, plot: Plot, metric: str) -> Quantity:
    """How ``metric`` is shown on ``plot``'s y axis: its declared quantity, or for a plot
    drawing its square root (``plot.root``) that label in the unit's square root."""
    shown = quantity(experiment, metric)
    if not plot.root:
        return shown
    declared = next((m.unit for m in experiment.metrics if m.name == metric), "")
    return Quantity(plot.root, unit_text(declared.removesuffix("^2")),
                    bounds=(0.0, float("inf")))


def looks_of(experiment: Experiment, name: str) -> Look:
    """The declared look of algorithm ``name``."""
    return look_of(experiment.looks, name)


def selected(summary: pd.DataFrame, plot: Plot) -> pd.DataFrame:
    """The summary rows a plot draws: its metrics, its row keys (or swept keys) held at
    ``plot.at`` (``"last"``: each algorithm's largest value at each point; a key the run
    has no column of is ignored)."""
    rows = summary[summary["metric"].isin(plot.metrics)]
    for key, value in ((k, v) for k, v in plot.at.items() if k in rows):
        if isinstance(value, tuple):
            rows = rows[rows[key].isin(value)]
        elif value == "last":
            last = rows.groupby(["point", "algorithm"])[key].transform("max")
            rows = rows[rows[key] == last]
        else:
            rows = rows[rows[key] == value]
    if plot.root:  # the root of a mean square and of its interval's ends
        ends = ["mean", "ci_low", "ci_high"]
        rows = rows.assign(**{c: np.sqrt(rows[c].clip(lower=0.0)) for c in ends})
    return rows


def _held(plot: Plot, key: str, value: Any) -> bool:
    """Whether a panel at ``key = value`` is drawn: ``plot.at`` holds ``key`` at it (or
    does not hold ``key``)."""
    wanted = plot.at.get(key)
    if isinstance(wanted, tuple):
        return value in wanted
    return wanted is None or wanted == "last" or wanted == value


def facets(run: RunData, plot: Plot) -> list[dict[str, Any]]:
    """``{swept key: value}`` of each panel: every setting of the swept keys but ``x`` and
    ``algorithms`` that ``plot.at`` keeps, in sweep-point order (``columns`` first varying
    fastest)."""
    keys = [k for k in run.sweep if k not in ("algorithms", plot.x, *plot.together)]
    seen: dict[tuple, dict[str, Any]] = {}
    for point in run.points:
        if not all(_held(plot, k, point.get(k)) for k in keys):
            continue
        seen.setdefault(tuple(point.get(k) for k in keys), {k: point.get(k) for k in keys})
    found = list(seen.values())
    if plot.columns in keys:
        rest = [k for k in keys if k != plot.columns]
        found.sort(key=lambda f: tuple(str(f[k]) for k in rest))
    return found


def algorithms(data: pd.DataFrame, plot: Plot) -> list[str]:
    """The curves drawn: the declared ones run (else every one run), references apart,
    at most :data:`MAX_ENTRIES` entries with the labelled references."""
    present = list(dict.fromkeys(data["algorithm"]))
    refs = {r.algorithm for r in plot.references if r.algorithm}
    names = [a for a in (plot.algorithms or present) if a in present and a not in refs]
    room = MAX_ENTRIES - sum(bool(r.label or r.algorithm) for r in plot.references)
    return names[:room]


def grid(plot: Plot, cells: list[dict[str, Any]]) -> tuple[int, int]:
    """``(rows, columns)`` of the panel grid: a row per metric when several, else the
    ``columns`` key's values across (or at most ``max_columns``), the rest wrapping."""
    if len(plot.metrics) > 1:
        return len(plot.metrics), max(1, len(cells))
    if plot.columns:
        across = len({str(c.get(plot.columns)) for c in cells})
    else:
        across = min(plot.max_columns, len(cells))
    across = max(1, across)
    return math.ceil(len(cells) / across), across


#: Extra drawing of one panel by a report module (a bound computed from the config):
#: ``decorate(axes, metric, panel setting, y factor of the shown unit)``.
Decorate = Callable[[Axes, str, dict[str, Any], float], None]


def draw(run: RunData, plot: Plot, title: str = "", decorate: Decorate | None = None
         ) -> Figure | str:
    """The figure ``plot`` declares for ``run``, or a one-line reason it cannot be drawn;
    ``decorate`` adds what a summary row cannot hold to each panel."""
    swept = len(run.sweep.get(plot.x, ())) >= 2
    if plot.x in run.experiment.schema and not swept and not plot.categories:
        return f"{plot.x} is not swept over at least 2 values"
    data = selected(run.summary, plot)
    if plot.categories and plot.x not in data and plot.x in run.params:
        data = data.assign(**{plot.x: run.params[plot.x]})  # one category: the setting
    if data.empty or plot.x not in data:
        return f"no {', '.join(plot.metrics)} rows against {plot.x} in this run"
    names = algorithms(data, plot)
    order = x_order(run, plot, data)
    cells = facets(run, plot)
    nrows, ncols = grid(plot, cells)
    share = "row" if len(plot.metrics) > 1 else "all"
    fig, axes = panels(nrows, ncols, plot.width, plot.panel_height,
                       extra_height=0.75 + 0.35 * bool(title), sharex=True, sharey=share)
    with context():
        groups = _grouped_rows(data)
        for ax, metric, cell in _cells(axes, plot, cells):
            _panel(ax, run.experiment, (data, groups), plot, (metric, cell), names, order)
            if decorate is not None:
                decorate(ax, metric, cell, _factor(run.experiment, plot, data, metric))
        _frame(fig, axes, run.experiment, plot, data, cells, order)
        legend_below(fig, axes.ravel())
        if title:
            fig.suptitle(textwrap.fill(title, int(fig.get_figwidth() / TITLE_CHAR_IN)))
    return fig


def _cells(axes: np.ndarray, plot: Plot, cells: list[dict[str, Any]]
           ) -> Iterator[tuple[Axes, str, dict[str, Any]]]:
    """``(axes, metric, cell)`` of each panel drawn; the grid's unused panels hidden."""
    if len(plot.metrics) > 1:
        for r, metric in enumerate(plot.metrics):
            for c, cell in enumerate(cells):
                yield axes[r, c], metric, cell
        return
    flat = axes.ravel()
    for ax, cell in zip(flat, cells, strict=False):
        yield ax, plot.metrics[0], cell
    for ax in flat[len(cells):]:
        ax.set_visible(False)


RowGroups = dict[tuple[Any, Any], pd.DataFrame]
"""A plot's summary rows grouped by (metric, algorithm), once a figure: each panel looks its
curves up there instead of filtering every row again."""


def _grouped_rows(data: pd.DataFrame) -> RowGroups:
    """``data``'s rows by (metric, algorithm), each group in its order."""
    return dict(tuple(data.groupby(["metric", "algorithm"], sort=False)))


def _rows(data: pd.DataFrame, groups: RowGroups, metric: str, cell: dict[str, Any], name: str,
          x: str) -> pd.DataFrame:
    """One algorithm's rows of one panel (from ``groups``, ``data``'s groups), sorted by
    ``x``."""
    found = groups.get((metric, name))
    sel = data.iloc[:0] if found is None else found
    for key, value in cell.items():
        sel = sel[sel[key] == value]
    return sel.sort_values(x)


def x_order(run: RunData, plot: Plot, data: pd.DataFrame) -> list[Any]:
    """The x values in drawing order: a category axis in the sweep's order (words allowed),
    a number axis sorted."""
    if plot.categories:
        return list(dict.fromkeys(run.sweep.get(plot.x) or list(data[plot.x].unique())))
    return list(np.unique(data[plot.x].to_numpy(float)))


def _positions(rows: pd.DataFrame, plot: Plot, order: list[Any], slot: float = 0.0
               ) -> np.ndarray:
    """Where ``rows`` are drawn on x: their category's index plus ``slot``, or x itself."""
    if plot.categories:
        return np.array([order.index(v) for v in rows[plot.x]], dtype=float) + slot
    return rows[plot.x].to_numpy(float)


def _slot(i: int, n: int) -> float:
    """Sideways place of the ``i``-th of ``n`` methods in a category."""
    return CATEGORY_SPREAD * (2 * i / (n - 1) - 1) if n > 1 else 0.0


def _factor(experiment: Experiment, plot: Plot, data: pd.DataFrame, metric: str) -> float:
    """The factor ``metric``'s values are drawn at (100 for %, 1e-3 for km)."""
    means = data.loc[data["metric"] == metric, "mean"].to_numpy(float)
    return y_quantity(experiment, plot, metric).shown(means)[0]


def _panel(ax: Axes, experiment: Experiment, summary: tuple[pd.DataFrame, RowGroups], plot: Plot,
           where: tuple[str, dict[str, Any]], names: list[str], order: list[Any]) -> None:
    """One panel (``where``: its metric and setting; ``summary``: the plot's rows and their
    :func:`_grouped_rows`): each algorithm's mean with its interval, then the references."""
    (data, groups), (metric, cell) = summary, where
    scale = _factor(experiment, plot, data, metric)
    drawn: list[np.ndarray] = []
    for i, name in enumerate(names):
        rows = _rows(data, groups, metric, cell, name, plot.x)
        if rows.empty:
            continue
        x = _positions(rows, plot, order, _slot(i, len(names)))
        mean = scale * rows["mean"].to_numpy(float)
        low, high = (scale * rows[c].to_numpy(float) for c in ("ci_low", "ci_high"))
        hidden = sum(len(m) == len(mean) and np.allclose(m, mean, equal_nan=True)
                     for m in drawn)  # curves this one would lie on: one shift each
        if not plot.categories and hidden:
            x = kit_axes.shifted(x, np.asarray(order, float), plot.xscale,
                                 hidden * COINCIDING_SHIFT)
        drawn.append(mean)
        _series(ax, x, mean, low, high, looks_of(experiment, name), plot.categories)
    for reference in (r for r in plot.references if not r.metrics or metric in r.metrics):
        _reference(ax, experiment, summary, plot, where, reference, (scale, order))
        if reference.values:
            _paper_values(ax, experiment, summary, plot, where, reference, (scale, order))


def _series(ax: Axes, x: np.ndarray, mean: np.ndarray, low: np.ndarray, high: np.ndarray,
            look: Look, categories: bool) -> None:
    """A mean with its interval: a band (bars for unjoined categories) for the emphasised
    methods, the mean alone for the others."""
    kw = look.line()
    if categories:  # unjoined: a markerless look (a reference) marks its mean by a bar
        kw["linestyle"] = "none"
        if not kw["marker"]:
            kw.update(marker="_", markersize=9)
        ax.errorbar(x, mean, yerr=np.maximum([mean - low, high - mean], 0), fmt="none",
                    ecolor=look.colour, elinewidth=0.8, zorder=kw["zorder"])
    ax.plot(x, mean, **kw)
    if look.emphasised and not categories:
        ax.fill_between(x, low, high, color=look.colour, alpha=BAND_ALPHA, linewidth=0)


def _reference(ax: Axes, experiment: Experiment, summary: tuple[pd.DataFrame, RowGroups],
               plot: Plot,
               where: tuple[str, dict[str, Any]], ref: Reference,
               shown: tuple[float, list[Any]]) -> None:
    """One :class:`~trackfuse.reportkit.spec.Reference` in a panel (``shown``: the y
    factor and the x order)."""
    (metric, cell), (scale, order) = where, shown
    kw = {"color": "k", "linestyle": "--", "linewidth": 0.9, "zorder": 4}
    if ref.y is not None:  # a level (a bound, chance): dotted, apart from the curves
        ax.axhline(scale * ref.y, label=ref.label, color="0.35", linestyle=":",
                   linewidth=1.0, zorder=1.5)
    for x in ref.x:
        ax.axvline(x, color="0.45", linewidth=0.7, linestyle=":", zorder=1)
    if ref.band is not None and ref.until is None:
        ax.axhspan(scale * ref.band[0], scale * ref.band[1], color="0.85", zorder=0,
                   label=ref.label)
    elif ref.band is not None:
        ax.fill_between([float(order[0]), ref.until], scale * ref.band[0],
                        scale * ref.band[1], color="0.85", linewidth=0, zorder=0,
                        label=ref.label)
    if not ref.algorithm:
        return
    rows = _rows(*summary, metric, cell, ref.algorithm, plot.x)
    if rows.empty:
        return
    label = ref.label or looks_of(experiment, ref.algorithm).label
    mean, low, high = (scale * rows[c].to_numpy(float) for c in ("mean", "ci_low", "ci_high"))
    if rows[plot.x].nunique() == 1:  # one value for every x: a level with its interval
        ax.axhline(mean[0], label=label, **kw)
        ax.axhspan(low[0], high[0], **REFERENCE_BAND)
        return
    x = _positions(rows, plot, order)
    if plot.categories:
        for xi, m in zip(x, mean, strict=True):
            ax.plot([xi - 0.42, xi + 0.42], [m, m], **kw)
        ax.lines[-1].set_label(label)
        return
    ax.plot(x, mean, label=label, **kw)
    ax.fill_between(x, low, high, **REFERENCE_BAND)


#: Marker of the paper's values: an open star in the method's colour.
PAPER_STAR = {"marker": "*", "markersize": 8, "markerfacecolor": "white",
              "markeredgewidth": 1.0, "linestyle": "none", "zorder": 5}


def _paper_values(ax: Axes, experiment: Experiment, summary: tuple[pd.DataFrame, RowGroups],
                  plot: Plot,
                  where: tuple[str, dict[str, Any]], ref: Reference,
                  shown: tuple[float, list[Any]]) -> None:
    """The paper's value of each method of ``ref.values`` as an open star in its colour,
    at the x of every point of ``ref.points`` in the panel: right of the methods of a
    category, beside our marker on a curve; one legend entry (``ref.label``, grey)."""
    (metric, cell), (scale, order) = where, shown
    for name, value in ref.values:
        rows = _rows(*summary, metric, cell, name, plot.x)
        rows = rows[rows["point"].isin(ref.points)]
        if rows.empty:
            continue
        x = _positions(rows, plot, order, CATEGORY_SPREAD + 0.14)
        if not plot.categories:
            x = kit_axes.shifted(x, np.asarray(order, float), plot.xscale, 2 * COINCIDING_SHIFT)
        ax.plot(x, np.full(len(x), scale * value), markeredgecolor=looks_of(
            experiment, name).colour, **PAPER_STAR)
    if ref.label and not any(h.get_label() == ref.label for h in ax.get_lines()):
        ax.plot([], [], markeredgecolor="0.3", label=ref.label, **PAPER_STAR)


def _frame(fig: Figure, axes: np.ndarray, experiment: Experiment, plot: Plot,
           data: pd.DataFrame, cells: list[dict[str, Any]], order: list[Any]) -> None:
    """Axes scales, ticks and labels, panel titles: the x label under each column's
    lowest panel, the y label on the first column."""
    xq = quantity(experiment, plot.x)
    shown = [ax for ax in axes.ravel() if ax.get_visible()]
    room = 0.85 * fig.get_figwidth() / axes.shape[1]
    xlabel = kit_axes.x_axis(shown, order, plot.xscale, xq, plot.categories, room)
    nrows, ncols = axes.shape
    for r in range(nrows):
        metric = plot.metrics[r] if len(plot.metrics) > 1 else plot.metrics[0]
        yscale = plot.yscale_of(metric)
        for ax in axes[r]:
            if yscale != "linear" and ax.get_visible():
                kit_axes.y_log(ax, yscale)
        factor, yq = y_quantity(experiment, plot, metric).shown(
            data.loc[data["metric"] == metric, "mean"].to_numpy(float))
        ylabel = yq.axis("" if yscale == "linear" else yscale, room=0.9 * plot.panel_height)
        if len(plot.metrics) > 1 or nrows == 1:
            axes[r, 0].set_ylabel(ylabel)
        elif r == 0:  # one metric over several rows: one label for them all
            fig.supylabel(ylabel.replace("\n", " "))
        if yq.bounds is not None:
            kit_axes.bounded_limits(axes[r, 0], *(factor * b for b in yq.bounds))
    for (r, c), ax in np.ndenumerate(axes):
        lowest = r + 1 == nrows or not axes[r + 1, c].get_visible()
        if ax.get_visible():
            ax.xaxis.set_tick_params(labelbottom=lowest)
            if lowest:
                ax.set_xlabel(xlabel)
    titled = axes[0] if len(plot.metrics) > 1 else axes.ravel()
    for ax, cell in zip(titled, cells, strict=False):
        ax.set_title(wrapped(panel_title(experiment, cell), 0.95 * room / 0.85))


def wrapped(title: str, width_in: float) -> str:
    """``title`` over as many lines as it needs to fit ``width_in`` inches at 8 pt: broken
    after its commas (between the settings it names), within a setting only where that
    alone is too long."""
    width = max(12, int(width_in / LABEL_CHAR_IN))
    lines: list[str] = []
    for part in title.split(", "):
        if lines and len(lines[-1]) + 2 + len(part) <= width:
            lines[-1] += ", " + part
        else:
            if lines:
                lines[-1] += ","
            lines += textwrap.wrap(part, width) or [""]
    return "\n".join(lines)


def panel_title(experiment: Experiment, cell: dict[str, Any]) -> str:
    """``N = 5, p_m = 0.2``: a panel's setting in the declared labels."""
    return ", ".join(quantity(experiment, k).title(v) for k, v in cell.items())


def setting_words(experiment: Experiment, values: dict[str, Any]) -> str:
    """``N = 5, P_D = 0.95``: a setting in the declared labels as plain text (a table's
    cell: mathtext unwrapped)."""
    return ", ".join(plain(quantity(experiment, k).title(v)) for k, v in values.items())


def draw_beside(parts: Sequence[tuple[RunData, str]], plot: Plot, title: str = ""
                ) -> Figure | str:
    """The same ``plot`` for each run of ``parts`` (``(run, panel title)``), one panel
    each side by side on one y axis: a paper's scenario beside an analogue where the effect
    shows (paper 000's Fig. 1: flat at 0 % at its scenario, rising with clutter in the close
    geometry). Each run sweeps ``plot.x`` alone but for keys ``plot.at`` holds; a one-line
    reason when one does not."""
    for run, _ in parts:
        if set(run.sweep) - {"algorithms", plot.x, *plot.at} or \
                len(run.sweep.get(plot.x, ())) < 2:
            return f"{run.path.name}: {plot.x} is not the one swept key"
    fig, axes = panels(1, len(parts), plot.width, plot.panel_height,
                       extra_height=0.75 + 0.35 * bool(title), sharey=True)
    with context():
        for ax, (run, panel_title) in zip(axes[0], parts, strict=True):
            data = selected(run.summary, plot)
            order = x_order(run, plot, data)
            _panel(ax, run.experiment, (data, _grouped_rows(data)), plot, (plot.metrics[0], {}),
                   algorithms(data, plot), order)
            ax.set_xlabel(kit_axes.x_axis([ax], order, plot.xscale,
                                          quantity(run.experiment, plot.x), plot.categories,
                                          0.85 * fig.get_figwidth() / len(parts)))
            ax.set_title(panel_title)
        run = parts[0][0]
        data = selected(run.summary, plot)
        factor, yq = y_quantity(run.experiment, plot, plot.metrics[0]).shown(
            data.loc[data["metric"] == plot.metrics[0], "mean"].to_numpy(float))
        axes[0, 0].set_ylabel(yq.axis(room=0.9 * plot.panel_height))
        if yq.bounds is not None:
            kit_axes.bounded_limits(axes[0, 0], *(factor * b for b in yq.bounds))
        legend_below(fig, axes.ravel())
        if title:
            fig.suptitle(textwrap.fill(title, int(fig.get_figwidth() / TITLE_CHAR_IN)))
    return fig
