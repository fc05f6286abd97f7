"""Checks the newer commands make before anything is computed, and the warnings they give after.

- :func:`check_overlay`: ``cablesim continue --overlay SWEEP.h5`` reads the sweep file at once
  (a missing, damaged or truncated file, a file of another kind, or a sweep of another cable is
  refused before the continuation runs; a sweep of other loads or damping is drawn with a note).
- :func:`continue_inputs`: every file ``continue`` reads, which no output may be.
- :func:`guard_continue`: the cost of ``continue`` estimated before it starts, printed for a
  long run and refused above the limits unless ``--force`` (:mod:`cablesim.analyses.estimates`).
- :func:`empty_continuation`: the refusal of a continuation that found no orbit (slack from the
  first orbit), saying why and what to try.

Like :mod:`cablesim.cli`, this module imports its machinery only when a check runs.
"""

from __future__ import annotations

from pathlib import Path

from .errors import CablesimError

#: Case sections whose difference makes a sweep's points another cable's.
_SAME_CABLE = ("spatial", "cable")
#: Case sections whose difference is noted when a sweep is drawn over a continuation.
_NOTED = ("loads", "supports", "damping", "analysis")


def continue_inputs(case_file, overlay) -> list:
    """The files ``cablesim continue`` reads: no output may be one of them."""
    return [p for p in (case_file, overlay) if p is not None]


#: Room allowed for a continuation file, bytes (the paper example's: 130 kB).
CONTINUATION_BYTES = 300e3


def continue_room(figures: int) -> float:
    """The room ``cablesim continue`` needs on disk: its file and ``figures`` PNGs, bytes."""
    from .io.finish import PNG_BYTES

    return CONTINUATION_BYTES + PNG_BYTES * figures


def _sections(case) -> dict:
    """The sections of a case compared between a continuation and its overlay (plain data)."""
    data = case.model_dump(mode="json", exclude_none=True)
    data.update(case.expanded())
    return data


def check_overlay(overlay: Path | None, case) -> list[str]:
    """Refuse, before the continuation runs, an ``--overlay`` that cannot be drawn over ``case``.

    Returns
    -------
    list of str
        Notes to print (the sweep's loads or damping differ, no channel in common); empty if none.

    Raises
    ------
    CablesimError
        The file is missing, not a readable sweep file, or a sweep of another cable.
    """
    if overlay is None:
        return []
    from .case import parse_case
    from .io.hdf5 import FAMILY_TEXT, inspect_result
    from .io.sweeps import read_sweep

    overlay = Path(overlay)
    fix = "give the HDF5 file `cablesim sweep` wrote for this case, or drop --overlay."
    if not overlay.exists():
        raise CablesimError(f"--overlay {overlay}: no such file; {fix}", field="overlay")
    try:
        info = inspect_result(overlay)
        if info.family != "sweep":
            raise CablesimError(f"it is {FAMILY_TEXT[info.family]}, not a sweep file")
        stored = parse_case(info.case_text, source=f"(the case stored in {overlay})", default_name="sweep")
        sweep = read_sweep(overlay)
    except CablesimError as exc:
        raise CablesimError(f"--overlay {overlay} cannot be drawn: {str(exc).rstrip('.')}. Nothing was computed; "
                            f"{fix}", field="overlay") from None
    except (OSError, KeyError, ValueError, TypeError, IndexError) as exc:
        raise CablesimError(f"--overlay {overlay} cannot be read as a sweep file ({type(exc).__name__}: {exc}); it "
                            f"may be truncated or damaged. Nothing was computed; {fix}", field="overlay") from None
    mine, theirs = _sections(case), _sections(stored)
    other = [k for k in _SAME_CABLE if mine.get(k) != theirs.get(k)]
    if other:
        raise CablesimError(f"--overlay {overlay} is a sweep of another cable (its {' and '.join(other)} "
                            f"section{'s differ' if len(other) > 1 else ' differs'} from this case's), so its "
                            f"points are not this case's responses. Nothing was computed; {fix}", field="overlay")
    notes = []
    differ = [k for k in _NOTED if mine.get(k) != theirs.get(k)]
    if differ:
        notes.append(f"the sweep {overlay} was computed with other {', '.join(differ)} than this case; its "
                     "points are drawn as they are, for comparison.")
    names, _ = _continuation_channels(case)
    if not set(names) & set(sweep.channels):
        notes.append(f"the sweep {overlay} holds none of the channels {', '.join(names)}; none of its "
                     "points can be drawn.")
    return notes


