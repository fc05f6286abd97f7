"""The steps the time-history commands share: the cost guard, the integration with its
progress bar, the replacement of an earlier result, and writing, drawing and reporting a
history. The command line (:mod:`cablesim.cli`) passes its ``note`` and ``echo`` (which follow
``--quiet`` and ``--verbose``).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import typer

from ..channels import channel_index
from ..dynamics import interrupts
from ..dynamics.status import Status
from .hdf5 import describe_result, is_complete_result
from .naming import remove_figures, replacing_note
from .paths import beside, check_room
from .report import history_summary
from .terminal import LazyBar, say_error, say_warnings


#: Room allowed for each PNG a run draws, bytes (the figures of a one-node history: 70-190 kB).
PNG_BYTES = 400e3


def guard(cost, force: bool, fix: str, out: Path | None, note, figures: int = 0) -> None:
    """Refuse a run above the cost limits (unless --force) or beyond this machine; say a long
    run's estimate before it starts; refuse a disk without room for the results (the HDF5 file
    and the ``figures`` PNGs drawn beside it)."""
    err = cost.refusal(force, fix)
    if err is not None:
        raise err
    if out is not None:
        check_room(out, cost.disk + PNG_BYTES * figures)
    note(f"estimate: {cost.text()}", verbose_only=not cost.long)


def simulate(planned, duration: float, notice, quiet: bool = False):
    """Integrate a planned history with a progress bar; ``(run, wall seconds)``, the seconds
    spent compiling kernels on their first use (``notice``) left out."""
    bar = LazyBar(1000, "simulating", quiet=quiet, show_eta=True)
    t0, c0 = time.perf_counter(), notice.seconds()
    with bar:
        run = planned.run(progress=lambda t: bar.set(int(1000 * t / duration)))
    return run, time.perf_counter() - t0 - (notice.seconds() - c0)


def replace_result(out: Path, kind: str | None, note) -> None:
    """Say so (``note``, unless None) before a complete result is replaced, and remove the
    figures the old one drew (those of ``kind``; none if None)."""
    text = replacing_note(out, describe_result) if note is not None else None
    if text:
        note(f"note: {text}")
    if kind is not None:
        remove_figures(out, kind)


def finish_history(run, out: Path, plot: bool, channels, wall: float, full: bool, note, echo):
    """Write the history (beside a complete result if this run is not complete), plot (not
    after Ctrl-C or SIGTERM: the figures of an interrupted run would delay the exit by
    seconds; `cablesim plot` draws them), report; exit 3 (stopped early) or 130/143."""
    case, hist = run.case, run.history
    if case.outputs.channels:  # a scene keeps only the channels it draws
        keep = list(dict.fromkeys(channel_index(c, hist.n_dof, case.dim) + 1 for c in case.outputs.channels))  # node20.v = z40
        run = replace(run, history=hist.keep(keep))
        hist = run.history
    target = out
    if not hist.completed and is_complete_result(out):
        target = beside(out)  # never replace a complete result with an incomplete one
    replace_result(target, "history", note)
    with interrupts.Deferred() as held:  # a signal while the file is written comes after it
        run.to_hdf5(target)
    late = held.hit or interrupts.received() is not None  # a signal after the time loop: the run is whole
    draw = plot and hist.t.size > 1 and hist.status is not Status.INTERRUPTED and not late
    pngs = run.plot(target.with_suffix(""), channels=channels) if draw else []
    say_warnings(hist.warnings)
    echo(history_summary(case, hist, run.integrator, wall, full=full))
    echo(f"\nWrote {target}" + (" and " + ", ".join(str(p) for p in pngs) if pngs else ""))
    if late and hist.completed:
        say_error(f"interrupted ({interrupts.signal_name()}) after the time integration had completed; {target} "
                  f"holds the whole run. No figures were drawn (`cablesim plot {target}` draws them).")
        raise typer.Exit(interrupts.exit_status())
    if not hist.completed:
        kept = f" The complete result {out} was kept; this run's results are in {target}." if target != out else ""
        drawn = "" if draw or not plot else f" No figures were drawn (`cablesim plot {target}` draws them)."
        say_error(f"the run did not complete: {hist.message}. Results up to that instant were written.{kept}{drawn}")
        if hist.status is Status.INTERRUPTED:
            raise typer.Exit(interrupts.exit_status())
        raise typer.Exit(3)
