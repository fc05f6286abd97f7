"""The ``cablesim`` command line: a thin layer over :mod:`cablesim.api`, the writers and plots.

Every problem a user can fix is reported as one paragraph on standard error with exit status
2, no traceback and no file written; every output is checked before anything is computed.
Ctrl-C exits with status 130 and SIGTERM with 143, both keeping whatever was computed (an
incomplete result never replaces a complete one: it is written beside it). A run that stopped
early (a slack segment; a sweep with failed points) exits with status 3.

Each command imports its machinery when it runs (numba, scipy, h5py, matplotlib are heavy), so
that ``cablesim --help`` starts at once.
"""

from __future__ import annotations

import functools
import os
import shlex
import sys
import warnings
from enum import Enum
from pathlib import Path
from typing import Optional

# cablesim uses no pydantic plugins: skip pydantic's search for them (a thirtieth of a second of
# every command's start-up).
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

import typer

from . import cli_charts, cli_figures, cli_guard, cli_results, cli_views
from .errors import CablesimError
from .io.terminal import (ANALYSIS_OPT, CASE_ARG, DT_OPT, FORCE_OPT, INTEGRATOR_OPT, MODES_DRAWN_OPT, MODES_OPT, RTOL_OPT, SET_OPT, SLACK_OPTION,
                           SNAPSHOTS_OPT, STAMP_OPT, Analysis, CommandGroup, IntegratorName, LazyBar, SlackPolicy, compiling,
                           say_error, say_warnings)
from .version import __version__

app = typer.Typer(
    cls=CommandGroup,
    add_completion=False,
    no_args_is_help=True,
    rich_markup_mode=None,  # help texts are plain: "[default: ...]" must not be read as markup
    help="Nonlinear statics and dynamics of weightless sagging elasto-flexible cables. "
    "Each command reads a YAML case file (or, given none, the paper's example: see "
    "`cablesim example`) and writes HDF5 results and PNG plots under runs/<case name>/. "
    "SI units throughout (m, N, kg, s, rad/s). Exit status: 0 done, 2 refused input (nothing "
    "written), 3 stopped early or a sweep point failed, 130 Ctrl-C, 143 SIGTERM.",
)


def _with_slack(overrides, slack):
    """The ``--set`` overrides with ``--slack`` added as ``slack=...``."""
    return [*(overrides or []), f"slack={slack.value}"] if slack is not None else overrides

#: --quiet / --verbose of this invocation.
_OUT = {"quiet": False, "verbose": False}


def _note(message: str, verbose_only: bool = False) -> None:
    """A line on standard error, unless --quiet (or, for details, unless --verbose)."""
    if not _OUT["quiet"] and (_OUT["verbose"] or not verbose_only):
        sys.stderr.write(message + "\n")


def _echo(text: str) -> None:
    """Standard output (summaries), unless --quiet."""
    if not _OUT["quiet"]:
        typer.echo(text)


