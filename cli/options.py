"""What the ``trackfuse`` commands share: option declarations, choices, and one-line
``error: ...`` messages on stderr (usage errors exit 2); a closed stdout (``| head``) is
silent (:class:`QuietClosedStdout`)."""

from __future__ import annotations

import gc
import io
import os
import re
import signal
import sys
from collections.abc import Callable
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from typer.core import TyperGroup


def _stop(signum: int, frame: object) -> None:
    """SIGTERM stops a command as Ctrl-C does: saved work resumable, one line, exit 130."""
    raise KeyboardInterrupt


def _forget_caught_ctrl_c() -> None:
    """Let a command's chosen exit status stand after a Ctrl-C it caught.

    CPython 3.11-3.13 (python/cpython#128130) would end the process by SIGINT after a caught
    ``KeyboardInterrupt`` left ``exec``'d code; running such code clears that mark."""
    exec("")


class QuietClosedStdout:
    """``sys.stdout`` that drops output silently once its reader has gone, as ``cat`` does."""

    def __init__(self, stream):
        self.stream = stream

    def write(self, text: str) -> int:
        try:
            return self.stream.write(text)
        except BrokenPipeError:
            self._discard()
            return len(text)

    def flush(self) -> None:
        try:
            self.stream.flush()
        except BrokenPipeError:
            self._discard()

    def _discard(self) -> None:
        """Point the stream's file descriptor at ``/dev/null``: what is still buffered and
        what comes later (the interpreter's last flush included) goes nowhere."""
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self.stream.fileno())
            os.close(null)
        except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
            pass  # a stream without a descriptor (a test's buffer) cannot break this way

    def __getattr__(self, name: str):
        return getattr(self.stream, name)


def _value_given(err: Exception) -> str | None:
    """The value a bad option was given, from typer's check of it (a pydantic validation
    error, whose message, "Input should be greater than or equal to 1", does not echo it)."""
    errors = getattr(err.__cause__, "errors", None)
    try:
        first = errors()[0] if callable(errors) else {}
    except (IndexError, TypeError, ValueError):
        return None
    return printable(str(first["input"]))[:80] if "input" in first else None


#: The commands that save work a second call resumes.
RESUMABLE = ("run", "reproduce")


class OneLineErrors(TyperGroup):
    """Usage errors (a bad option value, a missing argument) as one ``error:`` line, exit 2;
    a Ctrl-C or SIGTERM as one ``interrupted:`` line, exit 130."""

    def invoke(self, ctx):
        """A Ctrl-C that no command turned into its own message is one line too."""
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt:
            resumable = ctx.invoked_subcommand in RESUMABLE
            print("interrupted" + (": run the same command again to resume" if resumable
                                   else ""), file=sys.stderr)
            raise typer.Exit(130) from None

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True,
             **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        signal.signal(signal.SIGTERM, _stop)
        stdout = sys.stdout
        sys.stdout = QuietClosedStdout(stdout)
        try:
            code = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except typer.TyperException as err:  # click's ClickException and UsageError
            ctx = getattr(err, "ctx", None)
            hint = f" (see `{ctx.command_path} --help`)" if ctx is not None else ""
            # typer words a bad choice "Invalid value for '--x': Value error, 'y' is not..."
            message = err.format_message().replace(": Value error, ", ": ")
            given = _value_given(err)
            if given is not None:  # "Invalid value for '--trials': got -3; input should..."
                reason = str(getattr(err, "message", ""))
                message = message.replace(reason, f"got {given}; {reason[:1].lower()}"
                                                  f"{reason[1:]}", 1)
            print_error(f"{message}{hint}")
            sys.exit(err.exit_code)
        except typer.Abort:
            print_error("aborted")
            sys.exit(1)
        finally:
            sys.stdout.flush()  # a closed pipe is found here at the latest, and silenced
            sys.stdout = stdout
            _forget_caught_ctrl_c()
            # The interpreter's collections at exit walk every object still alive (the
            # libraries a run imported): about 0.5 s after a run. The process is ending and
            # its memory goes with it, so they are spared.
            gc.freeze()
        sys.exit(code if isinstance(code, int) else 0)


class Executor(StrEnum):
    """Where the batches run (``trackfuse.executors.KINDS``)."""

    serial = "serial"
    process = "process"
    dask = "dask"


class ClusterKind(StrEnum):
    """The batch systems ``--cluster`` starts workers through."""

    slurm = "slurm"
    pbs = "pbs"
    local = "local"


