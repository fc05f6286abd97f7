"""Moving supports: histories against an independent second-order formulation (own assembly,
scipy's DOP853), the damping that never damps a rigid motion, and the quasi-static limit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cablesim.cable import Cable
from cablesim.dynamics.equations import EquationsOfMotion
from cablesim.dynamics.integrators import DOPRI5, GeneralizedAlpha, Newmark, RK4
from cablesim.dynamics.simulate import simulate
from cablesim.modal import modal_analysis, rayleigh_coefficients
from cablesim.statics import exact_equilibrium, inextensible_equilibrium

from helpers_mechanics import SecondOrder

PAPER = dict(L=300.0, H=20.0, S=[130.0, 100.0, 110.0], EA=1e9, masses=[8000.0, 14000.0])
F0_PAPER = np.array([300e3, 1100e3, 450e3, 2000e3])


def equations(cable, F0, FL, omega, uA, uB, phA=0.0, phB=0.0, ratio=0.02, a=None):
    ex = exact_equilibrium(cable, F0)
    inext = inextensible_equilibrium(cable, F0)
    M = cable.mass_diagonal
    w = modal_analysis(ex.K, M).omega
    a0, a1 = rayleigh_coefficients(w[0], w[1], ratio) if a is None else a
    eom = EquationsOfMotion(cable=cable, analysis="exact", mass=M, F0=F0, FL=FL, omega=omega, y0=ex.y, x0=inext.x,
                            u0=ex.y - inext.x, T0=ex.T, F1=inext.segments.F[0], a0=a0, a1=a1, modal_omega=w,
                            K0_band=ex.K_band, uA=uA, uB=uB, phA=phA, phB=phB)
    ref = SecondOrder(cable.S, cable.EA, cable.chord, cable.dim, M, F0, FL, omega, ex.y, a0, a1, uA, uB, phA, phB)
    return eom, ref


def reference(ref, duration, t_out, v0=None):
    nd = ref.y0.size
    q0 = np.concatenate([ref.y0, np.zeros(nd) if v0 is None else v0])
    sol = solve_ivp(ref.rhs, (0.0, duration), q0, method="DOP853", rtol=1e-11, atol=1e-10, t_eval=t_out)
    assert sol.success
    return sol.y[:nd].T


CASES = {
    "planar, B along the chord": (Cable(**PAPER), F0_PAPER, np.zeros(4), 2.0, [0.0, 0.0], [0.3, 0.02], 0.0, 0.4),
    "planar, both ends, with FL": (Cable(**PAPER), F0_PAPER, np.array([-6e3, 22e3, -18e3, 120e3]), 2.4,
                                   [0.1, -0.2], [0.0, 0.4], 0.7, 0.0),
    "spatial, sideways": (Cable(**PAPER, W=15.0, dim=3), np.array([300e3, 1100e3, 50e3, 450e3, 2000e3, -80e3]),
                          np.array([0.0, 10e3, 20e3, 0.0, 30e3, -15e3]), 2.2, [0.0, 0.1, 0.3], [0.2, 0.0, -0.4], 0.3, 1.1),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_history_with_moving_supports_against_an_independent_formulation(name):
    cable, F0, FL, omega, uA, uB, phA, phB = CASES[name]
    eom, ref = equations(cable, F0, FL, omega, uA, uB, phA, phB)
    duration, step = 20.0, 0.05
    h = simulate(eom, DOPRI5(rtol=1e-11, atol=1e-12 * cable.chord_length), duration, step)
    assert h.completed, h.message
    y_ref = reference(ref, duration, h.t)
    z_ref = y_ref - ref.y0
    peak = np.abs(z_ref).max()
    assert peak > 0.05  # the supports do move the cable
    assert np.abs(h.z - z_ref).max() < 1e-6 * peak
    T_ref = np.array([ref.tensions(t, y) for t, y in zip(h.t, y_ref)])
    assert np.abs(h.T - T_ref).max() < 1e-6 * np.abs(T_ref - eom.T0).max()
    assert np.abs(h.residual).max() < 1e-8  # eq. 15 with the supports' damping holds along the run


@pytest.mark.parametrize("integ", [RK4(dt=0.005), Newmark(dt=0.002), GeneralizedAlpha(dt=0.002)],
                         ids=lambda i: i.name)
def test_every_integrator_follows_the_supports(integ):
    cable, F0, FL, omega, uA, uB, phA, phB = CASES["planar, both ends, with FL"]
    eom, ref = equations(cable, F0, FL, omega, uA, uB, phA, phB)
    h = simulate(eom, integ, 10.0, 0.05)
    assert h.completed, h.message
    z_ref = reference(ref, 10.0, h.t) - ref.y0
    tol = 1e-6 if integ.order == 4 else 2e-4  # second-order schemes: their error at this step
    assert np.abs(h.z - z_ref).max() < tol * np.abs(z_ref).max()


@pytest.mark.parametrize("a0_on", [False, True])
def test_a_rigid_translation_is_not_damped_by_the_stiffness_part(a0_on):
    """Both supports moving alike: in the frame that moves with them the cable feels the load
    ``-M s'' - a0 M s'`` and nothing from the stiffness-proportional damping, so its tensions are
    those of fixed supports under that load (an independent run of the reference)."""
    cable = Cable(**PAPER)
    u = np.array([0.0, 0.5])
    omega = 1.3
    eom, ref = equations(cable, F0_PAPER, np.zeros(4), omega, u, u, a=(0.05 if a0_on else 0.0, 0.004))
    duration = 15.0
    h = simulate(eom, DOPRI5(rtol=1e-11, atol=1e-12 * cable.chord_length), duration, 0.05)
    assert h.completed
    # the moving frame: w = y - s, fixed supports, load F0 - M s'' - a0 M s'
    M, a0, a1 = ref.mass, ref.a0, ref.a1
    nd = ref.y0.size
    rep = np.tile(u, nd // 2)

    def rhs(t, q):
        w, v = q[:nd], q[nd:]
        s1 = rep * omega * np.cos(omega * t)
        s2 = -rep * omega**2 * np.sin(omega * t)
        load = ref.F0 - M * s2 - a0 * M * s1
        acc = (load - a0 * M * v - a1 * ref.K0 @ v - ref.force(w, np.zeros(2), ref.chord)) / M
        return np.concatenate([v, acc])

    q0 = np.concatenate([ref.y0, -rep * omega])  # y'(0) = 0: relative velocity -s'(0)
    sol = solve_ivp(rhs, (0.0, duration), q0, method="DOP853", rtol=1e-11, atol=1e-10, t_eval=h.t)
    # tensions in the moving frame, where the supports rest: those of the moving cable
    pts = [np.vstack([np.zeros(2), w.reshape(-1, 2), ref.chord]) for w in sol.y[:nd].T]
    T_frame = np.array([cable.EA * (np.linalg.norm(np.diff(p, axis=0), axis=1) - cable.S) / cable.S for p in pts])
    change = np.abs(T_frame - eom.T0).max()
    assert change > 1e3  # the masses' inertia does load the cable
    assert np.abs(h.T - T_frame).max() < 1e-6 * change


def test_a_very_slow_support_motion_follows_the_moved_statics():
    """Support B moved along the span very slowly (a hundredth of the lowest frequency): at every
    instant the cable is in the static equilibrium for B where it is then, to the order of the
    dynamic amplification (w/w1)^2 and the damping's lag."""
    cable = Cable(**PAPER)
    eom, _ = equations(cable, F0_PAPER, np.zeros(4), 0.025, [0.0, 0.0], [1.0, 0.0], ratio=0.05)
    w1 = float(eom.frequencies[0])
    assert 0.025 / w1 < 0.011
    T = 2 * np.pi / 0.025
    h = simulate(eom, DOPRI5(rtol=1e-9, atol=1e-10 * cable.chord_length), T, T / 40)
    assert h.completed
    worst = 0.0
    for t, z in zip(h.t[10:], h.z[10:]):  # after the start-up transient
        b = 1.0 * np.sin(0.025 * t)
        moved = Cable(cable.L + b, cable.H, cable.S, cable.EA, cable.masses)
        y_static = exact_equilibrium(moved, F0_PAPER).y
        worst = max(worst, np.abs(eom.y0 + z - y_static).max())
    assert worst < 1e-2 * 1.0  # 1 % of the support's amplitude; measured below


@pytest.mark.parametrize("name", sorted(CASES))
def test_linear_response_to_moving_supports_is_the_small_orbit(name):
    """The supports' motion (and FL) made 1e-4 as large: the periodic orbit of the nonlinear
    equations of motion, solved by shooting from rest, is the linear steady response
    ``Im(Z exp(i w t))`` with the supports' linearised load (the first and last segments'
    tangent blocks, with the stiffness-proportional damping's ``i w a1``), to the size of the
    neglected quadratic terms, 1e-3 of the response."""
    from cablesim.orbits import Shooting, cable_system, linear_response_state, solve_orbit

    cable, F0, FL, omega, uA, uB, phA, phB = CASES[name]
    small = 1e-4
    eom, _ = equations(cable, F0, small * FL, omega, small * np.array(uA), small * np.array(uB), phA, phB)
    linear = linear_response_state(eom, omega)
    sol = solve_orbit(Shooting(cable_system(eom)), np.zeros_like(linear), omega)
    assert sol.converged
    nd = eom.n_dof
    for part in (slice(0, nd), slice(nd, 2 * nd)):
        size = np.abs(sol.u[part]).max()
        assert np.abs(linear[part] - sol.u[part]).max() < 1e-3 * size, (linear[part], sol.u[part])
