"""Setting up a dynamic run, once for every command: equations of motion, integrator, steps.

Every rule about *how* a case is integrated lives here: which scheme cablesim uses when the case
names none, how its step is chosen (and made to divide the forcing period), how finely results
are saved. The sweep, the time histories, continuation and the stress test all call these.
"""

from __future__ import annotations

import numpy as np

from ..case import Case, IntegratorSpec
from ..dynamics.equations import EquationsOfMotion
from ..dynamics.integrators import Integrator
from ..dynamics.integrators.settings import (DEFAULT_ATOL_PER_CHORD, DEFAULT_RTOL, RK4_SAFE_STEP, SCHEMES,
                                              STEPS_PER_PERIOD, STIFF_RATIO, default_atol, dividing_step,
                                              ignored_keys, is_stiff, make, rk4_stable_step)
from ..errors import CablesimError
from ..modal import fastest_rate, modal_analysis_banded, out_of_plane_shape, rayleigh_coefficients
from .static import StaticResult, damping_modes

#: Saved instants per period of the highest frequency of interest, by default.
SAMPLES_PER_PERIOD = 40


def build_equations(
    case: Case,
    static: StaticResult,
    omega: float = 0.0,
    load_scale: float = 1.0,
    damping_ratio: float | None = None,
    slack: str | None = None,
    support_scale: float = 1.0,
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
        Multiplies ``FL`` and the supports' motion (``gamma`` of the paper's Fig. 4; 0 for free
        vibration).
    damping_ratio : float, optional
        Overrides the case's damping ratio (same two modes).
    slack : str, optional
        ``"continue"`` or ``"stop"``; overrides the case's ``slack``.
    support_scale : float
        Multiplies the supports' motion alone (the support multiplier s of a continuation).

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
        i, j = damping_modes(case, static.modes)
        w = static.modes.omega
        a0, a1 = rayleigh_coefficients(w[i], w[j], damping_ratio)
    banded = static.K0_band is not None  # exact analysis: K0 is block-tridiagonal, so is C
    inext = static.inextensible
    uA, uB, phA, phB = case.support_motion()  # scaled with FL by load_scale, like the loads
    if static.analysis != "exact" and load_scale * support_scale != 0.0 and (np.any(uA) or np.any(uB)):
        raise CablesimError(  # (a case file with analysis: approximate is refused when read)
            "supports: moving supports need the exact analysis, and the approximate one was asked for "
            "(--analysis approximate); leave that flag out (or give --analysis exact) to run this case in the "
            "exact analysis, or remove supports: to use the approximate one.", field="analysis")
    # A taut cable (exact analysis only) has no natural state x(F0): x0 = y0, no elastic split.
    x0 = inext.x if inext is not None else static.y0.copy()
    F1 = inext.segments.F[0].copy() if inext is not None else _segment_one_force(static)
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
        F1=F1,
        a0=float(a0),
        a1=float(a1),
        modal_omega=static.modes.omega_with_highest().copy(),  # with the highest: explicit steps need it
        slack=slack or case.slack,
        K0_band=static.K0_band.copy() if banded else None,
        K0_dense=None if banded else static.K0.copy(),
        uA=uA * (load_scale * support_scale),
        uB=uB * (load_scale * support_scale),
        phA=phA,
        phB=phB,
    )


def need_inextensible(static: StaticResult) -> None:
    """Refuse a pretensioned cable (no inextensible state) for the dynamics of the approximate
    analysis, which is built on that state, with the reason; the exact analysis needs none."""
    if static.inextensible is None and static.analysis != "exact":
        raise CablesimError(
            "This cable is not longer than its chord (pretensioned, or within 1e-12 of it), so it "
            "has no inextensible natural state and the configurational/elastic split of the paper "
            "does not exist; the approximate analysis is built on it. Use the exact analysis "
            "(analysis: exact, or --analysis exact), or make sum(cable.S) greater than the chord.",
            field="cable.S",
        )


def taut(static: StaticResult) -> bool:
    """Whether the cable has no inextensible natural state (not longer than its chord), so its
    displacements have no configurational/elastic split."""
    return static.inextensible is None


