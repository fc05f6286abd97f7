"""Periodic orbits of spatial cables: the planar analysis run in space, the split of a planar
orbit's monodromy into its in-plane and out-of-plane blocks, and the out-of-plane bifurcations.

References written here, independent of the orbit code: the planar cable's own continuation;
the out-of-plane linearisation about a planar orbit, ``M w'' + (a0 M + a1 K0_ww) w' + K_w(t) w = 0``
with ``K_w(t)`` the string tridiagonal of the segment tensions over their lengths ``T_r / l_r``,
integrated with the planar motion by scipy's DOP853 from the segment forces written out below.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cablesim.analyses.continuation import run_continuation
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import case_from_dict
from cablesim.orbits import Shooting, cable_system, continue_branches, linear_response_state, solve_orbit
from cablesim.orbits.symmetry import split_multipliers

#: The paper's example cable (two nodes).
PAPER = {
    "cable": {"L": 300.0, "H": 20.0, "S": [130.0, 100.0, 110.0], "EA": 1.0e9, "masses": [8000.0, 14000.0]},
    "loads": {"F0": [300.0e3, 1100.0e3, 450.0e3, 2000.0e3], "FL": [-6.0e3, 22.0e3, -18.0e3, 120.0e3]},
    "damping": {"ratio": 0.01, "modes": [1, 2]},
}
#: A single mass on two segments, shallow sag, forced vertically: its out-of-plane (pendulum
#: like) mode is excited parametrically by the tension the in-plane motion modulates.
BEAD = {
    "cable": {"L": 2.0, "H": 0.0, "S": [1.02, 1.02], "EA": 2000.0, "masses": [1.0]},
    "loads": {"F0": [0.0, 9.81], "FL": [0.0, 0.6]},
    "damping": {"ratio": 0.005, "modes": [1, 2]},
}


def case_of(base: dict, spatial: bool, **sections):
    data = copy.deepcopy(base)
    data.update(sections)
    if spatial:
        data["spatial"] = True
    return case_from_dict(data)


def equations(case, omega):
    static = run_static(case)
    return build_equations(case, static, omega=omega)


def planar_orbit(eom, omega):
    """The periodic orbit of the spatial cable at ``omega`` from the linear response."""
    sh = Shooting(cable_system(eom))
    sol = solve_orbit(sh, linear_response_state(eom, omega), omega)
    assert sol.converged
    return sh, sol


# ------------------------------------------------------------------------------------------------
# The independent out-of-plane linearisation about a planar orbit
# ------------------------------------------------------------------------------------------------
def segment_geometry(eom, y):
    """Positions of supports and nodes (n + 2, 2) in the plane, segment lengths and tensions."""
    c = eom.cable
    A = np.asarray(c.support_A, dtype=float)[:2]
    B = np.asarray(c.support_B, dtype=float)[:2]
    pts = np.vstack([A, y.reshape(-1, 2), B])
    d = np.diff(pts, axis=0)
    l = np.linalg.norm(d, axis=1)
    S = np.asarray(c.S, dtype=float)
    T = np.maximum(c.EA * (l - S) / S, 0.0)
    return d, l, T


def planar_resisting_force(eom, y):
    """``P(y)``: at every node ``T_r e_r - T_{r+1} e_{r+1}`` (segment r ends at node r)."""
    d, l, T = segment_geometry(eom, y)
    f = (T / l)[:, None] * d
    return (f[:-1] - f[1:]).ravel()


def string_stiffness(T, l):
    """The out-of-plane stiffness of the string: tridiagonal in ``T_r / l_r``."""
    k = T / l
    n = k.size - 1
    K = np.diag(k[:-1] + k[1:])
    K -= np.diag(k[1:-1], 1) + np.diag(k[1:-1], -1)
    return K


def out_of_plane_multipliers(eom, x0_spatial, omega):
    """Floquet multipliers of the out-of-plane linearisation about the orbit through the spatial
    state ``x0_spatial`` (whose out-of-plane part is zero), integrated here with the planar motion."""
    n = eom.cable.n_nodes
    z = x0_spatial[: 3 * n].reshape(n, 3)
    v = x0_spatial[3 * n:].reshape(n, 3)
    y0 = eom.y0.reshape(n, 3)[:, :2].ravel()
    m2 = np.repeat(eom.cable.masses, 2)
    ip = np.array([[3 * i, 3 * i + 1] for i in range(n)]).ravel()
    wi = np.arange(n) * 3 + 2
    C2 = eom.C[np.ix_(ip, ip)]
    Cw = eom.C[np.ix_(wi, wi)]
    F0, FL = eom.F0[ip], eom.FL[ip]
    mw = eom.cable.masses

    def rhs(t, s):
        q, p = s[: 2 * n], s[2 * n: 4 * n]
        Y = s[4 * n:].reshape(2 * n, 2 * n)  # (w, w') variations, columns the initial conditions
        acc = (F0 + FL * np.sin(omega * t) - C2 @ p - planar_resisting_force(eom, y0 + q)) / m2
        _, l, T = segment_geometry(eom, y0 + q)
        Kw = string_stiffness(T, l)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Kw / mw[:, None], -Cw / mw[:, None]]])
        return np.concatenate([p, acc, (A @ Y).ravel()])

    s0 = np.concatenate([z[:, :2].ravel(), v[:, :2].ravel(), np.eye(2 * n).ravel()])
    sol = solve_ivp(rhs, (0.0, 2 * np.pi / omega), s0, method="DOP853", rtol=1e-12, atol=1e-13)
    end = sol.y[:, -1]
    drift = np.abs(end[: 4 * n] - s0[: 4 * n]).max()
    return np.linalg.eigvals(end[4 * n:].reshape(2 * n, 2 * n)), drift


def assert_same_multipliers(a, b, tol):
    a, b = np.asarray(a, dtype=complex), list(np.asarray(b, dtype=complex))
    assert len(a) == len(b)
    for mu in a:
        k = int(np.argmin([abs(mu - x) for x in b]))
        assert abs(mu - b[k]) < tol, (a, b)
        b.pop(k)


# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_spatial_continuation_of_an_in_plane_case_is_the_planar_one():
    """The same branch, the same located period doublings and the planar multipliers as the
    in-plane block, over the paper's period-doubling band; every channel of the spatial case
    is reported (x, v, w of both nodes)."""
    flat = run_continuation(case_of(PAPER, False, continuation={"omega": {"start": 5.0, "stop": 5.1},
                                                                 "switch_branches": False}))
    space = run_continuation(case_of(PAPER, True, continuation={"omega": {"start": 5.0, "stop": 5.1},
                                                                 "switch_branches": False}))
    assert space.channels == [f"z{i + 1}" for i in range(6)]
    b3 = space.branches[0]
    # every spatial point (the steps differ: the arclength counts the out-of-plane components)
    # is a periodic orbit of the planar cable, with the planar cable's multipliers in-plane
    planar = Shooting(cable_system(equations(case_of(PAPER, False), 5.0)))
    spatial = Shooting(cable_system(equations(case_of(PAPER, True), 5.0)))
    ip = np.array([0, 1, 3, 4, 6, 7, 9, 10])
    assert np.all(b3.amplitude[:, [2, 5]] < 1e-12)
    for k in range(b3.parameter.size):
        x = b3.state[k]
        ev = planar.evaluate(x[ip], b3.parameter[k])
        ev3 = spatial.evaluate(x, b3.parameter[k], jac=False)
        for half in (slice(0, 4), slice(4, 8)):  # displacements, velocities: at Newton's tolerance
            assert np.abs(ev.r[half]).max() < 1e-7 * np.abs(x[ip][half]).max()
        np.testing.assert_allclose(ev3.r[ip], ev.r, rtol=0, atol=1e-12 * np.abs(x).max())  # one map, to round-off
        mu_in = b3.multipliers[k][b3.planes[k] == "in-plane"]
        assert_same_multipliers(mu_in, ev.multipliers, 1e-8)
    pd2 = sorted(b.parameter for b in flat.bifurcations if b.kind == "period-doubling")
    pd3 = sorted(b.parameter for b in space.bifurcations if b.kind == "period-doubling")
    assert len(pd2) == 2 and np.allclose(pd3, pd2, rtol=0, atol=1e-8)
    assert all(b.plane == "in-plane" for b in space.bifurcations)


def test_planar_monodromy_splits_and_its_out_of_plane_block_is_the_string_linearisation():
    omega = 2.4
    eom = equations(case_of(PAPER, True), omega)
    sh, sol = planar_orbit(eom, omega)
    mirror = sh.system.mirror
    assert mirror is not None and mirror.n_odd == 4 and mirror.is_planar(sol.u, np.abs(sol.u).max() + 0 * sol.u)
    Q = mirror.Q
    np.testing.assert_allclose(Q.T @ Q, np.eye(12), atol=1e-15)
    _, _, off = mirror.blocks(sol.evaluation.monodromy)
    assert off < 1e-13
    mu_in, mu_out = split_multipliers(mirror, sol.evaluation.monodromy)
    assert mu_in.size == 8 and mu_out.size == 4
    reference, drift = out_of_plane_multipliers(eom, sol.u, omega)
    assert drift < 1e-8 * np.abs(sol.u).max()  # the orbit is periodic in the independent integration
    assert_same_multipliers(mu_out, reference, 1e-8)
    # and the whole spectrum is the union of the blocks'
    assert_same_multipliers(np.concatenate([mu_in, mu_out]), sol.evaluation.multipliers, 1e-9)


def test_a_load_out_of_the_plane_breaks_the_mirror():
    FL = [-6.0e3, 22.0e3, 1.0e3, -18.0e3, 120.0e3, 0.0]
    tilted = case_of(PAPER, True, loads={"F0": PAPER["loads"]["F0"], "FL": FL})
    assert cable_system(equations(tilted, 2.4)).mirror is None
    assert cable_system(equations(case_of(PAPER, False), 2.4)).mirror is None


def band_to_dense_of_one_node():
    """A one-node spatial cable's banded stiffness (6 rows for 3 unknowns) as a dense matrix."""
    from cablesim.statics import band_to_dense

    band = np.arange(18.0).reshape(6, 3)
    return band_to_dense(band)


