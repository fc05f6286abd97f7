"""Stability under stress: a sweep over parameters that strain the numerics (``cablesim stress``).

Every stress case is the paper's example (L = 300 m, H = 20 m, S = [130, 100, 110] m, EA = 1e9 N,
masses [8000, 14000] kg, F0 = [300, 1100, 450, 2000] kN, FL = [-6, 22, -18, 120] kN, xi = 0.01)
varied along one axis at a time:

========== =================================================================================
axis       values (reduced version: fewer values, 60 s runs)
========== =================================================================================
EA         1e6, 1e8, 1e9, 1e11, 1e13 N (stiff cables also with generalized-alpha and newmark)
sag        sum S / chord = 1.0001, 1.001, 1.13 (paper), 2, 3 (S scaled uniformly)
load       F0 and FL scaled together by 1e-3, 1, 1e3
n          2, 10, 50, 100 interior nodes: equal segments (sum S as in the paper), equal masses
           (total 22 t), equal vertical F0 (total 3100 kN), FL = 4 % of it vertically and
           +-1 % horizontally on every node
step       rk4 with dt = 0.5, 1, 2, 4 x its stability limit 2.8 / omega_max (paper's example),
           and 0.5 x on the 50-node cable
duration   1e3 s and one 1e4 s run
slack      FL scaled by 3, 10, 15, 20 until a segment goes slack; and a sustained load that makes
           a segment slack in statics
========== =================================================================================

Each case is solved with the analysis API (:func:`~cablesim.case.parse_case`,
:func:`~cablesim.analyses.static.run_static`, :func:`~cablesim.dynamics.history.build_equations`,
:func:`~cablesim.dynamics.history.simulate`) in the exact and, where cheap, the approximate
analysis, forced at ``w = 0.8 w1`` (clear of the primary, the 1/2-subharmonic and the
superharmonic resonances, so that the comparison between schemes is well conditioned).

Every run is checked three ways (thresholds in :data:`DRIFT_TOL_EXPLICIT` and below, justified in
the report):

- **success**: it ran to the end, or stopped early with a status message that names the cause;
- **accuracy**: the drift of eq. 15 stays small, and the displacements agree with those of an
  independent, much more accurate second scheme of the same case (relative max ``|dz|``);
- **clean failure**: no NaN or infinity in any output array; a stop's message points at the
  numerics (step size, tolerance, integrator) whenever an accurate run of the same case does not
  stop, and otherwise the stop is real (a segment is, or nearly is, slack where it stopped).

Outcomes: ``ok`` (completed, drift and agreement within tolerance), ``stopped-clean`` (stopped
early with a clear, correct message and finite outputs, or a
:class:`~cablesim.errors.CablesimError` up front) and ``FAILED`` (anything else: non-finite
outputs, an unexpected exception, a completed run that disagrees with the reference beyond
tolerance -- silently wrong -- or a misleading or spurious stop).

Entry points: :func:`run_stress` (rows) and :func:`write_report` (markdown table and PNG map);
``cablesim stress`` on the command line.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from .errors import CablesimError

# ----------------------------------------------------------------------------------------------
# The paper's example and the thresholds
# ----------------------------------------------------------------------------------------------
PAPER = dict(
    L=300.0,
    H=20.0,
    S=[130.0, 100.0, 110.0],
    EA=1.0e9,
    masses=[8000.0, 14000.0],
    F0=[300.0e3, 1100.0e3, 450.0e3, 2000.0e3],
    FL=[-6.0e3, 22.0e3, -18.0e3, 120.0e3],
    xi=0.01,
)

#: Forcing frequency of every run, as a multiple of the fundamental frequency w1.
OMEGA_FACTOR = 0.8
#: RK4's stability limit ``|lambda| dt`` (2.83 on the imaginary axis, 2.79 on the negative real
#: axis); cablesim states it as ``omega_max dt``, see :func:`fastest_rate` for when that is wrong.
RK4_LIMIT = 2.8
#: Saved instants per period of the frequency of interest (capped by :data:`MAX_SAMPLES`).
SAMPLES_PER_PERIOD = 20
MAX_SAMPLES = 20000

#: Drift of eq. 15 allowed for the explicit schemes on the third-order state: a spurious
#: constant force of 1e-4 |F0|, about 0.2 % of the harmonic load (|FL| is 4-5 % of |F0| except
#: on the slack axis). The residual of the third-order integration is neutral (nothing pulls it
#: back), so this also bounds its accumulation over the run.
DRIFT_TOL_EXPLICIT = 1e-4
#: The implicit alpha-schemes satisfy eq. 15 at ``t_{n+1-alpha_f}``, not at the saved instants:
#: there the residual is their equilibrium lag, of order ``w h |FL| / |F0|`` (2e-4 to 2e-3
#: measured at 100 steps per period), which does not accumulate. 1e-2 flags several times that.
DRIFT_TOL_IMPLICIT = 1e-2
#: Smallest agreement tolerance (relative max |dz|): dopri5 at rtol = 1e-8 against an
#: independent 4th-order run whose own error is below 1e-8; 1e-4 leaves room for the
#: accumulation of the 1e-8 local errors over 1e4 - 1e6 steps and for the reference's
#: interpolation to the saved instants.
AGREE_TOL_FLOOR = 1e-4
#: Safety factor on the step-halving error estimate of the fixed-step schemes ...
AGREE_SAFETY = 3.0
#: ... and the largest tolerance: an answer more than 5 % off is wrong, whatever the step.
AGREE_TOL_CAP = 5e-2

OK, STOPPED, FAILED = "ok", "stopped-clean", "FAILED"
AXES = ("EA", "sag", "load", "n", "step", "duration", "slack")
AXIS_SHORT = {"EA": "EA", "sag": "sag", "load": "load", "n": "n", "step": "rk4 step", "duration": "duration", "slack": "slack"}
AXIS_TITLES = {
    "EA": "Axial rigidity EA (N)",
    "sag": "Sag: sum S / chord",
    "load": "Load scale (F0 and FL together)",
    "n": "Number of interior nodes n",
    "step": "RK4 step / stability limit 2.8 / omega_max",
    "duration": "Duration (s)",
    "slack": "Loads driving a segment slack",
}


# ----------------------------------------------------------------------------------------------
# Cases
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Scheme:
    """A time-integration scheme for one run.

    ``kind``: ``dopri5`` (rtol 1e-8, cablesim's default settings), ``rk4`` (``factor`` x the
    stability limit 2.8 / omega_max), ``generalized-alpha`` or ``newmark`` (``steps`` per period of
    the frequency of interest; 100 is cablesim's default).
    """

    kind: str
    factor: float | None = None
    steps: int | None = None

    @property
    def label(self) -> str:
        if self.kind == "rk4":
            return f"rk4 dt={self.factor:g}x limit"
        if self.kind in ("generalized-alpha", "newmark"):
            return f"{self.kind} {self.steps}/period"
        return "dopri5 rtol=1e-8"


@dataclass(frozen=True)
class StressCase:
    """One cable, loads and duration, and the runs made on it."""

    label: str
    axis: str
    value: str
    spec: dict
    duration: float
    runs: tuple  # of (analysis, Scheme)

    def yaml_text(self) -> str:
        s = self.spec
        data = {
            "name": "stress-" + "".join(c if c.isalnum() or c in "._-" else "-" for c in self.label),
            "cable": {
                "L": float(s["L"]),
                "H": float(s["H"]),
                "S": [float(v) for v in s["S"]],
                "EA": float(s["EA"]),
                "masses": [float(v) for v in s["masses"]],
            },
            "loads": {"F0": [float(v) for v in s["F0"]], "FL": [float(v) for v in s["FL"]]},
            "analysis": "exact",
            "damping": {"ratio": float(s["xi"]), "modes": [1, 2]},
        }
        return yaml.safe_dump(data, sort_keys=False)


def _spec(**changes) -> dict:
    d = {k: (list(v) if isinstance(v, list) else v) for k, v in PAPER.items()}
    d.update(changes)
    return d


def _chord() -> float:
    return math.hypot(PAPER["L"], PAPER["H"])


def _n_spec(n: int) -> dict:
    """n equal segments/masses/loads with the paper's totals (sum S, sum M, vertical sum F0)."""
    total_S = sum(PAPER["S"])
    total_M = sum(PAPER["masses"])
    fv = (PAPER["F0"][1] + PAPER["F0"][3]) / n
    F0, FL = [], []
    for k in range(n):
        F0 += [0.0, fv]
        FL += [0.01 * fv * (-1) ** k, 0.04 * fv]
    return _spec(S=[total_S / (n + 1)] * (n + 1), masses=[total_M / n] * n, F0=F0, FL=FL)


DOPRI = Scheme("dopri5")
GALPHA = Scheme("generalized-alpha", steps=100)
NEWMARK = Scheme("newmark", steps=100)


def build_cases(reduced: bool = False) -> list[StressCase]:
    """The stress cases, one axis at a time (``reduced``: fewer values, shorter runs)."""
    both = lambda *schemes: tuple((a, s) for a in ("exact", "approximate") for s in schemes)  # noqa: E731
    exact = lambda *schemes: tuple(("exact", s) for s in schemes)  # noqa: E731
    dur = 60.0 if reduced else 300.0
    cases: list[StressCase] = []

    # Axial rigidity. Stiff cables also get cablesim's own choice for them, generalized-alpha;
    # the approximate analysis is skipped at EA = 1e13 (its explicit runs cost ~20 s).
    for EA in (1e6, 1e9, 1e13) if reduced else (1e6, 1e8, 1e9, 1e11, 1e13):
        if EA >= 1e11:
            runs = exact(DOPRI, GALPHA, NEWMARK) + (() if EA > 1e11 else (("approximate", DOPRI), ("approximate", GALPHA)))
        else:
            runs = both(DOPRI)
        cases.append(StressCase(f"EA={EA:.0e}", "EA", f"{EA:.0e}", _spec(EA=EA), dur, runs))

    # Sag: scale S so that sum S / chord takes each value.
    for ratio in (1.0001, 3.0) if reduced else (1.0001, 1.001, None, 2.0, 3.0):
        if ratio is None:  # the paper's own S
            cases.append(StressCase("sag=1.13 (paper)", "sag", f"{sum(PAPER['S']) / _chord():.4g}", _spec(), dur, both(DOPRI)))
            continue
        f = ratio * _chord() / sum(PAPER["S"])
        cases.append(
            StressCase(f"sag={ratio:g}", "sag", f"{ratio:g}", _spec(S=[s * f for s in PAPER["S"]]), dur, both(DOPRI))
        )

    # Load scale.
    for g in (1e-3, 1e3) if reduced else (1e-3, 1.0, 1e3):
        spec = _spec(F0=[g * v for v in PAPER["F0"]], FL=[g * v for v in PAPER["FL"]])
        runs = both(DOPRI) + (exact(GALPHA) if g < 1 else ())
        cases.append(StressCase(f"load x{g:g}", "load", f"{g:g}", spec, dur, runs))

    # Number of nodes. Explicit runs cost O(n^2) per evaluation and their step must resolve the
    # overdamped high modes (see fastest_rate: 3x omega_max at n = 50, 6.6x at n = 100), so the
    # finely divided cables run for a few fundamental periods only.
    for n in (10, 50) if reduced else (2, 10, 50, 100):
        d = {10: 30.0, 50: 5.0}[n] if reduced else {2: dur, 10: dur, 50: 40.0, 100: 10.0}[n]
        runs = both(DOPRI) if n <= 10 else exact(DOPRI, GALPHA)
        cases.append(StressCase(f"n={n}", "n", str(n), _n_spec(n), d, runs))

    # RK4 step size relative to its stability limit 2.8 / omega_max (paper's example), and the
    # same rule on the 50-node cable, whose overdamped high modes make it too long.
    factors = (0.5, 2.0) if reduced else (0.5, 1.0, 2.0, 4.0)
    for a in ("exact", "approximate") if not reduced else ("exact",):
        for f in factors:
            cases.append(StressCase(f"rk4 {f:g}x limit ({a})", "step", f"{f:g}", _spec(), dur, ((a, Scheme("rk4", factor=f)),)))
    cases.append(
        StressCase("rk4 0.5x limit (n=50)", "step", "0.5", _n_spec(50), 5.0 if reduced else 20.0, exact(Scheme("rk4", factor=0.5)))
    )

    # Long runs.
    for T in (1000.0,) if reduced else (1000.0, 10000.0):
        runs = exact(DOPRI) if T > 1000 or reduced else both(DOPRI)
        cases.append(StressCase(f"duration {T:g} s", "duration", f"{T:g}", _spec(), T, runs))

    # Loads driving a segment slack: FL scaled up, then a sustained load with a slack segment.
    gammas = (10.0, 20.0) if reduced else (3.0, 10.0, 15.0, 20.0)
    for g in gammas:
        spec = _spec(FL=[g * v for v in PAPER["FL"]])
        cases.append(StressCase(f"FL x{g:g}", "slack", f"FL x{g:g}", spec, dur, both(DOPRI)))
    f0 = list(PAPER["F0"])
    f0[0], f0[2] = 3000.0e3, -3000.0e3  # node 1 pushed towards B, node 2 towards A
    cases.append(StressCase("F0 slackens segment 2", "slack", "F0 static slack", _spec(F0=f0), dur, exact(DOPRI)))
    return cases


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
    from .dynamics.integrators import DOPRI5, RK4, GeneralizedAlpha, Newmark

    w_max = float(prep.static.modes.omega[-1])
    chord = prep.static.cable.chord_length
    if scheme.kind == "dopri5":
        return DOPRI5(rtol=1e-8, atol=1e-10 * chord)
    if scheme.kind == "rk4":
        return RK4(dt=scheme.factor * RK4_LIMIT / w_max)
    dt = 2.0 * np.pi / prep.omega_hi / scheme.steps
    if scheme.kind == "newmark":
        return Newmark(dt=dt)
    return GeneralizedAlpha(dt=dt, rho_inf=0.8)


def fastest_rate(static) -> float:
    """Largest ``|lambda|`` of the damped linear system ``M q'' + C q' + K0 q = 0``, 1/s.

    With Rayleigh damping every mode keeps its shape: ``lambda^2 + 2 xi w lambda + w^2 = 0``. A
    lightly damped mode has ``|lambda| = w``; an overdamped one (``xi > 1``, which stiffness-
    proportional damping makes of the high modes of a finely divided cable) has a fast real root
    ``w (xi + sqrt(xi^2 - 1)) ~ a1 w^2``, which can exceed ``omega_max`` several times. An explicit
    scheme's step must resolve this rate, not only ``omega_max``.
    """
    from .modal import fastest_rate as rate

    return rate(static.modes.omega, static.a0, static.a1)


def _reference(kind: str, prep: _Prepared, duration: float):
    """An independent, much more accurate run of the same equations (cached per case)."""
    from .dynamics.history import simulate
    from .dynamics.integrators import DOPRI5, RK4

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
    if scheme.kind == "dopri5" or half is None:
        return AGREE_TOL_FLOOR
    p = 4 if scheme.kind == "rk4" else 2
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
    from .analyses.static import run_static
    from .case import parse_case
    from .dynamics.history import build_equations

    if analysis not in cache:
        c = parse_case(case.yaml_text(), source=f"(stress case {case.label})")
        st = run_static(c, analysis, all_models=False)
        w1 = float(st.modes.omega[0])
        omega = OMEGA_FACTOR * w1
        w_hi = max(omega, w1)
        eom = build_equations(c, st, omega=omega)
        cache[analysis] = _Prepared(st, eom, omega, w_hi, _output_step(w_hi, case.duration))
    return cache[analysis]


def _static_tol(cable, P) -> float:
    """Equilibrium residual the static solver guarantees, relative to |F0|.

    It closes the polygon to ``CLOSURE_RTOL`` times the larger of chord and total length; through
    the stiffest segment (``EA / min S``) that length is a force. 10x that, and at least 1e-8.
    """
    from .statics import CLOSURE_RTOL

    length = max(cable.chord_length, cable.total_length)
    force = cable.EA / float(np.min(cable.S)) * CLOSURE_RTOL * length
    return max(1e-8, 10.0 * force / float(np.linalg.norm(P)))


def _static_check(prep: _Prepared) -> tuple[bool, str]:
    from .statics import resisting_force

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


#: A stop is a genuine slackening if, in the state where the run stopped, some segment carries
#: less than this fraction of the smallest static tension (exact tensions of the deformed state,
#: and the tensions of the inextensible state under the current resisting forces, solved by the
#: robust static solver of :mod:`cablesim.statics`).
SLACK_FRACTION = 0.01


def _raw_integrate(eom, integ, duration: float, output_step: float):
    """The integration simulate() performs, without its derived outputs (same trajectory)."""
    from .dynamics import kernels as kn

    prm = eom.params()
    nd = eom.n_dof
    n_out = int(np.floor(duration / output_step + 1e-9))
    t_out = np.arange(1, n_out + 1) * output_step
    out = np.empty((n_out, 3 * nd))
    state = integ.start(eom, eom.initial_state())
    code = state.extra.get("code", kn.OK)
    written = 0
    while code == kn.OK and state.t < duration - 1e-12 * max(duration, 1.0):
        n, code = integ.advance(prm, state, duration, t_out[written:], out[written:])
        written += n
    return t_out[:written], out[:written], state, code


def _stop_state_tensions(prep: _Prepared, integ, duration: float, status: str) -> dict:
    """Tensions in the state where a run stopped, from an independent solve.

    Integration stops: the integrator's last good state. Stops of the derived outputs (the
    record cut where an inner solve of ``observe`` failed): the saved state at that instant.
    """
    from .dynamics import kernels as kn
    from .statics import inextensible_equilibrium, resisting_force, segment_geometry

    eom = prep.eom
    nd = eom.n_dof
    t_rows, rows, state, code = _raw_integrate(eom, integ, duration, prep.output_step)
    if code != kn.OK:
        t, s = state.t, state.s
    else:
        m = re.match(r"stopped at t = ([0-9.eE+-]+) s", status)
        if not m or not t_rows.size:
            return {}
        j = int(np.argmin(np.abs(t_rows - float(m.group(1)))))
        t, s = float(t_rows[j]), rows[j]
    info = {"t": float(t)}
    if not np.all(np.isfinite(s)):
        info["finite"] = False
        return info
    cable = prep.static.cable
    if eom.analysis == "exact":
        y = eom.y0 + s[:nd]
        info["T_exact"] = segment_geometry(cable, y)[2]
        P = resisting_force(cable, y)
    else:
        P = eom.F0 + eom.FL * np.sin(eom.omega * t) - eom.C @ s[nd : 2 * nd] - eom.mass * s[2 * nd :]
    try:
        info["T_inext"] = inextensible_equilibrium(cable, P).T
    except CablesimError as exc:  # the robust solver finds it slack (or cannot solve): genuine
        info["inext_error"] = str(exc)
    return info


def run_one(case: StressCase, analysis: str, scheme: Scheme, cache: dict | None = None) -> dict:
    """Run and check one (case, analysis, scheme); ``cache`` shares statics and references."""
    from .dynamics.history import simulate

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
        if hist.status.startswith("interrupted"):
            raise KeyboardInterrupt
        ref_kind = "dopri5-tight" if scheme.kind == "rk4" else "rk4-fine"
        ref, ref_integ, ref_wall = _reference(ref_kind, prep, case.duration)
        row["reference"] = f"{ref_integ.name} " + ", ".join(
            f"{k}={v:.3g}" for k, v in ref_integ.settings().items() if isinstance(v, float) and math.isfinite(v)
        )
        row["ref_wall"] = ref_wall
        row["t_end"] = float(hist.t[-1])
        row["message"] = "" if hist.completed else hist.status
        stop = re.match(r"stopped at t = ([0-9.eE+-]+) s", hist.status)
        row["t_stop"] = float(stop.group(1)) if stop else row["t_end"]
        half = None
        if hist.completed and scheme.kind != "dopri5":
            # The same scheme at half the step: measures its own truncation error.
            from dataclasses import replace

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
    explicit = scheme.kind in ("rk4", "dopri5")
    row["drift_tol"] = DRIFT_TOL_EXPLICIT if explicit else DRIFT_TOL_IMPLICIT
    m = min(hist.t.size, ref.t.size)
    scale = float(np.max(np.abs(ref.z[:m]))) if m else 0.0
    if m <= 1:  # stopped before the first saved instant: nothing to compare
        agree = float("nan")
    else:
        diff = float(np.max(np.abs(hist.z[:m] - ref.z[:m])))
        agree = diff / scale if scale > 0 else (0.0 if diff == 0 else float("inf"))
    row["agreement"] = agree
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
            reasons.append(f"completed although the reference stops ({ref.status}): a missed event")
        row["outcome"] = OK if not reasons else FAILED
    else:
        # A stop: its message must name the cause; if an accurate run of the same case does not
        # stop, the cause is numerical and the message must point at the numerics.
        ck["run"] = "stop"
        ck["drift"] = "na"  # informative only before a stop
        clear = hist.status.startswith("stopped at t =") and len(hist.status) > 40
        numeric_msg = bool(_NUMERIC_WORDS.search(hist.status))
        misleading = ref.completed and not numeric_msg
        spurious = ""
        if clear and not ref.completed and ("slack" in hist.status or "inner" in hist.status):
            # The message blames the physics (a slack or nearly slack segment): check it.
            info = _stop_state_tensions(prep, integ, case.duration, hist.status)
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
        from joblib import Parallel, delayed

        # Longest cases first, so that the workers finish together.
        order = sorted(range(len(cases)), key=lambda i: -_cost_hint(cases[i]))
        res = Parallel(n_jobs=jobs, return_as="generator_unordered")(delayed(_run_indexed)(i, cases[i]) for i in order)
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


# ----------------------------------------------------------------------------------------------
# Report
# ----------------------------------------------------------------------------------------------
MAP_COLUMNS = ("static", "finite", "run", "drift", "agreement", "diagnostic", "outcome")
MAP_TITLES = {
    "static": "statics",
    "finite": "no NaN/inf",
    "run": "ran to end",
    "drift": "drift eq. 15",
    "agreement": "agrees with\n2nd scheme",
    "diagnostic": "stop message\nnames cause",
    "outcome": "OUTCOME",
}


def _fmt(x: float, digits: int = 2) -> str:
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:.{digits}e}"


