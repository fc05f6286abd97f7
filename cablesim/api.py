"""The Python API: the command line's analyses as functions, for scripts and notebooks.

Each function takes a :class:`~cablesim.case.Case` and returns a *run*: the result objects of
the analysis together with the case, with :meth:`to_hdf5` writing the same file the command line
writes (and :meth:`plot` its PNGs). Nothing here prints, exits or writes unless asked to. Ctrl-C interrupts every
analysis within about a second, inside the compiled flow of a long orbit too (the handlers stay
the caller's: a script gets ``KeyboardInterrupt``, or the analysis's ``Interrupted`` with what it
kept).

>>> import cablesim
>>> case = cablesim.load_case()                    # the paper's example (or a path, or a dict)
>>> run = cablesim.static(case)
>>> run.result.modes.omega[:2]                      # rad/s
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .analyses.charts import BackboneResult, run_backbone
from .analyses.continuation import ContinuationResult, run_continuation
from .analyses.cost import Cost
from .analyses.estimates import chosen_integrator
from .analyses.estimates import backbone_cost as _backbone_cost, continuation_cost as _continuation_cost
from .analyses.estimates import estimates as _estimates
from .analyses.pool import check_jobs
from .analyses.dynamic import HistoryPlan, plan_free_vibration, plan_history
from .analyses.static import StaticResult, run_static
from .analyses.sweep import SweepResult, estimate_sweep, run_sweep
from .case import Case, case_from_dict
from .case import load_case as _read_case_file
from .case.placement import placements_text
from .case.numbers import DAMPING_RATIO, DURATION, MODE, OMEGA, OUTPUT_STEP, PEAK_VELOCITY, check_flag
from .case.files import check_step_flags, step_flag_overrides
from .dynamics import interrupts
from .dynamics.integrators import Integrator
from .dynamics.result import HistoryResult
from .errors import CablesimError
from .io.charts import write_backbone
from .io.continuation import write_continuation
from .io.continuation_journal import ContinuationFile
from .io.hdf5 import write_history, write_static
from .io.journal import SweepFile, fingerprint
from .io.provenance import invocation
from .io.export import default_export_folder
from .io.export import export_csv as _export_csv
from .io.naming import rerun_output as _rerun_output
from .io.results import ResultFile, load_result  # noqa: F401 (cablesim.load_result)
from .io.sweeps import write_sweep
from .orbits import OrbitPoint
from .plots.animation import DEFAULT_FPS, DEFAULT_FRAMES, animate_file, animate_history, save_animation
from .plots.cable import plot_cable
from .plots.charts import plot_backbone, plot_stability_chart
from .plots.continuation import plot_continuation
from .plots.history import plot_history
from .plots.modes import DEFAULT_MODES_DRAWN, draw_modes, save_figure
from .plots.redraw import LabelledArrays, redraw
from .plots.style import figure_output
from .plots.run_report import write_run_report
from .plots.sweep import plot_sweep


def load_case(source: str | Path | dict | None = None, overrides: list[str] | None = None, *,
              dt: float | None = None, rtol: float | None = None, integrator: str | None = None) -> Case:
    """A validated case: from a YAML file, a mapping, or (None) the paper's example.

    Parameters
    ----------
    source : str, Path, dict or None
        Path of a case file; or a mapping with the keys of one; or None for the embedded
        example (``cablesim example`` prints it).
    overrides : list of str, optional
        ``KEY=VALUE`` settings over the file, as ``--set`` on the command line.
    dt, rtol : float, optional
        A fixed time step, s, or the tolerance of error-controlled steps, set in the
        ``integrator:`` section (clearing the other kind), as ``--dt`` and ``--rtol``.
    integrator : str, optional
        The scheme those apply to (``integrator.name``), as ``--integrator``.

    Raises
    ------
    CablesimError
        Naming the field at fault and what to do.
    """
    overrides = [*(overrides or ()), *step_flag_overrides(dt, rtol, integrator)]
    case = case_from_dict(source, overrides) if isinstance(source, dict) else _read_case_file(source, overrides)[0]
    check_step_flags(case, dt)
    return case


@dataclass(frozen=True)
class StaticRun(LabelledArrays):
    """A static analysis: ``result`` (:class:`~cablesim.analyses.static.StaticResult`)."""

    case: Case
    result: StaticResult

    def to_hdf5(self, path: str | Path, matrices: bool | None = None) -> Path:
        """Write the file ``cablesim static`` writes (``matrices``: see
        :func:`~cablesim.io.hdf5.write_static`)."""
        return write_static(path, self.result, self.case.text, matrices=matrices, placements=self.case.placements)

    def plot(self, path: str | Path) -> Path:
        """Draw the cable under F0 as a PNG."""
        return plot_cable(self.result, path, self.case.name)

    def plot_modes(self, path: str | Path | None = None, count: int = DEFAULT_MODES_DRAWN):
        """The lowest ``count`` mode shapes on the cable, as ``cablesim static`` draws them
        (``NAME-modes.png``): the matplotlib ``Figure``, also saved as a PNG at ``path`` if given."""
        fig = draw_modes(self.result, self.case.name, count)
        if path is not None:
            save_figure(fig, path)
        return fig


@dataclass(frozen=True)
class HistoryRun(LabelledArrays):
    """A time history: ``history`` (:class:`~cablesim.dynamics.result.HistoryResult`), the
    ``static`` equilibrium it started from and the ``integrator`` used."""

    case: Case
    command: str
    static: StaticResult
    history: HistoryResult
    integrator: Integrator

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the file ``cablesim history`` (or ``free-vibration``) writes."""
        return write_history(path, self.history, self.case.text, self.command)

    def plot(self, prefix: str | Path, channels=None) -> list[Path]:
        """Draw the waveform, phase, Lissajous, tension and spectrum PNGs (``prefix-*.png``)."""
        return plot_history(self.history, Path(prefix), self.case.name, channels=channels)


