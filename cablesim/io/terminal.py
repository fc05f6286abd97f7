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

from ..jit import cache_dir
from ..names import ANALYSES, INTEGRATORS, SLACK_POLICIES


#: Where numba caches the compiled kernels (their index files tell whether a run must compile).
KERNEL_CACHE = cache_dir()


def say_error(message: str, command: str | None = None) -> None:
    """A refusal or failure: one ``error:`` paragraph on standard error, then ``command`` (one to
    copy, such as the --resume hint) whole on a line of its own."""
    sys.stderr.write(textwrap.fill("error: " + message, width=100) + "\n")
    if command:  # a command to copy: whole, on one line of its own
        sys.stderr.write(command + "\n")


def say_warnings(warnings) -> None:
    """Plausibility warnings: one paragraph each on standard error; they never stop a run."""
    for w in warnings or ():
        sys.stderr.write(textwrap.fill("warning: " + w, width=100) + "\n")


class CommandGroup(TyperGroup):
    """Usage errors (an unknown option, ``--omega abc``) as one ``error:`` paragraph with exit
    status 2, like every other refusal; a closed output pipe (``cablesim example | head``) ends
    the command quietly."""

    def main(self, *args, standalone_mode: bool = True, **kwargs):
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
    refreshed at most ten times a second; silent when quiet or when standard error is not a
    terminal. Use as a context manager; call it with the text to show."""

    def __init__(self, quiet: bool = False):
        self.quiet = quiet
        self.shown = 0.0

    def __enter__(self):
        return self

    def __call__(self, text: str) -> None:
        now = time.monotonic()
        if not self.quiet and sys.stderr.isatty() and now - self.shown > 0.1:
            self.shown = now
            sys.stderr.write(f"\r{text}   ")
            sys.stderr.flush()

    def __exit__(self, *exc):
        if self.shown:
            sys.stderr.write("\n")
        return False


def compile_notice(note, cache: Path | None = None, pattern: str = "field.rate-*.nbi") -> bool:
    """Tell ``note`` (a line to print) that the compiled kernels are not yet in numba's cache."""
    cache = cache if cache is not None else KERNEL_CACHE
    if any(cache.rglob(pattern)):
        return False
    note("compiling the numerical kernels on first use (about a minute; cached for later runs) ...")
    return True


@contextlib.contextmanager
def compiling(note, pattern: str = "field.rate-*.nbi", delay: float = 1.5):
    """Say that the kernels are being compiled, if they are (cold cache) and it takes a while:
    a refusal found in the first moments is then never preceded by the notice."""
    timer = None
    if not any(KERNEL_CACHE.rglob(pattern)):
        timer = threading.Timer(delay, compile_notice, args=(note,), kwargs={"pattern": pattern})
        timer.daemon = True
        timer.start()
    try:
        yield
    finally:
        if timer is not None:
            timer.cancel()


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
                         "steps, a sweep 1e9, or 4 GB of memory).")
MODES_OPT = typer.Option(None, "--modes", min=1, metavar="K", help="Compute only the lowest K modes and the highest "
                         "frequency (sets modal.modes; default: every mode up to n = 300 nodes, else the lowest 100).")
SNAPSHOTS_OPT = typer.Option(None, "--snapshots", min=1, max=24, metavar="K", help="Time histories: draw the cable "
                             "at K instants spread over the record instead (<file>-snapshots.png).")
STAMP_OPT = typer.Option(None, "--stamp", metavar="TEXT", help="Text drawn in a corner of every figure and kept "
                         "in the PNG, e.g. 'preview: coarse grid'.")
