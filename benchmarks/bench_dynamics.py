"""Work-precision of the time integrators: wall time against error, scene by scene, in one run.

For each scene of the paper example (table ``SCENES`` below) every cablesim integrator runs over
a range of step sizes or tolerances, and scipy's ``solve_ivp`` with a plain Python/numpy
right-hand side runs beside them in the same process as the baseline. Each point is the median
wall time of repeated in-process runs and its error against an independent reference solution.

Scenes (``--scene N``, repeatable; all by default):

1. forced at w = 2.4 rad/s, near the softening fundamental resonance, 1000 s;
2. forced at w = 5.04 rad/s (about twice the fundamental), 3000 s: the response jumps to the
   1/2 subharmonic late in the run, and errors grow exponentially after an instability, so the
   error is reported over the whole run and over the first 800 s (before the jump; the summary
   and the ladders judge by the latter);
3. free vibration along linear mode 3, peak initial velocity 1 m/s, damping ratio 0.2, 6 s
   (paper Fig. 2);
4. the stiff "inextensible" cable EA = 1e12 N of paper Fig. 8 (configs/paper/fig8a.yaml),
   forced at 0.81 rad/s, 600 s;
5. the approximate analysis at the Fig. 3a case, forced at w = 2.4 rad/s, 300 s.

References (cached under runs/bench/reference-*.npz, keyed by scene and settings; a cached run
at least as long with the same settings is reused by slicing):

- exact analysis (scenes 1-3): the second-order formulation ``M z'' + C z' + P(y0 + z) = F(t)``
  written here independently of cablesim's kernels (segment geometry, ``T = EA (l - S) / S``,
  ``P_r = T_r e_r - T_{r+1} e_{r+1}``), compiled with numba, integrated by scipy's Fortran
  DOP853 (``scipy.integrate.ode``) at rtol 1e-12; checked against the same at rtol 1e-10;
- stiff cable (scene 4): the same second-order formulation by scipy's Radau with the analytic
  Jacobian (tangent stiffness written here) at rtol 1e-8 (1e-9 costs ~13x more: 300 s per
  100 s simulated); checked against Radau at rtol 1e-7 and against the Fortran DOP853 at
  rtol 1e-12 (explicit, but the cable is only moderately stiff: |lambda|_max = 1641 1/s);
- approximate analysis (scene 5; it has no second-order form independent of cablesim, its
  constitutive law is a rate law): cablesim's DOPRI5 at rtol 1e-12, checked against cablesim's
  RK4 at dt = 1e-3 s.

The difference between a reference and its check is written as a ``reference-check`` row and
drawn as a shaded band: errors below it are not resolved.

Error: max over the saved instants and all DOF of ``|z - z_ref|``, relative to ``max |z_ref|``.
Time: the median of 3 in-process runs (7 for runs under 50 ms) after a short warm-up run of
each scheme (numba's compilation excluded), the settings of a scene run round-robin so that a
change in the machine's load hits them all alike; a scipy run longer than 5 s is run once (it
is dominated by interpreter work; its spread, ~15 % here, is small next to the ratios).

Settings: rk4 dt from 0.95 x its stability limit 2.8 / |lambda|_max (largest eigenvalue modulus
of the linearised damped system) down by factors sqrt(2); dopri5 rtol 1e-5 ... 1e-10 with
atol = 1e-2 rtol x chord (the default's ratio); newmark and generalized-alpha (rho_inf 0.8) dt
from 25 steps per period of interest down by factors 2. A fixed-step ladder (at least three
points) stops once a setting costs more than 10x the cheapest run of the scene below 1e-4,
errs below 1e-8 (rk4) or 1e-6 (second-order schemes), or stops improving (error not halved).
make_integrator's default for the scene is always measured and marked (star in the plot,
``default`` column).

Output: runs/bench/dynamics.csv (all points, ``scene`` column; rows of scenes not rerun are kept),
runs/bench/work-precision-scene<N>.png, runs/bench/summary.md, and a printed summary per scene.
``--quick`` runs shorter durations and fewer settings into runs/bench/quick/. ``make bench``.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import hashlib
import io
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit
from scipy.integrate import ode, solve_ivp

from cablesim.analyses.setup import build_equations, make_integrator, mode_velocity
from cablesim.analyses.static import run_static
from cablesim.case import IntegratorSpec, load_case
from cablesim.dynamics.simulate import simulate
from cablesim.dynamics.integrators import DOPRI5, RK4, GeneralizedAlpha, Newmark

OUT = Path("runs/bench")
THRESHOLDS = (1e-4, 1e-6)
SCHEMES = ("rk4", "dopri5", "newmark", "generalized-alpha")


# ---------------------------------------------------------------------------------------------
# Scenes
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Scene:
    number: int
    title: str
    case: str | None  # case file (None: the embedded paper example)
    analysis: str
    omega: float  # forcing frequency, rad/s (0: free vibration)
    duration: float
    output_step: float
    quick_duration: float
    damping_ratio: float | None = None
    mode: int | None = None  # free vibration: initial velocities along this mode ...
    peak_velocity: float = 0.0  # ... scaled to this peak, m/s
    early: float | None = None  # also report the error over [0, early]
    reference: str = "dop853"  # dop853 | radau | approximate
    # scipy baseline: (method, rtol) pairs; quick runs take the first only
    scipy: tuple = (("RK45", 1e-4), ("RK45", 1e-6), ("DOP853", 1e-5), ("DOP853", 1e-7))
    dopri5_rtols: tuple = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
    # The README's recommended default when it differs from today's: generalized-alpha with this
    # many steps per period of interest (rounded, like make_integrator, to divide the forcing period).
    recommended_steps: int | None = None


SCENES = {
    1: Scene(1, "forced near the fundamental resonance, w = 2.4 rad/s, 1000 s", None, "exact", 2.4,
             1000.0, 0.05, 200.0),
    2: Scene(2, "forced at about twice the fundamental, w = 5.04 rad/s, 3000 s (late 1/2-subharmonic jump)",
             None, "exact", 5.04, 3000.0, 0.05, 400.0, early=800.0,
             scipy=(("RK45", 1e-5), ("DOP853", 1e-8))),
    3: Scene(3, "free vibration along mode 3, peak velocity 1 m/s, xi = 0.2, 6 s (Fig. 2)",
             "configs/paper/fig2.yaml", "exact", 0.0, 6.0, 0.002, 6.0, damping_ratio=0.2, mode=3,
             peak_velocity=1.0,
             scipy=(("RK45", 1e-4), ("RK45", 1e-6), ("RK45", 1e-8), ("DOP853", 1e-5), ("DOP853", 1e-7),
                    ("DOP853", 1e-9))),
    4: Scene(4, "stiff cable EA = 1e12 N (Fig. 8a loads), w = 0.81 rad/s, 600 s",
             "configs/paper/fig8a.yaml", "exact", 0.81, 600.0, 0.05, 100.0, reference="radau", recommended_steps=1600,
             scipy=(("Radau", 1e-4), ("Radau", 1e-6))),
    5: Scene(5, "approximate analysis, Fig. 3a loads, w = 2.4 rad/s, 300 s",
             "configs/paper/fig3a.yaml", "approximate", 2.4, 300.0, 0.05, 60.0, reference="approximate",
             scipy=(("RK45", 1e-5),)),
}


@dataclass
class Setup:
    """A scene's equations of motion, initial states and the quantities the settings derive from."""

    scene: Scene
    eom: object
    static: object
    s0: np.ndarray  # cablesim's third-order initial state (z, y', y'')
    duration: float
    t_out: np.ndarray
    w_interest: float
    lam_max: float  # largest |eigenvalue| of the linearised second-order system, 1/s
    chord: float
    default: object = None  # make_integrator's default for the scene
    note: str = ""


