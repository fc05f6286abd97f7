"""Periodic orbits, multipliers and bifurcations of small systems with independent answers.

The vector fields are written here; every reference is computed here without the code under
test:

0. The continuation algorithm on its own, on an algebraic S-curve ``u^3 - u = lam`` whose folds
   (``lam = -/+ 2 / (3 sqrt 3)``) are known in closed form.
1. Duffing oscillator ``x'' + 2 zeta x' + x + alpha x^3 = F cos(w t)``: its two folds from a
   high-order harmonic balance (21 odd harmonics, the fold found from the Moore-Spence extended
   system, started from the one-harmonic backbone); a stable orbit returns to itself and an
   unstable one (middle branch) leaves at the rate of its largest multiplier under scipy's DOP853;
   the multipliers agree with a finite-difference monodromy from DOP853.
2. Forced Hopf normal form ``z' = (lam + i w0) z - (1 + i b)|z|^2 z + F e^{i w t}``: in the frame
   rotating with the forcing its periodic orbits are equilibria, so the Floquet multipliers are
   ``exp(T eig(J_rot))`` in closed form, the Neimark-Sacker point is where ``tr J_rot = 0``
   (``|z|^2 = lam/2``, closed form) and the folds where ``det J_rot = 0`` (brentq). The same
   ``tr J_rot = 0`` condition also holds at a neutral saddle (``det J_rot < 0``), which must not be
   reported as a Neimark-Sacker bifurcation.
3. Parametrically excited (Mathieu-Duffing) oscillator
   ``x'' + c x' + (1 + eps cos(w t)) x + alpha x^3 = 0``: the trivial orbit loses stability by
   period doubling at the edges of the principal instability tongue, located here with scipy's
   DOP853 monodromy of the linear Mathieu equation and brentq; the period-2 branch started there
   consists of genuine period-2 orbits (DOP853 returns them to themselves over two forcing
   periods).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar, root

from cablesim.orbits import OdeSystem, Settings, Shooting, Status, continuation, trace_branches

RTOL = dict(rtol=1e-12, atol=1e-13, method="DOP853")


# ----------------------------------------------------------------------------------------------
# 0. The continuation algorithm alone, on an algebraic problem
# ----------------------------------------------------------------------------------------------
class SCurve:
    """``r(u, lam) = u^3 - u - lam`` (two components, decoupled copies scaled by 1 and 2), with
    a test function ``u`` (zero crossing at the middle of the S)."""

    u_scale = np.array([1.0, 2.0])
    lam_scale = 1.0
    test_names = ("u-zero",)

    def evaluate(self, u, lam):
        v = u / self.u_scale
        ev = SimpleNamespace(u=u)
        ev.r = (v**3 - v - lam) * self.u_scale
        ev.J_u = np.diag(3 * v**2 - 1)
        ev.J_lam = -self.u_scale
        return ev

    def test_functions(self, ev):
        return np.array([ev.u[0]])


def test_continuation_algorithm_on_s_curve():
    seen = []
    br = continuation(SCurve(), np.array([-1.2, -2.4]), -0.528, Settings(lam_min=-1.0, lam_max=1.0, ds_max=0.1),
                      callback=lambda p: seen.append(p) and False)
    assert br.status == Status.BOUND_REACHED
    assert seen == br.points and br.points[-1].lam == 1.0
    folds = [p for p in br.points if p.special == "fold"]
    zero = [p for p in br.points if p.special == "u-zero"]
    ref = 2 / (3 * np.sqrt(3))
    assert [round(p.lam, 12) for p in folds] == [round(ref, 12), round(-ref, 12)]
    assert abs(abs(folds[0].u[0]) - 1 / np.sqrt(3)) < 1e-6  # lam is quadratic in u at a fold
    assert len(zero) == 1 and abs(zero[0].u[0]) < 1e-9 and abs(zero[0].lam) < 1e-9
    for p in br.points:
        v = p.u / SCurve.u_scale
        assert np.abs(v**3 - v - p.lam).max() < 1e-9


# ----------------------------------------------------------------------------------------------
# 1. Duffing
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def duffing_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    zeta, alpha, F = prm[0], prm[1], prm[2]
    dx[0] = x[1]
    dx[1] = F * np.cos(theta) - 2.0 * zeta * x[1] - x[0] - alpha * x[0] ** 3
    J[0, 0] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = -1.0 - 3.0 * alpha * x[0] ** 2
    J[1, 1] = -2.0 * zeta
    if ipar == 2:
        dp[0] = 0.0
        dp[1] = np.cos(theta)
    return 0


ZETA, ALPHA, FORCE = 0.05, 0.2, 0.3


def duffing_system(omega=0.5):
    return OdeSystem(field=duffing_field, dim=2, prm=np.array([ZETA, ALPHA, FORCE]), work=np.zeros(1), omega=omega,
                     parameters={"F": 2}, fastest_rate=3.0, displacements=np.array([0]), divergence=-2.0 * ZETA)


def duffing_rhs(t, y, w):
    return [y[1], FORCE * np.cos(w * t) - 2 * ZETA * y[1] - y[0] - ALPHA * y[0] ** 3]


class HarmonicBalance:
    """Galerkin harmonic balance of the Duffing oscillator on odd harmonics 1, 3, ..., H."""

    def __init__(self, H=41, N=512):
        self.k = np.arange(1, H + 1, 2)
        self.K = self.k.size
        th = 2 * np.pi * np.arange(N) / N
        self.E = np.hstack([np.cos(np.outer(th, self.k)), np.sin(np.outer(th, self.k))])
        self.P = 2.0 / N * self.E.T

    def linear(self, w):
        K, k = self.K, self.k
        L = np.zeros((2 * K, 2 * K))
        i = np.arange(K)
        L[i, i] = L[K + i, K + i] = 1 - k**2 * w**2
        L[i, K + i] = 2 * ZETA * w * k
        L[K + i, i] = -2 * ZETA * w * k
        return L

    def residual(self, c, w):
        x = self.E @ c
        R = self.linear(w) @ c + self.P @ (ALPHA * x**3)
        R[0] -= FORCE
        return R

    def jacobian(self, c, w):
        x = self.E @ c
        return self.linear(w) + self.P @ (3 * ALPHA * x[:, None] ** 2 * self.E)

    def peak(self, c):
        def x(th):
            arg = np.outer(np.atleast_1d(th), self.k)
            return np.cos(arg) @ c[: self.K] + np.sin(arg) @ c[self.K :]

        th = np.linspace(0, 2 * np.pi, 4097)
        i = int(np.argmax(np.abs(x(th))))
        sgn = np.sign(x(th[i])[0])
        best = minimize_scalar(lambda t: -sgn * x(t)[0], bounds=(th[i] - 0.01, th[i] + 0.01), method="bounded",
                               options={"xatol": 1e-12})
        return abs(x(best.x)[0])

    def folds(self):
        """Both folds, started from the one-harmonic backbone's turning points."""
        A = np.linspace(0.05, 6, 200001)
        c0 = 1 + 0.75 * ALPHA * A**2
        disc = (c0 - 2 * ZETA**2) ** 2 - c0**2 + FORCE**2 / A**2
        guesses = []
        for sgn in (1, -1):
            u = (c0 - 2 * ZETA**2) + sgn * np.sqrt(np.maximum(disc, 0))
            w = np.where((disc >= 0) & (u > 0), np.sqrt(np.abs(u)), np.nan)
            dw = np.diff(w)
            for i in np.where(np.sign(dw[1:]) * np.sign(dw[:-1]) < 0)[0] + 1:
                guesses.append((w[i], A[i]))
        K = self.K
        out = []
        for w, a in guesses:
            phi = np.arctan2(2 * ZETA * w, 1 - w**2 + 0.75 * ALPHA * a**2)
            c = np.zeros(2 * K)
            c[0], c[K] = a * np.cos(phi), a * np.sin(phi)
            for _ in range(50):  # Newton at fixed w (the backbone guess is close)
                dc = np.linalg.solve(self.jacobian(c, w), -self.residual(c, w))
                c += dc
                if np.abs(dc).max() < 1e-13:
                    break
            ph0 = np.linalg.svd(self.jacobian(c, w))[2][-1]

            def extended(v):
                cc, ww, ph = v[: 2 * K], v[2 * K], v[2 * K + 1 :]
                return np.concatenate([self.residual(cc, ww), self.jacobian(cc, ww) @ ph, [ph @ ph0 - 1]])

            sol = root(extended, np.concatenate([c, [w], ph0]), method="hybr", options={"xtol": 1e-14})
            assert np.abs(extended(sol.x)).max() < 1e-12
            out.append((sol.x[2 * K], self.peak(sol.x[: 2 * K])))
        return sorted(out)