def test_a_band_deeper_than_its_matrix_is_cut():
    A = band_to_dense_of_one_node()
    assert A.shape == (3, 3) and np.array_equal(A, A.T)
    assert A[0, 0] == 0.0 and A[1, 0] == 3.0 and A[2, 0] == 6.0 and A[2, 1] == 4.0 and A[2, 2] == 2.0


def bead(FL: float):
    return case_of(BEAD, True, loads={"F0": BEAD["loads"]["F0"], "FL": [0.0, FL]})


def located_crossing(eom, omega_b, x_b, target, h=1e-5, **integration):
    """Where the independent out-of-plane multiplier nearest ``target`` (+1 or -1) passes it,
    by linear interpolation between planar orbits at ``omega_b +- h`` (the multiplier curves:
    at h = 2e-4 the interpolation alone is 1.3e-6 off)."""
    sh = Shooting(cable_system(eom), **integration)
    values = []
    for w in (omega_b - h, omega_b + h):
        sol = solve_orbit(sh, x_b, w)
        assert sol.converged
        mu, drift = out_of_plane_multipliers(eom, sol.u, w)
        assert drift < 1e-8 * np.abs(sol.u).max()
        values.append(float(mu[np.argmin(np.abs(mu - target))].real) - target)
    (w0, w1), (f0, f1) = (omega_b - h, omega_b + h), values
    assert f0 * f1 < 0.0, values  # the crossing is between them
    return w0 - f0 * (w1 - w0) / (f1 - f0)