def setup(scene: Scene, duration: float) -> Setup:
    case, _ = load_case(scene.case)
    static = run_static(case, scene.analysis, all_models=False)
    if scene.mode is None:
        eom = build_equations(case, static, omega=scene.omega)
        s0 = eom.initial_state()
        w_int = max(scene.omega, float(static.modes.omega[0]))
    else:
        eom = build_equations(case, static, omega=0.0, load_scale=0.0, damping_ratio=scene.damping_ratio)
        s0 = eom.initial_state(v0=mode_velocity(static, scene.mode, scene.peak_velocity))
        w_int = float(static.modes.omega[scene.mode - 1])
    nd = eom.n_dof
    A = np.block([[np.zeros((nd, nd)), np.eye(nd)], [-eom.K0 / eom.mass[:, None], -eom.C / eom.mass[:, None]]])
    lam = float(np.abs(np.linalg.eigvals(A)).max())
    n_out = int(math.floor(duration / scene.output_step + 1e-9))
    su = Setup(scene, eom, static, s0, duration, np.arange(n_out + 1) * scene.output_step, w_int, lam,
               float(eom.cable.chord_length))
    su.default = make_integrator(IntegratorSpec(), eom, w_int)
    return su


# ---------------------------------------------------------------------------------------------
# The second-order formulation, written independently of cablesim's kernels
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def _nb_force(y, S, EA, L, H, P, K, want_K):
    """Resisting force P(y) (and tangent stiffness K if want_K): segment j joins node j-1 to node j
    (0-based nodes 0..n-1 interior, -1 = support A, n = support B); P_k = F_k - F_{k+1}."""
    n = S.size - 1
    P[:] = 0.0
    if want_K:
        K[:, :] = 0.0
    px = 0.0
    py = 0.0
    for j in range(n + 1):
        qx = L if j == n else y[2 * j]
        qy = H if j == n else y[2 * j + 1]
        dx = qx - px
        dy = qy - py
        length = math.sqrt(dx * dx + dy * dy)
        T = EA * (length - S[j]) / S[j]
        ex = dx / length
        ey = dy / length
        if j < n:
            P[2 * j] += T * ex
            P[2 * j + 1] += T * ey
        if j > 0:
            P[2 * j - 2] -= T * ex
            P[2 * j - 1] -= T * ey
        if want_K:
            ka = EA / S[j]
            kg = T / length
            k11 = ka * ex * ex + kg * (1.0 - ex * ex)
            k12 = ka * ex * ey - kg * ex * ey
            k22 = ka * ey * ey + kg * (1.0 - ey * ey)
            for a in range(2):
                node = j - 1 if a == 0 else j
                if node < 0 or node >= n:
                    continue
                for b in range(2):
                    other = j - 1 if b == 0 else j
                    if other < 0 or other >= n:
                        continue
                    sg = 1.0 if a == b else -1.0
                    K[2 * node, 2 * other] += sg * k11
                    K[2 * node, 2 * other + 1] += sg * k12
                    K[2 * node + 1, 2 * other] += sg * k12
                    K[2 * node + 1, 2 * other + 1] += sg * k22
        px = qx
        py = qy


