"""Running and checking the stress cases of :mod:`cablesim.stress.cases`."""

from __future__ import annotations

import math
import time
import re
from dataclasses import dataclass, field, replace

import joblib
import numpy as np

from ..analyses.setup import build_equations
from ..analyses.static import run_static
from ..case import parse_case
from ..dynamics.status import OK as COMPLETED
from ..dynamics.integrators import DOPRI5, RK4
from ..dynamics.integrators.settings import SCHEMES
from ..dynamics.simulate import simulate
from ..dynamics.status import Status
from ..errors import CablesimError
from ..modal import fastest_rate as damped_fastest_rate
from ..mechanics.equilibrium import CLOSURE_RTOL
from ..statics import inextensible_equilibrium, resisting_force, segment_geometry
from .cases import (
    AGREE_SAFETY,
    AGREE_TOL_CAP,
    AGREE_TOL_FLOOR,
    DRIFT_TOL_EXPLICIT,
    DRIFT_TOL_IMPLICIT,
    FAILED,
    MAX_SAMPLES,
    OK,
    OMEGA_FACTOR,
    RK4_LIMIT,
    SAMPLES_PER_PERIOD,
    SLACK_FRACTION,
    STOPPED,
    Scheme,
    StressCase,
    build_cases,
)


# ----------------------------------------------------------------------------------------------
# Running
# ----------------------------------------------------------------------------------------------
@dataclass
class _Prepared:
    static: object
    eom: object
    omega: float
    omega_hi: float
    output_step: float
    refs: dict = field(default_factory=dict)


def _output_step(omega_hi: float, duration: float) -> float:
    step = max(2.0 * np.pi / omega_hi / SAMPLES_PER_PERIOD, duration / MAX_SAMPLES)
    return duration / math.ceil(duration / step)


def _make_integrator(scheme: Scheme, prep: _Prepared):
    """The scheme at the stress case's step (cablesim's defaults for everything else): an
    adaptive scheme at its default tolerances, an explicit fixed-step one at ``factor`` times its
    stability limit over ``omega_max``, an implicit one at ``steps`` per period."""
    row = SCHEMES[scheme.kind]
    given = {}
    if scheme.factor is not None:
        given["dt"] = scheme.factor * row.cls.stability_limit / prep.static.modes.highest
    elif scheme.steps is not None:
        given["dt"] = 2.0 * np.pi / prep.omega_hi / scheme.steps
    return row.build(prep.eom, prep.omega_hi, given)


def fastest_rate(static) -> float:
    """Largest ``|lambda|`` of the damped linear system ``M q'' + C q' + K0 q = 0``, 1/s.

    With Rayleigh damping every mode keeps its shape: ``lambda^2 + 2 xi w lambda + w^2 = 0``. A
    lightly damped mode has ``|lambda| = w``; an overdamped one (``xi > 1``, which stiffness-
    proportional damping makes of the high modes of a finely divided cable) has a fast real root
    ``w (xi + sqrt(xi^2 - 1)) ~ a1 w^2``, which can exceed ``omega_max`` several times. An explicit
    scheme's step must resolve this rate, not only ``omega_max``.
    """
    return damped_fastest_rate(static.modes.omega_with_highest(), static.a0, static.a1)


def _reference(kind: str, prep: _Prepared, duration: float):
    """An independent, much more accurate run of the same equations (cached per case)."""
    if kind not in prep.refs:
        if kind == "rk4-fine":
            lam = fastest_rate(prep.static)
            integ = RK4(dt=min(0.5 * RK4_LIMIT / lam, 2.0 * np.pi / prep.omega_hi / 400.0))
        else:
            integ = DOPRI5(rtol=1e-10, atol=1e-12 * prep.static.cable.chord_length)
        t0 = time.perf_counter()
        hist = simulate(prep.eom, integ, duration, prep.output_step)
        prep.refs[kind] = (hist, integ, time.perf_counter() - t0)
    return prep.refs[kind]