def summary_counts(rows: list[dict]) -> dict:
    """Number of rows per outcome."""
    return {o: sum(r["outcome"] == o for r in rows) for o in (OK, STOPPED, FAILED)}


def format_table(rows: list[dict]) -> str:
    """Markdown table, one section per axis."""
    out = []
    for axis in AXES:
        sel = [r for r in rows if r["axis"] == axis]
        if not sel:
            continue
        out.append(f"### {AXIS_TITLES[axis]}\n")
        out.append("| case | analysis | integrator | outcome | drift (tol) | agreement (tol) | min T / T0 | wall s | t reached / duration s | stop message / reason |")
        out.append("|---|---|---|---|---|---|---|---|---|---|")
        for r in sel:
            msg = r["message"]
            if r["reason"]:
                msg = (msg + " **" if msg else "**") + r["reason"] + "**"
            msg = msg.replace("|", "/").replace("\n", " ")
            outcome = r["outcome"] if r["outcome"] != FAILED else "**FAILED**"
            stopped = r["checks"]["run"] == "stop"  # values up to the stop: information only
            dtol = "until stop" if stopped else f"{r['drift_tol']:.0e}"
            drift = "-" if not np.isfinite(r["drift"]) else f"{_fmt(r['drift'])} ({dtol})"
            if r["analysis"] == "approximate" and np.isfinite(r.get("drift_pos", np.nan)):
                drift = f"{_fmt(r['drift'])}, pos. {_fmt(r['drift_pos'])} ({dtol})"
            atol = "until stop" if stopped else f"{r['agree_tol']:.1e}"
            agree = "-" if not np.isfinite(r["agreement"]) else f"{_fmt(r['agreement'])} ({atol})"
            out.append(
                f"| {r['label']} | {r['analysis']} | {r['integrator']} | {outcome} | {drift} | {agree} | "
                f"{'-' if not np.isfinite(r['tmin_ratio']) else format(r['tmin_ratio'], '.3g')} | "
                f"{r['wall']:.2f} | {r['t_stop'] if np.isfinite(r['t_stop']) else 0:.6g} / {r['duration']:g} | {msg} |"
            )
        out.append("")
    return "\n".join(out)


