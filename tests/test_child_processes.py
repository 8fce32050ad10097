"""trackfuse/child_processes.py: a stop signal held while a child process starts."""

from __future__ import annotations

import signal

import pytest

from trackfuse.child_processes import ctrl_c_held


def _raise_keyboard_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_a_stop_inside_the_block_is_raised_once_the_block_ends(stop):
    """SIGTERM was not held (only Ctrl-C): one arriving while a drawing process forked was
    raised inside a fork hook, printed as "Exception ignored" and lost; the run exited 0."""
    previous = signal.signal(stop, _raise_keyboard_interrupt)
    finished = False
    try:
        with pytest.raises(KeyboardInterrupt), ctrl_c_held():
            signal.raise_signal(stop)
            finished = True
        assert finished
        assert signal.getsignal(stop) is _raise_keyboard_interrupt
    finally:
        signal.signal(stop, previous)
