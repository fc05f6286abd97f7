"""Periodic orbits through slack (the dense shooting, :mod:`cablesim.orbits.slackflow`) against
an independent event-driven shooting written here: scipy's DOP853 (rtol 1e-12) on the
second-order equations with own geometry and tension-only segments by modes, the gaps as
terminal events, restarted in the new modes at each event; Newton's method on its period map
with a central finite-difference monodromy across the events.

The orbit: the paper's cable with the harmonic load scaled by 13.5 at 2.45 rad/s. Its slack
pattern: segment 3 (support B's) goes slack once a period, from 1.777 s to 1.834 s of the
2.565 s period (phase 0 at the forcing's zero crossing); segments 1 and 2 stay taut.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cablesim.analyses.setup import build_equations
from cablesim.orbits.shooting import Shooting, solve_orbit
from cablesim.orbits.slackpattern import slack_pattern
from cablesim.orbits.systems import cable_system

OMEGA, SCALE = 2.45, 13.5
#: A state near the orbit (displacements from the equilibrium, m, and velocities, m/s, at phase 0,
#: to 3 digits, from a time history after 60 periods): the start of both Newton iterations.
START = np.array([-4.334, 7.088, -2.68, -3.665, -18.247, 26.177, -14.215, -21.179])


# ----------------------------------------------------------------------------------------------
# The independent formulation
# ----------------------------------------------------------------------------------------------
def _geometry(y, L, H):
    pts = np.vstack([[0.0, 0.0], y.reshape(-1, 2), [L, H]])
    d = np.diff(pts, axis=0)
    return d, np.hypot(d[:, 0], d[:, 1])


class Reference:
    """The period map of ``M y'' + C y' + P(y) = F0 + FL sin(w t)``, ``P`` of the segments in
    their modes (taut: ``EA (l - S) / S`` along the segment; slack: nothing)."""

    def __init__(self, eom):
        c = eom.cable
        self.S, self.EA, self.L, self.H = np.asarray(c.S, float), float(c.EA), float(c.L), float(c.H)
        self.nd = eom.n_dof
        self.M, self.C, self.FL, self.w, self.y0 = eom.mass, eom.C, eom.FL, eom.omega, eom.y0
        # the sustained load that holds y0 (the static solve's tolerance aside), as cablesim's
        self.F0 = self.force(self.y0, np.ones(self.S.size))
        self.T = 2.0 * np.pi / self.w

    def force(self, y, taut):
        d, l = _geometry(y, self.L, self.H)
        f = (taut * self.EA * (l - self.S) / self.S / l)[:, None] * d
        return (f[:-1] - f[1:]).ravel()

    def gaps(self, x):
        return _geometry(self.y0 + x[: self.nd], self.L, self.H)[1] - self.S

    def gap_rates(self, x):
        nd = self.nd
        d, l = _geometry(self.y0 + x[:nd], self.L, self.H)
        dv = np.diff(np.vstack([[0.0, 0.0], x[nd:].reshape(-1, 2), [0.0, 0.0]]), axis=0)
        return np.einsum("ij,ij->i", d, dv) / l

    def flow(self, x0, rtol=1e-12, peaks=None):
        """``(x(T), events)`` from ``x0`` at phase 0; events ``(t, segment 0-based, new mode)``.
        ``peaks`` (an array, one per segment): raised to the largest tension found at the gap
        rates' zeros (non-terminal events) and the period's ends, N."""
        nd = self.nd
        x, t = np.asarray(x0, float), 0.0
        taut = (self.gaps(x) > 0).astype(float)
        events = []
        turns = [lambda t, s, k=k: self.gap_rates(s)[k] for k in range(self.S.size)]

        def rhs(t, s):
            acc = self.F0 + self.FL * np.sin(self.w * t) - self.C @ s[nd:] - self.force(self.y0 + s[:nd], taut)
            return np.concatenate([s[nd:], acc / self.M])

        def gap(k):
            ev = lambda t, s: self.gaps(s)[k]  # noqa: E731
            ev.terminal = True
            ev.direction = -1.0 if taut[k] else 1.0
            return ev

        while True:
            nk = self.S.size
            sol = solve_ivp(rhs, (t, self.T), x, method="DOP853", rtol=rtol, atol=1e-14 * self.L,
                            events=[gap(k) for k in range(nk)] + (turns if peaks is not None else []))
            assert sol.status >= 0, sol.message
            if peaks is not None:
                for k in range(nk):
                    for s in [*sol.y_events[nk + k], sol.y[:, 0], sol.y[:, -1]]:
                        peaks[k] = max(peaks[k], taut[k] * max(self.gaps(s)[k], 0.0) * self.EA / self.S[k])
            if sol.status == 0:
                return sol.y[:, -1], events
            k = min((k for k in range(nk) if sol.t_events[k].size), key=lambda k: sol.t_events[k][0])
            t, x = sol.t_events[k][0], sol.y_events[k][0]
            taut[k] = 1.0 - taut[k]
            events.append((t, k, taut[k]))

    def monodromy(self, x, rel=1e-6):
        """Central differences of the period map, across its events."""
        n = x.size
        scale = np.concatenate([np.full(self.nd, np.abs(x[: self.nd]).max()), np.full(self.nd, np.abs(x[self.nd:]).max())])
        Mo = np.empty((n, n))
        for i in range(n):
            e = np.zeros(n)
            e[i] = rel * scale[i]
            Mo[:, i] = (self.flow(x + e)[0] - self.flow(x - e)[0]) / (2.0 * e[i])
        return Mo

    def orbit(self, x, iterations=8):
        """Newton's method on ``flow(x) - x`` with the finite-difference monodromy."""
        for _ in range(iterations):
            r = self.flow(x)[0] - x
            Mo = self.monodromy(x)
            dx = np.linalg.solve(Mo - np.eye(x.size), -r)
            x = x + dx
            if np.abs(dx).max() < 1e-12 * np.abs(x).max():
                break
        return x, Mo


