"""Setting up a dynamic run, once for every command: equations of motion, integrator, steps.

Every rule about *how* a case is integrated lives here: which scheme cablesim uses when the case
names none, how its step is chosen (and made to divide the forcing period), how finely results
are saved. The sweep, the time histories, continuation and the stress test all call these.
"""

from __future__ import annotations

import numpy as np

from ..case import Case, IntegratorSpec
from ..dynamics.equations import EquationsOfMotion
from ..dynamics.integrators import INTEGRATORS, DOPRI5, GeneralizedAlpha, Integrator, Newmark, RK4
from ..errors import CablesimError
from ..modal import fastest_rate, modal_analysis_banded, rayleigh_coefficients
from .static import StaticResult

#: Saved instants per period of the highest frequency of interest, by default.
SAMPLES_PER_PERIOD = 40
#: Fixed steps per period of the highest frequency of interest, by default.
STEPS_PER_PERIOD = 100
#: The same for the default scheme of stiff cables (generalized-alpha): its error falls as dt^2,
#: and 1600 steps per period give about 3e-5 (100 steps: 7e-3), see benchmarks/README.md.
STIFF_STEPS_PER_PERIOD = 1600
#: A cable is stiff when its fastest damped root (the highest mode, or for stiffness-proportional
#: damping of a finely divided cable the overdamped root ~ a1 w_max^2, which grows as n^2) exceeds
#: the frequency of interest this many times: an explicit step would then be set by modes that
#: do not matter to the response, so cablesim integrates implicitly.
STIFF_RATIO = 200.0
#: Default tolerances of dopri5: relative, and absolute per metre of chord at that rtol. An atol
#: not given follows rtol (``atol = DEFAULT_ATOL_PER_CHORD * chord * rtol / DEFAULT_RTOL``): a
#: fixed atol would dominate the error test once rtol is tightened (the paper example's
#: displacements are metres, atol 3e-8 m), and halving rtol would change nothing.
DEFAULT_RTOL = 1e-8
DEFAULT_ATOL_PER_CHORD = 1e-10
#: Default rk4 steps stay inside this fraction of the stability limit 2.8 / rate.
RK4_SAFE_STEP = 2.0


def build_equations(
    case: Case,
    static: StaticResult,
    omega: float = 0.0,
    load_scale: float = 1.0,
    damping_ratio: float | None = None,
    slack: str | None = None,
) -> EquationsOfMotion:
    """The equations of motion of a case about its static equilibrium under F0.

    Parameters
    ----------
    case : Case
    static : StaticResult
        From :func:`cablesim.analyses.static.run_static` (its ``analysis`` is used).
    omega : float
        Forcing frequency, rad/s.
    load_scale : float
        Multiplies ``FL`` (``gamma`` of the paper's Fig. 4; 0 for free vibration).
    damping_ratio : float, optional
        Overrides the case's damping ratio (same two modes).
    slack : str, optional
        ``"continue"`` or ``"stop"``; overrides the case's ``slack``.

    Returns
    -------
    EquationsOfMotion
    """
    need_inextensible(static)
    cable = static.cable
    M = cable.mass_diagonal
    if damping_ratio is None:
        a0, a1 = static.a0, static.a1
    else:
        i, j = case.damping.modes
        w = static.modes.omega
        a0, a1 = rayleigh_coefficients(w[i - 1], w[j - 1], damping_ratio)
    banded = static.K0_band is not None  # exact analysis: K0 is block-tridiagonal, so is C
    inext = static.inextensible
    x0 = inext.x
    return EquationsOfMotion(
        cable=cable,
        analysis=static.analysis,
        mass=M,
        F0=static.P.copy(),
        FL=case.FL * load_scale,
        omega=float(omega),
        y0=static.y0.copy(),
        x0=x0.copy(),
        u0=static.y0 - x0,
        T0=static.T0.copy(),
        F1=inext.segments.F[0].copy(),
        a0=float(a0),
        a1=float(a1),
        modal_omega=static.modes.omega_with_highest().copy(),  # with the highest: explicit steps need it
        slack=slack or case.slack,
        K0_band=static.K0_band.copy() if banded else None,
        K0_dense=None if banded else static.K0.copy(),
    )