class Format(StrEnum):
    """Output of ``trackfuse list [EXPERIMENT]``."""

    table = "table"
    yaml = "yaml"
    json = "json"


def printable(message: str) -> str:
    """``message`` with every character a terminal would act on (escape sequences, line
    breaks, other controls) written as its Python escape (``\\x1b``)."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)


def print_error(message: str) -> None:
    print(f"error: {printable(message)}", file=sys.stderr)


def fail(message: str, code: int = 2) -> None:
    """Print a one-line error to stderr and exit."""
    print_error(message)
    raise typer.Exit(code)


def warn(message: str) -> None:
    """Print a one-line warning to stderr."""
    print(f"warning: {printable(message)}", file=sys.stderr, flush=True)


Cfg = Annotated[Path, typer.Argument(metavar="CONFIG", help="Scenario config (YAML), or a "
                                     "config name (twin_sensor_orbit, ci/twin_sensor_ci): "
                                     "./configs/NAME.yaml if present, else the shipped one.")]
Overrides = Annotated[list[str] | None, typer.Argument(
    metavar="KEY=VALUE", show_default=False,
    help="Overrides as in Hydra: clutter.mean=5 (same as --set).")]
Sets = Annotated[list[str], typer.Option(
    "--set", metavar="KEY=VALUE", show_default=False,
    help="Override a value: clutter.mean=5, a list in brackets: 'algorithms=\\[nn/ekf]' "
         "(repeatable).")]
Sweeps = Annotated[list[str], typer.Option(
    "--sweep", metavar="KEY=V1,V2", show_default=False,
    help="Sweep an axis: clutter.mean=0,5,10 or 'clutter.mean=range(0,21,2)'; lists in "
         "brackets: 'algorithms=\\[a,b],\\[c]' (repeatable).")]
def whole_number(low: int, high: int | None = None) -> Callable[[str | int], int]:
    """Parser of an integer option in ``[low, high]`` (``None``: no limit): digits with an optional
    sign, so ``--trials 2.0`` is refused like ``trials: 10.0``."""
    def parse(text: str | int) -> int:
        if isinstance(text, int):  # the option's default
            return text
        try:  # int() of more than 4300 digits raises too
            value = int(text) if re.fullmatch(r"[+-]?[0-9]+", text.strip()) else None
        except ValueError:
            value = None
        if value is None or value < low or (high is not None and value > high):
            allowed = f">= {low}" if high is None else f"from {low} to {high}"
            raise typer.BadParameter(f"got {printable(text)[:80]}; allowed: an integer "
                                     f"{allowed}")
        return value
    return parse


#: The most ``--workers`` (a process pool of 2**31 crashed in the standard library).
MAX_WORKERS = 1024


Workers = Annotated[int, typer.Option(metavar="N", parser=whole_number(0, MAX_WORKERS),
                                      show_default="all cores",
                                      help="Parallel workers (0 = all cores).")]
OutDir = Annotated[str, typer.Option("--out", metavar="FOLDER", help="Output root folder.")]


def out_folder(text: str) -> Path:
    """The ``--out`` folder; an empty value (an unset shell variable) is refused."""
    if not text.strip():
        fail("--out: got an empty folder name; allowed: a folder path (default: results)")
    return Path(text)
ExecutorOpt = Annotated[Executor, typer.Option(help="Where batches run.")]
Scheduler = Annotated[str | None, typer.Option(metavar="ADDRESS", help="dask scheduler "
                                               "address, e.g. tcp://host:8786.")]
SchedulerFile = Annotated[str | None, typer.Option(metavar="FILE", help="dask scheduler file.")]
ClusterOpt = Annotated[ClusterKind | None, typer.Option(
    show_default=False, help="Start dask workers as batch jobs (dask-jobqueue; the config's "
    "cluster section or dask's jobqueue config: queue, cores, memory, walltime, min_jobs, "
    "max_jobs); local runs the same jobs here. See docs/cluster.md.")]
DryRun = Annotated[bool, typer.Option("--dry-run", metavar="", help="Print the resolved "
                                      "config and the work; run nothing.")]
NoPlots = Annotated[bool, typer.Option(
    "--no-plots", metavar="", help="Skip the report (figures, tables, index.html): only the "
    "CSVs and summary.csv. `trackfuse plot RUN_DIR`, or the same command without it, writes "
    "it later.")]
NoProgress = Annotated[bool, typer.Option("--no-progress", metavar="",
                                          help="No progress output.")]