def out_of_plane_diagram(FL, start, stop, **integration):
    eom = equations(bead(FL), start)
    return eom, continue_branches(eom, "omega", start, stop, switch_branches=False, **integration)


def test_parametric_tongue_of_a_bead_is_an_out_of_plane_period_doubling_pair():
    """Forced in its plane near twice its out-of-plane frequency (6.285 rad/s), the bead's planar
    orbit loses stability across the plane: an out-of-plane multiplier through -1 at both edges of
    the tongue, located to 1e-6 in omega by the independent linearisation."""
    eom, d = out_of_plane_diagram(0.6, 12.0, 13.2)
    br = d.branches[0]
    assert br.planar and br.end.name == "BOUND_REACHED"
    assert [(b.kind, b.plane) for b in d.bifurcations] == [("period-doubling", "out-of-plane")] * 2
    for b in d.bifurcations:
        assert abs(b.multiplier + 1.0) < 1e-8
        w_ref = located_crossing(eom, b.parameter, b.state, -1.0)
        assert abs(w_ref - b.parameter) < 1e-6, (w_ref, b.parameter)
    inside = [p for p in br.points if d.bifurcations[0].parameter < p.parameter < d.bifurcations[1].parameter]
    assert inside and not any(p.stable for p in inside)
    assert all(p.planes.count("out-of-plane") == 2 for p in br.points)


