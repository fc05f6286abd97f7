"""Checks of the independent out-of-plane stability reference (helpers_whirl.py and
helpers_whirl_cases.py): its statics and tangents against central differences, its planar form
against its spatial form, the monodromy from the variational equations against central
differences of the flow map, the out-of-plane Hill problem against the spatial monodromy, the
located whirling pitchfork (square-root law), the stay's parametric tongue against the damped
Mathieu closed form, and that closed form's error orders against numerical Floquet."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.optimize import brentq

from cablesim.api import load_case
from helpers_whirl import (
    LumpedCable,
    Motion,
    cable_from_case,
    fd_monodromy,
    floquet_multipliers,
    flow,
    force,
    natural_frequencies,
    out_of_plane_block,
    out_of_plane_monodromy,
    periodic_orbit,
    planar_indices,
    static_equilibrium,
    stiffness,
    string_stiffness,
    support_stiffness,
    to_spatial,
)
from helpers_whirl_cases import (
    STAY_CASE,
    WHIRL_CASE,
    cable_from_yaml,
    continuous_string_frequency,
    lumped_string_frequency,
    mathieu_edges,
    mathieu_multipliers,
    mathieu_threshold,
    pitchfork_amplitude,
    pitchfork_omega,
    stay_case,
    stay_mathieu,
    tongue_edges,
    tongue_threshold,
    whirl_case,
    whirling_orbit,
)

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def spatial_state(x_planar):
    n2 = x_planar.size // 2
    return np.concatenate((to_spatial(x_planar[:n2]), to_spatial(x_planar[n2:])))


def skew_cable():
    """A spatial cable with B out of the plane, sideways loads and both supports moving in 3D."""
    n = 4
    return LumpedCable(S=[3.0, 2.5, 2.8, 3.1, 2.9], EA=2.0e4, masses=[2.0, 3.0, 2.5, 1.5],
                       B=[12.0, 3.0, 2.0], F0=np.tile([5.0, 30.0, 8.0], n),
                       FL=np.tile([1.0, 4.0, 2.0], n), uA=[0.002, 0.001, 0.003], uB=[-0.001, 0.002, 0.001],
                       phA=0.3, phB=1.1, a0=0.05, a1=0.002)


# ----------------------------------------------------------------------------------------------
# The model
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["spatial-span", "stay-anchorage", "paper-example", "heavy-span"])
def test_own_lumping_rules_give_the_case_formats_numbers(name):
    data = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    data["damping"] = {"a0": 0.01, "a1": 0.001}  # the damping rule is checked below, on the modes
    own, case = cable_from_yaml(data), cable_from_case(load_case(data))
    for key in ("S", "masses", "F0", "FL", "uA", "uB", "B", "EA", "phA", "phB", "a0", "a1"):
        np.testing.assert_allclose(getattr(own, key), getattr(case, key), rtol=1e-13, atol=0, err_msg=key)


@pytest.mark.parametrize("text", [WHIRL_CASE, STAY_CASE.format(nodes=5, omega=12.0)], ids=["whirl", "stay"])
def test_the_reference_cases_read_alike_both_ways(text):
    own, case = cable_from_yaml(yaml.safe_load(text)), cable_from_case(load_case(yaml.safe_load(text)))
    for key in ("S", "masses", "F0", "FL", "uA", "uB", "B", "EA", "a0", "a1"):
        np.testing.assert_allclose(getattr(own, key), getattr(case, key), rtol=1e-13, atol=0, err_msg=key)


def undamped(name):
    data = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    data["damping"] = {"a0": 0.0, "a1": 0.0}
    return cable_from_yaml(data)


CABLES = {
    "skew": skew_cable,
    "spatial-span": lambda: undamped("spatial-span"),  # a sideways wind: a spatial equilibrium
    "paper": lambda: undamped("paper-example"),
    "whirl": lambda: cable_from_case(whirl_case()),
    "stay": lambda: cable_from_case(stay_case(5)),
}


@pytest.mark.parametrize("name", ["skew", "spatial-span", "paper", "whirl", "stay"])
def test_static_solver_residual_and_tangents_against_central_differences(name):
    c = CABLES[name]()
    y = static_equilibrium(c)
    pts = np.vstack((np.zeros(c.dim), y.reshape(-1, c.dim), c.B))
    l = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    scale = max(np.abs(c.F0).max(), (c.EA * (l - c.S) / c.S).max())
    assert np.abs(force(c, y) - c.F0).max() < 1e-8 * scale
    # the tangent stiffness, and the support tangent, by central differences of the force
    h = 1e-6 * max(np.linalg.norm(c.B), 1.0)
    K, Ks = stiffness(c, y), support_stiffness(c, y)
    fd = np.column_stack([(force(c, y + h * e) - force(c, y - h * e)) / (2 * h) for e in np.eye(y.size)])
    assert np.abs(K - fd).max() < 1e-6 * np.abs(K).max()
    zero = np.zeros(c.dim)
    fds = np.column_stack(
        [(force(c, y, h * e, zero) - force(c, y, -h * e, zero)) / (2 * h) for e in np.eye(c.dim)]
        + [(force(c, y, zero, h * e) - force(c, y, zero, -h * e)) / (2 * h) for e in np.eye(c.dim)])
    assert np.abs(Ks - fds).max() < 1e-6 * np.abs(K).max()
    # a rigid translation of cable and supports deforms nothing: K0 v + K0s s' = 0
    v = np.array([0.3, -0.2, 0.1][: c.dim])
    assert np.abs(K @ np.tile(v, c.n) + Ks @ np.concatenate((v, v))).max() < 1e-9 * np.abs(K).max()


def test_in_plane_modes_are_the_planar_forms_and_out_of_plane_ones_the_beaded_strings():
    case = stay_case(5)
    c = cable_from_case(case)
    ip, op = natural_frequencies(c, static_equilibrium(c))
    ip_planar, none = natural_frequencies(c.planar(), static_equilibrium(c.planar()))
    assert none.size == 0 and ip.size == 2 * c.n and op.size == c.n
    np.testing.assert_allclose(ip, ip_planar, rtol=1e-12)
    cf = stay_mathieu(case)
    closed = [lumped_string_frequency(cf.tension, cf.node_mass, cf.segment, c.n, k) for k in range(1, c.n + 1)]
    np.testing.assert_allclose(op, closed, rtol=1e-10)
    # damping.modes counts the modes that are not out of the plane: ratio 0.002 in in-plane modes 1, 2
    zeta = c.a0 / (2 * ip[:2]) + c.a1 * ip[:2] / 2
    np.testing.assert_allclose(zeta, case.damping.ratio, rtol=1e-12)


def test_compiled_acceleration_is_the_numpy_formulation():
    c = skew_cable()
    motion = Motion(c, 3.7, gamma=0.8)
    rng = np.random.default_rng(1)
    for t in (0.0, 0.4, 1.3):
        y = motion.y0 + 0.05 * rng.standard_normal(motion.N)
        v = rng.standard_normal(motion.N)
        a = motion.acceleration(t, y[:, None], v[:, None])[:, 0]
        np.testing.assert_allclose(a, motion.acceleration_numpy(t, y, v), rtol=1e-12, atol=1e-12 * np.abs(a).max())


def test_string_stiffness_is_the_out_of_plane_tangent_of_the_spatial_force():
    """K_w(t) = tridiagonal of T_r / l_r: central differences of the full spatial force in w at a
    planar state away from equilibrium (supports displaced in their plane), and no w-x, w-v
    coupling."""
    rng = np.random.default_rng(2)
    whirl, stay = cable_from_case(whirl_case()), cable_from_case(stay_case(4))
    slack = replace(whirl, S=np.array([1.2, 0.95]))  # segment 1 slack at whirl's equilibrium
    for c, ref in ((whirl, whirl), (stay, stay), (slack, whirl)):
        yp = static_equilibrium(ref.planar())
        yp = yp + 1e-3 * rng.standard_normal(yp.size)
        sA, sB = np.array([0.01, -0.02, 0.0]), np.array([-0.015, 0.005, 0.0])
        y = to_spatial(yp)
        w = np.arange(2, 3 * c.n, 3)
        h = 1e-7
        fd = np.column_stack([(force(c, y + h * e, sA, sB) - force(c, y - h * e, sA, sB)) / (2 * h)
                              for e in np.eye(y.size)[w]])
        Kw = string_stiffness(c, yp, sA[:2], sB[:2])
        assert np.abs(fd[w] - Kw).max() < 1e-6 * np.abs(Kw).max()
        assert np.abs(np.delete(fd, w, axis=0)).max() < 1e-6 * np.abs(Kw).max()


# ----------------------------------------------------------------------------------------------
# Flow and monodromy
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("which", ["whirl", "stay"])
def test_planar_form_is_the_spatial_form_with_w_zero(which):
    case = whirl_case() if which == "whirl" else stay_case(3)
    c = cable_from_case(case)
    omega = 4.6 if which == "whirl" else 11.9
    planar, spatial = Motion(c.planar(), omega), Motion(c, omega)
    np.testing.assert_allclose(spatial.y0, to_spatial(planar.y0), rtol=0, atol=1e-13 * np.abs(planar.y0).max())
    ip = planar_indices(c.n)
    np.testing.assert_allclose(spatial.K0[np.ix_(ip, ip)], planar.K0, rtol=1e-12, atol=1e-12 * np.abs(planar.K0).max())
    x0 = planar.static_state()
    x0[planar.N + 1] += 0.1  # a vertical velocity of node 1
    xp, _ = flow(planar, x0)
    xs, _ = flow(spatial, spatial_state(x0))
    w = np.concatenate((np.arange(2, 3 * c.n, 3), 3 * c.n + np.arange(2, 3 * c.n, 3)))
    assert np.all(xs[w] == 0.0)
    keep = np.delete(np.arange(xs.size), w)
    assert np.abs(xs[keep] - xp).max() < 1e-9 * np.abs(xp - x0).max()


def test_variational_monodromy_matches_central_differences_of_the_flow():
    """Over one period of the forcing, from states off the plane (every block coupled): the
    one-node cable, and a skew cable with both supports moving in space."""
    c = cable_from_case(whirl_case())
    # steps ~1e-3 of the smallest segment stretch (2 cm, 1 cm): truncation O(h^2) below 1e-8
    for motion, offset, step in ((Motion(c, 4.6), [0.0, 0.03, 0.02], 1e-5), (Motion(skew_cable(), 2.0), 0.002, 1e-6)):
        x0 = motion.static_state()
        x0[: motion.N] += np.resize(offset, motion.N)
        x0[motion.N :] += 0.01
        _, Phi = flow(motion, x0, variational=True)
        fd = fd_monodromy(motion, x0, rel_step=step)
        assert np.abs(Phi - fd).max() < 1e-7 * np.abs(Phi).max()


def test_hill_monodromy_is_the_out_of_plane_block_of_the_spatial_monodromy():
    """Along a planar motion (from a displaced planar state, supports moving for the stay) the
    spatial variational monodromy has no coupling between (w, w') and the plane, and its (w, w')
    block is the monodromy of M dw'' + (a0 M + a1 K0_ww) dw' + K_w(t) dw = 0."""
    for c, omega in ((cable_from_case(whirl_case()), 4.6), (cable_from_case(stay_case(2)), 11.6)):
        planar = Motion(c.planar(), omega)
        x0 = planar.static_state()
        x0[1] += 0.02
        _, Phi = flow(Motion(c, omega), spatial_state(x0), variational=True)
        W = out_of_plane_monodromy(planar, x0)
        block = out_of_plane_block(Phi, c.n)
        assert np.abs(block - W).max() < 1e-8 * np.abs(W).max()
        w = np.concatenate((np.arange(2, 3 * c.n, 3), 3 * c.n + np.arange(2, 3 * c.n, 3)))
        rest = np.delete(np.arange(Phi.shape[0]), w)
        assert np.abs(Phi[np.ix_(w, rest)]).max() == 0 and np.abs(Phi[np.ix_(rest, w)]).max() == 0