def need_inextensible(static: StaticResult) -> None:
    """Refuse a pretensioned cable (no inextensible state) for dynamics, with the reason."""
    if static.inextensible is None:
        raise CablesimError(
            "This cable is not longer than its chord (pretensioned, or within 1e-12 of it), so it "
            "has no inextensible natural state and the configurational/elastic split of the paper "
            "does not exist; time histories need sum(cable.S) (or cable.length) greater than the chord.",
            field="cable.S",
        )


def frequency_of_interest(eom: EquationsOfMotion, omega: float = 0.0) -> float:
    """The highest frequency a run must resolve: the forcing or the lowest mode, rad/s."""
    return max(float(omega), float(eom.frequencies[0]))


def dividing_step(dt: float, omega: float) -> float:
    """The largest step not above ``dt`` that divides the forcing period ``2 pi / omega``.

    Once-per-period samples of the steady-state test then fall on steps rather than between
    them (interpolating a second-order scheme would add O(dt^2) jitter that masks periodicity).
    Without forcing (``omega <= 0``) ``dt`` is returned unchanged.
    """
    if omega <= 0:
        return dt
    period = 2.0 * np.pi / omega
    return period / np.ceil(period / dt - 1e-9)


def is_stiff(eom: EquationsOfMotion, omega_interest: float) -> bool:
    """Whether the fastest damped root of the linearised system (at least the highest mode, see
    :func:`cablesim.modal.fastest_rate`) is more than :data:`STIFF_RATIO` times the frequency
    of interest."""
    return fastest_rate(eom.frequencies, eom.a0, eom.a1) / omega_interest > STIFF_RATIO


def default_dopri5(eom: EquationsOfMotion, rtol: float | None = None, atol: float | None = None) -> DOPRI5:
    """``dopri5`` with cablesim's default tolerances.

    rtol 1e-8 unless given; atol, unless given, ``1e-10 * chord * (rtol / 1e-8)`` (m): it follows
    rtol, so that a tightened rtol tightens the run (see :data:`DEFAULT_ATOL_PER_CHORD`).
    """
    rtol = rtol or DEFAULT_RTOL
    return DOPRI5(rtol=rtol, atol=atol or default_atol(eom.cable.chord_length, rtol))


def default_atol(chord: float, rtol: float) -> float:
    """dopri5's absolute tolerance on displacements (m) when the case gives none: it scales with
    ``rtol``, ``1e-10`` of the chord at the default rtol 1e-8."""
    return DEFAULT_ATOL_PER_CHORD * chord * (rtol / DEFAULT_RTOL)


def default_integrator(eom: EquationsOfMotion, omega_interest: float) -> Integrator:
    """The scheme cablesim uses when the case names none.

    Non-stiff cables: the adaptive ``dopri5`` (rtol 1e-8). Stiff cables (fastest damped root more
    than :data:`STIFF_RATIO` times the frequency of interest, see :func:`is_stiff`): the implicit
    ``generalized-alpha``, which damps the spurious high modes, with
    :data:`STIFF_STEPS_PER_PERIOD` steps per period. Heavy cables with many nodes are stiff in
    this sense (their highest mode grows as n, its damped root as n^2); in the exact analysis
    each step then costs O(n) (banded Newton solves), so a simulated second costs O(n).
    """
    w_int = max(omega_interest, float(eom.frequencies[0]))
    if is_stiff(eom, w_int):
        # The non-stiff default step refined 16 times, each time divided into the forcing period.
        dt = dividing_step(2.0 * np.pi / w_int / STEPS_PER_PERIOD, eom.omega)
        dt = dividing_step(dt * STEPS_PER_PERIOD / STIFF_STEPS_PER_PERIOD, eom.omega)
        return GeneralizedAlpha(dt=dt, rho_inf=0.8)
    return default_dopri5(eom)