@njit(cache=True)
def _nb_rhs(t, s, S, EA, L, H, m, C, F0, FL, w, y0):
    nd = m.size
    y = y0 + s[:nd]
    P = np.empty(nd)
    K = np.empty((1, 1))
    _nb_force(y, S, EA, L, H, P, K, False)
    out = np.empty(2 * nd)
    sw = math.sin(w * t)
    for i in range(nd):
        out[i] = s[nd + i]
        acc = F0[i] + FL[i] * sw - P[i]
        for j in range(nd):
            acc -= C[i, j] * s[nd + j]
        out[nd + i] = acc / m[i]
    return out


@njit(cache=True)
def _nb_jac(t, s, S, EA, L, H, m, C, F0, FL, w, y0):
    nd = m.size
    y = y0 + s[:nd]
    P = np.empty(nd)
    K = np.empty((nd, nd))
    _nb_force(y, S, EA, L, H, P, K, True)
    J = np.zeros((2 * nd, 2 * nd))
    for i in range(nd):
        J[i, nd + i] = 1.0
        for j in range(nd):
            J[nd + i, j] = -K[i, j] / m[i]
            J[nd + i, nd + j] = -C[i, j] / m[i]
    return J


def _args(eom):
    c = eom.cable
    return (np.ascontiguousarray(c.S, dtype=float), float(c.EA), float(c.L), float(c.H),
            np.ascontiguousarray(eom.mass), np.ascontiguousarray(eom.C), np.ascontiguousarray(eom.F0),
            np.ascontiguousarray(eom.FL), float(eom.omega), np.ascontiguousarray(eom.y0))


def compiled_second_order(eom):
    """numba closures ``f(t, s)``, ``jac(t, s)`` with the problem's arrays frozen in: a call from
    scipy costs ~2 us instead of ~40 us for a dispatch with a dozen array arguments."""
    S, EA, L, H, m, C, F0, FL, w, y0 = _args(eom)
    rhs, jac = _nb_rhs, _nb_jac

    @njit
    def f(t, s):
        return rhs(t, s, S, EA, L, H, m, C, F0, FL, w, y0)

    @njit
    def J(t, s):
        return jac(t, s, S, EA, L, H, m, C, F0, FL, w, y0)

    return f, J


def python_second_order(eom):
    """Plain Python/numpy right-hand side and Jacobian of the second-order formulation (state (z, v))
    for the scipy baseline: no numba, one small numpy expression per quantity."""
    c = eom.cable
    nd = eom.n_dof
    n = c.n_nodes
    S, EA, m, C, F0, FL, w, y0 = c.S, c.EA, eom.mass, eom.C, eom.F0, eom.FL, eom.omega, eom.y0
    pts = np.zeros((n + 2, 2))
    pts[-1] = (c.L, c.H)
    I2 = np.eye(2)

    def geometry(z):
        pts[1:-1] = (y0 + z).reshape(-1, 2)
        d = pts[1:] - pts[:-1]
        length = np.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2)
        return d / length[:, None], length, EA * (length - S) / S

    def f(t, s):
        z, v = s[:nd], s[nd:]
        e, _, T = geometry(z)
        Fs = T[:, None] * e
        P = (Fs[:-1] - Fs[1:]).ravel()
        return np.concatenate([v, (F0 + FL * np.sin(w * t) - C @ v - P) / m])

    def jac(t, s):
        e, length, T = geometry(s[:nd])
        ee = e[:, :, None] * e[:, None, :]
        ks = (EA / S)[:, None, None] * ee + (T / length)[:, None, None] * (I2 - ee)
        K = np.zeros((nd, nd))
        for j in range(n + 1):
            a, b = j - 1, j
            if a >= 0:
                K[2 * a:2 * a + 2, 2 * a:2 * a + 2] += ks[j]
            if b < n:
                K[2 * b:2 * b + 2, 2 * b:2 * b + 2] += ks[j]
            if a >= 0 and b < n:
                K[2 * a:2 * a + 2, 2 * b:2 * b + 2] -= ks[j]
                K[2 * b:2 * b + 2, 2 * a:2 * a + 2] -= ks[j]
        J = np.zeros((2 * nd, 2 * nd))
        J[:nd, nd:] = np.eye(nd)
        J[nd:, :nd] = -K / m[:, None]
        J[nd:, nd:] = -C / m[:, None]
        return J

    return f, jac


def python_third_order_approximate(eom):
    """Plain Python right-hand side of the approximate analysis' third-order equations (state
    (z, y', y'')), with ``K = N(P)^-1`` from cablesim's pure-Python statics (no numba) at
    ``P = F - C y' - M y''`` (eq. 15), warm-started from the previous evaluation."""
    from cablesim.statics import approximate_equilibrium

    nd = eom.n_dof
    cable, m, C, F0, FL, w = eom.cable, eom.mass, eom.C, eom.F0, eom.FL, eom.omega
    warm = [np.array(eom.F1, dtype=float)]

    def f(t, s):
        v, a = s[nd:2 * nd], s[2 * nd:]
        P = F0 + FL * np.sin(w * t) - C @ v - m * a
        eq = approximate_equilibrium(cable, P, F_start=warm[0], check_slack=False)
        warm[0] = eq.inextensible.segments.F[0]
        jerk = (FL * w * np.cos(w * t) - np.linalg.solve(eq.N, v) - C @ a) / m
        return np.concatenate([v, a, jerk])

    return f


