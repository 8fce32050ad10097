"""How the last bit of numpy's ``arctan2`` and ``arcsin`` moves Stone Soup's finite-difference
measurement Jacobian (docs/stonesoup.md, "Why the two EKF + PDA differ").

Usage (needs the extra: ``pip install 'trackfuse[stonesoup]'``)::

    python examples/stonesoup_jacobian_rounding.py

It draws 3000 target states near the paper's geometry (seed 0: the paper's target
position (0, 128558, 4000) m plus a normal offset with sd 20 km in x and y and 1 km in z;
the sensor at (150, 2, 2.5) km, as in ``tests/test_stonesoup.py``) and computes Stone Soup's
``CartesianToElevationBearing`` Jacobian in two child processes: once with numpy's
defaults, once with numpy's AVX-512 code switched off
(``NPY_DISABLE_CPU_FEATURES="AVX512_ICL AVX512_SPR X86_V4"``). It prints

* the largest error of numpy's ``arctan2`` and ``arcsin`` on these states' arguments in
  each setting, in units of the last place, against a long-double reference;
* for the derivative of the azimuth with respect to the target's x coordinate, in how many
  states with x < 0 and with x >= 0 the two settings differ and by how much, and each
  setting's relative error against the exact Jacobian (rms and largest);
* that derivative's error in the state of ``tests/test_stonesoup.py``'s Jacobian test.

On a CPU without AVX-512 the two settings run the same code and agree everywhere. Takes
about 5 s.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

STATES = 3000
SENSOR = np.array([150e3, 2e3, 2.5e3])
TARGET = np.array([0.0, 128558.0, 4000.0])
NO_AVX512 = {"NPY_DISABLE_CPU_FEATURES": "AVX512_ICL AVX512_SPR X86_V4"}


TEST_STATE = [-23838.8, 97849.1 + 2e3, 32922.6 + 2.5e3]  # tests/test_stonesoup.py


def states() -> np.ndarray:
    """``(STATES + 1, 6)`` target states (m, m/s), our order, velocity zero: the random
    ones, then the state of the test."""
    rng = np.random.default_rng(0)
    x = np.zeros((STATES + 1, 6))
    x[:STATES, :3] = TARGET + rng.normal(0.0, 1.0, (STATES, 3)) * [20e3, 20e3, 1e3]
    x[STATES, :3] = TEST_STATE
    return x


def x_columns(exact: bool) -> np.ndarray:
    """``(STATES + 1, 2)``: Stone Soup's Jacobian column of our x, rows (elevation, azimuth)."""
    from trackfuse.interop import stonesoup as ss

    model = ss.angle_model(SENSOR, np.eye(2), exact_jacobian=exact)
    column = ss.TO_STONESOUP.tolist().index(0)
    return np.array([np.asarray(model.jacobian(ss.gaussian_prior(x, np.eye(6), 0.0)),
                                dtype=float)[:, column] for x in states()])


def relative() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The arguments of Stone Soup's bearing ``arctan2(dy, dx)`` and elevation
    ``arcsin(dz / rho)`` at each state (float64)."""
    d = states()[:, :3] - SENSOR
    return d[:, 1], d[:, 0], d[:, 2] / np.sqrt((d**2).sum(axis=1))


def ulp_errors(values: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Error of float64 ``values`` in units of the last place, against a long-double
    reference (x86: 64-bit mantissa, 11 bits more than float64)."""
    return np.abs((values.astype(np.longdouble) - reference)
                  / np.spacing(values).astype(np.longdouble)).astype(float)


def child(path: str) -> None:
    import numpy._core._multiarray_umath as umath

    y, x, s = relative()
    np.savez(path, column=x_columns(exact=False), atan2=np.arctan2(y, x), asin=np.arcsin(s))
    print(" ".join(f for f, on in umath.__cpu_features__.items() if on))


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        runs, features = [], []
        for name, extra in (("default", {}), ("no_avx512", NO_AVX512)):
            path = str(Path(tmp) / f"{name}.npz")
            out = subprocess.run([sys.executable, __file__, "--child", path], check=True,
                                 env={**os.environ, **extra}, capture_output=True, text=True)
            runs.append(dict(np.load(path)))
            features.append(set(out.stdout.split()))
    off = " ".join(sorted(features[0] - features[1])) or "none"
    print(f"{STATES} states; with {' '.join(f'{k}={v!r}' for k, v in NO_AVX512.items())} "
          f"numpy's CPU features switched off: {off}")
    y, x, s = (v[:STATES] for v in relative())
    references = {"atan2": np.arctan2(y.astype(np.longdouble), x.astype(np.longdouble)),
                  "asin": np.arcsin(s.astype(np.longdouble))}
    for function, reference in references.items():
        worst = [ulp_errors(run[function][:STATES], reference).max() for run in runs]
        print(f"{function}: largest error over these {STATES} arguments, default "
              f"{worst[0]:.2f}, no AVX-512 {worst[1]:.2f} units in the last place")
    exact = x_columns(exact=True)[:, 1]
    test = [100 * (run["column"][STATES, 1] / exact[STATES] - 1) for run in runs]
    exact, negative = exact[:STATES], states()[:STATES, 0] < 0
    print("Stone Soup's d azimuth / dx:")
    for where, label in ((negative, "x < 0"), (~negative, "x >= 0")):
        a, b = (run["column"][:STATES][where, 1] for run in runs)
        e = exact[where]
        between = np.abs(a - b) / np.abs(e)
        print(f"  {label}: the settings differ in {(a != b).sum()} of {where.sum()} states, "
              f"by up to {100 * between.max():.2f} % of the exact value")
        for column, setting in ((a, "default"), (b, "no AVX-512")):
            rel = column / e - 1
            print(f"    {setting}: error against the exact Jacobian rms "
                  f"{100 * np.sqrt(np.mean(rel**2)):.2f} %, largest "
                  f"{100 * np.abs(rel).max():.2f} %")
    print(f"  the state of tests/test_stonesoup.py (x = {TEST_STATE[0] / 1e3:.1f} km): "
          f"{test[0]:+.2f} % (default), {test[1]:+.2f} % (no AVX-512)")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        child(sys.argv[2])
    else:
        main()