# ----------------------------------------------------------------------------------------------
# The orbits, once per module
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def snap_eom(paper, exact_static):
    return build_equations(paper, exact_static, omega=OMEGA, load_scale=SCALE)


@pytest.fixture(scope="module")
def snap_orbit(snap_eom):
    sh = Shooting(cable_system(snap_eom), through_slack=True)
    sol = solve_orbit(sh, START)
    assert sol.converged, sol.status
    return sh, sol


@pytest.fixture(scope="module")
def reference_orbit(snap_eom):
    ref = Reference(snap_eom)
    x, Mo = ref.orbit(START.copy())
    return ref, x, Mo


def _matched(a, b):
    """Largest distance from each of ``a`` to the nearest of ``b`` (and back)."""
    d = np.abs(a[:, None] - b[None, :])
    return max(d.min(axis=1).max(), d.min(axis=0).max())


# ----------------------------------------------------------------------------------------------
# Tests
# ----------------------------------------------------------------------------------------------
def test_orbit_through_slack_agrees_with_an_event_driven_shooting(snap_orbit, reference_orbit):
    sh, sol = snap_orbit
    ref, x_ref, M_ref = reference_orbit
    ev = sol.evaluation
    nd = ref.nd
    # the slack pattern: segment 3 slack once a period, the others taut throughout
    _, events = ref.flow(x_ref)
    assert [(k, m) for _, k, m in events] == [(2, 0.0), (2, 1.0)]
    assert ev.events[:, 1:].tolist() == [[2.0, 0.0], [2.0, 1.0]]
    assert np.abs(ev.events[:, 0] - [t for t, _, _ in events]).max() < 1e-8  # s
    # the state to 1e-7 of each half's largest component (m, m/s)
    for part in (slice(0, nd), slice(nd, 2 * nd)):
        assert np.abs(sol.u[part] - x_ref[part]).max() < 1e-7 * np.abs(x_ref[part]).max()
    # the multipliers to 1e-5; Liouville's formula det = exp(-tr(M^-1 C) T) holds through the
    # kinks for both (the saltation matrices are the identity): the reference's to its finite
    # differences, cablesim's to the rk8 error on the axial modes it has without slack (1.6e-5)
    assert _matched(ev.multipliers, np.linalg.eigvals(M_ref)) < 1e-5
    assert abs(np.log(abs(np.linalg.det(M_ref))) - ev.divergence) < 5e-5
    assert ev.liouville < 5e-5