def check_formulations(su: Setup):
    """The numba and numpy right-hand sides agree with each other and with cablesim's statics."""
    from cablesim.statics import resisting_force, tangent_stiffness

    eom = su.eom
    nd = eom.n_dof
    rng = np.random.default_rng(1)
    s = np.concatenate([rng.normal(scale=0.3, size=nd), rng.normal(size=nd)])
    f, jac = python_second_order(eom)
    a = _nb_rhs(0.7, s, *_args(eom))
    b = f(0.7, s)
    c = (eom.F0 + eom.FL * np.sin(eom.omega * 0.7) - eom.C @ s[nd:] - resisting_force(eom.cable, eom.y0 + s[:nd])) / eom.mass
    assert np.allclose(a, b, rtol=1e-10, atol=1e-9) and np.allclose(a[nd:], c, rtol=1e-8, atol=1e-6), (a, b, c)
    K = tangent_stiffness(eom.cable, eom.y0 + s[:nd])
    Ja, Jb = _nb_jac(0.7, s, *_args(eom)), jac(0.7, s)
    assert np.allclose(Ja, Jb, rtol=1e-10) and np.allclose(-Ja[nd:, :nd] * eom.mass[:, None], K, rtol=1e-9)


# ---------------------------------------------------------------------------------------------
# References
# ---------------------------------------------------------------------------------------------
def _s0_second_order(su: Setup):
    nd = su.eom.n_dof
    return np.array(su.s0[:2 * nd], dtype=float)


def ref_dop853(su: Setup, rtol: float):
    """scipy's Fortran DOP853 (scipy.integrate.ode) on the numba-compiled second-order form."""
    f, _ = compiled_second_order(su.eom)
    r = ode(f)
    r.set_integrator("dop853", rtol=rtol, atol=rtol, nsteps=10**9)
    r.set_initial_value(_s0_second_order(su), 0.0)
    nd = su.eom.n_dof
    z = np.empty((su.t_out.size, nd))
    z[0] = r.y[:nd]
    for i, t in enumerate(su.t_out[1:], 1):
        r.integrate(t)
        if not r.successful():
            raise RuntimeError(f"reference dop853 failed at t = {r.t}")
        z[i] = r.y[:nd]
    return z


def ref_radau(su: Setup, rtol: float):
    """scipy's Radau IIA with the analytic Jacobian on the numba-compiled second-order form."""
    f, jac = compiled_second_order(su.eom)
    nd = su.eom.n_dof
    sol = solve_ivp(f, (0.0, su.t_out[-1]), _s0_second_order(su), method="Radau", jac=jac, t_eval=su.t_out,
                    rtol=rtol, atol=rtol * 1e-2)
    if not sol.success:
        raise RuntimeError(f"reference Radau failed: {sol.message}")
    return sol.y[:nd].T


def ref_cablesim(su: Setup, integ):
    h = simulate(su.eom, integ, su.duration, su.scene.output_step, s0=su.s0, split=False)
    if h.status != "completed":
        raise RuntimeError(f"reference {integ} did not complete: {h.status}")
    return h.z


def reference_plan(su: Setup):
    """(label, function) of the reference and of its checks."""
    kind = su.scene.reference
    if kind == "dop853":
        return ("scipy ode DOP853 rtol=1e-12 (numba 2nd order)", lambda: ref_dop853(su, 1e-12)), [
            ("scipy ode DOP853 rtol=1e-10", lambda: ref_dop853(su, 1e-10))]
    if kind == "radau":
        return ("scipy Radau rtol=1e-8 + analytic Jacobian (numba 2nd order)", lambda: ref_radau(su, 1e-8)), [
            ("scipy Radau rtol=1e-7", lambda: ref_radau(su, 1e-7)),
            ("scipy ode DOP853 rtol=1e-12", lambda: ref_dop853(su, 1e-12))]
    return ("cablesim DOPRI5 rtol=1e-12", lambda: ref_cablesim(su, DOPRI5(rtol=1e-12, atol=1e-14 * su.chord))), [
        ("cablesim RK4 dt=1e-3", lambda: ref_cablesim(su, RK4(dt=1e-3)))]


def _key(su: Setup, label: str) -> str:
    """Scene, reference settings and the numbers of the problem itself (not the duration)."""
    sc, e = su.scene, su.eom
    h = hashlib.sha1(json.dumps(dict(number=sc.number, analysis=sc.analysis, output_step=sc.output_step,
                                     label=label, version=2), sort_keys=True).encode())
    for a in (e.cable.S, e.cable.EA, e.cable.L, e.cable.H, e.mass, e.C, e.F0, e.FL, e.omega, e.y0, su.s0):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()[:10]