def _agreement_tol(scheme: Scheme, hist, half, ref) -> float:
    """Tolerance on the relative max |dz| against the reference.

    dopri5 (rtol = 1e-8): :data:`AGREE_TOL_FLOOR`. Fixed-step schemes: :data:`AGREE_SAFETY` times
    their own error as measured by step halving (Richardson), ``max |z_h - z_(h/2)| 2^p / (2^p - 1)
    / max |z_ref|`` (p = 4 for rk4, 2 for newmark and generalized-alpha), kept between
    :data:`AGREE_TOL_FLOOR` and :data:`AGREE_TOL_CAP`. A difference from the reference that the
    scheme's own truncation error does not explain (an answer that does not converge to the
    reference) is silently wrong, and so is any answer more than 5 % off.
    """
    if half is None:  # an adaptive scheme
        return AGREE_TOL_FLOOR
    p = SCHEMES[scheme.kind].cls.order
    m = min(hist.t.size, half.t.size, ref.t.size)
    scale = float(np.max(np.abs(ref.z[:m]))) if m else 0.0
    if scale == 0.0:
        return AGREE_TOL_FLOOR
    est = float(np.max(np.abs(hist.z[:m] - half.z[:m]))) / scale * 2**p / (2**p - 1)
    return float(min(AGREE_TOL_CAP, max(AGREE_TOL_FLOOR, AGREE_SAFETY * est)))


def _finite(hist) -> bool:
    arrays = [hist.t, hist.z, hist.v, hist.T, hist.residual]
    arrays += [a for a in (hist.zc, hist.ze) if a is not None]
    return all(np.all(np.isfinite(a)) for a in arrays)


def _drift(hist) -> tuple[float, float]:
    """(max eq.-15 residual as cablesim reports it, position form for the approximate analysis).

    The approximate analysis' residual is the mismatch ``y - x(P) - u(P)`` turned into a force by
    ``K0``; along the stretching direction ``K0 ~ EA / S``, so for stiff cables it reports
    sub-micrometre mismatches as large forces. Its position form, ``max |z - z_c - z_e| /
    max |z|``, is what the check uses there.
    """
    r = float(np.max(hist.residual)) if hist.residual.size else 0.0
    if hist.analysis == "approximate" and hist.zc is not None:
        scale = float(np.max(np.abs(hist.z))) or 1.0
        return r, float(np.max(np.abs(hist.z - hist.zc - hist.ze))) / scale
    return r, r


#: Stops whose message blames the physics (a slack or nearly slack segment): checked against
#: an independent solve of the state where the run stopped.
_PHYSICAL_STOPS = (Status.SLACK, Status.INNER_SOLVE, Status.OUTPUT_NONFINITE)
#: Words by which a stop message points at the numerics rather than the physics.
_NUMERIC_WORDS = re.compile(r"\b(step|dt|tolerance|integrator|stability)\b", re.IGNORECASE)


def _row(case: StressCase, analysis: str, scheme: Scheme) -> dict:
    return {
        "label": case.label,
        "axis": case.axis,
        "value": case.value,
        "analysis": analysis,
        "integrator": scheme.label,
        "settings": "",
        "duration": case.duration,
        "outcome": None,
        "drift": float("nan"),
        "drift_tol": float("nan"),
        "agreement": float("nan"),
        "agree_tol": float("nan"),
        "reference": "",
        "wall": 0.0,
        "ref_wall": 0.0,
        "t_end": 0.0,
        "t_stop": float("nan"),
        "tmin_ratio": float("nan"),
        "message": "",
        "reason": "",
        "checks": {"static": "na", "finite": "na", "run": "na", "drift": "na", "agreement": "na", "diagnostic": "na"},
    }


def _prepare(case: StressCase, analysis: str, cache: dict) -> _Prepared:
    if analysis not in cache:
        c = parse_case(case.yaml_text(), source=f"(stress case {case.label})")
        st = run_static(c, analysis, all_models=False)
        w1 = float(st.modes.omega[0])
        omega = OMEGA_FACTOR * w1
        w_hi = max(omega, w1)
        # The stress axes check clean stops where a segment goes slack (slack: stop); running
        # through slack episodes is checked by tests/test_slack.py.
        eom = build_equations(c, st, omega=omega, slack="stop")
        cache[analysis] = _Prepared(st, eom, omega, w_hi, _output_step(w_hi, case.duration))
    return cache[analysis]


def _static_tol(cable, P) -> float:
    """Equilibrium residual the static solver guarantees, relative to |F0|.

    It closes the polygon to ``CLOSURE_RTOL`` times the larger of chord and total length; through
    the stiffest segment (``EA / min S``) that length is a force. 10x that, and at least 1e-8.
    """
    length = max(cable.chord_length, cable.total_length)
    force = cable.EA / float(np.min(cable.S)) * CLOSURE_RTOL * length
    return max(1e-8, 10.0 * force / float(np.linalg.norm(P)))


