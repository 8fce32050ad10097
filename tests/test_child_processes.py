"""trackfuse/child_processes.py: a stop signal held while a child process starts."""

from __future__ import annotations

import json
import os
import platform
import signal
import subprocess
import time

import pytest

from trackfuse.child_processes import ctrl_c_held, process_alive
from trackfuse.runlock import HOLDER_FILE, held_by_a_live_process


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


@pytest.mark.skipif(not os.path.exists("/proc/self"), reason="reads /proc")
def test_a_killed_process_not_yet_reaped_is_not_alive(tmp_path):
    """A run killed by kill -9 stays a zombie until its parent reaps it: `trackfuse runs`
    listed it as running until then (its holder file names the pid)."""
    child = subprocess.Popen(["sleep", "30"])
    try:
        assert process_alive(child.pid)
        (tmp_path / HOLDER_FILE).write_text(json.dumps({"pid": child.pid,
                                                        "host": platform.node()}))
        assert held_by_a_live_process(tmp_path)
        os.kill(child.pid, signal.SIGKILL)
        deadline = time.monotonic() + 10
        while _state(child.pid) != "Z" and time.monotonic() < deadline:
            time.sleep(0.01)
        assert _state(child.pid) == "Z"  # killed, not reaped: the pid still exists
        assert not process_alive(child.pid)
        assert not held_by_a_live_process(tmp_path)
    finally:
        child.kill()
        child.wait()
    assert not process_alive(child.pid)


@pytest.mark.skipif(not os.path.exists("/proc/self"), reason="reads /proc")
def test_another_users_process_is_alive_until_it_is_a_zombie(monkeypatch):
    """Signalling another user's process is not permitted: such a zombie read as alive."""
    def not_permitted(pid, sig):
        raise PermissionError(1, "Operation not permitted")

    child = subprocess.Popen(["sleep", "30"])
    try:
        with monkeypatch.context() as patch:
            patch.setattr("trackfuse.child_processes.os.kill", not_permitted)
            assert process_alive(child.pid)
            real_open = open

            def hidden(path, *args, **kw):  # /proc mounted with hidepid: not ours, not seen
                if str(path) == f"/proc/{child.pid}/stat":
                    raise FileNotFoundError(path)
                return real_open(path, *args, **kw)

            patch.setattr("builtins.open", hidden)
            assert process_alive(child.pid)
        os.kill(child.pid, signal.SIGKILL)
        deadline = time.monotonic() + 10
        while _state(child.pid) != "Z" and time.monotonic() < deadline:
            time.sleep(0.01)
        monkeypatch.setattr("trackfuse.child_processes.os.kill", not_permitted)
        assert not process_alive(child.pid)
    finally:
        monkeypatch.undo()
        child.kill()
        child.wait()


def _state(pid: int) -> str:
    with open(f"/proc/{pid}/stat") as fh:
        return fh.read().rsplit(")", 1)[1].split()[0]