def cached(su: Setup, label: str, fn):
    """A reference from the cache (sliced from a run at least as long) or computed and stored."""
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / f"reference-scene{su.scene.number}-{_key(su, label)}.npz"
    n = su.t_out.size
    if path.exists():
        ref = np.load(path)
        if ref["z"].shape[0] >= n and np.allclose(ref["t"][:n], su.t_out):
            return ref["z"][:n], float(ref["wall"]), True
    t0 = time.perf_counter()
    z = fn()
    wall = time.perf_counter() - t0
    np.savez(path, t=su.t_out, z=z, wall=wall, label=label)
    return z, wall, False


# ---------------------------------------------------------------------------------------------
# Measurements
# ---------------------------------------------------------------------------------------------
def errors(su: Setup, z, zref):
    """(whole-run error, early-window error); inf when the run did not reach the end."""
    scale = np.abs(zref).max()
    if z.shape[0] < zref.shape[0] or not np.all(np.isfinite(z)):
        err = math.inf
    else:
        err = float(np.abs(z - zref).max() / scale)
    early = None
    if su.scene.early is not None:
        k = int(np.searchsorted(su.t_out, su.scene.early, side="right"))
        early = float(np.abs(z[:k] - zref[:k]).max() / scale) if z.shape[0] >= k and np.all(np.isfinite(z[:k])) else math.inf
    return err, early


def label_of(integ) -> str:
    st = integ.settings()
    if integ.name == "dopri5":
        return f"rtol={st['rtol']:.0e}"
    if integ.name == "generalized-alpha":
        return f"dt={st['dt']:.4g}, rho_inf={st['rho_inf']:g}"
    return f"dt={st['dt']:.4g}"


@dataclass
class Point:
    scene: int
    method: str
    setting: str
    wall_s: float
    n_runs: int
    error: float
    error_early: float | None
    status: str
    is_default: bool = False
    is_recommended: bool = False
    integ: object = field(default=None, repr=False)
    times: list = field(default_factory=list, repr=False)

    def row(self):
        return dict(scene=self.scene, method=self.method, setting=self.setting, wall_s=f"{self.wall_s:.6g}",
                    n_runs=self.n_runs, error=f"{self.error:.4g}",
                    error_early="" if self.error_early is None else f"{self.error_early:.4g}",
                    default=int(self.is_default), recommended=int(self.is_recommended), status=self.status)


def run_cablesim(su: Setup, integ):
    t0 = time.perf_counter()
    h = simulate(su.eom, integ, su.duration, su.scene.output_step, s0=su.s0, split=False)
    return time.perf_counter() - t0, h


def key_error(su: Setup, p: Point) -> float:
    """The error the scene judges by: before the jump in scene 2, the whole run elsewhere."""
    return p.error_early if su.scene.early is not None else p.error


def ladders(su: Setup, quick: bool):
    """Settings per scheme. rk4: dt from just inside its stability limit 2.8 / |lambda|_max down by
    sqrt(2); dopri5: fixed rtols with atol = 1e-2 rtol x chord (the default's ratio); newmark and
    generalized-alpha: from 25 steps per period of interest down by 2. Fixed-step ladders stop once
    a setting costs more than 10x the cheapest run that reached 1e-4 so far, errs below 1e-8 (rk4)
    or 1e-6 (second-order schemes), or stops improving (error not halved by the last refinement:
    a floor such as the third-order formulation's drift)."""
    dt_lim = 2.8 / su.lam_max
    n_fixed = 3 if quick else 9
    rk4 = [RK4(dt=0.95 * dt_lim * 2 ** (-k / 2)) for k in range(n_fixed + 2)]
    rtols = su.scene.dopri5_rtols[1:6:2] if quick else su.scene.dopri5_rtols
    dopri = [DOPRI5(rtol=r, atol=1e-2 * r * su.chord) for r in rtols]
    dt0 = 2 * math.pi / su.w_interest / 25
    nm = [Newmark(dt=dt0 * 2.0 ** -k) for k in range(n_fixed)]
    ga = [GeneralizedAlpha(dt=dt0 * 2.0 ** -k, rho_inf=0.8) for k in range(n_fixed)]
    return {"rk4": (rk4, 1e-8), "dopri5": (dopri, 0.0), "newmark": (nm, 1e-6), "generalized-alpha": (ga, 1e-6)}


def recommended(su: Setup):
    """The recommended default of the scene when it differs from today's (else None)."""
    n = su.scene.recommended_steps
    if n is None:
        return None
    def divisor(dt):  # make_integrator's rounding: a step that divides the forcing period
        if su.scene.omega <= 0:
            return dt
        period = 2 * math.pi / su.scene.omega
        return period / np.ceil(period / dt - 1e-9)

    return GeneralizedAlpha(dt=divisor(divisor(2 * np.pi / su.w_interest / 100) * 100 / n), rho_inf=0.8)


