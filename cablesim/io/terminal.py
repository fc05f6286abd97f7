"""The terminal: error and warning paragraphs, progress bars, usage errors as paragraphs, the
notice while the kernels compile on first use, and the options the commands share.

Light on purpose (the command line imports it before anything heavy).
"""

from __future__ import annotations

import contextlib
import os
import sys
import textwrap
import threading
import time
from enum import Enum
from pathlib import Path

import typer
from typer.core import TyperGroup

from .. import jit
from ..names import ANALYSES, INTEGRATORS, SLACK_POLICIES


def paragraph(text: str, width: int = 100) -> str:
    """``text`` wrapped to ``width`` at spaces only: a file path, a command or a hyphenated
    option is never cut in two (a long one runs past the width)."""
    return textwrap.fill(text, width=width, break_long_words=False, break_on_hyphens=False)


def quiet_outputs(quiet: bool) -> tuple:
    """``(echo, note)`` for a command: results to standard output, notes to standard error,
    both silent with ``--quiet``."""

    def echo(text: str) -> None:
        if not quiet:
            typer.echo(text)

    def note(text: str) -> None:
        if not quiet:
            sys.stderr.write(text + "\n")

    return echo, note


def say_error(message: str, command: str | None = None) -> None:
    """A refusal or failure: one ``error:`` paragraph on standard error, then ``command`` (one to
    copy, such as the --resume hint) whole on a line of its own."""
    sys.stderr.write(paragraph("error: " + message) + "\n")
    if command:  # a command to copy: whole, on one line of its own
        sys.stderr.write(command + "\n")


def say_warnings(warnings) -> None:
    """Plausibility warnings: one paragraph each on standard error; they never stop a run."""
    for w in warnings or ():
        sys.stderr.write(paragraph("warning: " + w) + "\n")


class CommandGroup(TyperGroup):
    """Usage errors (an unknown option, ``--omega abc``) as one ``error:`` paragraph with exit
    status 2, like every other refusal; a closed output pipe (``cablesim example | head``) ends
    the command quietly."""

    def main(self, *args, standalone_mode: bool = True, **kwargs):
        argv = kwargs.pop("args", None) if "args" in kwargs else (args[0] if args else None)
        args = (root_flags_first(sys.argv[1:] if argv is None else list(argv)), *args[1:])
        if not standalone_mode:
            return super().main(*args, standalone_mode=False, **kwargs)
        try:
            code = super().main(*args, standalone_mode=False, **kwargs)
        except BrokenPipeError:
            quiet_pipe()
            sys.exit(141)
        except Exception as exc:  # click's exception classes (typer carries its own copy of click)
            kinds = {c.__name__ for c in type(exc).__mro__}
            if "NoArgsIsHelpError" in kinds:  # `cablesim` alone: the help, which is no error
                typer.echo(exc.ctx.get_help() if getattr(exc, "ctx", None) is not None else exc.format_message())
                sys.exit(0)
            if "UsageError" in kinds:
                ctx = getattr(exc, "ctx", None)
                where = f"cablesim {ctx.info_name}" if ctx is not None and ctx.parent is not None else "cablesim"
                msg = exc.format_message().replace("Value error, ", "").rstrip()
                say_error(f"{msg}{'' if msg.endswith(('.', '!', '?')) else '.'} See `{where} --help` for the "
                           "options and their values.")
                sys.exit(2)
            if "Abort" in kinds:
                sys.stderr.write("error: aborted.\n")
                sys.exit(1)
            raise
        sys.exit(code if isinstance(code, int) else 0)


#: Options of cablesim itself that may also be written after the command (`cablesim static -q`).
ROOT_FLAGS = ("--quiet", "-q", "--verbose", "-v")


def root_flags_first(argv: list[str]) -> list[str]:
    """The arguments with ``--quiet`` and ``--verbose`` moved before the command, wherever they
    were given (they belong to cablesim, not to one command); nothing after ``--`` moves."""
    end = argv.index("--") if "--" in argv else len(argv)
    head = argv[:end]
    return [a for a in head if a in ROOT_FLAGS] + [a for a in head if a not in ROOT_FLAGS] + argv[end:]