def user_errors(func):
    """Turn CablesimError into a one-paragraph message and exit status 2; an interruption
    (Ctrl-C, SIGTERM) into a message and exit status 130 or 143."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        from .dynamics import interrupts

        from .io.provenance import set_invocation

        interrupts.install()
        set_invocation("", {})  # a command that records none leaves none from an earlier one
        try:
            with warnings.catch_warnings():
                # cablesim checks its numbers itself; numpy's notes on NaN would only precede the message
                warnings.simplefilter("ignore", RuntimeWarning)
                return func(*args, **kwargs)
        except CablesimError as exc:
            say_error(str(exc))
            raise typer.Exit(2)
        except KeyboardInterrupt:
            say_error(f"interrupted ({interrupts.signal_name()}); files already completed were kept.")
            raise typer.Exit(interrupts.exit_status())
        finally:
            interrupts.restore()

    return wrapper


def _version(value: bool):
    if value:
        typer.echo(f"cablesim {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Print only errors and warnings (no summary, no progress)."),
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Also print the effective options and the cost estimate."),
):
    if quiet and verbose:
        say_error("--quiet and --verbose exclude each other; give one of them.")
        raise typer.Exit(2)
    _OUT.update(quiet=quiet, verbose=verbose)


# ----------------------------------------------------------------------------------------------
# The command line as run, for provenance and for the --resume hint
# ----------------------------------------------------------------------------------------------
def _begin(ctx, **effective) -> str:
    """Record this invocation for the result files; print the options with --verbose."""
    from .io.provenance import command_words, plain, set_invocation

    line = shlex.join(command_words(ctx))
    options = {k: plain(v) for k, v in ctx.params.items()}
    options.update({k: plain(v) for k, v in effective.items()})
    set_invocation(line, options)
    _note(f"command: {line}", verbose_only=True)
    return line


def _effective(ctx, **values) -> None:
    """Add effective values (the output chosen, the frequency used) to the recorded options."""
    from .io.provenance import invocation, plain, set_invocation

    inv = invocation()
    set_invocation(inv["command_line"], {**inv["options"], **{k: plain(v) for k, v in values.items()}})
    _note("effective options: " + ", ".join(f"{k} = {plain(v)}" for k, v in values.items()), verbose_only=True)


# ----------------------------------------------------------------------------------------------
# Shared steps (the shared options are in cablesim.io.terminal)
# ----------------------------------------------------------------------------------------------
def _check_outputs(out: Path, case_file, companions=()) -> Path:
    """Refuse, before anything runs, an output that cannot or must not be written."""
    from .io.paths import check_output

    return check_output(out, inputs=[case_file] if case_file else [], companions=companions)


def _replace(out: Path, kind: str | None, note: bool = True) -> None:
    """Say so before a complete result is replaced; remove the figures the old one drew."""
    from .io.finish import replace_result

    replace_result(out, kind, _note if note else None)


# ----------------------------------------------------------------------------------------------
# Commands
# ----------------------------------------------------------------------------------------------
@app.command()
@user_errors
def example(
    name: str = typer.Option("paper-example", "--name", help="The shipped case to print (--list names them)."),
    list_: bool = typer.Option(False, "--list", help="List the shipped cases instead."),
):
    """Print a commented case file to start from: the paper's example, with every section
    (cablesim example > my-case.yaml), or another shipped case (--list, --name)."""
    from .case.files import example_cases, example_text

    cases = example_cases()
    text = "".join(f"{n:16s} {what}\n" for n, what in cases.items()) if list_ else example_text(name)
    typer.echo(text, nl=False)


@app.command("compile")
@user_errors
def compile_():
    """Compile the numerical kernels now, once for this machine (numba caches them), so that no
    later run waits for them; `make install` does it. Kernels already cached only load."""
    from . import jit, warmup

    _note(f"compiling the numerical kernels into {jit.cache_dir()} (a few minutes the first time) ...")
    seconds = warmup.compile_kernels(lambda k, n, what: _note(f"  [{k + 1}/{n}] {what}") if k < n else None)
    _echo(f"compiled {jit.kernels_compiled()} kernels in {seconds:.0f} s" if seconds else "every kernel was already compiled")


@app.command()
@user_errors
def check(
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = SET_OPT,
    analysis: Optional[Analysis] = ANALYSIS_OPT,
    integrator: Optional[IntegratorName] = INTEGRATOR_OPT,
):
    """Check a case file without writing anything: solve its statics, print the case as it will
    run (every default filled in, --set applied) and what each command would take (seconds
    measured on this machine by short runs of the same settings)."""
    from .case import load_case

    case = load_case(case_file, overrides)[0]
    from . import api

    an, integ = (analysis.value if analysis else None), (integrator.value if integrator else None)
    with compiling(_note):
        run = api.static(case, an)
        say_warnings(run.result.warnings)
        where = case_file or "the embedded paper example"
        typer.echo(f"# {where} is valid. The case as it runs (defaults filled in"
                   + (", --set applied" if overrides else "") + "):")
        typer.echo(api.effective_case_text(case, an, integ).rstrip("\n"))
        typer.echo("# What each command would take (a sweep: every point to its cap):")
        for command, text in api.estimates(case, an, integ).items():
            typer.echo(f"#   {command}: {text}")


@app.command()
@user_errors
def static(
    ctx: typer.Context,
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = SET_OPT,
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file (default: runs/<name>/static.h5); the plot goes beside it as .png."),
    analysis: Optional[Analysis] = ANALYSIS_OPT,
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Also draw the cable as a PNG beside the HDF5 file."),
    full: bool = typer.Option(False, "--full", help="Print every node, segment and mode (default: a cable of over 20 nodes shows the first and last)."),
    matrices: Optional[bool] = typer.Option(None, "--matrices/--no-matrices", help="Store the dense 2n x 2n matrices (default: up to n = 200 nodes)."),
    all_models: Optional[bool] = typer.Option(None, "--all-models/--chosen-model", help="Compute the inextensible and approximate models too (default: up to n = 300 nodes)."),
    modes: Optional[int] = MODES_OPT,
    modes_drawn: int = MODES_DRAWN_OPT,
):
    """Static equilibrium under F0 (inextensible, approximate and exact), modes and damping."""
    from .case import load_case

    _begin(ctx)
    case = load_case(case_file, [*(overrides or ()), *([f"modal.modes={modes}"] if modes else [])])[0]
    stem = "static" + (f"-{analysis.value}" if analysis else "")
    out = output if output is not None else Path("runs") / case.name / f"{stem}.h5"
    _check_outputs(out, case_file, cli_views.static_figures(modes_drawn) if plot else [])
    _effective(ctx, output=out)
    # Only the static machinery, and only now that the input is known to be good.
    from .analyses.static import run_static
    from .io.hdf5 import write_static
    from .io.report import static_summary
    with compiling(_note):
        result = run_static(case, analysis.value if analysis else None, all_models=all_models)
    say_warnings(result.warnings)
    _echo(static_summary(case, result, full=full))
    _replace(out, "static")
    write_static(out, result, case.text, matrices=matrices, placements=case.placements)
    msg = f"\nWrote {out}"
    if plot:
        msg += " and " + cli_views.draw_static(result, out, case.name, modes_drawn)
    _echo(msg)


@app.command()
@user_errors
def history(
    ctx: typer.Context,
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = SET_OPT,
    omega: Optional[float] = typer.Option(None, "--omega", help="Forcing frequency w, rad/s, 1e-4 to 1e4 (default: history.omega in the case file)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated time, s (default: history.duration, else 600)."),
    output_step: Optional[float] = typer.Option(None, "--output-step", help="Interval between saved instants, s (default: history.output_step, else 40 per period of w)."),
    analysis: Optional[Analysis] = ANALYSIS_OPT,
    integrator: Optional[IntegratorName] = INTEGRATOR_OPT,
    dt: Optional[float] = DT_OPT, rtol: Optional[float] = RTOL_OPT,
    channels: Optional[str] = typer.Option(None, "--channels", help="DOF to plot, e.g. z2,z4 (default: history.channels, else all)."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file (default: runs/<name>/history-w<omega>.h5); the plots go beside it."),
    slack: Optional[SlackPolicy] = SLACK_OPTION,
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw waveforms, phase, Lissajous, tension and FFT plots."),
    force: bool = FORCE_OPT,
    full: bool = typer.Option(False, "--full", help="Print every channel (default: over 40 channels show the first and last)."),
):
    """Forced response F(t) = F0 + FL sin(w t) at one frequency, from the equilibrium at rest."""
    from .case.files import load_with_steps
    from .case.numbers import DURATION, OMEGA, OUTPUT_STEP, check_flag
    from .channels import parse_channels

    _begin(ctx)
    check_flag(OMEGA, omega, "--omega", "history.omega")
    check_flag(DURATION, duration, "--duration", "history.duration")
    check_flag(OUTPUT_STEP, output_step, "--output-step", "history.output_step")
    case = load_with_steps(case_file, _with_slack(overrides, slack), dt, rtol, integrator and integrator.value)
    dur = duration if duration is not None else case.history.duration
    w = omega if omega is not None else case.history.omega
    if w is None:
        raise CablesimError(
            "No forcing frequency: give --omega W (rad/s), or history.omega in the case file (a "
            "`history:` section with `omega: 2.4`, say). `cablesim static` prints the cable's natural "
            "frequencies to choose from.",
            field="history.omega",
        )
    from .io.naming import figures, history_stem

    stem = history_stem(w, dur, analysis.value if analysis else None, integrator.value if integrator else None)
    out = output if output is not None else Path("runs") / case.name / f"{stem}.h5"
    chans = parse_channels(channels, case.history.channels, case.dim * case.cable.n_nodes, kept=case.outputs.channels, dim=case.dim)
    _check_outputs(out, case_file, (lambda o: figures(o, "history")[:5]) if plot else [])
    from . import api
    from .io.finish import finish_history, guard, simulate

    with compiling(_note) as notice:
        planned = api.plan_history_run(case, omega, dur, output_step, analysis.value if analysis else None,
                                       integrator.value if integrator else None)
        say_warnings(planned.plan.static.warnings)
        guard(planned.cost(), force, "Shorten --duration, raise --output-step or integrator.dt", out, _note, 5 * plot)
        _effective(ctx, output=out, omega=w, duration=dur, output_step=planned.plan.output_step,
                   integrator={"name": planned.plan.integrator.name, **planned.plan.integrator.settings()})
        run, wall = simulate(planned, dur, notice, quiet=_OUT["quiet"])
    finish_history(run, out, plot, chans, wall, full, note=_note, echo=_echo)


@app.command("free-vibration")
@user_errors
def free_vibration(
    ctx: typer.Context,
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = SET_OPT,
    mode: Optional[int] = typer.Option(None, "--mode", help="Linear mode K giving the initial velocities, 1 to 2n (default: free_vibration.mode)."),
    peak_velocity: Optional[float] = typer.Option(None, "--peak-velocity", help="Largest initial velocity V, m/s (default: free_vibration.peak_velocity)."),
    damping_ratio: Optional[float] = typer.Option(None, "--damping-ratio", help="Override damping.ratio, 0 to below 1 (same two modes; default: free_vibration.damping_ratio, else damping:)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated time, s (default: free_vibration.duration, else until the motion has decayed to 0.01 %, from the damping)."),
    output_step: Optional[float] = typer.Option(None, "--output-step", help="Interval between saved instants, s (default: free_vibration.output_step, else 40 per period)."),
    analysis: Optional[Analysis] = ANALYSIS_OPT,
    integrator: Optional[IntegratorName] = INTEGRATOR_OPT,
    dt: Optional[float] = DT_OPT, rtol: Optional[float] = RTOL_OPT,
    channels: Optional[str] = typer.Option(None, "--channels", help="DOF to plot, e.g. z2,z4 (default: free_vibration.channels, else all)."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file (default: runs/<name>/free-vibration-mode<K>-v<V>.h5); the plots go beside it."),
    slack: Optional[SlackPolicy] = SLACK_OPTION,
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw waveforms, phase, Lissajous, tension and FFT plots."),
    force: bool = FORCE_OPT,
):
    """Damped free vibration about the equilibrium, started with velocities along a linear mode."""
    from .case.files import load_with_steps
    from .case.numbers import DAMPING_RATIO, DURATION, MODE, OUTPUT_STEP, PEAK_VELOCITY, check_flag
    from .channels import parse_channels

    _begin(ctx)
    check_flag(MODE, mode, "--mode", "free_vibration.mode")
    check_flag(PEAK_VELOCITY, peak_velocity, "--peak-velocity", "free_vibration.peak_velocity")
    check_flag(DAMPING_RATIO, damping_ratio, "--damping-ratio", "free_vibration.damping_ratio")
    check_flag(DURATION, duration, "--duration", "free_vibration.duration")
    check_flag(OUTPUT_STEP, output_step, "--output-step", "free_vibration.output_step")
    case = load_with_steps(case_file, _with_slack(overrides, slack), dt, rtol, integrator and integrator.value)
    fv = case.free_vibration
    dur = duration if duration is not None else fv.duration
    k = mode if mode is not None else fv.mode
    v = peak_velocity if peak_velocity is not None else fv.peak_velocity
    from .io.naming import figures, free_vibration_stem

    stem = free_vibration_stem(k, v, damping_ratio, analysis.value if analysis else None,
                               integrator.value if integrator else None)
    out = output if output is not None else Path("runs") / case.name / f"{stem}.h5"
    chans = parse_channels(channels, fv.channels, case.dim * case.cable.n_nodes, kept=case.outputs.channels, dim=case.dim)
    _check_outputs(out, case_file, (lambda o: figures(o, "history")[:5]) if plot else [])
    from . import api
    from .io.finish import finish_history, guard, simulate

    with compiling(_note) as notice:
        planned = api.plan_free_vibration_run(case, mode, peak_velocity, damping_ratio, dur, output_step,
                                              analysis.value if analysis else None,
                                              integrator.value if integrator else None)
        say_warnings(planned.plan.static.warnings)
        guard(planned.cost(), force, "Shorten --duration, raise --output-step or integrator.dt", out, _note, 5 * plot)
        _effective(ctx, output=out, mode=k, peak_velocity=v, duration=planned.plan.duration,
                   output_step=planned.plan.output_step,
                   integrator={"name": planned.plan.integrator.name, **planned.plan.integrator.settings()})
        run, wall = simulate(planned, planned.plan.duration, notice, quiet=_OUT["quiet"])
    finish_history(run, out, plot, chans, wall, False, note=_note, echo=_echo)


class Backend(str, Enum):
    loky = "loky"
    dask = "dask"


@app.command()
@user_errors
def sweep(
    ctx: typer.Context,
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = SET_OPT,
    omega: Optional[str] = typer.Option(None, "--omega", metavar="W1,W2,...|START:STOP:NUM", help="Forcing frequencies, rad/s: a list, or a grid of NUM points (default: sweep.omega in the case file)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Cap on simulated seconds per point, s (default: sweep.duration, else 3000)."),
    window: Optional[float] = typer.Option(None, "--window", help="Final seconds of a point used for its amplitude when it is not steady, s (default: sweep.window, else 200)."),
    channels: Optional[str] = typer.Option(None, "--channels", help="DOF recorded and plotted, e.g. z2,z4 (default: sweep.channels, else all)."),
    jobs: int = typer.Option(-1, "--jobs", "-j", help="Parallel worker processes (-1: all cores)."),
    resume: bool = typer.Option(False, "--resume", help="Finish an interrupted sweep (same command, same -o)."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file (default: runs/<name>/sweep.h5); the plot goes beside it."),
    analysis: Optional[Analysis] = ANALYSIS_OPT,
    integrator: Optional[IntegratorName] = INTEGRATOR_OPT,
    dt: Optional[float] = DT_OPT, rtol: Optional[float] = RTOL_OPT,
    slack: Optional[SlackPolicy] = SLACK_OPTION,
    backend: Backend = typer.Option(Backend.loky, "--backend", help="Run points locally (loky) or on a Dask cluster."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Dask scheduler address, with --backend dask (e.g. tcp://host:8786)."),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw the frequency-response plot."),
    force: bool = FORCE_OPT,
):
    """Frequency-domain response: steady amplitude of each channel against forcing frequency.
    Exit status 3 if any point stopped early (the summary names which and why)."""
    from .analyses.pool import check_jobs
    from .case.files import load_with_steps, sweep_flag_error, sweep_flag_overrides
    from .io.naming import sweep_stem
    _begin(ctx)
    check_jobs(jobs)
    if scheduler is not None and backend != Backend.dask:
        raise CablesimError(
            f"--scheduler {scheduler} is used only with --backend dask (the default backend, loky, runs "
            "the points on this machine): add --backend dask, or drop --scheduler."
        )
    try:
        case = load_with_steps(case_file, _with_slack([*(overrides or ()), *sweep_flag_overrides(omega, duration, channels,
                                                                                               window)], slack),
                               dt, rtol, integrator and integrator.value)
    except CablesimError as exc:
        raise sweep_flag_error(exc, duration, window) from None
    stem = sweep_stem(omega, analysis.value if analysis else None, integrator.value if integrator else None)
    out = output if output is not None else Path("runs") / case.name / f"{stem}.h5"
    _check_outputs(out, case_file, lambda o: [o.with_name(o.name + ".journal"), o.with_name(o.name + ".lock"),
                                              *([o.with_suffix(".png")] if plot else [])])
    from . import api
    from .io.finish import guard
    from .io.journal import fingerprint, nothing_to_resume

    an, integ = (analysis.value if analysis else None), (integrator.value if integrator else None)
    if resume and nothing_to_resume(out, fingerprint(case.text, an, integ)):
        _echo(f"Nothing to do: {out} already holds this sweep, complete.")
        return
    if not resume:
        _replace(out, None)  # the note now; the old figure goes once this sweep is complete
    with compiling(_note) as notice:
        guard(api.sweep_cost(case, an, integ), force, "Use fewer points (sweep.omega), a shorter sweep.duration "
              "or a larger integrator.dt", out, _note, 1 * plot)
        _effective(ctx, output=out)
        _run_sweep(ctx, case, out, jobs, resume, an, integ, None if backend == Backend.loky else "dask", scheduler, plot,
                   notice)


def _run_sweep(ctx, case, out: Path, jobs, resume, analysis, integrator, backend, scheduler, plot: bool, notice):
    import time

    from . import api
    from .dynamics import interrupts
    from .io.journal import snapshot_path
    from .io.provenance import command_words
    from .io.report import sweep_summary
    from .plots.sweep import plot_sweep

    bar = LazyBar(1, "sweeping", quiet=_OUT["quiet"], show_pos=True, show_eta=True)
    snapshot = snapshot_path(out)
    t0, c0 = time.perf_counter(), notice.seconds()
    try:
        with bar:
            run = api.sweep(case, jobs, analysis, integrator, output=out, resume=resume, backend=backend,
                            scheduler=scheduler, progress=lambda done, total: bar.set(done, total))
    except KeyboardInterrupt:
        again = shlex.join(command_words(ctx, drop=("resume", "output")) + ["--output", str(out), "--resume"])
        kept = f" (the complete result {out} is untouched)" if snapshot != out else ""
        say_error(f"interrupted ({interrupts.signal_name()}); every completed point is kept in {snapshot}{kept} "
                   f"and the journal {out.name}.journal. Finish the sweep with:", command=again)
        raise typer.Exit(interrupts.exit_status())
    res = run.result
    say_warnings(res.warnings)
    _echo(sweep_summary(case, res, time.perf_counter() - t0 - (notice.seconds() - c0), full=_OUT["verbose"]))
    if res.complete:
        _replace(out, "sweep", note=False)  # the old figure goes with the result it drew
    msg = f"\nWrote {out}"
    if plot:
        msg += f" and {plot_sweep(out)}"
    _echo(msg)
    if res.n_failed:
        say_error(f"{res.n_failed} of {res.n_total} sweep points stopped early; their values are partial and "
                   "left out of the peaks (the summary above and /sweep/status name each with its cause). "
                   + res.failures()[0])
        raise typer.Exit(3)


@app.command("continue")
@user_errors
def continue_(
    ctx: typer.Context,
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = SET_OPT,
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file (default: runs/<name>/continuation.h5); the plot goes beside it as .png."),
    analysis: Optional[Analysis] = ANALYSIS_OPT,
    overlay: Optional[Path] = typer.Option(None, "--overlay", metavar="SWEEP.h5", help="Draw a sweep file's points on the plot."),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw the response diagram."),
    force: bool = FORCE_OPT,
    resume: bool = typer.Option(False, "--resume", help="Finish an interrupted continuation (same command, same -o)."),
):
    """Every periodic response over the continuation: range, stable and unstable, with Floquet
    multipliers and the bifurcations (folds, period doublings, Neimark-Sacker) where responses
    appear, vanish or jump."""
    from .case import load_case

    _begin(ctx)
    case = load_case(case_file, overrides)[0]
    out = output if output is not None else Path("runs") / case.name / (
        "continuation" + (f"-{analysis.value}" if analysis else "") + ".h5")
    from .io.paths import check_output

    pngs = (lambda o: [o.with_suffix(".png"), *cli_charts.chart_pngs(case, o)]) if plot else (lambda o: [])
    check_output(out, inputs=cli_guard.continue_inputs(case_file, overlay), companions=cli_guard.companions(pngs),
                 need_bytes=cli_guard.continue_room(len(pngs(out))))
    say_warnings(cli_guard.check_overlay(overlay, case))
    _effective(ctx, output=out)
    cli_guard.run_continue(case, out, analysis.value if analysis else None, overlay, plot, _note, _echo, _OUT["quiet"],
                           force, resume, ctx)


@app.command()
@user_errors
def plot(
    ctx: typer.Context,
    results: list[Path] = typer.Argument(..., metavar="RESULT.h5", show_default=False,
                                         help="HDF5 result files of any cablesim command, one type at a time (or "
                                         "continuations with a sweep or a backbone: drawn together)."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", metavar="PNG",
                                          help="Figure file: .png, .pdf or .svg (default: the first file with suffix .png)."),
    figure: Optional[Path] = typer.Option(None, "--figure", metavar="FIGURE.yaml",
                                          help="YAML file with a figure: section to draw instead of the stored case's."),
    stamp: Optional[str] = STAMP_OPT,
    snapshots: Optional[int] = SNAPSHOTS_OPT,
):
    """Redraw figures from stored results, recomputing nothing: the figure: section of the stored
    case (or of --figure) as one PNG from all the files, or else each file's standard plots."""
    from .io.paths import check_output
    from .plots.redraw import redraw

    _begin(ctx)
    if output is not None:
        check_output(output, inputs=[*results, figure], suffixes=(".png", ".pdf", ".svg", ""))
    paths = redraw(results, output, figure=figure, stamp=stamp, snapshots=snapshots)
    _echo("Wrote " + ", ".join(str(p) for p in paths))