def test_monodromy_through_slack_is_the_derivative_of_the_flow_map(snap_orbit):
    """The product of the smooth pieces' variational flows (saltation = identity) against
    central differences of cablesim's own period map, whose events move with the state."""
    sh, sol = snap_orbit
    u = sol.u
    n = u.size
    nd = n // 2
    scale = np.concatenate([np.full(nd, np.abs(u[:nd]).max()), np.full(nd, np.abs(u[nd:]).max())])
    fd = np.empty((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1e-6 * scale[i]
        plus, minus = sh.evaluate(u + e, sh.default_lam(), jac=False), sh.evaluate(u - e, sh.default_lam(), jac=False)
        assert plus.events.shape == minus.events.shape == (2, 3)
        fd[:, i] = (plus.ends[0] - minus.ends[0]) / (2.0 * e[i])
    mono = sol.evaluation.monodromy
    # relative to the largest entry of each block row (displacements, velocities) and column
    w = scale[:, None] / scale[None, :]
    assert np.abs((mono - fd) / w).max() < 1e-6 * np.abs(mono / w).max()


def test_slack_intervals_and_snap_loads_of_the_orbit(snap_orbit, reference_orbit):
    sh, sol = snap_orbit
    ref, x_ref, _ = reference_orbit
    pat = slack_pattern(sh, sol.u, sh.default_lam(), sol.evaluation)
    peaks = np.zeros(3)
    _, events = ref.flow(x_ref, peaks=peaks)
    assert pat.episodes.tolist() == [0, 0, 1]
    assert np.abs(pat.intervals[2] - [[events[0][0], events[1][0]]]).max() < 1e-8  # s
    assert np.abs(pat.peak_tension - peaks).max() < 1e-7 * peaks.max()  # N


def test_flow_without_slack_is_the_plain_kernels_bit_for_bit(forced_eom):
    """Where no segment goes slack the kernel with modes takes the plain kernel's steps: the
    same end state, Jacobian and extremes to the bit (a taut orbit of the paper's cable)."""
    from cablesim.orbits import kernels as ok
    from cablesim.orbits import slackflow as sf

    sh = Shooting(cable_system(forced_eom))
    system = sh.system
    x0 = np.array([0.01, -0.02, 0.005, 0.03, 0.0, 0.01, -0.02, 0.0])
    outs = []
    for kernel in ("plain", "modes"):
        n = x0.size
        ns = sh.segment_steps(sh.default_lam())
        res = [np.empty(n), np.empty((n, n)), np.zeros(n), np.empty(n), np.empty(n), np.empty((ns + 1, 2 * n)),
               np.zeros(4)]
        args = (system.model, system.prm, ok.copy_work(system.work), x0, 0.0, sh.default_lam(),
                2 * np.pi / sh.default_lam(), ns, sh.tableau.A, sh.tableau.b, sh.tableau.c, -1, ok.PARAM_OMEGA, True,
                np.arange(n), np.array([0, n]), *res)
        if kernel == "plain":
            code = ok.EntryPoint(ok.flow_segment)(system.field, *args)
        else:
            ev, nev = np.zeros((64 * 3, 3)), np.zeros(1, dtype=np.int64)
            code = ok.EntryPoint(sf.flow_segment_modes)(system.field, *system.slack, *args, ev, nev)
            assert nev[0] == 0
        assert code == ok.OK
        outs.append(res)
    for a, b in zip(*outs):
        assert np.array_equal(a, b)


def test_approximate_analysis_still_stops_where_a_segment_goes_slack(paper, approx_static):
    """Only the exact analysis' dense shooting follows slack segments; the approximate
    analysis has no state with a slack segment (x(P) undetermined) and stops there as before."""
    from cablesim.orbits.shooting import FlowStatus

    eom = build_equations(paper, approx_static, omega=OMEGA, load_scale=SCALE)
    system = cable_system(eom)
    assert system.slack is None
    ev = Shooting(system).evaluate(START, OMEGA, jac=False)
    # (from this far out the inner solve of x(P) may fail first: the same stop, named so)
    assert ev.status in (FlowStatus.SLACK, FlowStatus.INNER_SOLVE) and ev.events.size == 0