@pytest.fixture(scope="module")
def duffing_diagram():
    w0 = 0.5
    Z = FORCE / (1 - w0**2 + 2j * ZETA * w0)  # x = Re(Z e^{i w t})
    u0 = np.array([Z.real, -w0 * Z.imag])
    return trace_branches(duffing_system(w0), u0, "omega", 0.5, 3.0, state_scale=np.array([1.0, 1.0]))


def test_duffing_folds_match_harmonic_balance(duffing_diagram):
    folds = sorted((b.parameter, b.amplitude[0]) for b in duffing_diagram.of_kind("fold"))
    ref = HarmonicBalance().folds()
    assert len(folds) == 2 and len(ref) == 2
    for (w, a), (w_ref, a_ref) in zip(folds, ref):
        assert w == pytest.approx(w_ref, rel=1e-9)  # measured 4e-14 and 1e-12
        assert a == pytest.approx(a_ref, rel=1e-5)  # cubic Hermite peak between steps: measured 5e-7, 1.7e-6
    for b in duffing_diagram.of_kind("fold"):
        assert b.located and b.trusted
        assert abs(b.multiplier - 1.0) < 1e-6
    assert not duffing_diagram.of_kind("period-doubling") and not duffing_diagram.of_kind("neimark-sacker")


def test_duffing_branch_stability_and_orbits(duffing_diagram):
    """Between the folds the middle branch is unstable, the others stable; every point is a
    periodic orbit of the independent DOP853 integration."""
    br = duffing_diagram.branches[0]
    lam = br.values
    folds = sorted(b.point for b in duffing_diagram.of_kind("fold"))
    middle = np.zeros(lam.size, bool)
    middle[folds[0] + 1 : folds[1]] = True
    assert np.all(~br.stable[middle]) and np.all(br.stable[~middle & (br.values < 1.15)])
    for p in br.points[:: max(1, len(br.points) // 12)]:
        T = 2 * np.pi / p.omega
        sol = solve_ivp(duffing_rhs, (0, T), p.state, args=(p.omega,), **RTOL)
        assert np.abs(sol.y[:, -1] - p.state).max() < 1e-9 * max(1.0, np.abs(p.state).max())


def fd_monodromy(x0, w, h=1e-6):
    T = 2 * np.pi / w
    M = np.empty((2, 2))
    for j in range(2):
        d = np.zeros(2)
        d[j] = h
        a = solve_ivp(duffing_rhs, (0, T), x0 + d, args=(w,), **RTOL).y[:, -1]
        b = solve_ivp(duffing_rhs, (0, T), x0 - d, args=(w,), **RTOL).y[:, -1]
        M[:, j] = (a - b) / (2 * h)
    return M


def test_duffing_multipliers_and_departure(duffing_diagram):
    br = duffing_diagram.branches[0]
    i_fold = sorted(b.point for b in duffing_diagram.of_kind("fold"))
    stable = min((p for p in br.points if p.stable), key=lambda p: np.abs(p.multipliers).max())
    saddle = br.points[(i_fold[0] + i_fold[1]) // 2]
    for p in (stable, saddle):
        M = fd_monodromy(p.state, p.omega)
        mu_fd = np.sort_complex(np.linalg.eigvals(M))
        assert np.abs(np.sort_complex(p.multipliers) - mu_fd).max() < 1e-7  # measured ~1e-9
        # product of the multipliers = det = exp(-2 zeta T) (Liouville, constant divergence)
        T = 2 * np.pi / p.omega
        assert np.prod(p.multipliers).real == pytest.approx(np.exp(-2 * ZETA * T), rel=1e-9)
    # stable: returns to itself over many periods, and a perturbation decays as |mu|^k
    T = 2 * np.pi / stable.omega
    k = np.arange(1, 41)
    sol = solve_ivp(duffing_rhs, (0, 40 * T), stable.state, args=(stable.omega,), t_eval=k * T, **RTOL)
    assert np.abs(sol.y - stable.state[:, None]).max() < 1e-9
    k = k[:12]
    sol = solve_ivp(duffing_rhs, (0, k[-1] * T), stable.state + 1e-4, args=(stable.omega,), t_eval=k * T, **RTOL)
    dev = np.linalg.norm(sol.y - stable.state[:, None], axis=0)
    mu_max = np.abs(stable.multipliers).max()
    assert np.exp(np.polyfit(k, np.log(dev), 1)[0]) == pytest.approx(mu_max, rel=0.03)
    # unstable: leaves along the unstable eigenvector at the rate of the largest multiplier
    mu = saddle.multipliers[0].real
    assert mu > 1.2
    sh = Shooting(duffing_system(saddle.omega))
    ev = sh.evaluate(saddle.state, saddle.omega)
    vals, vecs = np.linalg.eig(ev.monodromy)
    v = np.real(vecs[:, np.argmax(np.abs(vals))])
    delta = 1e-9
    T = 2 * np.pi / saddle.omega
    k = np.arange(1, 9)
    sol = solve_ivp(duffing_rhs, (0, k[-1] * T), saddle.state + delta * v, args=(saddle.omega,), t_eval=k * T, **RTOL)
    dev = np.linalg.norm(sol.y - saddle.state[:, None], axis=0)
    rate = np.exp(np.polyfit(k[:5], np.log(dev[:5]), 1)[0])
    assert rate == pytest.approx(mu, rel=2e-3)


# ----------------------------------------------------------------------------------------------
# 2. Forced Hopf normal form
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def hopf_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    lam, w0, b, F = prm[0], prm[1], prm[2], prm[3]
    r2 = x[0] * x[0] + x[1] * x[1]
    dx[0] = lam * x[0] - w0 * x[1] - r2 * (x[0] - b * x[1]) + F * np.cos(theta)
    dx[1] = w0 * x[0] + lam * x[1] - r2 * (x[1] + b * x[0]) + F * np.sin(theta)
    J[0, 0] = lam - r2 - 2 * x[0] * (x[0] - b * x[1])
    J[0, 1] = -w0 + b * r2 - 2 * x[1] * (x[0] - b * x[1])
    J[1, 0] = w0 - b * r2 - 2 * x[0] * (x[1] + b * x[0])
    J[1, 1] = lam - r2 - 2 * x[1] * (x[1] + b * x[0])
    if ipar == 3:
        dp[0] = np.cos(theta)
        dp[1] = np.sin(theta)
    return 0


HLAM, HW0, HB, HF = 0.2, 1.0, 1.0, 0.05


def hopf_rotating(s, delta):
    """Trace and determinant of the rotating-frame Jacobian at |w|^2 = s, detuning w0 - w."""
    tr = 2 * (HLAM - 2 * s)
    det = (HLAM - 2 * s) ** 2 + (delta - 2 * HB * s) ** 2 - (1 + HB**2) * s**2
    return tr, det


@pytest.fixture(scope="module")
def hopf_diagram():
    sysm = OdeSystem(field=hopf_field, dim=2, prm=np.array([HLAM, HW0, HB, HF]), work=np.zeros(1), omega=0.4,
                     parameters={"F": 3}, fastest_rate=2.0, displacements=np.array([0, 1]))
    # far from resonance the orbit is nearly the linear response z = F e^{iwt} / (i w - lam - i w0)
    w = 0.4
    z = HF / (1j * w - HLAM - 1j * HW0)
    return trace_branches(sysm, np.array([z.real, z.imag]), "omega", 0.4, 1.4, state_scale=np.array([0.3, 0.3]))


def test_hopf_neimark_sacker_closed_form(hopf_diagram):
    # tr J_rot = 0 at s = lam/2; the response relation gives the detuning
    s = HLAM / 2
    root_ = np.sqrt(2 * HF**2 / HLAM - HLAM**2 / 4)
    candidates = [HB * s + root_, HB * s - root_]
    ns = [d for d in candidates if hopf_rotating(s, d)[1] > 0]
    saddles = [d for d in candidates if hopf_rotating(s, d)[1] < 0]
    assert len(ns) == 1 and len(saddles) == 1
    found = hopf_diagram.of_kind("neimark-sacker")
    assert len(found) == 1, [(b.kind, b.parameter) for b in hopf_diagram.bifurcations]
    assert found[0].parameter == pytest.approx(HW0 - ns[0], rel=1e-9)  # measured 1.3e-11
    assert abs(abs(found[0].multiplier) - 1.0) < 1e-8
    assert found[0].amplitude[0] == pytest.approx(np.sqrt(s), rel=1e-6)
    # the neutral saddle (tr = 0, det < 0) is not reported
    w_saddle = HW0 - saddles[0]
    assert all(abs(b.parameter - w_saddle) > 1e-3 for b in hopf_diagram.bifurcations)


def _hopf_curve_point(s, sign):
    """Detuning of the forced response at |w|^2 = s on one side of the resonance curve."""
    g = HF**2 / s - (HLAM - s) ** 2
    return HB * s + sign * np.sqrt(g)


def test_hopf_folds_and_multipliers(hopf_diagram):
    # folds: det J_rot = 0 along the response curve (parametrised by s), by brentq
    ref = []
    for sign in (1, -1):
        s = np.linspace(1e-3, 0.6, 60001)
        ok = HF**2 / s - (HLAM - s) ** 2 > 0
        s = s[ok]
        det = np.array([hopf_rotating(si, _hopf_curve_point(si, sign))[1] for si in s])
        for i in np.where(np.sign(det[1:]) != np.sign(det[:-1]))[0]:
            sr = brentq(lambda q: hopf_rotating(q, _hopf_curve_point(q, sign))[1], s[i], s[i + 1], xtol=1e-15)
            ref.append(HW0 - _hopf_curve_point(sr, sign))
    found = sorted(b.parameter for b in hopf_diagram.of_kind("fold"))
    assert len(found) == len(ref) == 2
    for w, wr in zip(found, sorted(ref)):
        assert w == pytest.approx(wr, rel=1e-9)
    # multipliers = exp(T eig(J_rot)) at every point, from the orbit's |z|^2
    for p in hopf_diagram.branches[0].points[::7]:
        s = float(p.state @ p.state)
        tr, det = hopf_rotating(s, HW0 - p.omega)
        lam_rot = np.roots([1.0, -tr, det])
        mu_ref = np.sort_complex(np.exp(lam_rot * 2 * np.pi / p.omega))
        assert np.abs(np.sort_complex(p.multipliers) - mu_ref).max() < 2e-8  # measured <= 4.8e-9
        assert p.trusted  # Liouville with a varying divergence (tr J = 2 lam - 4 |z|^2)


# ----------------------------------------------------------------------------------------------
# 3. Mathieu-Duffing: period doubling and branch switching
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def mathieu_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    c, eps, alpha = prm[0], prm[1], prm[2]
    k = 1.0 + eps * np.cos(theta)
    dx[0] = x[1]
    dx[1] = -c * x[1] - k * x[0] - alpha * x[0] ** 3
    J[0, 0] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = -k - 3.0 * alpha * x[0] ** 2
    J[1, 1] = -c
    if ipar >= 0:
        dp[0] = 0.0
        dp[1] = 0.0
    return 0


MC, MEPS, MALPHA = 0.05, 0.4, 1.0


def mathieu_rhs(t, y, w, alpha=MALPHA):
    return [y[1], -MC * y[1] - (1 + MEPS * np.cos(w * t)) * y[0] - alpha * y[0] ** 3]


def mathieu_pd_test(w):
    """det(I + monodromy) of the linear Mathieu equation (DOP853)."""
    T = 2 * np.pi / w
    M = np.column_stack([solve_ivp(mathieu_rhs, (0, T), e, args=(w, 0.0), **RTOL).y[:, -1] for e in np.eye(2)])
    return np.linalg.det(np.eye(2) + M)


@pytest.fixture(scope="module")
def mathieu_diagram():
    sysm = OdeSystem(field=mathieu_field, dim=2, prm=np.array([MC, MEPS, MALPHA]), work=np.zeros(1), omega=1.5,
                     parameters={}, fastest_rate=3.0, displacements=np.array([0]), divergence=-MC)
    return trace_branches(sysm, np.zeros(2), "omega", 1.5, 2.6, state_scale=np.array([0.5, 0.5]))


def test_mathieu_period_doubling_tongue(mathieu_diagram):
    grid = np.linspace(1.5, 2.6, 45)
    vals = [mathieu_pd_test(w) for w in grid]
    ref = [brentq(mathieu_pd_test, grid[i], grid[i + 1], xtol=1e-13)
           for i in range(grid.size - 1) if np.sign(vals[i]) != np.sign(vals[i + 1])]
    pds = sorted(b.parameter for b in mathieu_diagram.of_kind("period-doubling") if b.period == 1)
    assert len(ref) == 2 and len(pds) == 2
    for w, wr in zip(pds, ref):
        assert w == pytest.approx(wr, rel=1e-9)  # measured 4e-12, 1.5e-10
    for b in mathieu_diagram.of_kind("period-doubling"):
        assert abs(b.multiplier + 1.0) < 1e-6 and b.located


def test_mathieu_period_two_branch(mathieu_diagram):
    doubled = [b for b in mathieu_diagram.branches if b.period == 2]
    assert doubled, "no period-2 branch was started"
    for br in doubled:
        assert br.origin is not None and br.origin.kind == "period-doubling"
        pts = [p for p in br.points[1:] if p.amplitude[0] > 1e-3]
        assert len(pts) > 5
        for p in pts[:: max(1, len(pts) // 8)]:
            T2 = 4 * np.pi / p.omega
            sol = solve_ivp(mathieu_rhs, (0, T2), p.state, args=(p.omega,), t_eval=[T2 / 2, T2], **RTOL)
            assert np.abs(sol.y[:, 1] - p.state).max() < 1e-9 * max(1.0, np.abs(p.state).max())
            # a genuine period-2 orbit: after one forcing period it is elsewhere
            assert np.abs(sol.y[:, 0] - p.state).max() > 1e-4