def measure_cablesim(su: Setup, zref, quick: bool, repeats: int):
    sc = su.scene
    # Warm-up: one short run of each scheme compiles (or loads) its kernels.
    short = min(su.duration, 40 * sc.output_step)
    for integ in (RK4(dt=0.5 * 2.8 / su.lam_max), DOPRI5(rtol=1e-6, atol=1e-8), Newmark(dt=0.01),
                  GeneralizedAlpha(dt=0.01, rho_inf=0.8)):
        simulate(su.eom, integ, short, sc.output_step, s0=su.s0, split=False)
    points: list[Point] = []
    best = math.inf  # cheapest first-pass run that reached 1e-4

    def first_pass(integ, name):
        nonlocal best
        wall, h = run_cablesim(su, integ)
        err, early = errors(su, h.z, zref)
        p = Point(sc.number, name, label_of(integ), wall, 1, err, early, h.status, integ=integ, times=[wall])
        points.append(p)
        if key_error(su, p) < 1e-4:
            best = min(best, wall)
        print(f"  {name:18s} {p.setting:26s} first run {wall:8.3f} s  error {err:9.2e}"
              + ("" if early is None else f"  (first {sc.early:g} s: {early:9.2e})")
              + ("" if h.status == "completed" else f"  [{h.status[:70]}]"), flush=True)
        return p

    default_label = (su.default.name, label_of(su.default))
    for name, (ladder, floor) in ladders(su, quick).items():
        prev = math.inf
        for k, integ in enumerate(ladder):
            p = first_pass(integ, name)
            e = key_error(su, p)
            if integ.fixed_step and k >= 2 and (e < floor or p.wall_s > 10 * best or e > 0.5 * prev):
                break
            prev = e
    if not any((p.method, p.setting) == default_label for p in points):
        first_pass(su.default, su.default.name)
    rec = recommended(su)
    rec_label = (rec.name, label_of(rec)) if rec is not None else default_label
    if not any((p.method, p.setting) == rec_label for p in points):
        first_pass(rec, rec.name)
    for p in points:
        p.is_default = (p.method, p.setting) == default_label
        p.is_recommended = (p.method, p.setting) == rec_label
    # Further runs, round-robin over the settings (short runs get a few more).
    for rep in range(repeats - 1 + 4):
        for p in points:
            if rep >= repeats - 1 and p.wall_s > 0.05:
                continue
            p.times.append(run_cablesim(su, p.integ)[0])
    for p in points:
        p.wall_s = float(np.median(p.times))
        p.n_runs = len(p.times)
    return points


def measure_scipy(su: Setup, zref, quick: bool, repeats: int):
    sc = su.scene
    nd = su.eom.n_dof
    if sc.analysis == "approximate":
        f, jac, y0, label = python_third_order_approximate(su.eom), None, su.s0, "Python rhs, 3rd order"
    else:
        f, jac = python_second_order(su.eom)
        y0, label = _s0_second_order(su), "Python rhs"
    points = []
    for method, rtol in ((sc.scipy[1:2] or sc.scipy[:1]) if quick else sc.scipy):
        kw = dict(jac=jac) if method in ("Radau", "BDF") else {}
        atol = 1e-2 * rtol * su.chord
        if sc.analysis == "approximate":  # same scaling of velocity/acceleration as cablesim's DOPRI5
            w1 = float(su.static.modes.omega[0])
            atol = np.concatenate([np.full(nd, atol), np.full(nd, atol * w1), np.full(nd, atol * w1 ** 2)])
        times = []
        while True:
            t0 = time.perf_counter()
            sol = solve_ivp(f, (0.0, su.t_out[-1]), y0, method=method, t_eval=su.t_out, rtol=rtol, atol=atol, **kw)
            times.append(time.perf_counter() - t0)
            if times[0] > 5.0 or len(times) >= repeats:
                break
        err, early = errors(su, sol.y[:nd].T, zref)
        p = Point(sc.number, f"scipy {method} ({label})", f"rtol={rtol:.0e}", float(np.median(times)),
                  len(times), err, early, "completed" if sol.success else sol.message)
        points.append(p)
        print(f"  {p.method:30s} {p.setting:14s} wall {p.wall_s:8.3f} s ({len(times)} run{'s' * (len(times) > 1)}, "
              f"nfev {sol.nfev})  error {err:9.2e}" + ("" if early is None else f"  (first {sc.early:g} s: {early:9.2e})"),
              flush=True)
    return points


# ---------------------------------------------------------------------------------------------
# Summary, CSV, plots
# ---------------------------------------------------------------------------------------------
def cheapest(points, thr, su):
    ok = [p for p in points if key_error(su, p) < thr]
    return min(ok, key=lambda p: p.wall_s) if ok else None


