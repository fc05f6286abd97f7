"""Backbone curves of small conservative systems, against independent references.

The vector fields (with the artificial damping ``delta`` that unfolds the conservative family)
are written here; the references are computed here without the code under test:

1. Duffing oscillator ``x'' + x + alpha x^3 = 0``: its frequency against its amplitude ``a``
   from the Lindstedt-Poincare series to third order,
   ``w = 1 + 3/8 e - 21/256 e^2 + 81/2048 e^3`` (``e = alpha a^2``; truncation below 2e-9 for
   ``e <= 0.015``), and at large amplitude from an independent shooting: scipy's DOP853 from
   ``(a, 0)`` to the first zero of ``x`` (a quarter period, by the symmetry of the potential);
2. two masses, a cubic spring on the first (``x1'' + 2 x1 - x2 + 0.5 x1^3 = 0``,
   ``x2'' + 2 x2 - x1 = 0``; linear frequencies 1 and sqrt 3): the in-phase mode's backbone
   hardens and meets the out-of-phase mode at a rational frequency ratio; at each internal
   resonance reported, the monodromy matrix computed independently (DOP853, central
   differences) has every multiplier at +1 (integer ratio) or a pair at -1 (half-integer).
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from scipy.integrate import solve_ivp

from cablesim.orbits import OdeSystem
from cablesim.orbits.backbone import trace_backbone
from cablesim.orbits.continuation import Settings

RTOL = dict(rtol=1e-12, atol=1e-14, method="DOP853")


@njit(cache=True)
def two_mass_unfolded(theta, omega, x, model, prm, work, dx, J, dp, ipar):
    delta, w2, c, alpha = prm[0], prm[1], prm[2], prm[3]
    for i in range(4):
        for j in range(4):
            J[i, j] = 0.0
    dx[0] = x[2]
    dx[1] = x[3]
    dx[2] = -x[0] - alpha * x[0] ** 3 - c * (x[0] - x[1]) - delta * x[2]
    dx[3] = -w2 * w2 * x[1] - c * (x[1] - x[0]) - delta * x[3]
    J[0, 2] = 1.0
    J[1, 3] = 1.0
    J[2, 0] = -1.0 - 3.0 * alpha * x[0] ** 2 - c
    J[2, 1] = c
    J[3, 0] = c
    J[3, 1] = -w2 * w2 - c
    J[2, 2] = -delta
    J[3, 3] = -delta
    if ipar == 0:
        dp[0] = 0.0
        dp[1] = 0.0
        dp[2] = -x[2]
        dp[3] = -x[3]
    return 0


W2, COUPLING, TALPHA = 3.2, 0.1, 1.0
ALPHA = 1.0


def duffing(alpha=ALPHA):
    """The Duffing oscillator: the two-mass field above uncoupled (the second mass stays at rest;
    one compiled field for the module)."""
    return OdeSystem(field=two_mass_unfolded, dim=4, prm=np.array([0.0, W2, 0.0, alpha]), work=np.zeros(1),
                     omega=1.0, parameters={"delta": 0}, fastest_rate=4.0, displacements=np.array([0, 1]))


def lindstedt(a, alpha=ALPHA):
    e = alpha * a * a
    return 1 + 3 / 8 * e - 21 / 256 * e**2 + 81 / 2048 * e**3


def shooting_reference(a, alpha=ALPHA):
    """Frequency of the free orbit through (a, 0): four times the time to the first x = 0."""
    def rhs(t, y):
        return [y[1], -y[0] - alpha * y[0] ** 3]

    def zero(t, y):
        return y[0]

    zero.terminal, zero.direction = True, -1
    sol = solve_ivp(rhs, (0, 10.0), [a, 0.0], events=zero, **RTOL)
    return 2 * np.pi / (4 * sol.t_events[0][0])


def test_duffing_backbone_small_amplitude_against_lindstedt_poincare():
    bb = trace_backbone(duffing(), mode=1, amplitude=0.15, start_fraction=0.05, settings=Settings(ds_max=0.02),
                        channels=[0])
    assert bb.end == "reached the amplitude 0.15"
    small = [p for p in bb.points if ALPHA * p.state[0] ** 2 <= 0.015]
    assert len(small) >= 5
    for p in small:
        a = abs(p.state[0])  # the phase condition puts t = 0 at a turning point: x(0) = +-a
        assert abs(p.state[2]) < 1e-12 and abs(p.delta) < 1e-10 and np.abs(p.state[[1, 3]]).max() < 1e-12
        assert p.omega == pytest.approx(lindstedt(a), rel=1e-8)  # measured 1.2e-9: the series truncation
        assert p.amplitude[0] == pytest.approx(a, rel=1e-7) and p.stable and p.trusted
    assert bb.linear_omega == pytest.approx(1.0, rel=1e-12)


def test_duffing_backbone_large_amplitude_against_an_independent_shooting():
    bb = trace_backbone(duffing(), mode=1, amplitude=2.0, channels=[0])
    omega = bb.values("omega")
    assert np.all(np.diff(omega) > 0)  # hardening
    big = [p for p in bb.points if abs(p.state[0]) > 0.5]
    assert len(big) >= 5 and max(abs(p.state[0]) for p in big) >= 2.0
    for p in big:
        assert p.omega == pytest.approx(shooting_reference(abs(p.state[0])), rel=1e-9)  # measured 1.2e-12
    # far from the series' range: it is off by percents there, the backbone is not
    p = big[-1]
    assert abs(lindstedt(abs(p.state[0])) / p.omega - 1) > 0.05


def two_mass_rhs(t, y):
    return [y[2], y[3], -y[0] - TALPHA * y[0] ** 3 - COUPLING * (y[0] - y[1]),
            -W2 * W2 * y[1] - COUPLING * (y[1] - y[0])]


def two_mass_monodromy(x0, omega, h=1e-4):
    T = 2 * np.pi / omega
    cols = []
    for j in range(4):
        d = np.zeros(4)
        d[j] = h
        a = solve_ivp(two_mass_rhs, (0, T), x0 + d, **RTOL).y[:, -1]
        b = solve_ivp(two_mass_rhs, (0, T), x0 - d, **RTOL).y[:, -1]
        cols.append((a - b) / (2 * h))
    return np.column_stack(cols)


def test_internal_resonances_of_two_masses_have_multipliers_at_plus_or_minus_one():
    """A hardening oscillator coupled to a linear one three times as fast: the first mode's
    backbone meets the second mode's frequency at 3:1, 5:2 and 2:1 (ratios of the linearised
    frequencies about the orbit); there the independent monodromy has the second mode's pair at
    +1 or -1, or split along the real axis from there (a short unstable stretch of the family),
    as the backbone's own multipliers and stability say."""
    sysm = OdeSystem(field=two_mass_unfolded, dim=4, prm=np.array([0.0, W2, COUPLING, TALPHA]), work=np.zeros(1),
                     omega=1.0, parameters={"delta": 0}, fastest_rate=4.0, displacements=np.array([0, 1]))
    bb = trace_backbone(sysm, mode=1, amplitude=1.5, max_ratio=3.5)
    w = np.sqrt(np.linalg.eigvalsh(np.array([[1 + COUPLING, -COUPLING], [-COUPLING, W2**2 + COUPLING]])))
    assert bb.modes == pytest.approx(w, rel=1e-12)
    res = bb.resonances
    assert [p.special.split()[0] for p in res] == ["3:1", "5:2", "2:1"]
    for p in res:
        assert p.located and p.special.endswith("internal resonance with mode 2")
        end = solve_ivp(two_mass_rhs, (0, 2 * np.pi / p.omega), p.state, **RTOL).y[:, -1]
        assert np.abs(end - p.state).max() < 1e-8  # a periodic orbit of the independent integration
        # a symplectic 4 x 4 monodromy with the trivial pair at +1 has the characteristic
        # polynomial (mu - 1)^2 (mu^2 - 2 c mu + 1): tr M = 2 + 2 c, with c = cos(2 pi rho) while
        # the mode's pair is on the unit circle and |c| > 1 where it has split along the real axis
        c = (np.trace(two_mass_monodromy(p.state, p.omega)) - 2.0) / 2.0
        target = -1.0 if p.special.split()[0].endswith(":2") else 1.0
        assert c * target >= 1.0 - 1e-6, (p.special, c)  # at the resonance or inside its stretch
        assert c == pytest.approx((np.sum(p.multipliers).real - 2.0) / 2.0, abs=1e-6)
        if abs(c) > 1.0 + 1e-6:  # clearly split (at the collision itself either is right)
            assert not p.stable
    # between them the ratio is not at a resonance (so the check above can fail)
    mid = bb.points[(res[0].index + res[1].index) // 2]
    c = (np.trace(two_mass_monodromy(mid.state, mid.omega)) - 2.0) / 2.0
    assert abs(abs(c) - 1.0) > 1e-2
