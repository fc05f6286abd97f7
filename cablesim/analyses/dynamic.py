"""Forced and free vibration of a case: set up, choose the integrator, simulate."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from ..case import Case
from ..case.model import node_components
from ..dynamics.equations import EquationsOfMotion
from ..dynamics.integrators import Integrator
from ..dynamics.result import HistoryResult
from ..dynamics.simulate import simulate
from ..errors import CablesimError
from ..modal import modal_damping_ratios
from ..statics import segment_geometry
from .cost import Cost, history_cost
from .setup import (build_equations, disturbed_start, make_integrator, mode_velocity, need_inextensible,
                    output_interval, taut)
from .static import SMALL_STRAINS_TEXT, StaticResult, beyond_small_strains, run_static


#: Above this many nodes time histories skip the configurational/elastic split unless the case
#: asks for it (``outputs.split: true``): it solves the dense inextensible problem at every
#: saved instant, which costs more than the integration itself for heavy cables.
SPLIT_NODES = 100


def split_outputs(case: Case, split: bool | None = None, taut_cable: bool = False) -> bool:
    """Whether a time history computes the split: the argument, the case's ``outputs.split``,
    or by default up to :data:`SPLIT_NODES` nodes; never for a ``taut_cable`` (no natural state
    to split from), which refuses an explicit request."""
    wanted = bool(split) if split is not None else case.outputs.split
    if taut_cable:
        if wanted:
            raise CablesimError(
                "outputs.split asks for the configurational and elastic parts of the motion, which a cable "
                "not longer than its chord has not (no inextensible natural state); set outputs.split: false "
                "or remove it.", field="outputs.split")
        return False
    if wanted is not None:
        return wanted
    return case.cable.n_nodes <= SPLIT_NODES


@dataclass(frozen=True)
class HistoryPlan:
    """A time history ready to run: every input checked, the integrator and steps chosen.

    :meth:`cost` estimates it before anything is integrated; :meth:`run` integrates it.
    """

    what: str  # "history" or "free-vibration"
    static: StaticResult
    eom: EquationsOfMotion
    integrator: Integrator
    omega_interest: float
    duration: float
    output_step: float
    s0: np.ndarray | None
    split: bool

    def cost(self) -> Cost:
        """Steps, saved instants, memory and disk of this run (:mod:`cablesim.analyses.cost`)."""
        return history_cost(self.what, self.eom, self.integrator, self.omega_interest, self.duration,
                            self.output_step, self.split)

    def run(self, progress: Callable[[float], None] | None = None) -> tuple[StaticResult, HistoryResult, Integrator]:
        """Integrate: ``(static, history, integrator)``."""
        hist = simulate(self.eom, self.integrator, self.duration, self.output_step, s0=self.s0, progress=progress,
                        split=self.split)
        return (self.static, replace(hist, warnings=(*hist.warnings, *history_warnings(self.eom.cable, hist))),
                self.integrator)


#: Largest drift of eq. 15 (relative to |F0|) before a history is flagged: a scheme that holds
#: its tolerance stays below 1e-5 on the paper example (dopri5 5e-8, generalized-alpha 8e-6);
#: a Newmark step of half a second reaches 7e-2.
DRIFT_BOUND = 1e-3


def history_warnings(cable, hist: HistoryResult) -> tuple[str, ...]:
    """Plausibility warnings of a time history: a strain T/EA beyond the model's range
    (:func:`~cablesim.analyses.static.beyond_small_strains`) and a drift of eq. 15 beyond :data:`DRIFT_BOUND`."""
    out = []
    if hist.T.size:
        strain = np.asarray(hist.T, dtype=float) / cable.EA
        i, k = np.unravel_index(int(np.argmax(strain)), strain.shape)
        if beyond_small_strains(strain[i, k]):
            out.append(f"the strain T/EA of segment {k + 1} reaches {100 * strain[i, k]:.3g} % at t = {hist.t[i]:.6g} s, "
                       f"beyond {SMALL_STRAINS_TEXT}: "
                       "these are not the motions of a real cable. Check the loads (loads.FL) and cable.EA.")
    if hist.residual.size and np.nanmax(hist.residual) > DRIFT_BOUND:
        j = int(np.nanargmax(hist.residual))
        out.append(f"the drift of eq. 15 reaches {hist.residual[j]:.3g} times |F0| at t = {hist.t[j]:.6g} s, beyond "
                   f"the bound {DRIFT_BOUND:g}: the integration does not hold the equations of motion. Tighten "
                   "the step (--rtol, or a smaller --dt) or use another integrator.")
    return tuple(out)


def plan_history(
    case: Case,
    omega: float | None = None,
    duration: float | None = None,
    output_step: float | None = None,
    analysis: str | None = None,
    integrator: str | None = None,
    split: bool | None = None,
) -> HistoryPlan:
    """Check and set up a forced response (see :func:`run_history`), without integrating."""
    omega = omega if omega is not None else case.history.omega
    if omega is None or omega <= 0:
        raise CablesimError(
            "No forcing frequency: give omega (rad/s; on the command line --omega W) or history.omega in the "
            "case file.", field="history.omega",
        )
    if not case.forced:
        raise CablesimError(
            "loads.FL is zero and no support moves, so there is no forcing; give peak harmonic loads FL "
            "or a support amplitude (supports:) in the case file (or use free-vibration).",
            field="loads.FL",
        )
    duration = duration if duration is not None else case.history.duration
    static = run_static(case, analysis, all_models=False)
    need_inextensible(static)
    eom = build_equations(case, static, omega=omega)
    w_int = max(omega, float(static.modes.omega[0]))
    step = output_interval(output_step or case.history.output_step, w_int, duration)
    integ = make_integrator(case.integrator, eom, w_int, integrator)
    split = split_outputs(case, split, taut(static))
    check_initial_state(eom.initial_state(), "loads.F0")
    s0 = disturbed_start(eom, static, case.history.disturbance, "history.disturbance")
    return HistoryPlan("history", static, eom, integ, w_int, duration, step, s0, split)


def run_history(
    case: Case,
    omega: float | None = None,
    duration: float | None = None,
    output_step: float | None = None,
    analysis: str | None = None,
    integrator: str | None = None,
    progress: Callable[[float], None] | None = None,
    split: bool | None = None,
) -> tuple[StaticResult, HistoryResult, Integrator]:
    """Forced response at one frequency from the static equilibrium under F0, at rest.

    Arguments left as None come from the case's ``history:`` and ``integrator:`` sections.

    Returns
    -------
    static : StaticResult
    history : HistoryResult
    integrator : Integrator
    """
    return plan_history(case, omega, duration, output_step, analysis, integrator, split).run(progress)


def check_initial_state(s0: np.ndarray, field: str) -> None:
    """Refuse an initial state that is not finite (the equations of motion cannot start there)."""
    if not np.all(np.isfinite(s0)):
        raise CablesimError(
            f"The initial state at t = 0 is not finite (NaN or infinity): the cable cannot start from "
            f"what {field} describes. Give smaller initial displacements or velocities, or check the loads.",
            field=field,
        )


def plan_free_vibration(
    case: Case,
    mode: int | None = None,
    peak_velocity: float | None = None,
    damping_ratio: float | None = None,
    duration: float | None = None,
    output_step: float | None = None,
    analysis: str | None = None,
    integrator: str | None = None,
    split: bool | None = None,
) -> HistoryPlan:
    """Check and set up a free vibration (see :func:`run_free_vibration`), without integrating."""
    fv = case.free_vibration
    mode = mode if mode is not None else fv.mode
    peak_velocity = peak_velocity if peak_velocity is not None else fv.peak_velocity
    damping_ratio = damping_ratio if damping_ratio is not None else fv.damping_ratio
    duration = duration if duration is not None else fv.duration
    n_dof = case.to_cable().n_dof
    if mode is not None and not 1 <= mode <= n_dof:  # before the statics compute up to that mode
        raise CablesimError(f"--mode must be between 1 and {n_dof}; got {mode}.", field="free_vibration.mode")
    static = run_static(case, analysis, all_models=False, modes_at_least=mode or 0)
    need_inextensible(static)
    explicit = fv.z0 is not None or fv.v0 is not None
    if mode is None and not explicit:
        raise CablesimError(
            "No initial condition: give --mode K and --peak-velocity V, or free_vibration.mode and "
            "peak_velocity (or z0/v0) in the case file.",
            field="free_vibration.mode",
        )
    eom = build_equations(case, static, omega=0.0, load_scale=0.0, damping_ratio=damping_ratio)
    if mode is not None:
        z0, v0, w_int = _mode_start(static, mode, peak_velocity)
    else:
        n, dim = case.cable.n_nodes, case.dim
        v0 = None if fv.v0 is None else node_components(fv.v0, n, dim)
        z0 = None if fv.z0 is None else node_components(fv.z0, n, dim)
        if z0 is not None and static.analysis == "approximate":
            raise CablesimError(
                "free_vibration.z0 needs the exact analysis: the approximate analysis defines the "
                "configuration through the loads, so it starts from its equilibrium (use v0).",
                field="free_vibration.z0",
            )
        w = static.modes.omega
        w_int = static.modes.highest if n_dof <= 4 else float(w[min(3, w.size - 1)])
    s0 = eom.initial_state(z0=z0, v0=v0)
    check_initial_state(s0, "free_vibration.z0 and v0" if mode is None else "free_vibration.peak_velocity")
    if z0 is not None:
        _check_taut_start(static, z0)
    if duration is None:
        duration = decay_duration(static.modes.omega, eom.a0, eom.a1, mode)
    step = output_interval(output_step or fv.output_step, w_int, duration)
    integ = make_integrator(case.integrator, eom, w_int, integrator)
    split = split_outputs(case, split, taut(static))
    return HistoryPlan("free-vibration", static, eom, integ, w_int, duration, step, s0, split)


#: A free vibration runs by default until its motion has decayed to this fraction ...
DECAY_TO = 1e-4
#: ... and for at least this many periods of its mode (a spectrum needs a few), at most this many.
DECAY_PERIODS = (4, 2000)


def decay_duration(omega: np.ndarray, a0: float, a1: float, mode: int | None) -> float:
    """The default length of a free vibration: until the linear response of ``mode`` (or of
    the slowest-decaying mode, for a start given by z0 and v0) has decayed to
    :data:`DECAY_TO` of its start, within :data:`DECAY_PERIODS` of its periods, s.

    Under Rayleigh damping mode ``k`` decays as ``exp(-sigma t)`` with ``sigma = xi w`` when
    underdamped and ``w (xi - sqrt(xi^2 - 1))`` (its slow root) when overdamped.
    """
    w = np.asarray(omega, dtype=float)
    xi = modal_damping_ratios(w, a0, a1)
    sigma = np.where(xi < 1.0, xi * w, w * (xi - np.sqrt(np.maximum(xi * xi - 1.0, 0.0))))
    k = (mode - 1) if mode is not None and mode <= w.size else int(np.argmin(np.where(sigma > 0, sigma, np.inf)))
    period = 2.0 * np.pi / w[k]
    t = np.log(1.0 / DECAY_TO) / sigma[k] if sigma[k] > 0 else np.inf
    lo, hi = DECAY_PERIODS
    return float(np.clip(t, lo * period, hi * period))


def _check_taut_start(static: StaticResult, z0: np.ndarray) -> None:
    """Refuse an initial displacement that leaves a segment slack (the model needs tension)."""
    cable = static.cable
    T = segment_geometry(cable, static.y0 + z0)[2]
    k = int(np.argmin(T))
    if not T[k] > 0:
        raise CablesimError(
            f"free_vibration.z0 leaves segment {k + 1} slack at t = 0 (its tension would be {T[k]:.4g} N, "
            f"against {static.T0[k]:.4g} N at equilibrium), and this model needs every segment taut. Give a "
            "smaller initial displacement z0 (m, from the equilibrium).",
            field="free_vibration.z0",
        )


def _mode_start(static: StaticResult, mode: int, peak_velocity: float | None):
    if peak_velocity is None:
        raise CablesimError(
            f"Mode {mode} gives the shape of the initial velocities but not their size: give "
            "--peak-velocity V too (the largest initial velocity, m/s), or free_vibration.peak_velocity "
            "in the case file.",
            field="free_vibration.peak_velocity",
        )
    if not peak_velocity > 0:
        raise CablesimError("--peak-velocity must be a positive speed in m/s.", field="free_vibration.peak_velocity")
    return None, mode_velocity(static, mode, peak_velocity), float(static.modes.omega[mode - 1])


def run_free_vibration(
    case: Case,
    mode: int | None = None,
    peak_velocity: float | None = None,
    damping_ratio: float | None = None,
    duration: float | None = None,
    output_step: float | None = None,
    analysis: str | None = None,
    integrator: str | None = None,
    progress: Callable[[float], None] | None = None,
    split: bool | None = None,
) -> tuple[StaticResult, HistoryResult, Integrator]:
    """Free vibration about the equilibrium under F0 (no harmonic load).

    The initial velocities follow linear mode ``mode``, scaled so that their largest component
    equals ``peak_velocity`` (and is positive); or the case's explicit ``z0``/``v0``.
    """
    return plan_free_vibration(case, mode, peak_velocity, damping_ratio, duration, output_step, analysis,
                               integrator, split).run(progress)


#: Saved instants per forcing period of an orbit's history (the animation's frames come from them).
ORBIT_SAMPLES = 120


def plan_orbit(case: Case, omega: float, gamma: float, state: np.ndarray, period: int, periods: int = 2,
               analysis: str | None = None, samples: int = ORBIT_SAMPLES, support: float = 1.0) -> HistoryPlan:
    """A forced response started on a periodic orbit of a continuation, without integrating.

    Parameters
    ----------
    case : Case
        The case the continuation ran (its ``loads.FL`` scaled by ``gamma``).
    omega : float
        Forcing frequency of the orbit, rad/s.
    gamma : float
        Scale of the harmonic loads of the orbit.
    state : ndarray
        ``(z, y')`` at forcing phase 0 (m, m/s), as the continuation file stores it.
    period : int
        The orbit's period in forcing periods.
    periods : int
        Orbit periods to integrate (two: the animation checks the second repeats the first).
    analysis : str, optional
        Must be the exact analysis (the approximate one starts only from its equilibrium).
    samples : int
        Saved instants per forcing period.
    support : float
        The orbit's support motion multiplier s (the supports move by ``gamma s`` times the
        amplitudes of ``supports:``).

    Returns
    -------
    HistoryPlan
    """
    static = run_static(case, analysis, all_models=False)
    if static.analysis != "exact":
        raise CablesimError("An orbit of the approximate analysis cannot be started away from its equilibrium; "
                            "continue in the exact analysis (--analysis exact) to animate its orbits, or animate "
                            "a history at the orbit's frequency.", field="analysis")
    eom = build_equations(case, static, omega=omega, load_scale=gamma, support_scale=support)
    n = eom.n_dof
    state = np.asarray(state, dtype=float)
    if state.size < 2 * n:
        raise CablesimError(f"The orbit's state holds {state.size} values, but this cable has 2 x {n}; the "
                            "continuation file does not belong to its stored case.", field="continuation")
    s0 = eom.initial_state(z0=state[:n], v0=state[n:2 * n])
    check_initial_state(s0, "the orbit's state")
    duration = periods * period * 2.0 * np.pi / omega
    integ = make_integrator(case.integrator, eom, max(omega, float(static.modes.omega[0])))
    return HistoryPlan("history", static, eom, integ, omega, duration, 2.0 * np.pi / omega / samples, s0, False)