def _static_check(prep: _Prepared) -> tuple[bool, str]:
    st = prep.static
    finite = np.all(np.isfinite(st.y0)) and np.all(np.isfinite(st.K0)) and np.all(st.T0 > 0)
    if not finite:
        return False, "static equilibrium not finite or a tension not positive"
    if st.analysis == "exact":
        r = float(np.linalg.norm(resisting_force(st.cable, st.y0) - st.P) / np.linalg.norm(st.P))
        tol = _static_tol(st.cable, st.P)
        if r > tol:
            return False, f"static equilibrium residual {r:.2e} > {tol:.1e}"
    return True, ""




def _raw_integrate(eom, integ, duration: float, output_step: float):
    """The integration simulate() performs, without its derived outputs (same trajectory)."""
    model = eom.model()
    nd = eom.n_dof
    n_out = int(np.floor(duration / output_step + 1e-9))
    t_out = np.arange(1, n_out + 1) * output_step
    out = np.empty((n_out, 3 * nd))
    state = integ.start(eom, eom.initial_state())
    code = state.extra.get("code", COMPLETED)
    written = 0
    while code == COMPLETED and state.t < duration - 1e-12 * max(duration, 1.0):
        n, code = integ.advance(model, state, duration, t_out[written:], out[written:])
        written += n
    return t_out[:written], out[:written], state, code


def _stop_state_tensions(prep: _Prepared, integ, duration: float, hist) -> dict:
    """Tensions in the state where a run stopped, from an independent solve.

    Integration stops: the integrator's last good state. Stops of the derived outputs (the
    record cut where an inner solve of ``observe`` failed): the saved state at that instant.
    """
    eom = prep.eom
    nd = eom.n_dof
    t_rows, rows, state, code = _raw_integrate(eom, integ, duration, prep.output_step)
    if code != COMPLETED:
        t, s = state.t, state.s
    else:
        if hist.t_stop is None or not t_rows.size:
            return {}
        j = int(np.argmin(np.abs(t_rows - hist.t_stop)))
        t, s = float(t_rows[j]), rows[j]
    info = {"t": float(t)}
    if not np.all(np.isfinite(s)):
        info["finite"] = False
        return info
    cable = prep.static.cable
    if eom.exact:
        y = eom.y0 + s[:nd]
        info["T_exact"] = segment_geometry(cable, y)[2]
        P = resisting_force(cable, y)
    else:
        P = eom.internal_force(t, s)
    try:
        info["T_inext"] = inextensible_equilibrium(cable, P).T
    except CablesimError as exc:  # the robust solver finds it slack (or cannot solve): genuine
        info["inext_error"] = str(exc)
    return info


def run_one(case: StressCase, analysis: str, scheme: Scheme, cache: dict | None = None) -> dict:
    """Run and check one (case, analysis, scheme); ``cache`` shares statics and references."""
    cache = {} if cache is None else cache
    row = _row(case, analysis, scheme)
    ck = row["checks"]
    try:
        try:
            prep = _prepare(case, analysis, cache)
        except CablesimError as exc:
            row.update(outcome=STOPPED, message=f"{type(exc).__name__}: {exc}")
            ck["static"] = "stop"
            ck["diagnostic"] = "ok"
            return row
        ok, why = _static_check(prep)
        ck["static"] = "ok" if ok else "fail"
        integ = _make_integrator(scheme, prep)
        row["settings"] = ", ".join(
            f"{k}={v:.3g}" for k, v in integ.settings().items() if isinstance(v, float) and math.isfinite(v)
        ) + f"; w={prep.omega:.4g} rad/s"
        t0 = time.perf_counter()
        hist = simulate(prep.eom, integ, case.duration, prep.output_step)
        row["wall"] = time.perf_counter() - t0
        if hist.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        # an independent reference: a tight adaptive run for explicit fixed-step schemes, fine rk4 otherwise
        explicit_fixed = integ.fixed_step and integ.stability_limit is not None
        ref_kind = "dopri5-tight" if explicit_fixed else "rk4-fine"
        ref, ref_integ, ref_wall = _reference(ref_kind, prep, case.duration)
        row["reference"] = f"{ref_integ.name} " + ", ".join(
            f"{k}={v:.3g}" for k, v in ref_integ.settings().items() if isinstance(v, float) and math.isfinite(v)
        )
        row["ref_wall"] = ref_wall
        row["t_end"] = float(hist.t[-1])
        row["message"] = "" if hist.completed else hist.message
        row["t_stop"] = hist.t_stop if hist.t_stop is not None else row["t_end"]
        half = None
        if hist.completed and integ.fixed_step:
            # The same scheme at half the step: measures its own truncation error.
            half = simulate(prep.eom, replace(integ, dt=integ.dt / 2.0), case.duration, prep.output_step)
            row["richardson"] = True
        return _classify(row, hist, ref, half, scheme, integ, prep, case, ok, why)
    except KeyboardInterrupt:
        raise
    except CablesimError as exc:
        row.update(outcome=STOPPED, message=f"{type(exc).__name__}: {exc}")
        ck["run"] = "stop"
        ck["diagnostic"] = "ok"
        return row
    except Exception as exc:  # noqa: BLE001 - anything else is a failure to report, not hide
        row.update(outcome=FAILED, message=f"{type(exc).__name__}: {exc}", reason="unexpected exception")
        ck["run"] = "fail"
        return row