def format_summary(rows: list[dict], wall: float | None = None) -> str:
    c = summary_counts(rows)
    text = f"{len(rows)} runs: {c[OK]} ok, {c[STOPPED]} stopped-clean, {c[FAILED]} FAILED"
    if wall is not None:
        text += f" ({wall:.0f} s wall time)"
    text += "."
    for r in rows:
        if r["outcome"] == FAILED:
            text += f"\n- FAILED: {r['label']} ({r['analysis']}, {r['integrator']}): {r['reason'] or r['message']}"
    return text


_METHOD = f"""\
## How to read this

Each row is one time history of a case built from the paper's example, varied along one axis at
a time, forced at `w = {OMEGA_FACTOR} w1` (clear of the primary, superharmonic and 1/2-subharmonic
resonances, so that two schemes can be compared meaningfully), from the static equilibrium at
rest, with Rayleigh damping `xi = 0.01` in modes 1 and 2. Checks (columns of the map):

- **statics**: the equilibrium under F0 exists; in the exact analysis `|P(y0) - F0| / |F0|` is
  within 10x what the static solver's closure tolerance allows (at least 1e-8). A
  `CablesimError` here (e.g. a slack segment) is a clean stop.
- **no NaN/inf**: every output array (`t, z, v, zc, ze, T, residual`) of the run and of its
  reference is finite.
- **drift of eq. 15**: the residual `|M y'' + C y' + P - F| / |F0|` that cablesim stores. Explicit
  schemes (third-order state): at most {DRIFT_TOL_EXPLICIT:.0e}, a spurious force of 1e-4 |F0|,
  about 0.2 % of the harmonic load (|FL| is 4-5 % of |F0| except on the slack axis); the
  residual of the third-order integration is neutral (nothing pulls it back), so this also bounds
  its accumulation. The implicit alpha-schemes satisfy eq. 15 at `t_(n+1-alpha_f)`, so at the
  saved instants the residual is their O(w h) equilibrium lag (2e-4 to 2e-3 here at 100 steps
  per period), which does not grow: at most
  {DRIFT_TOL_IMPLICIT:.0e}. In the approximate analysis the stored residual is the mismatch
  `y - x(P) - u(P)` multiplied by `K0`, which grows like EA for stiff cables; the check uses its
  position form `max |z - zc - ze| / max |z|` (the table shows both).
- **agreement with a second scheme**: relative `max |z - z_ref| / max |z_ref|` over the saved
  instants against an independent, far more accurate run of the same equations: classical RK4
  with `dt = min(0.5 x 2.8 / lambda_max, T / 400)` (T the period of interest; `lambda_max` the
  fastest rate of the damped linear system, see below) for dopri5 and the implicit schemes, and
  dopri5 with `rtol = 1e-10` for the rk4 rows. Tolerance: {AGREE_TOL_FLOOR:.0e} for dopri5
  (`rtol = 1e-8`: 1e4 times its tolerance, room for the accumulation of local errors over
  1e4-1e6 steps); for the fixed-step schemes {AGREE_SAFETY:g} x their own error measured by
  step halving (`|z_h - z_(h/2)| 2^p / (2^p - 1)`, p = 4 for rk4, 2 for newmark and
  generalized-alpha), between {AGREE_TOL_FLOOR:.0e} and {AGREE_TOL_CAP:.0e}. A completed run
  beyond its tolerance is **silently wrong**: its error is not the scheme's truncation error, or
  it is more than 5 % off.
- **stop message names cause**: a stop must say when and why (`stopped at t = ...: ...`). If the
  accurate reference of the same case runs to the end, the cause is numerical and the message
  must point at the numerics (step, tolerance, integrator); a message that blames the loads is
  misleading. If the reference stops too, the stop must be real: in the state where the run
  stopped some segment must carry less than {100 * SLACK_FRACTION:g} % of the smallest static
  tension (deformed-state tensions, and the inextensible state under the current resisting
  forces solved by the robust solver of `cablesim.statics`); otherwise the stop is spurious.

Outcome: **ok** = ran to the end within drift and agreement tolerances; **stopped-clean** = stopped
early (or refused up front with a `CablesimError`) with a clear, correct message and finite
outputs; **FAILED** = anything else (NaN, an unexpected exception, silently wrong, misleading or
spurious stop). `min T / T0` is the smallest segment tension at the saved instants relative to
the smallest static tension (how close the run came to slackness; a stop between two saved
instants is not in it).

**Explicit stability limit.** RK4 is stable for `|lambda| dt` up to about 2.8, where `lambda` runs
over the eigenvalues of the damped linear system: `lambda^2 + 2 xi_i w_i lambda + w_i^2 = 0` per
mode. With Rayleigh damping fitted to modes 1 and 2 the stiffness term overdamps the high modes
of a finely divided cable (`xi_i = a1 w_i / 2 > 1`), whose fast real root `~ a1 w_i^2` then
exceeds `omega_max` (3x at n = 50, 6.6x at n = 100), so `2.8 / omega_max` is not a safe step
there (row `rk4 0.5x limit (n=50)`).
"""