def test_whirling_onset_is_a_pitchfork_never_a_fold_of_the_planar_branch():
    """Near its out-of-plane frequency the bead's planar orbit (forced harder) loses stability to
    a nonplanar one: an out-of-plane multiplier through +1, a pitchfork on each side, located to
    1e-6 in omega by the independent linearisation; the planar branch has no fold or branch point
    there (a test on the whole monodromy sees +1 and cannot tell)."""
    eom, d = out_of_plane_diagram(5.0, 5.0, 6.6)
    assert [(b.kind, b.plane) for b in d.bifurcations] == [("pitchfork", "out-of-plane")] * 2
    values = d.branches[0].values
    assert np.all(np.diff(values) > 0)  # no turning point: the planar branch goes straight through
    for b in d.bifurcations:
        assert abs(b.multiplier - 1.0) < 1e-8
        w_ref = located_crossing(eom, b.parameter, b.state, 1.0)
        assert abs(w_ref - b.parameter) < 1e-6, (w_ref, b.parameter)


def test_continue_command_stores_and_names_the_out_of_plane_bifurcations(tmp_path):
    """`cablesim continue` on the bead across its whirling onset: the file's bifurcations carry
    their plane, the branches the block of every multiplier, the summary names both."""
    import h5py
    import yaml
    from typer.testing import CliRunner

    from cablesim.cli import app
    from cablesim.io.continuation import read_continuation

    data = copy.deepcopy(BEAD)
    data.update(spatial=True, name="bead")
    data["loads"]["FL"] = [0.0, 5.0]
    data["continuation"] = {"omega": {"start": 5.0, "stop": 6.6}, "switch_branches": False}
    path = tmp_path / "bead.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "bead.h5"
    res = CliRunner().invoke(app, ["continue", str(path), "-o", str(out)])
    assert res.exit_code == 0, (res.stdout, res.exception)
    assert "pitchfork" in res.stdout and "out-of-plane" in res.stdout
    d = read_continuation(out)
    assert d["channels"] == ["z1", "z2", "z3"]  # every component of the spatial node (x, v, w)
    assert d["bifurcations"]["kind"] == ["pitchfork", "pitchfork"]
    assert d["bifurcations"]["plane"] == ["out-of-plane", "out-of-plane"]
    np.testing.assert_allclose(d["bifurcations"]["frequency_ratio"], 0.0, atol=1e-9)  # mu = +1
    b = d["branches"][0]
    assert b["planar"] and b["multiplier_plane"].shape == b["multipliers"].shape
    assert np.all((b["multiplier_plane"] == "out-of-plane").sum(axis=1) == 2)
    with h5py.File(out) as f:
        assert f["continuation/bifurcations/plane"].attrs["units"] == "1"


def spatial_rhs(eom, omega):
    """The spatial cable's equations of motion ``M y'' + C y' + P(y) = F0 + FL sin(omega t)``
    for the state ``(z, y')``, written here from the segment forces (P(y0) taken as F0)."""
    c = eom.cable
    A = np.asarray(c.support_A, dtype=float)
    B = np.asarray(c.support_B, dtype=float)
    S = np.asarray(c.S, dtype=float)
    nd = eom.n_dof
    m = eom.mass

    def force(y):
        d = np.diff(np.vstack([A, y.reshape(-1, 3), B]), axis=0)
        l = np.linalg.norm(d, axis=1)
        f = (np.maximum(c.EA * (l - S) / S, 0.0) / l)[:, None] * d
        return (f[:-1] - f[1:]).ravel()

    F0 = force(eom.y0)

    def rhs(t, s):
        z, v = s[:nd], s[nd:]
        return np.concatenate([v, (F0 + eom.FL * np.sin(omega * t) - eom.C @ v - force(eom.y0 + z)) / m])

    return rhs


