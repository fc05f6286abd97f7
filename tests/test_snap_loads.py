"""Peak tensions (snap loads) located on the step interpolant (cablesim.dynamics.peaks).

The reference, written here: scipy's DOP853 (rtol 1e-13) on the second-order equations of
motion with the tension-only law by segment modes (own geometry), restarted at every slack onset
and re-tightening its terminal events locate, with non-terminal events on ``g' = 0`` (falling:
a maximum of the gap ``g = l - S``) locating each taut segment's tension maxima on its dense
output. The case: the paper example with FL x 15 at 5 rad/s for 3 s (segment 3 goes slack
twice and snaps taut again).

Measured (largest relative peak tension error / time error over the segments): dopri5 at rtol
1e-7, 1e-9, 1e-11 (atol following rtol): 1.4e-6 / 9.1e-7 s, 3.1e-8 / 3.8e-8 s, 3.9e-10 / 2.8e-9 s;
rk4 at dt = 5e-4 s: 1.2e-9 / 1.1e-9 s. Before (peaks taken at four samples a step): 2.3e-5 /
5.5e-4 s, 7.6e-7 / 9.8e-5 s, 6.0e-7 / 7.9e-5 s, and rk4 2.2e-7: no better than the samples,
whatever the tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cablesim.analyses.setup import build_equations, default_atol
from cablesim.dynamics.integrators import DOPRI5, RK4
from cablesim.dynamics.simulate import simulate

DURATION = 3.0


def _geometry(y, L, H):
    pts = np.vstack([[0.0, 0.0], y.reshape(-1, 2), [L, H]])
    d = np.diff(pts, axis=0)
    return d, np.hypot(d[:, 0], d[:, 1])


def snap_reference(eom, t_end, rtol=1e-13):
    """Per segment: the largest tension (N) over ``[0, t_end]`` and its time (s); the events."""
    c = eom.cable
    S, EA, L, H = np.asarray(c.S, float), float(c.EA), float(c.L), float(c.H)
    nd = eom.n_dof
    M, C, F0, FL, w, y0 = eom.mass, eom.C, eom.F0, eom.FL, eom.omega, eom.y0
    x = np.zeros(2 * nd)
    taut = (_geometry(y0, L, H)[1] > S).astype(float)

    def rhs(t, s):
        d, l = _geometry(y0 + s[:nd], L, H)
        f = (taut * EA * (l - S) / S / l)[:, None] * d
        return np.concatenate([s[nd:], (F0 + FL * np.sin(w * t) - C @ s[nd:] - (f[:-1] - f[1:]).ravel()) / M])

    def gap(k):
        ev = lambda t, s: _geometry(y0 + s[:nd], L, H)[1][k] - S[k]  # noqa: E731
        ev.terminal = True
        ev.direction = -1.0 if taut[k] else 1.0
        return ev

    def gap_rate(k):  # g' = d.d'/l, zero at a maximum of g when falling through zero
        def ev(t, s):
            vel = np.vstack([[0.0, 0.0], s[nd:].reshape(-1, 2), [0.0, 0.0]])
            d, l = _geometry(y0 + s[:nd], L, H)
            return float(d[k] @ np.diff(vel, axis=0)[k] / l[k])
        ev.direction = -1.0
        return ev

    def tension(s):
        return EA * np.maximum(_geometry(y0 + s[:nd], L, H)[1] - S, 0.0) / S

    peak, when = tension(x), np.zeros(S.size)
    events, t = [], 0.0
    while t < t_end:
        sol = solve_ivp(rhs, (t, t_end), x, method="DOP853", rtol=rtol, atol=1e-14 * c.chord_length,
                        events=[gap(k) for k in range(S.size)] + [gap_rate(k) for k in range(S.size)])
        assert sol.status >= 0, sol.message
        for k in range(S.size):
            for tk, sk in zip(sol.t_events[S.size + k], sol.y_events[S.size + k]):
                if taut[k] and tension(sk)[k] > peak[k]:
                    peak[k], when[k] = tension(sk)[k], tk
        last = sol.y[:, -1]
        if sol.status == 1:
            k = min((k for k in range(S.size) if sol.t_events[k].size), key=lambda k: sol.t_events[k][0])
            t_new, last = sol.t_events[k][0], sol.y_events[k][0]
            taut[k] = 1.0 - taut[k]
            events.append((t_new, k + 1))
        else:
            t_new = sol.t[-1]
        end = tension(last)
        up = end > peak
        peak[up], when[up] = end[up], t_new
        t, x = t_new, last
    return peak, when, events


@pytest.fixture(scope="module")
def snapping(paper, exact_static):
    eom = build_equations(paper, exact_static, omega=5.0, load_scale=15.0)
    peak, when, events = snap_reference(eom, DURATION)
    assert sum(1 for _, k in events if k == 3) >= 4  # segment 3: slack and taut again, twice
    return eom, peak, when, events


def _errors(eom, integ, ref):
    peak, when, events = ref
    hist = simulate(eom, integ, DURATION, 0.05)
    assert hist.completed, hist.message
    r = hist.slack
    assert list(r.segment) == [k for _, k in events]
    return float(np.max(np.abs(r.peak_tension - peak) / peak)), float(np.max(np.abs(r.peak_time - when)))


def test_snap_loads_and_times_converge_with_the_tolerance(snapping):
    """dopri5 at rtol 1e-7, 1e-9 and 1e-11 (atol following rtol): the peak tensions and their
    times against the event-driven reference, within 1e-8 and 1e-6 s at 1e-11, the errors
    falling with the tolerance."""
    eom, *ref = snapping
    chord = eom.cable.chord_length
    errs = [_errors(eom, DOPRI5(rtol=r, atol=default_atol(chord, r)), ref) for r in (1e-7, 1e-9, 1e-11)]
    print("dopri5 (rtol 1e-7, 1e-9, 1e-11): " + ", ".join(f"{e:.2e} / {dt:.2e} s" for e, dt in errs))
    (e1, dt1), (e2, dt2), (e3, dt3) = errs
    assert e3 < 1e-8 and dt3 < 1e-6
    assert e3 < e2 / 5 < e1 / 25
    assert dt3 < dt1 / 10


def test_snap_loads_with_a_fixed_step(snapping):
    """The same peak location serves every scheme (the events' interpolant): rk4 at 5e-4 s."""
    eom, *ref = snapping
    e, dt = _errors(eom, RK4(dt=5e-4), ref)
    print(f"rk4 dt = 5e-4 s: {e:.2e} / {dt:.2e} s")
    assert e < 1e-8 and dt < 1e-6