def write_report(rows: list[dict], md_path, png_path, wall: float | None = None, title: str = "Stability under stress") -> tuple[Path, Path]:
    """Write the markdown table (grouped by axis, with a summary) and the PNG map.

    Parameters
    ----------
    rows : list of dict
        From :func:`run_stress`.
    md_path, png_path : path
        Output files (folders are created); the markdown links the PNG by a relative path.
    wall : float, optional
        Total wall time of the stress run, s.

    Returns
    -------
    (Path, Path)
    """
    import os

    md_path, png_path = Path(md_path), Path(png_path)
    md_path.parent.mkdir(parents=True, exist_ok=True)
    plot_map(rows, png_path)
    rel = os.path.relpath(png_path, md_path.parent)
    text = (
        f"# {title}\n\n"
        "Generated by `cablesim stress` (`cablesim/stress.py`); rerun it to refresh this page.\n\n"
        f"**Summary.** {format_summary(rows, wall)}\n\n"
        f"![stress map]({rel})\n\n"
        f"{_METHOD}\n"
        "## Runs by axis\n\n"
        f"{format_table(rows)}\n"
    )
    tmp = md_path.with_name(md_path.name + ".part")
    tmp.write_text(text)
    tmp.replace(md_path)
    return md_path, png_path


def plot_map(rows: list[dict], path) -> Path:
    """Grid of coloured cells: one row per run, one column per check and the outcome."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    from .plotting import _plt, save_atomic

    plt = _plt()
    code = {"ok": 0, "stop": 1, "fail": 2, "na": 3}
    colours = ["#2e9e44", "#f0a30a", "#d62728", "#d9d9d9"]
    grid = np.zeros((len(rows), len(MAP_COLUMNS)), dtype=int)
    labels = []
    for i, r in enumerate(rows):
        for j, col in enumerate(MAP_COLUMNS):
            if col == "outcome":
                grid[i, j] = {OK: 0, STOPPED: 1, FAILED: 2}[r["outcome"]]
            else:
                grid[i, j] = code[r["checks"][col]]
        labels.append(f"{AXIS_SHORT[r['axis']]:<8} | {r['label']:<28} | {r['analysis'][:6]:<6} | {r['integrator']:<28}")
    h = 1.2 + 0.24 * len(rows)
    fig, ax = plt.subplots(figsize=(11.5, h))
    ax.imshow(grid, cmap=ListedColormap(colours), vmin=0, vmax=3, aspect="auto", interpolation="nearest")
    for i, r in enumerate(rows):
        for j, col in enumerate(MAP_COLUMNS):
            txt = ""
            if col == "drift" and np.isfinite(r["drift"]):
                txt = f"{r.get('drift_pos', r['drift']):.0e}"
            elif col == "agreement" and np.isfinite(r["agreement"]):
                txt = f"{r['agreement']:.0e}"
            elif col == "run" and r["checks"]["run"] == "stop":
                txt = f"stop t={r['t_stop']:.3g}" if np.isfinite(r["t_stop"]) else "up front"
            elif col == "outcome":
                txt = r["outcome"]
            if txt:
                ax.text(j, i, txt, ha="center", va="center", fontsize=6.5, color="black")
    ax.set_xticks(range(len(MAP_COLUMNS)))
    ax.set_xticklabels([MAP_TITLES[c] for c in MAP_COLUMNS], fontsize=8)
    ax.xaxis.tick_top()
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(labels, fontsize=7, family="monospace")
    ax.set_xticks(np.arange(-0.5, len(MAP_COLUMNS)), minor=True)
    ax.set_yticks(np.arange(-0.5, len(rows)), minor=True)
    ax.grid(which="minor", color="white", linewidth=1.2)
    ax.tick_params(which="minor", length=0)
    # Separate the axes of the sweep.
    for i in range(1, len(rows)):
        if rows[i]["axis"] != rows[i - 1]["axis"]:
            ax.axhline(i - 0.5, color="black", linewidth=1.5)
    c = summary_counts(rows)
    ax.set_title(
        f"cablesim stress: {len(rows)} runs, {c[OK]} ok, {c[STOPPED]} stopped-clean, {c[FAILED]} FAILED\n"
        "cells: drift = max eq.-15 residual (approximate: position form), agreement = rel. max |dz| vs reference",
        fontsize=9,
        pad=38,
    )
    ax.legend(
        handles=[
            Patch(color=colours[0], label="ok / passed"),
            Patch(color=colours[1], label="stopped cleanly (clear message, finite outputs)"),
            Patch(color=colours[2], label="FAILED"),
            Patch(color=colours[3], label="not applicable"),
        ],
        loc="upper center",
        bbox_to_anchor=(0.5, -0.02 * 40 / max(len(rows), 1) - 0.005),
        ncol=4,
        fontsize=8,
        frameon=False,
    )
    return save_atomic(fig, path)
