"""Forced and free vibration of a case: set up, choose the integrator, simulate."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..case import Case, IntegratorSpec
from ..dynamics.equations import EquationsOfMotion
from ..dynamics.history import build_equations, default_integrator, mode_velocity, simulate
from ..dynamics.integrators import INTEGRATORS, DOPRI5, GeneralizedAlpha, Integrator, Newmark, RK4
from ..dynamics.result import HistoryResult
from ..errors import CablesimError
from ..modal import fastest_rate, modal_analysis
from .static import StaticResult, run_static

#: Saved instants per period of the highest frequency of interest, by default.
SAMPLES_PER_PERIOD = 40
#: Fixed steps per period of the highest frequency of interest, by default.
STEPS_PER_PERIOD = 100
#: The same for the default scheme of stiff cables (generalized-alpha): its error falls as dt^2,
#: and 1600 steps per period give about 3e-5 (100 steps: 7e-3), see benchmarks/README.md.
STIFF_STEPS_PER_PERIOD = 1600


def make_integrator(
    spec: IntegratorSpec, eom: EquationsOfMotion, omega_interest: float, name: str | None = None
) -> Integrator:
    """The integrator a case asks for, with defaults filled in.

    Parameters
    ----------
    spec : IntegratorSpec
        The case's ``integrator:`` section.
    eom : EquationsOfMotion
    omega_interest : float
        Highest frequency the response must resolve, rad/s (forcing or excited mode).
    name : str, optional
        Overrides ``spec.name`` (command-line flag).

    Returns
    -------
    Integrator
    """
    name = name or spec.name
    w = modal_analysis(eom.K0, eom.mass).omega
    w_int = max(omega_interest, float(w[0]))
    if spec.dt is not None:
        dt = spec.dt
    else:
        dt = 2.0 * np.pi / w_int / STEPS_PER_PERIOD
        if eom.omega > 0:
            # Make the default step divide the forcing period, so that the once-per-period samples
            # of the steady-state test fall on steps rather than between them (interpolating a
            # second-order scheme would add O(dt^2) jitter that masks periodicity).
            period = 2.0 * np.pi / eom.omega
            dt = period / np.ceil(period / dt - 1e-9)
    if name is None:
        chosen = default_integrator(eom, w_int)
        if isinstance(chosen, DOPRI5):
            return DOPRI5(rtol=spec.rtol or chosen.rtol, atol=spec.atol or chosen.atol)
        if spec.dt is None:
            dt = dt * STEPS_PER_PERIOD / STIFF_STEPS_PER_PERIOD
            if eom.omega > 0:  # still a divisor of the forcing period
                period = 2.0 * np.pi / eom.omega
                dt = period / np.ceil(period / dt - 1e-9)
        return GeneralizedAlpha(dt=dt, rho_inf=spec.rho_inf if spec.rho_inf is not None else chosen.rho_inf)
    if name not in INTEGRATORS:
        raise CablesimError(f"integrator.name must be one of {', '.join(INTEGRATORS)}; got {name!r}.")
    if name == "rk4":
        if spec.dt is None:  # inside RK4's stability limit 2.8 / (fastest rate of the damped system)
            limit = 2.0 / fastest_rate(w, eom.a0, eom.a1)
            if dt > limit:
                dt = limit
                if eom.omega > 0:
                    period = 2.0 * np.pi / eom.omega
                    dt = period / np.ceil(period / dt)
        return RK4(dt=dt)
    if name == "dopri5":
        return DOPRI5(rtol=spec.rtol or 1e-8, atol=spec.atol or 1e-10 * eom.cable.chord_length)
    if name == "newmark":
        return Newmark(dt=dt)
    return GeneralizedAlpha(dt=dt, rho_inf=spec.rho_inf if spec.rho_inf is not None else 0.8)


def _output_step(step: float | None, omega_interest: float, duration: float) -> float:
    if step is None:
        step = 2.0 * np.pi / omega_interest / SAMPLES_PER_PERIOD
        step = duration / np.ceil(duration / step)  # end exactly at the duration
    if step > duration:
        raise CablesimError(
            f"The output step {step:g} s is longer than the duration {duration:g} s; shorten it.",
            field="output_step",
        )
    return step


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
    omega = omega if omega is not None else case.history.omega
    if omega is None or omega <= 0:
        raise CablesimError(
            "No forcing frequency: give --omega W (rad/s) or history.omega in the case file.",
            field="history.omega",
        )
    if not np.any(case.FL):
        raise CablesimError(
            "loads.FL is zero, so there is no forcing; give peak harmonic loads FL in the case "
            "file (or use free-vibration).",
            field="loads.FL",
        )
    duration = duration if duration is not None else case.history.duration
    static = run_static(case, analysis, all_models=False)
    _need_inextensible(static)
    eom = build_equations(case, static, omega=omega)
    w_int = max(omega, float(static.modes.omega[0]))
    step = _output_step(output_step or case.history.output_step, w_int, duration)
    integ = make_integrator(case.integrator, eom, w_int, integrator)
    split = case.outputs.split if split is None else split
    hist = simulate(eom, integ, duration, step, progress=progress, split=split)
    return static, hist, integ


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
    fv = case.free_vibration
    mode = mode if mode is not None else fv.mode
    peak_velocity = peak_velocity if peak_velocity is not None else fv.peak_velocity
    damping_ratio = damping_ratio if damping_ratio is not None else fv.damping_ratio
    duration = duration if duration is not None else fv.duration
    static = run_static(case, analysis, all_models=False)
    _need_inextensible(static)
    n_dof = static.cable.n_dof
    explicit = fv.z0 is not None or fv.v0 is not None
    if mode is None and not explicit:
        raise CablesimError(
            "No initial condition: give --mode K and --peak-velocity V, or free_vibration.mode and "
            "peak_velocity (or z0/v0) in the case file.",
            field="free_vibration.mode",
        )
    eom = build_equations(case, static, omega=0.0, load_scale=0.0, damping_ratio=damping_ratio)
    if mode is not None:
        if not 1 <= mode <= n_dof:
            raise CablesimError(f"--mode must be between 1 and {n_dof}; got {mode}.", field="free_vibration.mode")
        if peak_velocity is None or peak_velocity <= 0:
            raise CablesimError("--peak-velocity must be a positive speed in m/s.", field="free_vibration.peak_velocity")
        v0 = mode_velocity(static, mode, peak_velocity)
        z0 = None
        w_int = float(static.modes.omega[mode - 1])
    else:
        v0 = None if fv.v0 is None else np.array(fv.v0)
        z0 = None if fv.z0 is None else np.array(fv.z0)
        if z0 is not None and static.analysis == "approximate":
            raise CablesimError(
                "free_vibration.z0 needs the exact analysis: the approximate analysis defines the "
                "configuration through the loads, so it starts from its equilibrium (use v0).",
                field="free_vibration.z0",
            )
        w_int = float(static.modes.omega[-1]) if n_dof <= 4 else float(static.modes.omega[min(3, n_dof - 1)])
    s0 = eom.initial_state(z0=z0, v0=v0)
    step = _output_step(output_step or fv.output_step, w_int, duration)
    integ = make_integrator(case.integrator, eom, w_int, integrator)
    split = case.outputs.split if split is None else split
    hist = simulate(eom, integ, duration, step, s0=s0, progress=progress, split=split)
    return static, hist, integ


def _need_inextensible(static: StaticResult) -> None:
    if static.inextensible is None:
        raise CablesimError(
            "This cable is shorter than its chord (pretensioned), so it has no inextensible "
            "natural state and the configurational/elastic split of the paper does not exist; "
            "time histories need sum(cable.S) greater than the chord.",
            field="cable.S",
        )
