"""Stability under stress: a sweep over parameters that strain the numerics (``cablesim stress``).

Every stress case is the paper's example (L = 300 m, H = 20 m, S = [130, 100, 110] m, EA = 1e9 N,
masses [8000, 14000] kg, F0 = [300, 1100, 450, 2000] kN, FL = [-6, 22, -18, 120] kN, xi = 0.01)
varied along one axis at a time:

========== =================================================================================
axis       values (reduced version: fewer values, 60 s runs)
========== =================================================================================
EA         1e6, 1e8, 1e9, 1e11, 1e13 N (stiff cables also with generalized-alpha and newmark, at a
           fixed step and error-controlled)
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
:func:`~cablesim.analyses.static.run_static`, :func:`~cablesim.analyses.setup.build_equations`,
:func:`~cablesim.dynamics.simulate.simulate`) in the exact and, where cheap, the approximate
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

The cases are built here (:func:`build_cases`), run and checked in :mod:`cablesim.stress.run`
(:func:`~cablesim.stress.run.run_stress`) and reported in :mod:`cablesim.stress.report`
(markdown table and PNG map); ``cablesim stress`` on the command line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import yaml

from ..dynamics.integrators.settings import DEFAULT_TOLERANCES


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

#: A stop is a genuine slackening if, in the state where the run stopped, some segment carries
#: less than this fraction of the smallest static tension (exact tensions of the deformed state,
#: and the tensions of the inextensible state under the current resisting forces, solved by the
#: robust static solver of :mod:`cablesim.statics`).
SLACK_FRACTION = 0.01

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

    ``kind``: ``rk4`` (``factor`` x the stability limit 2.8 / omega_max), ``generalized-alpha`` or
    ``newmark`` with ``steps`` per period of the frequency of interest (a fixed step), or without
    ``factor`` and ``steps`` an error-controlled scheme (``dopri5``, ``newmark``,
    ``generalized-alpha``) at cablesim's default tolerances.
    """

    kind: str
    factor: float | None = None
    steps: int | None = None

    @property
    def label(self) -> str:
        if self.factor is not None:  # an explicit fixed step, relative to the stability limit
            return f"{self.kind} dt={self.factor:g}x limit"
        if self.steps is not None:  # an implicit fixed step
            return f"{self.kind} {self.steps}/period"
        return f"{self.kind} rtol={DEFAULT_TOLERANCES[self.kind]:g}"  # adaptive, at cablesim's default tolerances


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
GALPHA_AUTO = Scheme("generalized-alpha")  # error-controlled, at the default tolerances
NEWMARK_AUTO = Scheme("newmark")


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
            runs = exact(DOPRI, GALPHA, NEWMARK, GALPHA_AUTO, NEWMARK_AUTO) + (
                () if EA > 1e11 else (("approximate", DOPRI), ("approximate", GALPHA), ("approximate", GALPHA_AUTO)))
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
        runs = both(DOPRI) + (exact(GALPHA, GALPHA_AUTO) if g < 1 else ())
        cases.append(StressCase(f"load x{g:g}", "load", f"{g:g}", spec, dur, runs))

    # Number of nodes. Explicit runs cost O(n^2) per evaluation and their step must resolve the
    # overdamped high modes (see fastest_rate: 3x omega_max at n = 50, 6.6x at n = 100), so the
    # finely divided cables run for a few fundamental periods only.
    for n in (10, 50) if reduced else (2, 10, 50, 100):
        d = {10: 30.0, 50: 5.0}[n] if reduced else {2: dur, 10: dur, 50: 40.0, 100: 10.0}[n]
        runs = both(DOPRI) if n <= 10 else exact(DOPRI, GALPHA, GALPHA_AUTO)
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
        cases.append(StressCase(f"FL x{g:g}", "slack", f"FL x{g:g}", spec, dur, both(DOPRI) + exact(GALPHA_AUTO)))
    f0 = list(PAPER["F0"])
    f0[0], f0[2] = 3000.0e3, -3000.0e3  # node 1 pushed towards B, node 2 towards A
    cases.append(StressCase("F0 slackens segment 2", "slack", "F0 static slack", _spec(F0=f0), dur, exact(DOPRI)))
    return cases