def _agreement(hist, ref) -> float:
    """Relative max ``|dz|`` against the reference over the common instants (NaN if none)."""
    m = min(hist.t.size, ref.t.size)
    scale = float(np.max(np.abs(ref.z[:m]))) if m else 0.0
    if m <= 1:  # stopped before the first saved instant: nothing to compare
        return float("nan")
    diff = float(np.max(np.abs(hist.z[:m] - ref.z[:m])))
    return diff / scale if scale > 0 else (0.0 if diff == 0 else float("inf"))


def _classify(row, hist, ref, half, scheme, integ, prep, case, static_ok, static_why) -> dict:
    ck = row["checks"]
    reasons = [] if static_ok else [static_why]
    finite = _finite(hist) and _finite(ref)
    ck["finite"] = "ok" if finite else "fail"
    if not _finite(hist):
        reasons.append("non-finite values in the outputs")
    if not _finite(ref):
        reasons.append("non-finite values in the reference's outputs")
    reported, drift = _drift(hist)
    row["drift"] = reported
    row["drift_pos"] = drift
    explicit = integ.stability_limit is not None
    row["drift_tol"] = DRIFT_TOL_EXPLICIT if explicit else DRIFT_TOL_IMPLICIT
    row["agreement"] = agree = _agreement(hist, ref)
    row["agree_tol"] = _agreement_tol(scheme, hist, half, ref)
    drift_ok = drift <= row["drift_tol"]
    agree_ok = bool(agree <= row["agree_tol"])
    ck["drift"] = "ok" if drift_ok else "fail"
    if hist.completed:
        ck["run"] = "ok"
        ck["diagnostic"] = "na"
        ck["agreement"] = "ok" if agree_ok else "fail"
        if not drift_ok:
            reasons.append(f"drift {drift:.2e} above {row['drift_tol']:.0e}")
        if not agree_ok:
            reasons.append(f"disagrees with the reference by {agree:.2e} (tolerance {row['agree_tol']:.1e}): silently wrong")
        if not ref.completed:
            ck["agreement"] = "fail"
            reasons.append(f"completed although the reference stops ({ref.message}): a missed event")
        row["outcome"] = OK if not reasons else FAILED
    else:
        # A stop: its message must name the cause; if an accurate run of the same case does not
        # stop, the cause is numerical and the message must point at the numerics.
        ck["run"] = "stop"
        ck["drift"] = "na"  # informative only before a stop
        # A clear message says when the run stopped and why, in more than a few words.
        clear = hist.t_stop is not None and len(hist.message) > 40
        numeric_msg = bool(_NUMERIC_WORDS.search(hist.message))
        misleading = ref.completed and not numeric_msg
        spurious = ""
        if clear and not ref.completed and hist.status in _PHYSICAL_STOPS:
            # The message blames the physics (a slack or nearly slack segment): check it.
            info = _stop_state_tensions(prep, integ, case.duration, hist)
            row["stop_check"] = info
            t_min0 = float(np.min(prep.static.T0))
            mins = [float(np.min(info[k])) for k in ("T_exact", "T_inext") if k in info]
            if info.get("finite", True) and "inext_error" not in info and mins and min(mins) > SLACK_FRACTION * t_min0:
                parts = []
                for k, what in (("T_exact", "deformed state"), ("T_inext", "inextensible state under the current P")):
                    if k in info:
                        parts.append(f"{what}: min tension {np.min(info[k]) / 1e3:.4g} kN in segment {int(np.argmin(info[k])) + 1}")
                spurious = (
                    f"spurious stop: the message blames a (nearly) slack segment, but in the state where "
                    f"the run stopped (t = {info['t']:.6g} s) every segment is taut ("
                    + "; ".join(parts)
                    + f"; smallest static tension {t_min0 / 1e3:.4g} kN), the inextensible state solved "
                    "by cablesim's robust static solver (cablesim.statics)"
                )
        ck["diagnostic"] = "ok" if clear and not misleading and not spurious else "fail"
        if spurious:
            reasons.append(spurious)
        if not clear:
            reasons.append("stopped without a clear message")
        if misleading:
            reasons.append(
                f"misleading diagnostic: the reference ({ref.integrator}) completes the run with every "
                f"segment taut (min tension {ref.T.min() / 1e3:.4g} kN), so the stop is numerical, but "
                "the message blames the physics (a slack segment, the loads) and does not point at the step size"
            )
        row["outcome"] = STOPPED if not reasons else FAILED
    row["reason"] = "; ".join(reasons)
    if hist.T.size and np.all(np.isfinite(hist.T)):
        row["tmin_ratio"] = float(np.min(hist.T) / np.min(prep.static.T0))
    if not finite:
        row["outcome"] = FAILED
    return row