def test_whirling_branch_is_born_at_the_pitchfork_and_is_a_nonplanar_orbit():
    """Switched at the upper pitchfork (6.388 rad/s), the nonplanar branch leaves the plane along
    the out-of-plane null vector; its out-of-plane amplitude follows the normal form's square-root
    law near the pitchfork, its mirror image is reported, and its orbits are periodic orbits of an
    independent integration of the spatial equations of motion (stable whirling)."""
    eom = equations(bead(5.0), 6.0)
    d = continue_branches(eom, "omega", 6.0, 6.6)
    pf = [b for b in d.bifurcations if b.kind == "pitchfork"]
    assert len(pf) == 1 and pf[0].child is not None
    whirl = d.branches[pf[0].child]
    assert whirl.mirror_image and not whirl.planar and whirl.parent == pf[0].branch
    assert whirl.points[0].parameter == pf[0].parameter
    lam0 = pf[0].parameter
    near = [p for p in whirl.points[1:] if abs(p.parameter - lam0) < 0.1]
    assert len(near) >= 2
    dl = np.array([abs(p.parameter - lam0) for p in near])
    w = np.array([p.amplitude[2] for p in near])
    slope = np.polyfit(np.log(dl), np.log(w), 1)[0]
    assert abs(slope - 0.5) < 0.05, slope
    p = near[-1]
    sol = solve_ivp(spatial_rhs(eom, p.omega), (0.0, 2 * np.pi / p.omega), p.state, method="DOP853",
                    rtol=1e-12, atol=1e-14)
    # (at the continuation's Newton tolerance; a wrong orbit would be off by its own size)
    assert np.abs(sol.y[:, -1] - p.state).max() < 1e-7 * np.abs(p.state).max()
    assert np.abs(p.state[[2, 5]]).max() > 0.01  # well out of the plane
    assert p.stable
    # whirling measures against the same orbit sampled by the independent integration
    t = np.linspace(0.0, 2 * np.pi / p.omega, 2001)
    ref = solve_ivp(spatial_rhs(eom, p.omega), (t[0], t[-1]), p.state, method="DOP853", rtol=1e-12,
                    atol=1e-14, t_eval=t).y
    v, w = ref[1], ref[2]  # the plane's frame is (x, v, w) for this level span
    area = 0.5 * np.trapezoid(w * np.gradient(v, t) - v * np.gradient(w, t), t)
    assert p.whirl.area[0] == pytest.approx(area, rel=1e-4)
    evals, evecs = np.linalg.eigh(np.cov(np.vstack([v, w])))
    tilt = np.degrees(np.arctan2(abs(evecs[1, -1]), abs(evecs[0, -1])))
    assert p.whirl.tilt == pytest.approx(tilt, abs=0.05)
    assert 45.0 < tilt < 90.0 and abs(area) > 1e-4  # mostly across the plane, going round
    planar = d.branches[pf[0].branch]
    assert all(q.whirl is None for q in planar.points)


def test_out_of_plane_period_doubling_is_switched_onto_a_nonplanar_period_two_branch():
    """At the lower edge of the bead's parametric tongue the period-2 branch leaves the plane:
    its orbits close after two forcing periods (not one) in an independent integration of the
    spatial equations, with a clear out-of-plane motion."""
    eom = equations(bead(0.6), 12.1)
    d = continue_branches(eom, "omega", 12.1, 12.3)
    pd = [b for b in d.bifurcations if b.kind == "period-doubling"]
    assert len(pd) == 1 and pd[0].plane == "out-of-plane" and pd[0].child is not None
    child = d.branches[pd[0].child]
    assert child.period == 2 and not child.planar and len(child.points) > 3
    p = child.points[-1]
    T = 2 * np.pi / p.omega
    sol = solve_ivp(spatial_rhs(eom, p.omega), (0.0, 2 * T), p.state, method="DOP853", rtol=1e-12, atol=1e-14,
                    dense_output=True)
    scale = np.abs(p.state).max()
    assert np.abs(sol.y[:, -1] - p.state).max() < 1e-7 * scale  # closes after two periods
    assert np.abs(sol.sol(T) - p.state).max() > 1e-2 * scale  # but not after one
    assert p.amplitude[2] > 0.01  # w of the bead, m


