"""Build hook: compile the numba kernels into the wheel (the rest of the build is in
pyproject.toml).

After the package files are copied into the build tree, ``python -m trackfuse.precompile``
runs on them, so numba's on-disk cache (``__pycache__/*.nbi, *.nbc`` beside each kernel
module) is packed with them and the first run after ``pip install .`` loads the kernels
instead of compiling them (docs/benchmarks.md, "First run after installing"). An editable
install compiles on first use instead; a kernel that fails to compile here only warns: it
compiles on first use.
"""

import os
import subprocess
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithKernels(build_py):
    """``build_py``, then the kernels compiled into the build tree's numba cache."""

    def run(self) -> None:
        super().run()
        if self.editable_mode or self.dry_run:
            return
        tree = Path(self.build_lib).resolve()
        for stale in [*tree.rglob("*.nbi"), *tree.rglob("*.nbc")]:  # an earlier build's
            stale.unlink()
        env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
        # the build tree first, then pip's isolated build environment (numba, numpy)
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(tree), env.get("PYTHONPATH")]))
        done = subprocess.run([sys.executable, "-m", "trackfuse.precompile"], env=env,
                              cwd=tree, capture_output=True, text=True)
        if done.returncode != 0:
            self.warn("trackfuse: some numba kernels did not compile here; they will compile "
                      f"on first use:\n{done.stderr[-2000:]}")


setup(cmdclass={"build_py": BuildPyWithKernels})