@pytest.mark.slow
def test_out_of_plane_multipliers_of_a_periodic_orbit_both_ways():
    """On the one-node cable's planar periodic response at 4.6 rad/s (unstable out of the plane):
    the spatial orbit's monodromy (variational, and central differences) and the Hill
    multipliers agree; the planar multipliers are those of the spatial monodromy's planar block."""
    c = cable_from_case(whirl_case())
    spatial = Motion(c, 4.6)
    orbit = periodic_orbit(spatial)
    fd = fd_monodromy(spatial, orbit.x0)
    assert np.abs(orbit.monodromy - fd).max() < 1e-7 * np.abs(fd).max()
    planar = Motion(c.planar(), 4.6)
    keep = np.concatenate((planar_indices(1), 3 + planar_indices(1)))
    hill = floquet_multipliers(out_of_plane_monodromy(planar, orbit.x0[keep]))
    block = floquet_multipliers(out_of_plane_block(orbit.monodromy, 1))
    np.testing.assert_allclose(hill, block, rtol=1e-9)
    assert abs(hill[0]) > 1.005  # the planar response whirls here
    mu_planar = floquet_multipliers(orbit.monodromy[np.ix_(keep, keep)])
    assert np.abs(mu_planar).max() < 0.98


# ----------------------------------------------------------------------------------------------
# The whirling pitchfork of the one-node cable
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def gamma_pitchfork():
    return pitchfork_amplitude(whirl_case())


