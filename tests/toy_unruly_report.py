"""Report module of toy_unruly_report (tests only): its figures() or tables() end the
process the way the config's ``report_how`` names (``sys.exit`` or ``os._exit``)."""

from __future__ import annotations

import os
import sys
from collections.abc import Collection

import pandas as pd

from trackfuse.rundata import RunData


def _misbehave(run: RunData, where: str) -> None:
    how = run.config["params"]["report_how"]
    if how.startswith(where):
        if how.endswith("os_exit"):
            os._exit(0)
        sys.exit(0)


def figures(run: RunData, wanted: Collection[str]) -> dict[str, object]:
    _misbehave(run, "figures")
    return {name: "nothing to draw" for name in wanted}


def tables(run: RunData) -> dict[str, pd.DataFrame]:
    _misbehave(run, "tables")
    return {"values": run.summary}
