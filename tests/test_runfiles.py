"""``trackfuse.runfiles``: a run folder is read without the experiment registry."""

from __future__ import annotations

import subprocess
import sys

from trackfuse.harness import run_data


def test_a_run_folder_is_read_without_importing_any_experiment(tmp_path):
    folder = run_data(tmp_path, "toy_gaussian", sweep={"mu": [0.0, 1.0]}, trials=3).path
    code = ("import sys\n"
            "from trackfuse.runfiles import read_run\n"
            f"run = read_run({str(folder)!r})\n"
            "print(len(run.trials), len(run.points), run.config['experiment'])\n"
            "print(sorted(m for m in sys.modules if m.startswith('trackfuse.experiments')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split("\n")
    assert out[0] == "12 2 toy_gaussian"  # points x trials x algorithms
    assert out[1] == "[]"