def quiet_pipe() -> None:
    """The reader went away: point stdout at /dev/null so that the interpreter's last flush is silent."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


class LazyBar:
    """A progress bar on standard error that appears only once there is progress to show
    (so that an input error is never preceded by a bar's label); none if ``quiet``."""

    def __init__(self, length: int, label: str, quiet: bool = False, **kw):
        self._args = dict(length=length, label=label, file=sys.stderr, **kw)
        self._bar = None
        self.done = 0
        self.quiet = quiet

    def __enter__(self):
        return self

    def set(self, done: int, length: int | None = None):
        if self.quiet:
            return
        if self._bar is None:
            if length is not None:
                self._args["length"] = length
            self._bar = typer.progressbar(**self._args).__enter__()
        if length is not None:
            self._bar.length = length
        if done > self.done:
            self._bar.update(done - self.done)
            self.done = done

    def __exit__(self, *exc):
        if self._bar is not None:
            self._bar.__exit__(*exc)
        return False


class StatusLine:
    """One status line on a terminal for a run of unknown length (``cablesim continue``),
    refreshed at most ten times a second; when standard error is not a terminal (a log file),
    one plain line every ``every`` seconds instead, the first after ``every`` seconds (a short
    run prints none); silent when quiet. Use as a context manager; call it with the text to show."""

    def __init__(self, quiet: bool = False, every: float = 5.0):
        self.quiet = quiet
        self.shown = 0.0
        self.every = every
        self.tty = sys.stderr.isatty()
        self.logged = time.monotonic()

    def __enter__(self):
        return self

    def __call__(self, text: str) -> None:
        now = time.monotonic()
        if self.quiet:
            return
        if self.tty and now - self.shown > 0.1:
            self.shown = now
            sys.stderr.write(f"\r{text}   ")
            sys.stderr.flush()
        elif not self.tty and now - self.logged >= self.every:
            self.logged = now
            sys.stderr.write(text + "\n")
            sys.stderr.flush()

    def __exit__(self, *exc):
        if self.shown:
            sys.stderr.write("\n")
        return False


class CompileNotice:
    """Tells a user that the numerical kernels are being compiled (their first use on this
    machine), and for how long: :func:`compiling` makes one.

    numba compiles a kernel the first time it is needed and caches it on disk; only a cache
    miss counts (:mod:`cablesim.jit` watches numba's compile events). Once compilation has
    lasted ``delay`` seconds a line names the kernel; on a terminal a status line counts the
    kernels; at the end one line says how many took how long. A refusal found in the first
    moments is never preceded by the notice.
    """

    def __init__(self, note, delay: float = 1.0, tty: bool | None = None):
        self.note, self.delay = note, delay
        self.tty = sys.stderr.isatty() if tty is None else tty
        self.kernels0, self.seconds0 = jit.kernels_compiled(), jit.compile_seconds()
        self.said = False
        self.timer = None
        self.shown = 0.0
        self.last = None

    def kernels(self) -> int:
        """Kernels compiled since the notice began."""
        return jit.kernels_compiled() - self.kernels0

    def seconds(self) -> float:
        """Seconds spent compiling since the notice began."""
        return jit.compile_seconds() - self.seconds0

    def started(self, name: str) -> None:
        """A kernel starts compiling (the hook of :class:`cablesim.jit.on_compile`)."""
        self.last = name
        if self.said:
            self._status(name)
        elif self.timer is None or not self.timer.is_alive():  # the delay counts compiling time only
            self.timer = threading.Timer(max(0.05, self.delay - self.seconds()), self._say)
            self.timer.daemon = True
            self.timer.start()

    def _say(self) -> None:
        name = jit.compiling_now()
        if self.said:
            return
        remaining = self.delay - self.seconds()
        if remaining > 0.0:  # compiling (or loading from the cache) has not lasted the delay yet
            if name is not None:  # look again once it could have; otherwise the next compile re-arms
                self.timer = threading.Timer(max(0.05, remaining), self._say)
                self.timer.daemon = True
                self.timer.start()
            return
        self.said = True
        name = name or self.last or "the kernels"  # (one that ended before the timer is still named)
        self.note(f"compiling {name} and the kernels it needs (first use on this machine; cached for later "
                  "runs: `cablesim compile` compiles them all at once) ...")

    def _status(self, name: str) -> None:
        now = time.monotonic()
        if self.tty and now - self.shown > 0.2:
            self.shown = now
            sys.stderr.write(f"\rcompiling: {self.kernels()} kernels, {self.seconds():.0f} s ({name})   ")
            sys.stderr.flush()

    def close(self) -> None:
        """Stop watching; if the notice was given, say what the compilation took."""
        if self.timer is not None:
            self.timer.cancel()
        if not self.said and self.kernels() and self.seconds() >= self.delay:
            self.said = True  # it ended between two checks: say it now
        if self.said:
            if self.tty and self.shown:
                sys.stderr.write("\n")
            self.note(f"compiled {self.kernels()} kernels in {self.seconds():.1f} s (not counted in the run's "
                      "times; later runs load them from the cache)")


@contextlib.contextmanager
def compiling(note, delay: float = 1.0):
    """Within this context, say so when the kernels are compiled (see :class:`CompileNotice`);
    yields the notice, whose :meth:`~CompileNotice.seconds` a caller subtracts from its times."""
    notice = CompileNotice(note, delay)
    with jit.on_compile(notice.started):
        try:
            yield notice
        finally:
            notice.close()


# ----------------------------------------------------------------------------------------------
# Options the commands share
# ----------------------------------------------------------------------------------------------
Analysis = Enum("Analysis", {a.replace("-", "_"): a for a in ANALYSES}, type=str)
IntegratorName = Enum("IntegratorName", {a.replace("-", "_"): a for a in INTEGRATORS}, type=str)
SlackPolicy = Enum("SlackPolicy", {a: a for a in SLACK_POLICIES}, type=str)
SLACK_OPTION = typer.Option(None, "--slack", help="Exact analysis: continue through slack segments or stop where one goes slack [default: the case's slack].")
CASE_ARG = typer.Argument(None, help="YAML case file; omit it to run the paper's example.", show_default=False)
SET_OPT = typer.Option(None, "--set", metavar="KEY=VALUE", help="Override a case-file value, with a dotted key "
                       "(e.g. sweep.duration=1000); repeatable. Values are read as YAML.")
ANALYSIS_OPT = typer.Option(None, "--analysis", help="Override the case file's analysis (default: analysis: in "
                            "the case file, else exact).")
INTEGRATOR_OPT = typer.Option(None, "--integrator", help="Time-integration scheme (default: integrator.name in "
                              "the case file, else dopri5, or generalized-alpha for a stiff cable).")
DT_OPT = typer.Option(None, "--dt", metavar="SECONDS", help="Fixed time step, s, of the scheme named (rk4, newmark, "
                      "generalized-alpha; sets integrator.dt, clears its rtol and atol).")
RTOL_OPT = typer.Option(None, "--rtol", help="Relative tolerance of the error-controlled steps (dopri5, newmark, "
                        "generalized-alpha; sets integrator.rtol, clears its dt) [default: 1e-8 for dopri5, 1e-5 for "
                        "the implicit schemes].")
FORCE_OPT = typer.Option(False, "--force", help="Run even when the cost estimate is above the limits (1e8 time "
                         "steps, a sweep 1e9; a continuation's first branch 1e8 Runge-Kutta steps or 20000 orbits; "
                         "or 4 GB of memory).")
MODES_OPT = typer.Option(None, "--modes", min=1, metavar="K", help="Compute only the lowest K modes and the highest "
                         "frequency (sets modal.modes; default: every mode up to n = 300 nodes, else the lowest 100).")
MODES_DRAWN_OPT = typer.Option(4, "--modes-drawn", min=0, max=20, metavar="K", help="Draw the lowest K mode shapes "
                               "beside the cable (<name>-modes.png; 0: none).")
SNAPSHOTS_OPT = typer.Option(None, "--snapshots", min=1, max=24, metavar="K", help="Time histories: draw the cable "
                             "at K instants spread over the record instead (<file>-snapshots.png).")
STAMP_OPT = typer.Option(None, "--stamp", metavar="TEXT", help="Text drawn in a corner of every figure and kept "
                         "in the PNG, e.g. 'preview: coarse grid'.")