def summarise(su: Setup, points, ref_rows, lines):
    sc = su.scene
    start = len(lines)
    cs = [p for p in points if not p.method.startswith("scipy")]
    sp = [p for p in points if p.method.startswith("scipy")]
    by = "error over the first %g s" % sc.early if sc.early is not None else "error"
    lines.append(f"\n### Scene {sc.number}: {sc.title}\n")
    lines.append(f"Reference: {ref_rows[0].setting}; " + "; ".join(
        f"check {r.setting}: difference {r.error:.1e}" + ("" if r.error_early is None else f" (first {sc.early:g} s: {r.error_early:.1e})")
        for r in ref_rows[1:]) + f". Largest |eigenvalue| {su.lam_max:.4g} 1/s (rk4 limit 2.8/|lambda| = {2.8 / su.lam_max:.3g} s).\n")
    if su.note:
        lines.append(su.note)
    lines.append(f"Cheapest setting per scheme with {by} below the threshold (median wall time):\n")
    lines.append("| threshold | scheme | setting | wall (s) | error | " + ("error whole run | " if sc.early else "") + "runs |")
    lines.append("|---|---|---|---|---|" + ("---|" if sc.early else "") + "---|")
    for thr in THRESHOLDS:
        for m in list(dict.fromkeys(p.method for p in points)):
            b = cheapest([p for p in points if p.method == m], thr, su)
            if b is None:
                lines.append(f"| {thr:.0e} | {m} | none reached it | | | " + ("| " if sc.early else "") + "|")
            else:
                lines.append(f"| {thr:.0e} | {m} | {b.setting} | {b.wall_s:.3g} | {key_error(su, b):.1e} | "
                             + (f"{b.error:.1e} | " if sc.early else "") + f"{b.n_runs} |")
    lines.append("")
    for thr in THRESHOLDS:
        b, s = cheapest(cs, thr, su), cheapest(sp, thr, su)
        if b is None:
            lines.append(f"- {by} < {thr:.0e}: no cablesim setting tried reached it.")
            continue
        txt = f"- {by} < {thr:.0e}: best cablesim **{b.method} {b.setting}**, {b.wall_s:.3g} s"
        if s is not None:
            txt += f"; scipy baseline {s.method} {s.setting}, {s.wall_s:.3g} s: ratio scipy/cablesim = **{s.wall_s / b.wall_s:.0f}**"
        else:
            close = min(sp, key=lambda p: abs(math.log10(max(key_error(su, p), 1e-300) / thr))) if sp else None
            txt += "; no scipy setting tried reached it" + (
                f" (closest: {close.method} {close.setting}, {close.wall_s:.3g} s, error {key_error(su, close):.1e})" if close else "")
        lines.append(txt + ".")
    lines.append(f"- each scipy run against the cheapest cablesim run at least as accurate ({by}):")
    for q in sp:
        e = key_error(su, q)
        b = min((p for p in cs if key_error(su, p) <= e), key=lambda p: p.wall_s, default=None)
        lines.append(f"  - {q.method} {q.setting}: {q.wall_s:.3g} s, error {e:.1e}; "
                     + ("no cablesim run that accurate" if b is None else
                        f"{b.method} {b.setting}: {b.wall_s:.3g} s, error {key_error(su, b):.1e}: ratio **{q.wall_s / b.wall_s:.0f}**"))
    d = [p for p in cs if p.is_default]
    if d:
        d = d[0]
        b4 = cheapest(cs, 1e-4, su)
        ed = key_error(su, d)
        lines.append(f"- default today (make_integrator): {d.method} {d.setting}: {d.wall_s:.3g} s, {by} {ed:.1e}"
                     + (f", whole run {d.error:.1e}" if sc.early else "")
                     + ("" if b4 is None else f" ({d.wall_s / b4.wall_s:.1f}x the cost of the cheapest run below 1e-4)"
                        if ed < 1e-4 else " (above 1e-4)") + ".")
    r = [p for p in cs if p.is_recommended and not p.is_default]
    if r:
        r = r[0]
        lines.append(f"- recommended default (README): {r.method} {r.setting}: {r.wall_s:.3g} s, {by} {key_error(su, r):.1e}"
                     + (f" ({r.wall_s / d.wall_s:.1f}x today's default)" if d else "") + ".")
    print("\n".join(lines[start:]), flush=True)


def plot(su: Setup, points, ref_rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sc = su.scene
    panels = [("early", f"first {sc.early:g} s (before the jump)"), ("whole", f"whole run ({su.duration:g} s)")] \
        if sc.early is not None else [("whole", None)]
    fig, axes = plt.subplots(1, len(panels), figsize=(8 * len(panels), 5.5), squeeze=False)
    for ax, (which, sub) in zip(axes[0], panels):
        def e(p):
            return p.error_early if which == "early" else p.error

        for k, m in enumerate(dict.fromkeys(p.method for p in points)):
            rs = sorted((p for p in points if p.method == m and np.isfinite(e(p)) and e(p) > 0), key=e)
            if not rs:
                continue
            style = "s--" if m.startswith("scipy") else "o-"
            ax.loglog([e(p) for p in rs], [p.wall_s for p in rs], style, label=m, color=f"C{k}")
            for p in rs:
                if p.is_default:
                    ax.plot(e(p), p.wall_s, "*", ms=16, mfc="none", mec="k", label="default today")
                if p.is_recommended and not p.is_default:
                    ax.plot(e(p), p.wall_s, "D", ms=11, mfc="none", mec="k", label="recommended default")
        ax.axvline(1e-4, color="0.5", ls=":", label="error 1e-4")
        # The reference's accuracy: its smallest difference from a check (a looser check differs
        # by about its own error, a tighter or independent one by about the reference's).
        ref_err = min((r.error_early if which == "early" else r.error) for r in ref_rows[1:])
        if np.isfinite(ref_err) and ref_err > 0:
            lo, hi = ax.get_xlim()
            lo = min(lo, ref_err / 3)
            ax.axvspan(1e-30, ref_err, color="0.85", alpha=0.6, label=f"not resolved: reference check {ref_err:.0e}")
            ax.set_xlim(lo, hi)
        ax.set_xlabel("max |z - z_ref| / max |z_ref|" + (f", {sub}" if sub else ""))
        ax.set_ylabel("wall time (s), median")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"Scene {sc.number}: {sc.title}\n(duration {su.duration:g} s)", fontsize=10)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def write_csv(path: Path, rows, scenes_run):
    old = []
    if path.exists():
        with open(path, newline="") as fh:
            old = [r for r in csv.DictReader(fh) if (r.get("scene") or "").isdigit() and int(r["scene"]) not in scenes_run]
    rows = old + rows
    rows.sort(key=lambda r: int(r["scene"]))
    fields = ["scene", "method", "setting", "wall_s", "n_runs", "error", "error_early", "default", "recommended", "status"]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


