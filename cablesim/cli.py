"""The ``cablesim`` command line: a thin layer over :mod:`cablesim.api`, the writers and plots.

Every problem a user can fix is reported as one paragraph on standard error with exit status
2 and no traceback; Ctrl-C exits with status 130 and keeps whatever was already written.

Each command imports its machinery when it runs (numba, scipy, h5py, matplotlib are heavy), so
that ``cablesim --help`` starts at once.
"""

from __future__ import annotations

import functools
import sys
import textwrap
from enum import Enum
from pathlib import Path
from typing import Optional

import typer

from .errors import CablesimError
from .names import ANALYSES, INTEGRATORS
from .version import __version__

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Nonlinear statics and dynamics of weightless sagging elasto-flexible cables. "
    "Each command reads a YAML case file (or, given none, the paper's example: see "
    "`cablesim example`) and writes HDF5 results and PNG plots under runs/<case name>/.",
)


Analysis = Enum("Analysis", {a.replace("-", "_"): a for a in ANALYSES}, type=str)
IntegratorName = Enum("IntegratorName", {a.replace("-", "_"): a for a in INTEGRATORS}, type=str)


def _say_error(message: str) -> None:
    width = 100
    sys.stderr.write(textwrap.fill("error: " + message, width=width) + "\n")


def user_errors(func):
    """Turn CablesimError into a one-paragraph message and exit status 2."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except CablesimError as exc:
            _say_error(str(exc))
            raise typer.Exit(2)
        except KeyboardInterrupt:
            _say_error("interrupted; files already completed were kept.")
            raise typer.Exit(130)

    return wrapper


def _version(value: bool):
    if value:
        typer.echo(f"cablesim {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version."),
):
    pass


CASE_ARG = typer.Argument(None, help="YAML case file; omit it to run the paper's example.", show_default=False)


def _output(case, out: Optional[Path], stem: str) -> Path:
    return out if out is not None else Path("runs") / case.name / f"{stem}.h5"


@app.command()
@user_errors
def example():
    """Print the paper's example as a commented case file to start from."""
    from .case import example_text

    typer.echo(example_text(), nl=False)


