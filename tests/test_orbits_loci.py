"""Bifurcation curves in two parameters (loci) of small systems, against independent references.

The vector fields are written here, and every reference is computed here without the code under
test:

1. Duffing oscillator ``x'' + 2 zeta x' + x + alpha x^3 = F cos(w t)``, lightly damped
   (``zeta = 2e-6``, so that the nonlinearity at the folds is small): the fold curve in
   ``(w, F)`` and its cusp against the one-harmonic balance in closed form, whose own error is
   measured here against a 21-harmonic balance (Moore-Spence folds, scipy's root);
2. linear Mathieu equation ``x'' + c x' + (1 + eps cos(w t)) x = 0``: the period-doubling curves
   bounding the first instability tongue against ``det(I + monodromy) = 0`` with the monodromy
   from scipy's DOP853 and brentq, and the tongue's tip against the minimum of ``eps`` on that
   set (scipy's root on the two conditions);
3. forced Hopf normal form (as in ``test_orbits_systems.py``): its periodic orbits are equilibria
   in the rotating frame, so the Neimark-Sacker curve (``tr J_rot = 0``), the fold curve
   (``det J_rot = 0``), their meeting point (both zero: the 1:1 resonance that ends the
   Neimark-Sacker curve) and the strong resonances on the curve (``cos(T sqrt(det)) = -1/2, 0``)
   are closed forms;
4. a Duffing oscillator beside an uncoupled parametrically excited oscillator: the fold curve of
   the first crosses the period-doubling boundary of the second (two vertical lines in the
   plane) at fold-flip points, whose forcing is the Duffing fold at that frequency (computed by
   the 21-harmonic balance) and whose frequency the Mathieu boundary (DOP853).
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, root

from cablesim.orbits import OdeSystem, trace_branches
from cablesim.orbits.curves import trace_locus

RTOL = dict(rtol=1e-12, atol=1e-14, method="DOP853")


# ----------------------------------------------------------------------------------------------
# 1. Duffing: fold curve and cusp
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def pair_field(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    zeta, alpha, F, c, k, eps = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5]
    for i in range(4):
        for j in range(4):
            J[i, j] = 0.0
    dx[0] = x[1]
    dx[1] = F * np.cos(theta) - 2.0 * zeta * x[1] - x[0] - alpha * x[0] ** 3
    J[0, 1] = 1.0
    J[1, 0] = -1.0 - 3.0 * alpha * x[0] ** 2
    J[1, 1] = -2.0 * zeta
    kk = k * (1.0 + eps * np.cos(theta))
    dx[2] = x[3]
    dx[3] = -c * x[3] - kk * x[2]
    J[2, 3] = 1.0
    J[3, 2] = -kk
    J[3, 3] = -c
    if ipar >= 0:
        for i in range(4):
            dp[i] = 0.0
        if ipar == 2:
            dp[1] = np.cos(theta)
        elif ipar == 5:
            dp[3] = -k * np.cos(theta) * x[2]
    return 0


def pair_system(zeta, alpha, F, c, k, eps, omega, parameters):
    """Duffing oscillator x beside an uncoupled parametric oscillator y (one compiled field for
    every system of this module but the Hopf form: each new field costs a compilation)."""
    return OdeSystem(field=pair_field, dim=4, prm=np.array([zeta, alpha, F, c, k, eps]), work=np.zeros(1),
                     omega=omega, parameters=parameters, fastest_rate=3.0, displacements=np.array([0, 2]))


ZETA, ALPHA = 2e-6, 1.0
KAPPA = 0.75 * ALPHA  # the one-harmonic cubic coefficient


def hb1_cusp():
    """Cusp of the one-harmonic fold curve: the discriminant of its amplitude equation vanishes."""
    w = np.sqrt(3) * ZETA + np.sqrt(3 * ZETA**2 + 1)
    D = 1 - w**2
    u = -2 * D / (3 * KAPPA)
    return w, np.sqrt(((D + KAPPA * u) ** 2 + 4 * ZETA**2 * w**2) * u)


def hb1_fold_force(w, sign):
    """Forcing of the one-harmonic fold at frequency w (``sign``: the two branches).

    ``H = ((1 - w^2 + k A^2)^2 + 4 zeta^2 w^2) A^2 - F^2 = 0`` with ``dH/d(A^2) = 0``."""
    D = 1 - w**2
    u = (-2 * D + sign * np.sqrt(D**2 - 12 * ZETA**2 * w**2)) / (3 * KAPPA)
    return np.sqrt(((D + KAPPA * u) ** 2 + 4 * ZETA**2 * w**2) * u)


class HarmonicBalance:
    """Galerkin harmonic balance of the Duffing oscillator on odd harmonics 1, 3, ..., H."""

    def __init__(self, zeta=ZETA, alpha=ALPHA, H=41, N=512):
        self.zeta, self.alpha = zeta, alpha
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
        L[i, K + i] = 2 * self.zeta * w * k
        L[K + i, i] = -2 * self.zeta * w * k
        return L

    def residual(self, c, w, F):
        R = self.linear(w) @ c + self.P @ (self.alpha * (self.E @ c) ** 3)
        R[0] -= F
        return R

    def jacobian(self, c, w):
        x = self.E @ c
        return self.linear(w) + self.P @ (3 * self.alpha * x[:, None] ** 2 * self.E)

    def fold(self, w_guess, a_guess, F):
        """The fold (w, first-harmonic amplitude) at forcing F near the guesses: Moore-Spence."""
        K = self.K
        phi = np.arctan2(2 * self.zeta * w_guess, 1 - w_guess**2 + 0.75 * self.alpha * a_guess**2)
        c = np.zeros(2 * K)
        c[0], c[K] = a_guess * np.cos(phi), a_guess * np.sin(phi)
        for _ in range(60):
            dc = np.linalg.solve(self.jacobian(c, w_guess), -self.residual(c, w_guess, F))
            c += dc
            if np.abs(dc).max() < 1e-15:
                break
        ph0 = np.linalg.svd(self.jacobian(c, w_guess))[2][-1]

        def extended(v):
            cc, ww, ph = v[: 2 * K], v[2 * K], v[2 * K + 1 :]
            return np.concatenate([self.residual(cc, ww, F), self.jacobian(cc, ww) @ ph, [ph @ ph0 - 1]])

        sol = root(extended, np.concatenate([c, [w_guess], ph0]), method="hybr", options={"xtol": 1e-15})
        assert np.abs(extended(sol.x)).max() < 1e-13
        return sol.x[2 * K]


def duffing_system(F, zeta=ZETA, alpha=ALPHA, omega=0.95):
    """The Duffing oscillator (y strongly damped and at rest: its multipliers stay near 0)."""
    return pair_system(zeta, alpha, F, 1.0, 0.25, 0.0, omega, {"F": 2})


@pytest.fixture(scope="module")
def duffing_locus():
    """The fold curve of the Duffing oscillator, started from a fold of the response at F = 4 F_c."""
    w_c, F_c = hb1_cusp()
    F = 4 * F_c
    A = 3 * np.sqrt(-2 * (1 - w_c**2) / (3 * KAPPA))
    w0 = 0.95
    Z = F / (1 - w0**2 + 2j * ZETA * w0)
    d = trace_branches(duffing_system(F), np.array([Z.real, -w0 * Z.imag, 0.0, 0.0]), "omega", w0, 1.2,
                       state_scale=np.array([A, A, A, A]), switch_branches=False)
    folds = d.of_kind("fold")
    assert len(folds) == 2
    b = folds[0]
    p = d.branches[b.branch].points[b.point]
    levels = (1.5 * F_c, 2.0 * F_c, 3.0 * F_c, F)
    loc = trace_locus(duffing_system(F), "fold", p.u, p.parameter, F, (w0, 1.2), (0.5 * F_c, 5 * F_c),
                      parameters=("omega", "F"), state_scale=np.array([A, A, A, A]), levels=levels)
    return loc, folds, (w_c, F_c)


def test_duffing_fold_curve_against_harmonic_balance(duffing_locus):
    """Away from the cusp the fold curve is the one-harmonic closed form: the forcing at the
    curve's frequency to 1e-6 up to twice the cusp's forcing (HB's own error there: below)."""
    loc, _, (w_c, F_c) = duffing_locus
    assert loc.ends == ("reached the bound of F", "reached the bound of F")
    i_cusp = [p.index for p in loc.points if p.special == "cusp"]
    assert len(i_cusp) == 1
    worst = 0.0
    for p in loc.points:
        if not 1.05 * F_c < p.p2 < 2.0 * F_c:
            continue
        # the two sides of the cusp are the two branches of the closed form
        ref = min((hb1_fold_force(p.p1, s) for s in (1, -1)), key=lambda f: abs(f - p.p2))
        worst = max(worst, abs(p.p2 - ref) / ref)
        assert p.trusted and p.special != "turning point"
    assert 0 < worst < 1e-6  # measured 5.0e-7: the one-harmonic truncation (3.2e-6 at 5 F_c; last test)


def test_duffing_cusp_against_harmonic_balance(duffing_locus):
    loc, _, (w_c, F_c) = duffing_locus
    (cusp,) = [p for p in loc.points if p.special == "cusp"]
    assert cusp.located
    assert cusp.p1 == pytest.approx(w_c, rel=1e-9)  # measured 4.5e-13
    assert cusp.p2 == pytest.approx(F_c, rel=1e-6)  # measured 1.9e-7: the HB truncation (last test)
    # at the cusp both fold branches meet: the forcing is the least on the curve
    assert cusp.p2 <= loc.values("p2").min() * (1 + 1e-9)
    assert abs(cusp.multipliers - 1.0).min() < 1e-7


@pytest.mark.slow
def test_duffing_fold_curve_against_many_harmonics(duffing_locus):
    """At the located crossings of given forcings the curve agrees with a 21-harmonic balance
    (both folds, the other fold of the starting response included); and the one-harmonic closed
    form is off the 21-harmonic folds by the amount the tests above allow: that is the
    harmonic-balance error (1e-7 to 5e-7 up to 2 F_c, 1.2e-6 at 3 F_c), not the curve's."""
    loc, folds, (w_c, F_c) = duffing_locus
    hb = HarmonicBalance()
    levels = [p for p in loc.points if p.special == "level"]
    assert len(levels) == 2 * 3 + 1  # 1.5, 2, 3 F_c on both branches; 4 F_c at the other fold
    hb1_error = []
    for p in levels:
        w = hb.fold(p.p1, p.amplitude[0], p.p2)
        assert p.p1 == pytest.approx(w, rel=1e-12), p.p2 / F_c  # measured 1.6e-14
        ref = min((hb1_fold_force(w, s) for s in (1, -1)), key=lambda f: abs(f - p.p2))
        hb1_error.append((p.p2 / F_c, abs(ref - p.p2) / p.p2))
    near = max(e for f, e in hb1_error if f < 2.01)
    assert 5e-8 < near < 1e-6  # measured 5.1e-7 (both branches at 1.5 and 2 F_c)
    assert max(e for f, e in hb1_error) > near  # it grows with the forcing: 1.2e-6 at 3 F_c
    other = [p for p in levels if abs(p.p2 - 4 * F_c) < 1e-9 * F_c]
    assert len(other) == 1 and other[0].p1 == pytest.approx(folds[1].parameter, rel=1e-9)


# ----------------------------------------------------------------------------------------------
# 2. Mathieu: the first instability tongue
# ----------------------------------------------------------------------------------------------
MC, MEPS = 0.05, 0.4


def mathieu_monodromy(w, eps):
    T = 2 * np.pi / w

    def rhs(t, y):
        return [y[1], -MC * y[1] - (1 + eps * np.cos(w * t)) * y[0]]

    return np.column_stack([solve_ivp(rhs, (0, T), e, **RTOL).y[:, -1] for e in np.eye(2)])


def mathieu_pd(w, eps):
    return np.linalg.det(np.eye(2) + mathieu_monodromy(w, eps))


@pytest.fixture(scope="module")
def tongue():
    # y is the Mathieu oscillator; x, unforced and strongly damped, stays at rest
    sysm = pair_system(0.5, 0.0, 0.0, MC, 1.0, MEPS, 1.5, {"eps": 5})
    d = trace_branches(sysm, np.zeros(4), "omega", 1.5, 2.6, state_scale=np.full(4, 0.5), switch_branches=False)
    pds = d.of_kind("period-doubling")
    assert len(pds) == 2
    p = d.branches[pds[0].branch].points[pds[0].point]
    return trace_locus(sysm, "period-doubling", p.u, p.parameter, MEPS, (1.0, 3.0), (0.02, 0.9),
                       parameters=("omega", "eps"), state_scale=np.full(4, 0.5),
                       levels=(0.15, 0.3, 0.5, 0.8, MEPS)), pds


def test_mathieu_tongue_edges_against_floquet(tongue):
    """Both edges of the tongue: at each located eps the frequency is where the independent
    monodromy has a multiplier -1, to 1e-8."""
    loc, pds = tongue
    levels = [p for p in loc.points if p.special == "level"]
    assert len(levels) == 2 * 4 + 1  # four levels on both edges, MEPS at the other edge
    for p in levels:
        w_ref = brentq(lambda w: mathieu_pd(w, p.p2), p.p1 - 0.01, p.p1 + 0.01, xtol=1e-14)
        assert p.p1 == pytest.approx(w_ref, rel=1e-8)  # measured 2.4e-10 at most
        assert abs(p.multipliers + 1).min() < 1e-8
    at_start = [p for p in levels if abs(p.p2 - MEPS) < 1e-9]
    assert at_start[0].p1 == pytest.approx(pds[1].parameter, rel=1e-9)  # the other edge of the response


def test_mathieu_tongue_tip(tongue):
    """The tip: the least eps of the tongue (a turning point of the curve in eps), against the
    independent solution of det(I + M) = 0 and d/dw det(I + M) = 0."""
    loc, _ = tongue
    (tip,) = [p for p in loc.points if p.special == "turning point"]

    def conditions(v):
        w, eps = v
        h = 1e-5
        return [mathieu_pd(w, eps), (mathieu_pd(w + h, eps) - mathieu_pd(w - h, eps)) / (2 * h)]

    sol = root(conditions, [tip.p1 + 1e-3, tip.p2 + 1e-3], method="hybr", options={"xtol": 1e-12})
    assert sol.success
    # measured 4.3e-10 and 2.7e-13 (the reference's central differences limit it)
    assert tip.p1 == pytest.approx(sol.x[0], rel=1e-8) and tip.p2 == pytest.approx(sol.x[1], rel=1e-8)
    assert tip.p2 == pytest.approx(2 * MC, rel=0.05)  # first-order theory: eps_min = 2 c


# ----------------------------------------------------------------------------------------------
# 3. Forced Hopf normal form: Neimark-Sacker and fold curves, strong resonances
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
    elif ipar >= 0:
        dp[0] = 0.0
        dp[1] = 0.0
    return 0


HLAM, HW0, HB, HF = 0.2, 1.0, 1.0, 0.05


def rotating(s, delta):
    """Trace and determinant of the rotating-frame Jacobian at |z|^2 = s, detuning w0 - w."""
    return 2 * (HLAM - 2 * s), (HLAM - 2 * s) ** 2 + (delta - 2 * HB * s) ** 2 - (1 + HB**2) * s**2


def response_force(s, delta):
    """Forcing of the rotating-frame equilibrium with |z|^2 = s at detuning delta."""
    return np.sqrt(s * ((HLAM - s) ** 2 + (delta - HB * s) ** 2))


@pytest.fixture(scope="module")
def hopf():
    sysm = OdeSystem(field=hopf_field, dim=2, prm=np.array([HLAM, HW0, HB, HF]), work=np.zeros(1), omega=0.4,
                     parameters={"F": 3}, fastest_rate=2.0, displacements=np.array([0, 1]))
    w = 0.4
    z = HF / (1j * w - HLAM - 1j * HW0)
    d = trace_branches(sysm, np.array([z.real, z.imag]), "omega", 0.4, 1.4, state_scale=np.array([0.3, 0.3]),
                       switch_branches=False)
    return sysm, d


def test_hopf_neimark_sacker_curve_and_its_strong_resonances(hopf):
    sysm, d = hopf
    (ns,) = d.of_kind("neimark-sacker")
    p = d.branches[ns.branch].points[ns.point]
    loc = trace_locus(sysm, "neimark-sacker", p.u, p.parameter, HF, (0.0, 2.0), (0.01, 0.2), parameters=("omega", "F"),
                      kappa=ns.multiplier.real, state_scale=np.array([0.3, 0.3]))
    s = HLAM / 2  # tr J_rot = 0
    for q in loc.points:
        assert q.p2 == pytest.approx(response_force(s, HW0 - q.p1), rel=1e-8)  # measured 1.3e-9 at most
        tr, det = rotating(s, HW0 - q.p1)
        if det > 0:  # on the curve kappa = cos(T sqrt(det J_rot))
            assert q.kappa == pytest.approx(np.cos(2 * np.pi / q.p1 * np.sqrt(det)), abs=1e-8)
    # it ends where the fold curve meets it: det J_rot = 0 too (closed form)
    assert loc.ends[0].startswith("ends at a 1:1 resonance")
    (r11,) = [q for q in loc.points if q.special == "1:1 resonance"]
    delta = HB * HLAM - np.sqrt(1 + HB**2) * HLAM / 2
    # the Neimark-Sacker system is singular at its 1:1 end (the pair merges at +1, two solutions
    # meet): there Newton's steps shrink only linearly and the point is determined only to about
    # the square root of the rounding (measured 1.6e-8 in p1; 2.6e-6 before the locator's trials
    # were retried patiently from the nearer bracket end, when its first trial there failed)
    assert r11.p1 == pytest.approx(HW0 - delta, rel=1e-7) and r11.p2 == pytest.approx(response_force(s, delta), rel=1e-7)
    # strong resonances 1:3 and 1:4 where T sqrt(det) = 2 pi / 3 and pi / 2
    for name, angle in (("1:3 resonance", 2 * np.pi / 3), ("1:4 resonance", np.pi / 2)):
        (q,) = [q for q in loc.points if q.special == name]
        w_ref = brentq(lambda w: 2 * np.pi / w * np.sqrt(rotating(s, HW0 - w)[1]) - angle, q.p1 - 0.02, q.p1 + 0.02,
                       xtol=1e-14)
        assert q.p1 == pytest.approx(w_ref, rel=1e-8)


def test_hopf_fold_curve_meets_the_neimark_sacker_curve(hopf):
    """The fold curve from the response's upper fold: det J_rot = 0 all along (closed form), and
    its 1:1 resonances are where it meets the Neimark-Sacker curve: both points where
    tr J_rot = det J_rot = 0 (closed form), one of them the end of the curve above."""
    sysm, d = hopf
    fold = max(d.of_kind("fold"), key=lambda b: b.parameter)
    p = d.branches[fold.branch].points[fold.point]
    loc = trace_locus(sysm, "fold", p.u, p.parameter, HF, (0.0, 2.0), (0.01, 0.2), parameters=("omega", "F"),
                      state_scale=np.array([0.3, 0.3]))
    for q in loc.points:
        s = float(q.state @ q.state)
        _, det = rotating(s, HW0 - q.p1)
        assert abs(det) < 1e-8 * (1 + HLAM**2)
        assert q.p2 == pytest.approx(response_force(s, HW0 - q.p1), rel=1e-8)
    found = sorted((q.p1, q.p2) for q in loc.points if q.special == "1:1 resonance")
    deltas = [HB * HLAM + sign * np.sqrt(1 + HB**2) * HLAM / 2 for sign in (1, -1)]
    ref = sorted((HW0 - dl, response_force(HLAM / 2, dl)) for dl in deltas)
    assert len(found) == 2
    for (w, F), (w_ref, F_ref) in zip(found, ref):
        assert w == pytest.approx(w_ref, rel=1e-8) and F == pytest.approx(F_ref, rel=1e-8)


# ----------------------------------------------------------------------------------------------
# 4. Fold-flip: the Duffing oscillator beside the parametric one (pair_field above)
# ----------------------------------------------------------------------------------------------
PZ, PA, PF, PC, PK, PEPS = 0.05, 0.2, 0.3, 0.02, 0.36, 0.3


def test_fold_flip_where_a_fold_curve_crosses_a_period_doubling_boundary():
    sysm = pair_system(PZ, PA, PF, PC, PK, PEPS, 0.5, {"F": 2})
    w0 = 0.5
    Z = PF / (1 - w0**2 + 2j * PZ * w0)
    scale = np.array([1.0, 1.0, 0.1, 0.1])
    d = trace_branches(sysm, np.array([Z.real, -w0 * Z.imag, 0.0, 0.0]), "omega", w0, 1.6, state_scale=scale,
                       switch_branches=False)
    fold = min(d.of_kind("fold"), key=lambda b: b.parameter)
    p = d.branches[fold.branch].points[fold.point]
    loc = trace_locus(sysm, "fold", p.u, p.parameter, PF, (0.5, 1.6), (0.05, 0.6), parameters=("omega", "F"),
                      state_scale=scale)
    flips = [q for q in loc.points if q.special == "fold-flip"]
    assert flips, [(q.special, q.p1, q.p2) for q in loc.points if q.special]

    def edge(w):  # the parametric oscillator's period-doubling boundary (DOP853 monodromy)
        T = 2 * np.pi / w
        rhs = lambda t, y: [y[1], -PC * y[1] - PK * (1 + PEPS * np.cos(w * t)) * y[0]]  # noqa: E731
        M = np.column_stack([solve_ivp(rhs, (0, T), e, **RTOL).y[:, -1] for e in np.eye(2)])
        return np.linalg.det(np.eye(2) + M)

    hb = HarmonicBalance(zeta=PZ, alpha=PA, H=15)  # harmonics above 15 below 1e-12 here
    for q in flips:
        w_ref = brentq(edge, q.p1 - 0.02, q.p1 + 0.02, xtol=1e-14)
        assert q.p1 == pytest.approx(w_ref, rel=1e-8)
        # the Duffing fold at that forcing is at that frequency
        assert hb.fold(q.p1, q.amplitude[0], q.p2) == pytest.approx(q.p1, rel=1e-8)