def rk4_stable_step(eom: EquationsOfMotion) -> float:
    """A step safely inside rk4's stability limit ``2.8 / rate`` (rate: fastest damped root)."""
    return RK4_SAFE_STEP / fastest_rate(eom.frequencies, eom.a0, eom.a1)


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
    if name is not None and name != spec.name:
        check_override(spec, name)
    name = name or spec.name
    w_int = max(omega_interest, float(eom.frequencies[0]))
    if name is None:
        chosen = default_integrator(eom, w_int)
        if isinstance(chosen, DOPRI5):
            return default_dopri5(eom, spec.rtol, spec.atol)
        dt = spec.dt if spec.dt is not None else chosen.dt
        return GeneralizedAlpha(dt=dt, rho_inf=spec.rho_inf if spec.rho_inf is not None else chosen.rho_inf)
    if name not in INTEGRATORS:
        raise CablesimError(f"integrator.name must be one of {', '.join(INTEGRATORS)}; got {name!r}.")
    if name == "dopri5":
        return default_dopri5(eom, spec.rtol, spec.atol)
    dt = spec.dt
    if dt is None:
        dt = dividing_step(2.0 * np.pi / w_int / STEPS_PER_PERIOD, eom.omega)
    if name == "rk4":
        if spec.dt is None and dt > rk4_stable_step(eom):
            dt = rk4_stable_step(eom)
            if eom.omega > 0:
                period = 2.0 * np.pi / eom.omega
                dt = period / np.ceil(period / dt)
        return RK4(dt=dt)
    if name == "newmark":
        return Newmark(dt=dt)
    return GeneralizedAlpha(dt=dt, rho_inf=spec.rho_inf if spec.rho_inf is not None else 0.8)


def check_override(spec: IntegratorSpec, name: str) -> None:
    """Refuse an ``--integrator`` that would silently ignore settings of the case file."""
    given = [k for k in ("rtol", "atol", "dt", "rho_inf") if getattr(spec, k) is not None]
    applies = {"dopri5": ("rtol", "atol"), "rk4": ("dt",), "newmark": ("dt",), "generalized-alpha": ("dt", "rho_inf")}
    ignored = [k for k in given if k not in applies.get(name, ())]
    if ignored:
        keys = " and ".join(f"integrator.{k}" for k in ignored)
        raise CablesimError(
            f"--integrator {name} conflicts with the case file: {keys} would be ignored ({name} uses "
            f"{', '.join(applies[name])}). Remove {keys} (e.g. --set integrator.{ignored[0]}=null), or choose "
            "the integrator in the case file with its settings.",
            field="integrator",
        )


def output_interval(step: float | None, omega_interest: float, duration: float) -> float:
    """Interval between saved instants: ``step``, or :data:`SAMPLES_PER_PERIOD` per period of
    ``omega_interest`` rounded so that the run ends exactly at ``duration``."""
    if step is None:
        step = 2.0 * np.pi / omega_interest / SAMPLES_PER_PERIOD
        step = duration / np.ceil(duration / step)  # end exactly at the duration
    if step > duration:
        raise CablesimError(
            f"The output step {step:g} s is longer than the duration {duration:g} s; shorten it.",
            field="output_step",
        )
    return step


def mode_velocity(static: StaticResult, mode: int, peak_velocity: float) -> np.ndarray:
    """Initial velocities along linear mode ``mode`` (1-based), largest component = V > 0."""
    shapes = static.modes.shapes
    if mode > shapes.shape[1]:  # a heavy cable keeps the lowest shapes only: compute up to this one
        shapes = modal_analysis_banded(static.K0_band, static.cable.mass_diagonal, n_modes=mode, n_shapes=mode).shapes
    phi = shapes[:, mode - 1]
    k = int(np.argmax(np.abs(phi)))
    return phi * (peak_velocity / phi[k])


def integrator_record(integ: Integrator) -> dict:
    """What a sweep's file and summary state about its integrator: the name and, for the
    adaptive scheme, the effective tolerances (``integrator_rtol``, ``integrator_atol`` in m,
    ``integrator_dt_max`` in s), the same at every point. A fixed step is chosen per point (to
    divide its forcing period), so it is not stated once for the sweep."""
    out: dict = {"integrator": integ.name}
    if not integ.fixed_step:
        out.update({f"integrator_{k}": float(v) for k, v in integ.settings().items()})
    return out
