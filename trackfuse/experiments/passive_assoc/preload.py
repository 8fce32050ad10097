"""Load the compiled PGA loop once, in the fork server (``Experiment.preload``), so every worker
inherits it instead of loading or compiling it on its own."""

from __future__ import annotations

from trackfuse.precompile import load_pga

load_pga()
