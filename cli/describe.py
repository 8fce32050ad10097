"""What ``trackfuse list`` prints: the experiments, or one experiment's parameters, metrics,
algorithms and figures as a table (keys never cut), a commented YAML template or JSON."""

from __future__ import annotations

import shutil
import textwrap
from typing import Any

import yaml

from trackfuse.config import FORMATS, allowed_text
from trackfuse.experiments import Listed
from trackfuse.experiments.base import Experiment, Param


def print_listing(listed: list[Listed], width: int | None = None) -> None:
    """The experiments a config may name, with where each comes from."""
    out = _Wrapper(width or shutil.get_terminal_size().columns)
    out.line("experiments (experiment: in a config):")
    for item in listed:
        origin = item.origin + (f", {item.reference}" if ":" in item.reference else "")
        out.entry(f"{item.name} ({origin})", item.description)
    out.line("")
    out.line("`trackfuse list EXPERIMENT` shows its parameters, metrics, algorithms and "
             "figures; `--format yaml` prints a config template.")


def listing_data(listed: list[Listed]) -> list[dict[str, str]]:
    """:func:`print_listing` as JSON-ready data: name, origin, reference, description."""
    return [{"name": item.name, "origin": item.origin, "reference": item.reference,
             "description": item.description} for item in listed]


#: How ``summary.csv`` sums a metric up, by its kind (binary) or its aggregate.
_SUMMED_UP = {"binary": "0/1, Wilson interval", "mean": "mean, t interval",
              "rms": "root mean square, bootstrap-t interval"}


def print_experiment(exp: Experiment, width: int | None = None) -> None:
    """Parameters, metrics, algorithms and figures of ``exp``, each name in full on its own line."""
    width = width or shutil.get_terminal_size().columns
    out = _Wrapper(width)
    out.line(f"{exp.name}: {exp.title}")
    out.heading("parameters (params: in a config; KEY=VALUE or --set KEY=VALUE on the "
                "command line)")
    for p in exp.params:
        unit = f" {p.unit}" if p.unit and p.unit != "1" else ""
        quiet = "" if p.draws else (" Changes no random draw: sweep points that differ only "
                                    "in it share their simulated data.")
        out.entry(f"{p.key} = {_flow(p.default)}{unit}",
                  f"{p.doc.rstrip('.')}. Allowed: {allowed_text(p)}.{quiet}")
    out.heading("metrics (columns of trials.csv; rows of summary.csv)")
    for m in exp.metrics:
        kind = _SUMMED_UP["binary" if m.binary else m.aggregate]
        better = f", {m.better} is better" if m.better else ""
        out.entry(f"{m.name} [{m.unit}]", f"{m.doc} ({kind}{better}).")
    if exp.algorithms:
        out.heading("algorithms (params.algorithms)")
        out.entry("", ", ".join(exp.algorithms))
    out.heading("figures (outputs.figures)")
    for name, spec in exp.figures.items():
        paper = f" (paper {spec.paper})" if spec.paper else ""
        out.entry(f"{name}{paper}", spec.caption)


class _Wrapper:
    """Prints names unbroken and descriptions wrapped and indented below them."""

    def __init__(self, width: int):
        self.width = max(width, 40)
        self.text = textwrap.TextWrapper(width=self.width, initial_indent="    ",
                                         subsequent_indent="    ", break_on_hyphens=False,
                                         break_long_words=False)

    def line(self, text: str) -> None:
        print(self.line_text(text))

    def heading(self, text: str) -> None:
        print("\n" + self.line_text(f"{text}:"))

    def line_text(self, text: str) -> str:
        return textwrap.fill(text, self.width, break_long_words=False)

    def entry(self, name: str, description: str) -> None:
        if name:
            print(f"  {name}")
        print(self.text.fill(" ".join(description.split())))


def _flow(value: Any) -> str:
    """``value`` as one line of YAML (``[1.0, 2.0]``, ``orbit``, ``'yes'``)."""
    text = yaml.safe_dump(value, default_flow_style=True, width=10**6, sort_keys=False)
    return text.removesuffix("\n").removesuffix("\n...").strip()


def _comment(text: str) -> str:
    return " ".join(text.split())


def _param_lines(p: Param) -> list[str]:
    unit = f" [{p.unit}]" if p.unit else ""
    return [f"  # {_comment(p.doc)}{unit}; allowed: {allowed_text(p)}",
            f"  {p.key}: {_flow(p.default)}"]


def config_template(exp: Experiment, reference: str) -> str:
    """A commented config of ``reference`` with every parameter at its default (valid as it is)."""
    figures = ", ".join(exp.figures) or "none"
    lines = [
        f"# {_comment(exp.title)}",
        "# Every parameter at its default (`trackfuse list "
        f"{reference}` explains them); delete the",
        "# lines you keep at the default. Check the file with `trackfuse validate FILE`.",
        f"experiment: {_flow(reference)}",
        f"title: {_flow(exp.title)}",
        "trials: 1          # Monte Carlo trials per sweep point",
        "seed: 0            # root seed (an integer >= 0)",
        f"batch_size: {exp.batch_size}    # trials per task (part of the run id)",
        "params:",
        *[line for p in exp.params for line in _param_lines(p)],
        "# sweep axes: KEY: [v1, v2] or KEY: 'range(start, stop, step)', e.g.",
        f"#   {exp.params[0].key}: [{_flow(exp.params[0].default)}]" if exp.params else "#",
        "sweep: {}",
        "sweep_mode: grid   # grid (every combination) or zip (axes side by side)",
        "outputs:",
        f"  # all, or a list of: {figures}",
        "  figures: all",
        f"  formats: [png, pdf]   # any of {', '.join(FORMATS)}",
    ]
    return "\n".join(lines) + "\n"


def as_data(exp: Experiment, reference: str) -> dict[str, Any]:
    """Everything ``trackfuse list`` shows about ``exp`` as plain JSON-ready data."""
    return {
        "name": exp.name,
        "reference": reference,
        "title": exp.title,
        "batch_size": exp.batch_size,
        "row_keys": list(exp.row_keys),
        "params": [{"key": p.key, "default": p.default, "unit": p.unit,
                    "kind": p.kind.__name__, "low": p.low, "high": p.high,
                    "choices": list(p.choices) if p.choices is not None else None,
                    "allowed": allowed_text(p), "draws": p.draws, "doc": p.doc}
                   for p in exp.params],
        "metrics": [{"name": m.name, "unit": m.unit, "binary": m.binary, "better": m.better,
                     "aggregate": m.aggregate,
                     "doc": m.doc} for m in exp.metrics],
        "algorithms": list(exp.algorithms),
        "figures": [{"name": name, "paper": spec.paper, "caption": spec.caption}
                    for name, spec in exp.figures.items()],
    }