@dataclass(frozen=True)
class SweepRun(LabelledArrays):
    """A frequency sweep: ``result`` (:class:`~cablesim.analyses.sweep.SweepResult`)."""

    case: Case
    result: SweepResult

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the file ``cablesim sweep`` writes."""
        return write_sweep(path, self.result)

    def plot(self, path: str | Path, h5_path: str | Path) -> Path:
        """Draw the frequency response from the stored file ``h5_path`` as the PNG ``path``."""
        return plot_sweep(h5_path, path)


@dataclass(frozen=True)
class Planned:
    """A time history checked and set up but not yet integrated: ``cost()`` says what it will
    take (:class:`~cablesim.analyses.cost.Cost`), ``run()`` integrates it."""

    case: Case
    command: str
    plan: HistoryPlan

    def cost(self) -> Cost:
        """Steps, saved instants, memory and disk of the run."""
        return self.plan.cost()

    @interrupts.watching()
    def run(self, progress: Callable[[float], None] | None = None) -> HistoryRun:
        """Integrate (``progress`` is called with the simulated time reached, s)."""
        st, hist, integ = self.plan.run(progress)
        return HistoryRun(self.case, self.command, st, hist, integ)


def static(case: Case, analysis: str | None = None, all_models: bool | None = None,
           n_modes: int | None = None) -> StaticRun:
    """Static equilibrium under F0 (inextensible, approximate, exact), modes and damping.

    ``analysis`` (``"exact"`` or ``"approximate"``) overrides the case's. ``all_models``: every
    model (True), the chosen one (False), or every model up to
    :data:`~cablesim.analyses.static.ALL_MODELS_NODES` nodes (None). ``n_modes``: only the
    lowest this many modes and the highest frequency (overrides ``modal.modes``; default:
    every mode up to n = 300 nodes, else the lowest 100).
    """
    return StaticRun(case, run_static(case, analysis, all_models=all_models, n_modes=n_modes))


def history(
    case: Case,
    omega: float | None = None,
    duration: float | None = None,
    output_step: float | None = None,
    analysis: str | None = None,
    integrator: str | None = None,
    progress: Callable[[float], None] | None = None,
) -> HistoryRun:
    """Forced response ``F(t) = F0 + FL sin(w t)`` from the equilibrium at rest.

    Parameters
    ----------
    case : Case
    omega : float, optional
        Forcing frequency, rad/s (default: the case's ``history.omega``).
    duration, output_step : float, optional
        Simulated time and interval between saved instants, s.
    analysis, integrator : str, optional
        Override the case's choices.
    progress : callable, optional
        Called with the simulated time reached, s.
    """
    return plan_history_run(case, omega, duration, output_step, analysis, integrator).run(progress)


def plan_history_run(case: Case, omega: float | None = None, duration: float | None = None,
                     output_step: float | None = None, analysis: str | None = None,
                     integrator: str | None = None) -> Planned:
    """:func:`history` checked and set up, not integrated (see :class:`Planned`)."""
    _check_numbers(omega=(OMEGA, omega), duration=(DURATION, duration), output_step=(OUTPUT_STEP, output_step))
    return Planned(case, "history", plan_history(case, omega, duration, output_step, analysis, integrator))


def _check_numbers(**values) -> None:
    """The arguments' ranges, as the command line checks its flags: ``name=(type, value)``."""
    for name, (kind, value) in values.items():
        check_flag(kind, value, name)


def free_vibration(
    case: Case,
    mode: int | None = None,
    peak_velocity: float | None = None,
    damping_ratio: float | None = None,
    duration: float | None = None,
    output_step: float | None = None,
    analysis: str | None = None,
    integrator: str | None = None,
    progress: Callable[[float], None] | None = None,
) -> HistoryRun:
    """Damped free vibration started with velocities along linear mode ``mode`` (largest
    component ``peak_velocity``, m/s); defaults from the case's ``free_vibration:`` section."""
    return plan_free_vibration_run(case, mode, peak_velocity, damping_ratio, duration, output_step, analysis,
                                   integrator).run(progress)


def plan_free_vibration_run(case: Case, mode: int | None = None, peak_velocity: float | None = None,
                            damping_ratio: float | None = None, duration: float | None = None,
                            output_step: float | None = None, analysis: str | None = None,
                            integrator: str | None = None) -> Planned:
    """:func:`free_vibration` checked and set up, not integrated (see :class:`Planned`)."""
    _check_numbers(mode=(MODE, mode), peak_velocity=(PEAK_VELOCITY, peak_velocity),
                   damping_ratio=(DAMPING_RATIO, damping_ratio), duration=(DURATION, duration),
                   output_step=(OUTPUT_STEP, output_step))
    plan = plan_free_vibration(case, mode, peak_velocity, damping_ratio, duration, output_step, analysis, integrator)
    return Planned(case, "free-vibration", plan)


def sweep_cost(case: Case, analysis: str | None = None, integrator: str | None = None) -> Cost:
    """Upper bound of what :func:`sweep` will take (every point to the cap), nothing integrated."""
    return estimate_sweep(case, analysis, integrator)


@interrupts.watching()
def backbone_cost(case: Case, mode: int | None = None, analysis: str | None = None) -> Cost:
    """The most a backbone of ``mode`` can cost (:func:`cablesim.analyses.estimates.backbone_cost`)."""
    return _backbone_cost(case, mode, analysis)


@interrupts.watching()
def continuation_cost(case: Case, analysis: str | None = None) -> Cost:
    """What :func:`continuation` will take on its first branch: orbits, Runge-Kutta steps,
    memory and seconds, from a probe of its first few orbits (or the least the range can take,
    when already above the limits; :func:`cablesim.analyses.estimates.continuation_cost`)."""
    return _continuation_cost(case, analysis)


@interrupts.watching()
def sweep(
    case: Case,
    jobs: int = 1,
    analysis: str | None = None,
    integrator: str | None = None,
    output: str | Path | None = None,
    resume: bool = False,
    backend: str | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SweepRun:
    """Steady response of each channel over the case's ``sweep:`` frequencies.

    Parameters
    ----------
    case : Case
    jobs : int
        Worker processes (-1: all cores).
    analysis, integrator : str, optional
        Override the case's choices.
    output : str or Path, optional
        Keep the HDF5 file and its journal up to date while the sweep runs (a killed sweep
        loses no finished point; ``resume=True`` finishes it). Without it nothing is written.
    backend, scheduler : str, optional
        ``"dask"`` and a scheduler address to run the points on a Dask cluster.
    progress : callable, optional
        Called as ``progress(done, total)``.
    """
    check_jobs(jobs)
    recorder = None
    if output is not None:
        recorder = SweepFile(Path(output), fingerprint(case.text, analysis, integrator), resume=resume,
                             command=invocation()["command_line"])
    res = run_sweep(case, case.text, analysis, integrator, n_jobs=jobs, backend=backend, scheduler=scheduler,
                    progress=progress, recorder=recorder)
    return SweepRun(case, res)


@dataclass(frozen=True)
class ContinuationRun(LabelledArrays):
    """Periodic responses by continuation: ``result``
    (:class:`~cablesim.analyses.continuation.ContinuationResult`: branches with their Floquet
    multipliers and stability, and the bifurcations)."""

    case: Case
    result: ContinuationResult

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the file ``cablesim continue`` writes."""
        return write_continuation(path, self.result)

    def plot(self, path: str | Path, h5_path: str | Path, overlay: str | Path | None = None) -> Path:
        """Draw the response diagram of the stored file ``h5_path`` as the PNG ``path``
        (``overlay``: a sweep file whose points are drawn on top)."""
        return plot_continuation(h5_path, path, overlay=overlay)


    def chart(self, path: str | Path, h5_path: str | Path) -> Path:
        """Draw the stability chart (bifurcation curves in omega and gamma or the support
        multiplier s, with ``continuation.loci``) of the stored file ``h5_path`` as the PNG ``path``."""
        return plot_stability_chart(h5_path, path)


@interrupts.watching()
def continuation(
    case: Case,
    analysis: str | None = None,
    progress: Callable[[OrbitPoint], None] | None = None,
    loci_progress: Callable | None = None,
    output: str | Path | None = None,
    resume: bool = False,
    force: bool = False,
) -> ContinuationRun:
    """Every periodic response over the case's ``continuation:`` range, stable and unstable.

    Periodic orbits are found by shooting on ``(z, y')`` (Newton with the monodromy matrix of
    the variational equations) and followed by pseudo-arclength continuation in the forcing
    frequency, the load factor ``gamma`` (FL and the supports' motion) or the support motion
    multiplier ``s`` (``continuation.parameter: support``: the amplitudes of ``supports:``
    alone; ``result.branches[k].support``); folds, period doublings and Neimark-Sacker points
    are located, and every period doubling is followed onto its period-2p branch. With
    ``continuation.loci`` every fold, period doubling and Neimark-Sacker point is then continued
    in omega and gamma over ``continuation.gamma``, or in omega and the support multiplier s over
    ``continuation.support`` (``result.loci``, ``result.codim2``: cusps, fold-flip points, strong
    resonances; ``result.loci_parameter`` names the second parameter).

    Parameters
    ----------
    case : Case
        With a ``continuation:`` section.
    analysis : str, optional
        Overrides the case's analysis.
    progress : callable, optional
        Receives each converged orbit (``branch``, ``parameter``, ``period``, ``stable``, ...).
    loci_progress : callable, optional
        ``loci_progress(locus, point)`` for every point of every bifurcation curve.
    output : str or Path, optional
        Journal every orbit as it comes and keep this HDF5 file current while the branches are
        traced (a killed continuation loses no finished orbit; ``resume=True`` goes on from
        the journal, :mod:`cablesim.io.continuation_journal`); written at the end. Without
        it nothing is written.
    force : bool
        With ``continuation.loci``: trace the curves even when their estimate, made once the
        branches are traced (:func:`cablesim.analyses.charts.loci_cost`), is above the limits.

    Raises
    ------
    cablesim.analyses.charts.Interrupted
        Ctrl-C or SIGTERM while the branches or the curves were traced; its ``result`` keeps what
        was done (``complete`` False).
    cablesim.analyses.charts.CurvesRefused
        The curves' estimate is above the limits; its ``result`` keeps the branches (with
        ``output``, in the file and its journal: ``resume=True, force=True`` traces the curves).
    """
    recorder = None
    if output is not None:
        recorder = ContinuationFile(Path(output), fingerprint(case.text, analysis, "continue"), resume=resume,
                                    command=invocation()["command_line"])
    return ContinuationRun(case, run_continuation(case, analysis, progress, loci_progress, recorder, force))


@dataclass(frozen=True)
class BackboneRun(LabelledArrays):
    """A backbone curve: ``result`` (:class:`~cablesim.analyses.charts.BackboneResult`: the
    free undamped orbits from a linear mode, frequency against amplitude per channel, their
    multipliers and the internal resonances met)."""

    case: Case
    result: BackboneResult

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the file ``cablesim backbone`` writes."""
        return write_backbone(path, self.result)

    def plot(self, path: str | Path, h5_path: str | Path, responses=()) -> Path:
        """Draw the stored file ``h5_path`` as the PNG ``path`` (over the frequency responses of
        the continuation files ``responses``)."""
        return plot_backbone(h5_path, path, responses=responses)


@interrupts.watching()
def backbone(
    case: Case,
    mode: int | None = None,
    amplitude: float | None = None,
    analysis: str | None = None,
    progress: Callable | None = None,
) -> BackboneRun:
    """The backbone curve of a linear mode: the unforced, undamped cable's periodic orbits from
    mode ``mode`` up to the amplitude ``amplitude`` (m, largest ``|z|`` of the channels).

    The orbits' period is unknown and fixed by a phase condition; an artificial damping
    parameter, which Newton's method keeps at zero, makes the conservative family a regular
    curve for the pseudo-arclength continuation. Defaults from the case's ``backbone:`` section
    (mode 1, 2 % of the chord).

    Raises
    ------
    cablesim.analyses.charts.Interrupted
        Ctrl-C or SIGTERM; its ``result`` keeps the orbits computed until then.
    """
    return BackboneRun(case, run_backbone(case, mode, amplitude, analysis, progress))
def estimates(case: Case, analysis: str | None = None, integrator: str | None = None) -> dict[str, str]:
    """What each command would take on this case, in words and in seconds measured on this
    machine (``cablesim check``; see :mod:`cablesim.analyses.estimates`)."""
    return _estimates(case, analysis, integrator)


def effective_case_text(case: Case, analysis: str | None = None, integrator: str | None = None) -> str:
    """The case as it will run, every default filled in, as YAML: what ``cablesim check``
    prints. Sections whose settings cablesim chooses per run are comments saying what it chooses,
    and so are the placements of point loads given by position, with their snap distances."""
    chosen = chosen_integrator(case, analysis, integrator) if not case.integrator.model_dump(exclude_none=True) else None
    modes = case.modal.modes
    notes = {
        "integrator: {}": f"# integrator: none given: {chosen or 'cablesim chooses per command and frequency'}",
        "modal: {}": "# modal: none given: " + (f"the lowest {modes} modes" if modes else
                                                 "every mode (the lowest 100 above 300 nodes)"),
        "outputs: {}": "# outputs: none given: every DOF, and the configurational/elastic split up to 100 nodes",
    }
    placed = placements_text(case.placements)
    lines = [notes.get(line, line) for line in case.effective_yaml().rstrip("\n").splitlines()]
    return "\n".join(lines + ["# " + line for line in placed.splitlines()]) + "\n"


def plot(results, output: str | Path | None = None, figure: str | Path | None = None,
         stamp: str | None = None, snapshots: int | None = None, format: str | None = None,
         width: float | None = None, dpi: int | None = None) -> list[Path]:
    """Redraw figures from stored result files, as ``cablesim plot`` does (nothing is
    recomputed): the ``figure:`` section of the stored case (or of ``figure``) as one PNG, or
    else each file's standard plots.

    Parameters
    ----------
    results : list of str or Path
        HDF5 files of ``static``, ``history``, ``free-vibration``, ``sweep`` or ``continue``.
    output : str or Path, optional
        The PNG (or, for time histories, the prefix of the PNGs).
    figure : str or Path, optional
        A YAML file with a ``figure:`` section to draw instead of the stored case's.
    stamp : str, optional
        Text drawn in a corner of every figure and kept in the PNG metadata, e.g.
        ``"preview: coarse grid"``.
    snapshots : int, optional
        Time histories: draw the cable at this many instants of each record instead
        (``<file>-snapshots.png``).
    format : {"png", "pdf", "svg"}, optional
        Figure format (default: the suffix of ``output``, else PNG); PDF embeds its fonts.
    width : float, optional
        Figure width, in (default 7; e.g. 3.5 for one journal column); the text keeps its sizes.
    dpi : int, optional
        Resolution of PNG figures (default 200).

    Returns
    -------
    list of Path
        The figures written.
    """
    with figure_output(format, width, dpi):
        return redraw(results, output, figure=figure, stamp=stamp, snapshots=snapshots)


def animate(source, output: str | Path | None = None, *, frames: int = DEFAULT_FRAMES, fps: float = DEFAULT_FPS,
            start: float | None = None, stop: float | None = None, branch: str | None = None,
            omega: float | None = None):
    """The cable moving, as ``cablesim animate`` draws it: a time history at true scale, with
    the static shape, the envelope of the motion, a time marker and the tensions in colour.

    Parameters
    ----------
    source : str, Path or HistoryRun
        A file of ``cablesim history`` or ``free-vibration``, or the run itself; or a file of
        ``cablesim continue``, whose orbit (``branch``, default the first, nearest ``omega``,
        default the largest response) is integrated over two periods from its stored state and
        animated over the second (exact analysis).
    output : str or Path, optional
        Also write it: ``.gif`` (pillow), or ``.mp4`` where ffmpeg is installed.
    frames : int
        Number of frames, 2 to 600 (fewer when the window holds fewer saved instants).
    fps : float
        Frames per second, 1 to 50.
    start, stop : float, optional
        The window, s (default: one steady period of a periodic forced response; else 20 frames
        per period of interest, from the start of a free vibration or at the end of the record).

    Returns
    -------
    matplotlib.animation.FuncAnimation
        With ``frame_times`` (s), ``fps``, ``frame_plan`` and ``summary`` (the frames, the frame
        rate, the length and the window in words).
    """
    if isinstance(source, HistoryRun):
        anim = animate_history(source.history, source.case.to_cable(), source.case.name, frames, fps, start, stop)
    else:
        anim = animate_file(source, frames, fps, start, stop, branch, omega)
    if output is not None:
        save_animation(anim, output)
    return anim


def report(results, output: str | Path) -> Path:
    """Write one self-contained HTML page of the result files ``results``, as ``cablesim
    report`` does: per file how it was run, the case, tables of results, every figure (those
    beside the file, else drawn from it) and the warnings. Returns the page's path."""
    return write_run_report([Path(p) for p in results], output)


def export_csv(result: str | Path, folder: str | Path | None = None) -> list[Path]:
    """Write every dataset of a result file as a tidy CSV file, as ``cablesim export`` does.

    Parameters
    ----------
    result : str or Path
        HDF5 result file of any command.
    folder : str or Path, optional
        Where the files go (default ``RESULT-csv`` beside the file); an earlier export there is
        replaced, any other existing folder refused.

    Returns
    -------
    list of Path
        One CSV file per dataset (a row per value, a column per axis, units in the header),
        then ``index.csv`` and ``attributes.csv``.
    """
    stored = load_result(result)
    return _export_csv(stored, default_export_folder(stored.path) if folder is None else folder)


def rerun(result: str | Path, output: str | Path | None = None) -> ResultFile:
    """Rerun a result file's stored case with its stored command line, as ``cablesim rerun``
    does (in a child process: the command line is what the file records), and read the new file.

    Parameters
    ----------
    result : str or Path
        HDF5 result file written by the command line (a file written through this API records
        no command line and is refused).
    output : str or Path, optional
        The new file (default ``RESULT-rerun.h5`` beside it); never the original.

    Returns
    -------
    ResultFile
        The rerun's file (:func:`load_result`).

    Raises
    ------
    CablesimError
        With the command's own message, if it refused or failed.
    """
    out = Path(output) if output is not None else _rerun_output(Path(result))
    args = [sys.executable, "-m", "cablesim.cli", "--quiet", "rerun", str(result), "-o", str(out)]
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        said = " ".join(done.stderr.split()).removeprefix("error: ")  # the command's paragraph, unwrapped
        raise CablesimError(said or f"cablesim rerun {result} exited with status {done.returncode}")
    return load_result(out)