@pytest.fixture(scope="module")
def omega_pitchfork():
    return pitchfork_omega(whirl_case())


@pytest.mark.slow
def test_whirling_pitchfork_in_omega_and_in_gamma_agree(gamma_pitchfork, omega_pitchfork):
    """The frequency at the case's amplitude and the amplitude at that frequency are one point;
    the multiplier there is +1, real, with the planar branch stable."""
    case = whirl_case()
    at_omega = omega_pitchfork
    assert abs(at_omega.multipliers[0] - 1.0) < 1e-9 and at_omega.multipliers.imag.max() == 0
    back = pitchfork_amplitude(case, bracket=(0.99, 1.01), omega=at_omega.value)
    assert abs(back.value - 1.0) < 1e-9
    for p in (at_omega, gamma_pitchfork):
        planar = Motion(cable_from_case(case).planar(), p.omega, p.gamma)
        Phi = flow(planar, p.orbit.x0, variational=True)[1]
        assert np.abs(floquet_multipliers(Phi)).max() < 0.98
    assert abs(gamma_pitchfork.multipliers[0] - 1.0) < 1e-9


@pytest.mark.slow
def test_whirling_orbits_follow_the_square_root_law(gamma_pitchfork):
    """max|w|^2 = c (gamma - gamma_c) + O(h^4): c(h) from three nonplanar orbits converges at
    second order in the branch parameter h; the branch leaves on the side where the planar
    response is unstable (supercritical)."""
    gc = gamma_pitchfork.value
    orbits = [whirling_orbit(whirl_case(), gamma_pitchfork, h) for h in (0.01, 0.005, 0.0025)]
    assert all(o.value > gc for o in orbits)
    ratio = [o.max_w**2 / (o.value - gc) for o in orbits]
    assert abs(ratio[2] - ratio[1]) < 0.05 * ratio[2]
    assert 3.0 < (ratio[1] - ratio[0]) / (ratio[2] - ratio[1]) < 5.0
    mw = [o.max_w for o in orbits]
    assert 1.9 < mw[0] / mw[1] < 2.1 and 1.9 < mw[1] / mw[2] < 2.1