@app.command()
@user_errors
def stress(
    reduced: bool = typer.Option(False, "--reduced", help="Fewer values per axis and short runs (~15 s; the test suite's version)."),
    md: Path = typer.Option(Path("runs/stress/stability.md"), "--md", help="Markdown table to write (docs/stability.md holds the project's last full run)."),
    png: Path = typer.Option(Path("runs/stress/stability.png"), "--png", help="PNG map to write."),
    jobs: int = typer.Option(2, "--jobs", "-j", help="Parallel worker processes (cases are independent)."),
):
    """Stability under stress: sweep EA, sag, load scale, n, step size, duration and slackening
    loads; check every run for success, drift of eq. 15, agreement with a second scheme and
    clean failure. Exit status 0 if no run FAILED, else 1."""
    import time

    from .io.paths import check_output
    from .stress import FAILED, build_cases, format_summary, format_table, run_stress, write_report

    from .analyses.pool import check_jobs

    check_jobs(jobs)
    check_output(md, flag="--md", suffixes=(".md",))
    check_output(png, flag="--png", suffixes=(".png",))
    total = len(build_cases(reduced))
    done = {"n": 0}

    def progress(rows):
        done["n"] += 1
        r = rows[0]
        outcomes = ", ".join(x["outcome"] for x in rows)
        _note(f"[{done['n']}/{total}] {r['axis']}: {r['label']} -> {outcomes}")

    t0 = time.perf_counter()
    rows = run_stress(reduced, jobs=jobs, progress=progress)
    wall = time.perf_counter() - t0
    md_path, png_path = write_report(rows, md, png, wall)
    _echo(format_table(rows))
    _echo(format_summary(rows, wall))
    _echo(f"\nWrote {md_path} and {png_path}")
    failed = sum(r["outcome"] == FAILED for r in rows)
    if failed:
        say_error(f"{failed} stress run(s) FAILED (listed above and in {md_path}); each is a bug to fix.")
        raise typer.Exit(1)


for _m in (cli_charts, cli_results, cli_views, cli_figures): _m.register(app, user_errors)  # noqa: E701 (figures: last)


def main():
    """Entry point of the ``cablesim`` console script."""
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