def test_out_of_plane_multipliers_match_a_finite_difference_monodromy_of_the_spatial_flow():
    """The out-of-plane block's multipliers of the bead's planar orbit are eigenvalues of the
    monodromy of the whole spatial flow by central differences (independent equations of motion
    above, DOP853 at rtol 1e-12, steps 1e-5 of the state's scale: truncation ~1e-10, round-off
    ~1e-8), to 1e-7."""
    omega = 5.5
    eom = equations(bead(5.0), omega)
    sh, sol = planar_orbit(eom, omega)
    _, mu_out = split_multipliers(sh.system.mirror, sol.evaluation.monodromy)
    assert mu_out.size == 2
    rhs, T, x0 = spatial_rhs(eom, omega), 2 * np.pi / omega, sol.u
    scale = np.concatenate([np.full(3, np.abs(x0[:3]).max()), np.full(3, np.abs(x0[3:]).max())])

    def flow(x):
        return solve_ivp(rhs, (0.0, T), x, method="DOP853", rtol=1e-12, atol=1e-15).y[:, -1]

    Phi = np.empty((6, 6))
    for j in range(6):
        h = 1e-5 * scale[j]
        e = np.zeros(6)
        e[j] = h
        Phi[:, j] = (flow(x0 + e) - flow(x0 - e)) / (2 * h)
    fd = np.linalg.eigvals(Phi)
    for mu in mu_out:
        assert np.abs(fd - mu).min() < 1e-7, (mu, fd)


def test_history_from_the_disturbed_planar_orbit_settles_on_the_whirling_orbit():
    """Past the bead's upper pitchfork (6.388 rad/s) the planar orbit is unstable across its
    plane: the third-order time integration started on it with 1 micrometre out of the plane
    settles on the nonplanar orbit the continuation found there (or its mirror image) — the
    state at the forcing phase 0 after 750 periods to 1e-4 of the orbit's size, and max|w| over
    a last period sampled finely to 1e-4 of the continuation's."""
    from cablesim.dynamics.integrators import DOPRI5
    from cablesim.dynamics.simulate import simulate

    d = continue_branches(equations(bead(5.0), 6.0), "omega", 6.0, 6.6)
    (pf,) = [b for b in d.bifurcations if b.kind == "pitchfork"]
    target = min(d.branches[pf.child].points, key=lambda q: abs(q.omega - 6.2))
    assert target.stable and target.amplitude[2] > 0.05
    omega = target.omega
    T = 2 * np.pi / omega
    eom = equations(bead(5.0), omega)
    sh = Shooting(cable_system(eom))
    start = min(d.branches[pf.branch].points, key=lambda q: abs(q.omega - omega))
    planar = solve_orbit(sh, start.state, omega)
    assert planar.converged and np.abs(planar.evaluation.multipliers).max() > 1 and np.abs(planar.u[[2, 5]]).max() < 1e-12
    z0, v0 = planar.u[:3].copy(), planar.u[3:].copy()
    z0[2] = 1e-6
    integ = DOPRI5(rtol=1e-10, atol=1e-13)
    settled = simulate(eom, integ, 750 * T, T / 50, s0=eom.initial_state(z0, v0), split=False)
    end = np.concatenate([settled.z[-1], settled.v[-1]])
    mirror = target.state * np.array([1, 1, -1, 1, 1, -1])
    size = np.abs(target.state).max()
    assert min(np.abs(end - target.state).max(), np.abs(end - mirror).max()) < 1e-4 * size
    last = simulate(eom, integ, T, T / 4000, s0=eom.initial_state(settled.z[-1], settled.v[-1]), split=False)
    assert abs(np.abs(last.z[:, 2]).max() / target.amplitude[2] - 1) < 1e-4