# ---------------------------------------------------------------------------------------------
def prepare(sc: Scene, quick: bool):
    """Set-up, reference (computed or cached) and its checks."""
    duration = sc.quick_duration if quick else sc.duration
    su = setup(sc, duration)
    print(f"\n=== Scene {sc.number}: {sc.title}" + (f" [quick: {duration:g} s]" if quick else ""), flush=True)
    print(f"  default today: {su.default}; |lambda|_max = {su.lam_max:.4g} 1/s", flush=True)
    if sc.analysis == "exact":
        check_formulations(su)
    (rlabel, rfn), checks = reference_plan(su)
    zref, rwall, hit = cached(su, rlabel, rfn)
    print(f"  reference {rlabel}: {'cached' if hit else 'computed'} ({rwall:.1f} s); max |z| = {np.abs(zref).max():.4g} m",
          flush=True)
    if sc.early is not None:
        k = int(np.searchsorted(su.t_out, sc.early, side="right"))
        amp = np.abs(zref).max(axis=1)
        big = np.nonzero(amp > 3 * amp[:k].max())[0]
        su.note = (f"The reference's max |z| is {amp[:k].max():.3g} m over the first {sc.early:g} s and {amp.max():.3g} m "
                   "over the whole run; it first exceeds 3x the early maximum at t = "
                   + (f"{su.t_out[big[0]]:.0f} s (the jump).\n" if big.size else "- never (no jump in this run).\n"))
        print("  " + su.note.strip(), flush=True)
    ref_rows = [Point(sc.number, "reference", rlabel, rwall, 1, 0.0, 0.0 if sc.early else None, "")]
    for clabel, cfn in checks:
        zc, cwall, hit = cached(su, clabel, cfn)
        err, early = errors(su, zc, zref)
        ref_rows.append(Point(sc.number, "reference-check", clabel, cwall, 1, err, early, "cached" if hit else "computed"))
        print(f"  reference check {clabel}: difference {err:.2e}" + ("" if early is None else f" (first {sc.early:g} s: {early:.2e})"),
              flush=True)
    return su, zref, ref_rows


def point_of(r) -> Point:
    return Point(int(r["scene"]), r["method"], r["setting"], float(r["wall_s"]), int(r["n_runs"]), float(r["error"]),
                 float(r["error_early"]) if r["error_early"] else None, r["status"], is_default=r["default"] == "1",
                 is_recommended=r.get("recommended") == "1" or (r["default"] == "1" and SCENES[int(r["scene"])].recommended_steps is None))


def report(out: Path, quick: bool):
    """summary.md and the PNGs of every scene in dynamics.csv (also those not rerun now)."""
    with open(out / "dynamics.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    lines = []
    print("\n" + "=" * 100 + "\nSummary" + (" (quick)" if quick else ""))
    for n in sorted({int(r["scene"]) for r in rows}):
        pts = [point_of(r) for r in rows if int(r["scene"]) == n]
        ref_rows = [p for p in pts if p.method.startswith("reference")]
        if SCENES[n].early is not None:  # the note on the jump needs the (cached) reference
            with contextlib.redirect_stdout(io.StringIO()):
                su, _, _ = prepare(SCENES[n], quick)
        else:
            su = setup(SCENES[n], SCENES[n].quick_duration if quick else SCENES[n].duration)
        points = [p for p in pts if not p.method.startswith("reference")]
        summarise(su, points, ref_rows, lines)
        plot(su, points, ref_rows, out / f"work-precision-scene{n}.png")
    stamp = time.strftime("%Y-%m-%d %H:%M", time.localtime((out / "dynamics.csv").stat().st_mtime))
    (out / "summary.md").write_text(HEADER.format(stamp=stamp, cores=os.cpu_count()) + "\n".join(lines) + "\n")


HEADER = """# Work-precision of cablesim's integrators (generated by benchmarks/bench_dynamics.py)

Measured {stamp} on {cores} cores (shared with other jobs). Wall times are medians of
in-process runs; error = max over saved instants and DOF of |z - z_ref| / max |z_ref|.
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=int, action="append", choices=sorted(SCENES), help="scene number (repeatable; default all)")
    ap.add_argument("--quick", action="store_true", help="shorter durations, fewer settings (into runs/bench/quick/)")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per setting (median)")
    ap.add_argument("--report-only", action="store_true", help="redraw summary.md and the PNGs from dynamics.csv")
    args = ap.parse_args(argv)
    scenes = args.scene or sorted(SCENES)
    out = OUT / "quick" if args.quick else OUT
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if not args.report_only:
        rows = []
        for n in scenes:
            su, zref, ref_rows = prepare(SCENES[n], args.quick)
            points = measure_cablesim(su, zref, args.quick, args.repeats)
            points += measure_scipy(su, zref, args.quick, args.repeats)
            rows += [p.row() for p in ref_rows + points]
            write_csv(out / "dynamics.csv", rows, set(scenes))
    report(out, args.quick)
    print(f"\nwrote {out / 'dynamics.csv'}, {out / 'summary.md'} and work-precision-scene<N>.png "
          f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