def _continuation_channels(case):
    from .analyses.continuation import continuation_channels

    return continuation_channels(case)


def empty_continuation(result, case) -> CablesimError | None:
    """The refusal of a continuation that found no orbit at all, with why and what to try (None
    when it found one)."""
    if result.branches:
        return None
    spec = case.continuation
    why = result.start_failure or "the first orbit could not be computed"
    start = f"continuation.{spec.parameter}.start"
    if result.start_cause == "SLACK":  # orbits with slack intervals are not followed
        fix = (f"Orbits with slack segments are not followed: give smaller harmonic loads (loads.FL) or load factor "
               f"(continuation.gamma), or a {start} where the response is small (away from resonance); "
               "`cablesim history` integrates through slack episodes")
    else:
        fix = (f"Try a {start} where the response is small (away from resonance), more shooting segments "
               "(continuation.segments) or start_from: history")
    return CablesimError(f"The continuation found no periodic orbit: {why}. Nothing was written. {fix}.",
                         field="continuation")


def kept_text(result) -> str:
    """What an interrupted continuation kept, in words."""
    n, k = result.n_points, sum(b.kind != "grazing" for b in result.bifurcations)
    parts = [f"the {n} periodic orbit{'s' if n != 1 else ''} on {len(result.branches)} branch(es) computed"]
    parts += [f"the {k} bifurcation{'s' if k != 1 else ''} located on them"] if k else []
    parts += ["the bifurcation curves traced"] if result.loci else []
    return ", ".join(parts[:-1]) + (" and " if len(parts) > 1 else "") + parts[-1]


#: What to change when a continuation is above the cost limits.
CONTINUE_FIX = ("Give a shorter range (continuation.omega, .gamma or .support: start and stop nearer each other, or "
                "away from the lowest frequencies, whose long forcing periods take the most steps), a smaller "
                "limit of orbits per branch (continuation.max_points), fewer nodes (cable.nodes, or fewer "
                "segments in cable.S) or fewer shooting segments (continuation.segments)")


def guard_continue(case, analysis, force: bool, note) -> None:
    """Estimate the continuation's cost (:func:`cablesim.api.continuation_cost`), print it for
    a long run and refuse one above the limits unless ``force``; Ctrl-C or SIGTERM while it is
    estimated ends the command with nothing written."""
    from . import api
    from .dynamics import interrupts
    from .io.finish import guard
    from .io.terminal import say_error

    import typer

    try:
        cost = api.continuation_cost(case, analysis)
    except KeyboardInterrupt:
        say_error(f"interrupted ({interrupts.signal_name()}) before any orbit was computed (while the cost of the "
                  "continuation was estimated); nothing was written.")
        raise typer.Exit(interrupts.exit_status()) from None
    guard(cost, force, CONTINUE_FIX, None, note)


def companions(pngs):
    """Every file ``cablesim continue -o OUT`` writes beside ``OUT``: the figures ``pngs(OUT)``,
    the journal and the lock."""
    return lambda o: [*pngs(o), o.with_name(o.name + ".journal"), o.with_name(o.name + ".lock")]


def nothing_to_resume(out: Path, fingerprint: str, echo) -> bool:
    """``--resume`` without a journal beside ``out``: True (said so) when ``out`` already holds
    this continuation, complete; refused otherwise."""
    from .io.journal import stored_state
    from .io.continuation_journal import nothing_to_resume_error

    if out.with_name(out.name + ".journal").exists():
        return False
    complete, fp = stored_state(out, "continuation", complete_if_unmarked=True)
    if complete and fp in (None, fingerprint):
        echo(f"Nothing to do: {out} already holds this continuation, complete (there is no journal to resume).")
        return True
    raise nothing_to_resume_error(out, fingerprint)