@app.command()
@user_errors
def static(
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = typer.Option(None, "--set", help="Override a case-file value, KEY=VALUE with a dotted key (e.g. sweep.duration=1000); repeatable."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file [default: runs/<name>/static.h5]"),
    analysis: Optional[Analysis] = typer.Option(None, "--analysis", help="Override the case file's analysis."),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Also draw the cable as a PNG beside the HDF5 file."),
    full: bool = typer.Option(False, "--full", help="Print every node, segment and mode (large cables show the first and last)."),
    matrices: Optional[bool] = typer.Option(None, "--matrices/--no-matrices", help="Store the dense 2n x 2n matrices [default: up to n = 200 nodes]."),
    all_models: Optional[bool] = typer.Option(None, "--all-models/--chosen-model", help="Compute the inextensible and approximate models too [default: up to n = 300 nodes]."),
):
    """Static equilibrium under F0 (inextensible, approximate and exact), modes and damping."""
    from . import api
    from .io.report import static_summary

    case = api.load_case(case_file, overrides)
    run = api.static(case, analysis.value if analysis else None, all_models=all_models)
    typer.echo(static_summary(case, run.result, full=full))
    out = _output(case, output, "static")
    run.to_hdf5(out, matrices=matrices)
    msg = f"\nWrote {out}"
    if plot:
        msg += f" and {run.plot(out.with_suffix('.png'))}"
    typer.echo(msg)


class _LazyBar:
    """A progress bar on standard error that appears only once there is progress to show
    (so that an input error is never preceded by a bar's label)."""

    def __init__(self, length: int, label: str, **kw):
        self._args = dict(length=length, label=label, file=sys.stderr, **kw)
        self._bar = None
        self.done = 0

    def __enter__(self):
        return self

    def set(self, done: int, length: int | None = None):
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


def _progress(duration: float):
    """A progress bar for a run of ``duration`` simulated seconds, and its update function."""
    bar = _LazyBar(1000, "simulating", show_eta=True)
    return bar, lambda t: bar.set(int(1000 * t / duration))


def _channels(spec: Optional[str], fallback) -> Optional[list[str]]:
    if spec:
        return [c.strip() for c in spec.split(",") if c.strip()]
    return list(fallback) if fallback else None


def _finish_history(run, out: Path, plot: bool, channels, wall: float, full: bool = False):
    from dataclasses import replace

    from .channels import channel_index
    from .dynamics.status import Status
    from .io.report import history_summary

    case, hist = run.case, run.history
    if case.outputs.channels:  # a scene keeps only the channels it draws
        keep = [channel_index(c, hist.n_dof) + 1 for c in case.outputs.channels]
        run = replace(run, history=hist.keep(keep))
        hist = run.history
    run.to_hdf5(out)
    pngs = run.plot(out.with_suffix(""), channels=channels) if plot and hist.t.size > 1 else []
    typer.echo(history_summary(case, hist, run.integrator, wall, full=full))
    typer.echo(f"\nWrote {out}" + (" and " + ", ".join(str(p) for p in pngs) if pngs else ""))
    if not hist.completed:
        _say_error(f"the run did not complete: {hist.message}. Results up to that instant were written.")
        raise typer.Exit(130 if hist.status is Status.INTERRUPTED else 3)


@app.command()
@user_errors
def history(
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = typer.Option(None, "--set", help="Override a case-file value, KEY=VALUE with a dotted key (e.g. sweep.duration=1000); repeatable."),
    omega: Optional[float] = typer.Option(None, "--omega", help="Forcing frequency w, rad/s [default: history.omega]."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated time, s [default: history.duration]."),
    output_step: Optional[float] = typer.Option(None, "--output-step", help="Interval between saved instants, s."),
    analysis: Optional[Analysis] = typer.Option(None, "--analysis", help="Override the case file's analysis."),
    integrator: Optional[IntegratorName] = typer.Option(None, "--integrator", help="Time-integration scheme."),
    channels: Optional[str] = typer.Option(None, "--channels", help="DOF to plot, e.g. z2,z4."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file [default: runs/<name>/history-w<omega>.h5]"),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw waveforms, phase, Lissajous, tension and FFT plots."),
    full: bool = typer.Option(False, "--full", help="Print every channel (large cables show the first and last)."),
):
    """Forced response F(t) = F0 + FL sin(w t) at one frequency, from the equilibrium at rest."""
    import time

    from . import api

    case = api.load_case(case_file, overrides)
    dur = duration if duration is not None else case.history.duration
    if dur <= 0:
        raise CablesimError("--duration must be a positive number of seconds.", field="history.duration")
    w = omega if omega is not None else case.history.omega
    out = output if output is not None else Path("runs") / case.name / f"history-w{w:g}.h5"
    bar, update = _progress(dur)
    t0 = time.perf_counter()
    with bar:
        run = api.history(case, omega, dur, output_step, analysis.value if analysis else None,
                          integrator.value if integrator else None, progress=update)
    _finish_history(run, out, plot, _channels(channels, case.history.channels), time.perf_counter() - t0, full)


@app.command("free-vibration")
@user_errors
def free_vibration(
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = typer.Option(None, "--set", help="Override a case-file value, KEY=VALUE with a dotted key (e.g. sweep.duration=1000); repeatable."),
    mode: Optional[int] = typer.Option(None, "--mode", help="Linear mode K giving the initial velocities."),
    peak_velocity: Optional[float] = typer.Option(None, "--peak-velocity", help="Largest initial velocity V, m/s."),
    damping_ratio: Optional[float] = typer.Option(None, "--damping-ratio", help="Override damping.ratio (same two modes)."),
    duration: Optional[float] = typer.Option(None, "--duration", help="Simulated time, s [default: free_vibration.duration]."),
    output_step: Optional[float] = typer.Option(None, "--output-step", help="Interval between saved instants, s."),
    analysis: Optional[Analysis] = typer.Option(None, "--analysis", help="Override the case file's analysis."),
    integrator: Optional[IntegratorName] = typer.Option(None, "--integrator", help="Time-integration scheme."),
    channels: Optional[str] = typer.Option(None, "--channels", help="DOF to plot, e.g. z2,z4."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file [default: runs/<name>/free-vibration-mode<K>.h5]"),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw waveforms, phase, Lissajous, tension and FFT plots."),
):
    """Damped free vibration about the equilibrium, started with velocities along a linear mode."""
    import time

    from . import api

    case = api.load_case(case_file, overrides)
    if damping_ratio is not None and not 0 <= damping_ratio < 1:
        raise CablesimError("--damping-ratio must be in [0, 1).", field="free_vibration.damping_ratio")
    dur = duration if duration is not None else case.free_vibration.duration
    if dur <= 0:
        raise CablesimError("--duration must be a positive number of seconds.", field="free_vibration.duration")
    k = mode if mode is not None else case.free_vibration.mode
    stem = f"free-vibration-mode{k}" if k is not None else "free-vibration"
    out = output if output is not None else Path("runs") / case.name / f"{stem}.h5"
    bar, update = _progress(dur)
    t0 = time.perf_counter()
    with bar:
        run = api.free_vibration(case, mode, peak_velocity, damping_ratio, dur, output_step,
                                 analysis.value if analysis else None, integrator.value if integrator else None,
                                 progress=update)
    _finish_history(run, out, plot, _channels(channels, case.free_vibration.channels), time.perf_counter() - t0)


class Backend(str, Enum):
    loky = "loky"
    dask = "dask"


@app.command()
@user_errors
def sweep(
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = typer.Option(None, "--set", help="Override a case-file value, KEY=VALUE with a dotted key (e.g. sweep.duration=1000); repeatable."),
    jobs: int = typer.Option(-1, "--jobs", "-j", help="Parallel worker processes (-1: all cores)."),
    resume: bool = typer.Option(False, "--resume", help="Finish an interrupted sweep (same case, same -o)."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file [default: runs/<name>/sweep.h5]"),
    analysis: Optional[Analysis] = typer.Option(None, "--analysis", help="Override the case file's analysis."),
    integrator: Optional[IntegratorName] = typer.Option(None, "--integrator", help="Time-integration scheme."),
    backend: Backend = typer.Option(Backend.loky, "--backend", help="Run points locally (loky) or on a Dask cluster."),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", help="Dask scheduler address, with --backend dask."),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw the frequency-response plot."),
):
    """Frequency-domain response: steady amplitude of each channel against forcing frequency."""
    import time

    from . import api
    from .io.report import sweep_summary
    from .plots.sweep import plot_sweep

    case = api.load_case(case_file, overrides)
    if jobs == 0 or jobs < -1:
        raise CablesimError("--jobs must be a positive number of processes, or -1 for all cores.")
    out = output if output is not None else Path("runs") / case.name / "sweep.h5"
    bar = _LazyBar(1, "sweeping", show_pos=True, show_eta=True)

    def update(done: int, total: int):
        bar.set(done, total)

    t0 = time.perf_counter()
    try:
        with bar:
            run = api.sweep(case, jobs, analysis.value if analysis else None, integrator.value if integrator else None,
                            output=out, resume=resume, backend=None if backend == Backend.loky else "dask",
                            scheduler=scheduler, progress=update)
    except KeyboardInterrupt:
        where = f" {case_file}" if case_file else ""
        _say_error(
            f"interrupted; every completed point is kept in {out} and its journal. Finish the sweep "
            f"with: cablesim sweep{where} -o {out} --resume"
        )
        raise typer.Exit(130)
    typer.echo(sweep_summary(case, run.result, time.perf_counter() - t0))
    msg = f"\nWrote {out}"
    if plot:
        msg += f" and {plot_sweep(out)}"
    typer.echo(msg)


@app.command("continue")
@user_errors
def continue_(
    case_file: Optional[Path] = CASE_ARG,
    overrides: Optional[list[str]] = typer.Option(None, "--set", help="Override a case-file value, KEY=VALUE with a dotted key (e.g. continuation.period=2); repeatable."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file [default: runs/<name>/continuation.h5]"),
    analysis: Optional[Analysis] = typer.Option(None, "--analysis", help="Override the case file's analysis."),
    overlay: Optional[Path] = typer.Option(None, "--overlay", metavar="SWEEP.h5", help="Draw a sweep file's points on the plot."),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Draw the response diagram."),
):
    """Every periodic response over the continuation: range, stable and unstable, with Floquet
    multipliers and the bifurcations (folds, period doublings, Neimark-Sacker) where responses
    appear, vanish or jump."""
    import time

    from . import api
    from .io.report import continuation_summary
    from .plots.continuation import plot_continuation

    case = api.load_case(case_file, overrides)
    out = output if output is not None else Path("runs") / case.name / "continuation.h5"
    if overlay is not None and not overlay.is_file():
        raise CablesimError(f"--overlay {overlay}: no such sweep file; give the output of cablesim sweep.")

    shown = {"t": 0.0}

    def update(point):
        # One status line on a terminal, refreshed at most ten times a second.
        now = time.monotonic()
        if sys.stderr.isatty() and now - shown["t"] > 0.1:
            shown["t"] = now
            sys.stderr.write(f"\rcontinuing: branch {point.branch} (period {point.period}), "
                             f"{point.parameter:.5g}, orbit {point.index}   ")
            sys.stderr.flush()

    t0 = time.perf_counter()
    run = api.continuation(case, analysis.value if analysis else None, progress=update)
    if shown["t"]:
        sys.stderr.write("\n")
    run.to_hdf5(out)
    typer.echo(continuation_summary(case, run.result, time.perf_counter() - t0))
    msg = f"\nWrote {out}"
    if plot:
        msg += f" and {plot_continuation(out, out.with_suffix('.png'), overlay=overlay)}"
    typer.echo(msg)


@app.command()
@user_errors
def plot(
    results: list[Path] = typer.Argument(..., metavar="RESULT.h5", show_default=False,
                                         help="HDF5 result files of cablesim static, history, free-vibration "
                                         "or sweep (one type at a time)."),
    output: Optional[Path] = typer.Option(None, "-o", "--output", metavar="PNG",
                                          help="PNG file (default: the first file with suffix .png)."),
    figure: Optional[Path] = typer.Option(None, "--figure", metavar="FIGURE.yaml",
                                          help="YAML file with a figure: section to draw instead of the stored case's."),
):
    """Redraw figures from stored results, recomputing nothing: the figure: section of the stored
    case (or of --figure) as one PNG from all the files, or else each file's standard plots."""
    from .plots.redraw import redraw

    paths = redraw(results, output, figure=figure)
    typer.echo("Wrote " + ", ".join(str(p) for p in paths))


@app.command()
@user_errors
def stress(
    reduced: bool = typer.Option(False, "--reduced", help="Fewer values per axis and short runs (~15 s; the test suite's version)."),
    md: Path = typer.Option(Path("docs/stability.md"), "--md", help="Markdown table to write."),
    png: Path = typer.Option(Path("docs/stability.png"), "--png", help="PNG map to write."),
    jobs: int = typer.Option(2, "--jobs", "-j", help="Parallel worker processes (cases are independent)."),
):
    """Stability under stress: sweep EA, sag, load scale, n, step size, duration and slackening
    loads; check every run for success, drift of eq. 15, agreement with a second scheme and
    clean failure. Exit status 0 if no run FAILED, else 1."""
    import time

    from .stress import FAILED, build_cases, format_summary, format_table, run_stress, write_report

    if jobs == 0 or jobs < -1:
        raise CablesimError("--jobs must be a positive number of processes, or -1 for all cores.")
    total = len(build_cases(reduced))
    done = {"n": 0}

    def progress(rows):
        done["n"] += 1
        r = rows[0]
        outcomes = ", ".join(x["outcome"] for x in rows)
        sys.stderr.write(f"[{done['n']}/{total}] {r['axis']}: {r['label']} -> {outcomes}\n")

    t0 = time.perf_counter()
    rows = run_stress(reduced, jobs=jobs, progress=progress)
    wall = time.perf_counter() - t0
    md_path, png_path = write_report(rows, md, png, wall)
    typer.echo(format_table(rows))
    typer.echo(format_summary(rows, wall))
    typer.echo(f"\nWrote {md_path} and {png_path}")
    failed = sum(r["outcome"] == FAILED for r in rows)
    if failed:
        _say_error(f"{failed} stress run(s) FAILED (listed above and in {md_path}); each is a bug to fix.")
        raise typer.Exit(1)


def main():
    """Entry point of the ``cablesim`` console script."""
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