def run_case(case: StressCase) -> list[dict]:
    """All runs of one case (statics and references shared)."""
    caches: dict = {}
    return [run_one(case, a, s, caches.setdefault(a, {})) for a, s in case.runs]


def run_stress(reduced: bool = False, jobs: int = 1, progress=None) -> list[dict]:
    """Run every stress case; ``jobs > 1`` runs cases in parallel processes.

    Parameters
    ----------
    reduced : bool
        Fewer values per axis and shorter runs (the test suite's version, ~15 s).
    jobs : int
        Worker processes (cases are independent).
    progress : callable, optional
        Called with each finished case's rows.

    Returns
    -------
    list of dict
        One row per run, in case order, with: ``label``, ``axis``, ``value``, ``analysis``,
        ``integrator`` (scheme and settings in ``settings``), ``outcome`` (``ok``,
        ``stopped-clean``, ``FAILED``), ``drift`` (max eq.-15 residual as stored; ``drift_pos``
        its position form) and ``drift_tol``, ``agreement`` (relative max |dz| against
        ``reference``) and ``agree_tol``, ``tmin_ratio`` (min tension / min static tension),
        ``wall`` and ``ref_wall`` (s), ``t_end`` (last saved instant), ``t_stop`` (where it
        stopped), ``duration``, ``message`` (the stop message), ``reason`` (why FAILED) and
        ``checks`` (``ok``/``stop``/``fail``/``na`` per column of the map).
    """
    cases = build_cases(reduced)
    if jobs == 1:
        out = []
        for c in cases:
            rows = run_case(c)
            if progress:
                progress(rows)
            out.append(rows)
    else:
        # Longest cases first, so that the workers finish together.
        order = sorted(range(len(cases)), key=lambda i: -_cost_hint(cases[i]))
        res = joblib.Parallel(n_jobs=jobs, return_as="generator_unordered")(joblib.delayed(_run_indexed)(i, cases[i]) for i in order)
        got = {}
        for i, rows in res:
            got[i] = rows
            if progress:
                progress(rows)
        out = [got[i] for i in range(len(cases))]
    return [r for rows in out for r in rows]


def _run_indexed(i: int, case: StressCase):
    return i, run_case(case)


def _cost_hint(case: StressCase) -> float:
    # Explicit runs: O(n^2) per evaluation, steps ~ fastest rate ~ n (more when overdamped).
    n = len(case.spec["masses"])
    stiff = case.spec["EA"] / 1e9
    return case.duration * n**3 * max(1.0, stiff**0.5) * len(case.runs)