def interrupted(result, out: Path, ctx=None) -> None:
    """Say what an interrupted ``continue -o`` kept (the file written from the journal, beside a
    complete result of the same name) and the command that finishes it (from the invocation
    ``ctx``); exit 130 or 143."""
    import shlex

    import typer

    from .dynamics import interrupts
    from .io.journal import snapshot_path
    from .io.provenance import command_words
    from .io.terminal import say_error

    if not result.n_points:
        say_error(f"interrupted ({interrupts.signal_name()}) before any orbit was computed; nothing was written.")
        raise typer.Exit(interrupts.exit_status())
    target = snapshot_path(out)  # where the run wrote: beside a complete result, never over it
    again = shlex.join(command_words(ctx, drop=("resume", "output")) + ["--output", str(out), "--resume"]) if ctx else None
    kept = f" (the complete result {out} is untouched)" if target != out else ""
    say_error(f"interrupted ({interrupts.signal_name()}); {kept_text(result)} until then are in {target}{kept}, marked "
              f"incomplete (`cablesim plot {target}` draws them), and in the journal {out.name}.journal. Finish the "
              "continuation with:", command=again)
    raise typer.Exit(interrupts.exit_status())


def curves_refused(exc, out: Path, ctx=None) -> None:
    """Say why the bifurcation curves were not traced, where the branches are and the command
    that traces the curves from them (from the invocation ``ctx``); exit 2."""
    import shlex

    import typer

    from .io.journal import snapshot_path
    from .io.provenance import command_words
    from .io.terminal import say_error

    target = snapshot_path(out)
    again = (shlex.join(command_words(ctx, drop=("resume", "output", "force")) + ["--output", str(out), "--resume", "--force"])
             if ctx else None)
    cost = exc.cost.text().split(": ", 1)[1]
    say_error(f"continuation.loci: the bifurcation curves would take {cost}, more than allowed ({exc.why}), so they "
              f"were not traced. The branches ({kept_text(exc.result)}) are in {target}, marked incomplete, and in the "
              f"journal {out.name}.journal. Narrow continuation.{exc.second} or continuation.omega, or "
              "lower continuation.max_points (points per curve direction), and run again; or trace these curves "
              "from the branches with:", command=again)
    raise typer.Exit(2)


def run_continue(case, out: Path, analysis, overlay, plot: bool, note, echo, quiet: bool, force: bool = False,
                 resume: bool = False, ctx=None) -> None:
    """The computing part of ``cablesim continue``, its inputs and outputs checked: bound its
    cost, continue (every orbit journaled and the file kept current; ``resume``: from the
    journal of an interrupted run), say what an interruption kept, refuse an empty result,
    report and draw; ``ctx``, the invocation, gives the commands that finish an interrupted or
    refused run."""
    import time

    from . import api, cli_charts
    from .analyses.charts import CurvesRefused, Interrupted
    from .io.finish import replace_result
    from .io.journal import fingerprint
    from .io.report import continuation_summary
    from .io.terminal import StatusLine, compiling, say_warnings
    from .plots.continuation import plot_continuation

    if resume and nothing_to_resume(out, fingerprint(case.text, analysis, "continue"), echo):
        return
    if resume:  # a damaged or foreign journal is refused before anything is computed
        from .io.journal import read_journal

        read_journal(out.with_name(out.name + ".journal"), fingerprint(case.text, analysis, "continue"), "continuation")
    if not resume:
        replace_result(out, None, note)  # the note now; the old figures go once this one is complete
    with compiling(note) as notice, StatusLine(quiet=quiet) as status:
        guard_continue(case, analysis, force, note)
        t0, c0 = time.perf_counter(), notice.seconds()  # the estimate's time left out
        try:
            run = api.continuation(case, analysis, progress=cli_charts.branch_status(status),
                                   loci_progress=cli_charts.loci_status(status), output=out, resume=resume,
                                   force=force)
        except Interrupted as exc:
            interrupted(exc.result, out, ctx)
        except CurvesRefused as exc:
            curves_refused(exc, out, ctx)
    err = empty_continuation(run.result, case)
    if err is not None:
        raise err
    say_warnings(run.result.warnings)
    replace_result(out, "continuation", None)  # the figures of the result it replaced
    echo(continuation_summary(case, run.result, time.perf_counter() - t0 - (notice.seconds() - c0))
         + cli_charts.loci_text(run.result))
    drawn = f" and {plot_continuation(out, out.with_suffix('.png'), overlay=overlay)}" if plot else ""
    echo(f"\nWrote {out}" + drawn + (cli_charts.chart_text(out, run.result) if plot else ""))
