"""The design-chart parts of the command line: ``cablesim backbone``, and what ``cablesim
continue`` adds with ``continuation.loci`` (the curves' summary, the stability chart, keeping the
curves traced when interrupted).

:func:`register` adds the commands to the application of :mod:`cablesim.cli`; like it, this
module imports its machinery only when a command runs, so that ``cablesim --help`` starts at once.
"""

from __future__ import annotations

import math
import shlex
import sys
from pathlib import Path
from typing import Optional

import typer

from .errors import CablesimError
from .io.terminal import ANALYSIS_OPT, CASE_ARG, FORCE_OPT, SET_OPT, Analysis, StatusLine, compiling, say_error


def chart_png(out: Path) -> Path:
    """Where the stability chart of the continuation file ``out`` goes."""
    return out.with_name(out.stem + "-chart.png")


def chart_pngs(case, out: Path) -> list[Path]:
    """The chart PNG ``cablesim continue`` writes beside ``out`` for this case, if any."""
    return [chart_png(out)] if case.continuation is not None and case.continuation.loci else []


def branch_status(status):
    """A progress callback that shows the orbit of the branch being continued, the orbits
    computed and their rate."""
    import time

    count, t0 = [0], time.monotonic()

    def show(p):
        count[0] += 1
        rate = count[0] / max(time.monotonic() - t0, 1e-9)
        status(f"continuing: branch {p.branch} (period {p.period}), parameter {p.parameter:.5g}, orbit {p.index} "
               f"of the branch, {count[0]} orbits, {rate:.3g} orbits/s")

    return show


def loci_status(status):
    """A progress callback that shows the point of the bifurcation curve being traced."""
    return lambda L, p: status(f"bifurcation curve {L.index} ({L.kind}): omega {p.p1:.5g} rad/s, "
                               f"{'s' if L.parameters[1] == 'support' else L.parameters[1]} {p.p2:.5g}")


def loci_text(result) -> str:
    """The summary of the bifurcation curves of a continuation result ("" without them)."""
    if result.loci_range is None:
        return ""
    from .io.chart_report import loci_summary

    return "\n" + loci_summary(result)


def chart_text(out: Path, result) -> str:
    """Draw the stability chart of ``out`` if the result has curves: ``" and <png>"``, else ""."""
    if result.loci_range is None:
        return ""
    from .plots.charts import plot_stability_chart

    return f" and {plot_stability_chart(out, chart_png(out))}"


def interruptible(compute, case, out: Path, what: str = "the results computed"):
    """``compute()``; on Ctrl-C or SIGTERM during a chart (:class:`~cablesim.analyses.charts.Interrupted`)
    write what it kept (beside a complete result of the same name, never over it), say so (``what``:
    text, or a function of the kept result giving it) and exit with status 130 or 143."""
    from . import api
    from .analyses.charts import BackboneResult, Interrupted
    from .dynamics import interrupts
    from .io.hdf5 import is_complete_result
    from .io.paths import beside

    try:
        return compute()
    except Interrupted as exc:
        points = exc.result.n_points if hasattr(exc.result, "n_points") else exc.result.omega.size
        if not points:  # an empty file would only pass for a result
            say_error(f"interrupted ({interrupts.signal_name()}) before any orbit was computed; nothing was written.")
            raise typer.Exit(interrupts.exit_status())
        target = beside(out) if is_complete_result(out) else out
        run = (api.BackboneRun if isinstance(exc.result, BackboneResult) else api.ContinuationRun)(case, exc.result)
        run.to_hdf5(target)
        kept = f" (the complete result {out} is untouched)" if target != out else ""
        what = what(exc.result) if callable(what) else what
        say_error(f"interrupted ({interrupts.signal_name()}); {what} until then are in {target}{kept}, marked "
                  f"incomplete (`cablesim plot {target}` draws them).")
        raise typer.Exit(interrupts.exit_status())


def _begin(ctx, **effective) -> tuple:
    """Record the invocation for the result files; ``(echo, note)`` honouring --quiet/--verbose."""
    from .io.provenance import command_words, plain, set_invocation

    root = ctx.find_root().params
    quiet, verbose = bool(root.get("quiet")), bool(root.get("verbose"))
    options = {k: plain(v) for k, v in {**ctx.params, **effective}.items()}
    set_invocation(shlex.join(command_words(ctx)), options)

    def echo(text: str) -> None:
        if not quiet:
            typer.echo(text)

    def note(text: str, verbose_only: bool = False) -> None:
        if not quiet and (verbose or not verbose_only):
            sys.stderr.write(text + "\n")

    if verbose:
        note("effective options: " + ", ".join(f"{k} = {v}" for k, v in options.items()))
    return echo, note, quiet