@pytest.mark.slow
def test_whirling_orbits_in_omega_follow_the_square_root_law(omega_pitchfork):
    """In omega the branch also leaves where the planar response is unstable (omega > omega_c),
    max|w|^2 / (omega - omega_c) the same at two orbits to 0.2 %."""
    wc = omega_pitchfork.value
    orbits = [whirling_orbit(whirl_case(), omega_pitchfork, h) for h in (0.01, 0.005)]
    assert all(o.value > wc for o in orbits)
    ratio = [o.max_w**2 / (o.value - wc) for o in orbits]
    assert abs(ratio[0] / ratio[1] - 1) < 2e-3


# ----------------------------------------------------------------------------------------------
# The damped Mathieu closed form
# ----------------------------------------------------------------------------------------------
def _numerical_edges(w1, zeta, eps):
    lo, hi = mathieu_edges(w1, zeta, eps)
    mid, width = 0.5 * (lo + hi), hi - lo

    def f(w):
        return abs(mathieu_multipliers(w1, zeta, eps, w)[0]) - 1.0

    return brentq(f, lo - 0.5 * width, mid, xtol=1e-13), brentq(f, mid, hi + 0.5 * width, xtol=1e-13)


def test_mathieu_edges_converge_at_second_order_in_eps():
    w1 = 1.3
    errors = []
    for eps in (0.04, 0.02, 0.01):
        closed = np.array(mathieu_edges(w1, eps / 8, eps))  # damping at half the threshold
        errors.append(np.abs(np.array(_numerical_edges(w1, eps / 8, eps)) - closed))
        assert errors[-1].max() < 0.05 * eps**2 * w1
    for a, b in zip(errors[:-1], errors[1:]):
        assert np.all(np.abs(np.log2(a / b) - 2.0) < 0.1)