def _segment_one_force(static: StaticResult) -> np.ndarray:
    """The force of segment 1 at the equilibrium, ``T_1`` along it (N): the warm start of
    inner solves where no inextensible state gives one."""
    cable = static.cable
    d = np.asarray(static.y0[:cable.dim], dtype=float) - np.asarray(cable.support_A, dtype=float)
    return float(static.T0[0]) * d / np.linalg.norm(d)


def frequency_of_interest(eom: EquationsOfMotion, omega: float = 0.0) -> float:
    """The highest frequency a run must resolve: the forcing or the lowest mode, rad/s."""
    return max(float(omega), float(eom.frequencies[0]))


def make_integrator(
    spec: IntegratorSpec, eom: EquationsOfMotion, omega_interest: float, name: str | None = None
) -> Integrator:
    """The integrator a case asks for, with defaults filled in (the table of
    :mod:`cablesim.dynamics.integrators.settings`).

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
    if name is not None and name not in SCHEMES:
        raise CablesimError(f"integrator.name must be one of {', '.join(SCHEMES)}; got {name!r}.")
    return make(name, eom, max(omega_interest, float(eom.frequencies[0])), spec.settings())


def default_dopri5(eom: EquationsOfMotion, rtol: float | None = None, atol: float | None = None) -> Integrator:
    """``dopri5`` with cablesim's default tolerances (rtol 1e-8, atol 1e-10 chord, m)."""
    return make("dopri5", eom, float(eom.frequencies[0]), {"rtol": rtol, "atol": atol})


def check_override(spec: IntegratorSpec, name: str) -> None:
    """Refuse an ``--integrator`` that would silently ignore settings of the case file."""
    ignored = ignored_keys(name, spec.settings())
    if ignored:
        keys = " and ".join(f"integrator.{k}" for k in ignored)
        raise CablesimError(
            f"--integrator {name} conflicts with the case file: {keys} would be ignored ({name} uses "
            f"{', '.join(SCHEMES[name].keys)}). Remove {keys} (e.g. --set integrator.{ignored[0]}=null), or choose "
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


#: Default size of the out-of-plane disturbance of a spatial sweep's points, per m of chord.
DISTURBANCE_PER_CHORD = 1e-6


def sweep_disturbance(case: Case, analysis: str) -> float:
    """The out-of-plane disturbance of each sweep point, m: ``sweep.disturbance``, else
    :data:`DISTURBANCE_PER_CHORD` of the chord for a spatial cable in the exact ``analysis`` (the
    one that can start displaced) and none otherwise."""
    if case.sweep is not None and case.sweep.disturbance is not None:
        return float(case.sweep.disturbance)
    spatial_exact = case.dim == 3 and analysis == "exact"
    return DISTURBANCE_PER_CHORD * case.to_cable().chord_length if spatial_exact else 0.0


def disturbed_start(eom: EquationsOfMotion, static: StaticResult, size: float, field: str,
                    s0: np.ndarray | None = None) -> np.ndarray | None:
    """The state ``s0`` (or the equilibrium at rest) with the nodes moved out of the plane by at
    most ``size`` m (:func:`cablesim.modal.out_of_plane_shape`), ``y''(0)`` from eq. 19 again;
    ``s0`` unchanged when ``size`` is 0.

    Raises
    ------
    CablesimError
        For the approximate analysis, whose configuration cannot start displaced (``field``
        names the setting).
    """
    if size <= 0.0:
        return s0
    if static.analysis != "exact":
        raise CablesimError(
            f"{field} = {size:g} m displaces the cable at the start, which only the exact analysis can do; "
            f"set analysis: exact (or --analysis exact), or {field}: 0.", field=field)
    cable = static.cable
    d = size * out_of_plane_shape(static.y0, np.asarray(cable.support_A), np.asarray(cable.support_B))
    nd = eom.n_dof
    if s0 is None:
        return eom.initial_state(d)
    s0 = np.asarray(s0, dtype=float)
    return eom.initial_state(s0[:nd] + d, s0[nd:2 * nd])