def _check_amplitude(amplitude: float | None) -> None:
    if amplitude is not None and not (math.isfinite(amplitude) and 0.0 < amplitude <= 1e5):
        raise CablesimError(f"--amplitude {amplitude:g}: give the largest amplitude to follow the orbits to, in m, "
                            "above 0 and at most 1e5 (e.g. --amplitude 5).", field="backbone.amplitude")


#: What to change when a backbone is refused on its cost.
BACKBONE_FIX = "Give fewer orbits (backbone.max_points), a smaller --amplitude or fewer nodes"


def run_backbone_command(ctx, case_file, overrides, mode, amplitude, output, analysis, plot, force=False) -> None:
    """``cablesim backbone`` (see :func:`register`)."""
    import time

    from . import api
    from .case.numbers import MODE, check_flag
    from .io.chart_report import backbone_summary
    from .io.finish import guard, replace_result
    from .io.paths import check_output

    check_flag(MODE, mode, "--mode", "backbone.mode")
    _check_amplitude(amplitude)
    case = api.load_case(case_file, overrides)
    k = mode if mode is not None else case.backbone.mode
    n_dof = case.dim * case.cable.n_nodes
    if k > n_dof:
        raise CablesimError(f"--mode {k}: this cable has {case.dim}n = {n_dof} modes; give a mode from 1 to {n_dof} "
                            "(cablesim static lists their frequencies).", field="backbone.mode")
    out = output if output is not None else Path("runs") / case.name / f"backbone-mode{k}.h5"
    check_output(out, inputs=[case_file] if case_file else [], companions=(lambda o: [o.with_suffix(".png")]) if plot else [])
    echo, note, quiet = _begin(ctx, output=out, mode=k)
    guard(api.backbone_cost(case, k, analysis.value if analysis else None), force, BACKBONE_FIX, out, note, int(plot))
    t0 = time.perf_counter()
    with compiling(note) as notice, StatusLine(quiet=quiet) as status:
        run = interruptible(lambda: api.backbone(
            case, k, amplitude, analysis.value if analysis else None,
            progress=lambda p: status(f"backbone of mode {k}: orbit {p.index}, {p.omega:.6g} rad/s, "
                                      f"largest |z| {p.amplitude.max():.4g} m")), case, out, "the orbits computed")
    replace_result(out, "backbone", note)
    run.to_hdf5(out)
    echo(backbone_summary(case, run.result, time.perf_counter() - t0 - notice.seconds()))
    echo(f"\nWrote {out}" + (f" and {run.plot(out.with_suffix('.png'), out)}" if plot else ""))


def register(app, user_errors) -> None:
    """Add ``cablesim backbone`` to the application ``app`` (``user_errors`` turns a
    :class:`~cablesim.errors.CablesimError` into a one-paragraph message and exit status 2)."""

    @app.command()
    @user_errors
    def backbone(
        ctx: typer.Context,
        case_file: Optional[Path] = CASE_ARG,
        overrides: Optional[list[str]] = SET_OPT,
        mode: Optional[int] = typer.Option(None, "--mode", help="Linear mode K the backbone starts from, 1 to 2n, or 3n for a spatial cable (default: backbone.mode, else 1)."),
        amplitude: Optional[float] = typer.Option(None, "--amplitude", help="Follow the orbits until the largest |z| of the channels reaches this, m (default: backbone.amplitude, else 2 % of the chord)."),
        output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file (default: runs/<name>/backbone-mode<K>.h5); the plot goes beside it as .png."),
        analysis: Optional[Analysis] = ANALYSIS_OPT,
        plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw the backbone (frequency against amplitude per channel)."),
        force: bool = FORCE_OPT,
    ):
        """Backbone curve of a linear mode: the free, undamped cable's periodic orbits from mode K
        to large amplitude, their frequency against their amplitude per channel (the curve the
        peaks of every lightly damped forced response follow), their stability and the internal
        resonances met. `cablesim plot BACKBONE.h5 CONT.h5` draws it over frequency responses."""
        run_backbone_command(ctx, case_file, overrides, mode, amplitude, output, analysis, plot, force)