@pytest.mark.slow
def test_mathieu_threshold_error_is_third_order_in_zeta():
    w1, found = 0.8, []
    for zeta in (0.01, 0.005):
        ec = mathieu_threshold(zeta)
        lo, hi = mathieu_edges(w1, zeta, 1.5 * ec)

        def edge(w):
            return brentq(lambda e: abs(mathieu_multipliers(w1, zeta, e, w)[0]) - 1, 0.5 * ec, 3 * ec, xtol=1e-15)

        from scipy.optimize import minimize_scalar
        res = minimize_scalar(edge, bounds=(lo, hi), method="bounded", options={"xatol": 1e-8})
        found.append(abs(res.fun - ec))
        assert found[-1] < 3 * zeta**3  # measured: 1.75 zeta^3
    assert abs(math.log2(found[0] / found[1]) - 3.0) < 0.15


def test_lumped_string_frequency_tends_to_the_continuous_at_second_order():
    T, mu, length = 2.0e6, 80.0, 100.0
    err = []
    for n in (7, 15, 31):
        h = length / (n + 1)
        err.append(1 - lumped_string_frequency(T, mu * h, h, n) / continuous_string_frequency(T, mu, length))
    for a, b in zip(err[:-1], err[1:]):
        assert abs(math.log2(a / b) - 2.0) < 0.02


# ----------------------------------------------------------------------------------------------
# The parametric tongue of the taut stay against the closed form
# ----------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_stay_tongue_edges_against_mathieu_as_nodes_grow():
    """The edges (numerical Floquet of the reference) agree with the lumped closed form to
    O(eps^2) (eps = 0.033: eps^2/32 of 2 w1 is 3e-5); the tongue's centre tends to the
    continuous string's 2 w1 at second order in 1/(n+1)."""
    centre_err = []
    for n in (3, 7):
        case = stay_case(n)
        cf = stay_mathieu(case)
        tongue = tongue_edges(case)
        for located, closed in zip((tongue.lower, tongue.upper), cf.edges()):
            assert abs(located.multipliers[0] + 1.0) < 1e-9
            assert abs(located.value - closed) < 1e-4 * 2 * cf.w1
        centre = 0.5 * (tongue.lower.value + tongue.upper.value)
        centre_err.append(abs(centre - 0.5 * sum(cf.edges(continuous=True))))
    assert abs(math.log2(centre_err[0] / centre_err[1]) - 2.0) < 0.15


@pytest.mark.slow
def test_stay_threshold_against_mathieu():
    case = stay_case(3)
    cf = stay_mathieu(case)
    tip = tongue_threshold(case)
    assert abs(tip.gamma_c / cf.threshold_gamma() - 1) < 5e-3
    assert abs(tip.omega_c / (2 * cf.w1) - 1) < 1e-4
