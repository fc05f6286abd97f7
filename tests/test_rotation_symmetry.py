"""A taut stay without sag is symmetric under rotations about its chord: the multiplier +1 that
the symmetry forces on the orbits it moves is excluded from the bifurcation tests
(:mod:`cablesim.orbits.rotation`), and the period-2 branches born at the stay's parametric
resonance are followed without spurious branch points.

Independent references written here: the generator ``g = (e x y, e x y')`` of the rotation (``e``
the chord's unit vector, support A at the origin) and the monodromy of the reference flow of
``helpers_whirl`` (DOP853 on its own force law, variational equations integrated with it), and the
rotation of an orbit by a finite angle (Rodrigues' formula) integrated by that flow."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
import yaml

from cablesim.analyses.continuation import run_continuation
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import case_from_dict
from cablesim.io.continuation import write_continuation
from cablesim.orbits.rotation import cable_rotation

from helpers_whirl import Motion, cable_from_case, flow
from helpers_whirl_cases import STAY_CASE, stay_case, stay_mathieu, whirl_case


def stay_data(nodes: int = 1, **changes) -> dict:
    data = yaml.safe_load(STAY_CASE.format(nodes=nodes, omega=12.0))
    for key, value in changes.items():
        section, _, name = key.partition(".")
        data[section][name] = value
    return data


@pytest.fixture(scope="module")
def stay_branches():
    """One node of the stay at twice its transverse frequency, continued in gamma across its
    parametric threshold with the period-2 branches followed."""
    case = stay_case(1)
    cf = stay_mathieu(case)
    data = stay_data(1)
    data["continuation"] = {"switch_branches": True, "parameter": "gamma", "omega": float(2 * cf.w1),
                            "gamma": {"start": 0.5 * cf.threshold_gamma(), "stop": 3.0 * cf.threshold_gamma()}}
    return case, float(2 * cf.w1), run_continuation(case_from_dict(data))


def generator(x: np.ndarray, e: np.ndarray) -> np.ndarray:
    n = x.size // 6
    y, v = x[: 3 * n].reshape(n, 3), x[3 * n :].reshape(n, 3)
    return np.concatenate([np.cross(e, y).ravel(), np.cross(e, v).ravel()])


def rotated(x: np.ndarray, e: np.ndarray, angle: float) -> np.ndarray:
    K = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
    R = np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K
    return (x.reshape(-1, 3) @ R.T).ravel()


def test_the_symmetry_is_found_from_the_model():
    """Straight along its chord, loads and support motion along it: the stay has the rotation.
    With gravity (sag out of the chord), with its anchorage moving across the chord, or the
    sagging one-node whirling case: none."""
    def rotation(data):
        case = case_from_dict(data)
        return cable_rotation(build_equations(case, run_static(case), omega=12.0))

    found = rotation(stay_data(1))
    assert found is not None and np.allclose(found.axis, [0.8, -0.6, 0.0], atol=1e-12)
    assert rotation(stay_data(1, **{"loads.gravity": 9.81})) is None
    assert rotation(stay_data(1, **{"supports.A": {"amplitude": [0.004, 0.003, 0.0]}})) is None
    case = whirl_case()
    assert cable_rotation(build_equations(case, run_static(case), omega=4.6)) is None


def test_the_generator_is_an_eigenvector_of_the_monodromy_with_multiplier_one(stay_branches):
    """On an orbit of the nonplanar period-2 branch the reference flow's monodromy maps the
    generator onto itself to its integration accuracy (measured 1e-14), and the orbit rotated by
    0.7 rad about the chord is again periodic (to 4e-9 of its velocities); cablesim's own residual of the excluded multiplier
    is at the level of its monodromy's accuracy."""
    case, omega, res = stay_branches
    (branch,) = [b for b in res.branches if b.period == 2 and not b.planar]
    k = branch.parameter.size // 2
    gamma, x = float(branch.parameter[k]), branch.state[k]
    motion = Motion(cable_from_case(case), omega, gamma)
    e = np.array([0.8, -0.6, 0.0])
    x0 = np.concatenate([motion.y0 + x[:3], x[3:]])  # cablesim's state is (y - y0, y')
    end, M = flow(motion, x0, periods=2.0, variational=True)
    scale = np.abs(x0[3:]).max()
    assert np.abs(end - x0)[3:].max() < 1e-7 * scale  # the orbit is the reference's (period 2)
    g = generator(x0, e)
    assert np.linalg.norm(g) > 1e-3 * np.linalg.norm(x0)  # the orbit leaves the chord line
    assert np.linalg.norm(M @ g - g) / np.linalg.norm(g) < 1e-7
    turned = rotated(x0, e, 0.7)
    assert np.abs(flow(motion, turned, periods=2.0)[0] - turned).max() < 1e-7 * scale
    assert np.isfinite(branch.neutral_residual[1:]).all() and np.nanmax(branch.neutral_residual) < 1e-9


def test_the_period_two_branches_of_the_stay_have_no_spurious_branch_points(stay_branches):
    """Both period-2 branches born at the double multiplier -1 (in the plane and across it)
    run to the end of the range: no pitchfork or branch point on them (the neutral +1 their
    monodromies carry is excluded), the orbits stable (the others inside the circle), and the
    only bifurcations the period doublings of the axial response."""
    _, _, res = stay_branches
    doubled = [b for b in res.branches if b.period == 2]
    assert len(doubled) == 2 and {b.planar for b in doubled} == {True, False}
    for b in doubled:
        assert b.end == "bound reached", b.end
        assert b.stable[1:].all()
        assert np.max(np.abs(b.multipliers[1:]), axis=1).min() > 0.999  # the neutral one, reported
    assert sorted((b.kind, b.plane, b.branch) for b in res.bifurcations) == [
        ("period-doubling", "in-plane", 0), ("period-doubling", "out-of-plane", 0)]
    assert res.branches[0].neutral_residual is None  # the axial response: nothing moved, nothing excluded


def test_the_excluded_multiplier_is_recorded_in_the_results_file(stay_branches, tmp_path):
    """The HDF5 file holds, per point of each period-2 branch, the residual ``|M g - g| / |g|`` of
    the excluded multiplier (NaN at the branch's first point, the period doubling on the axial
    response, where nothing is excluded); the axial branch has none."""
    _, _, res = stay_branches
    path = write_continuation(tmp_path / "stay.h5", res)
    with h5py.File(path, "r") as f:
        groups = f["continuation/branches"]
        axial = groups[res.branches[0].name]
        assert "neutral_residual" not in axial
        for b in res.branches[1:]:
            stored = groups[b.name]["neutral_residual"][()]
            assert np.isnan(stored[0]) and np.all(stored[1:] < 1e-9)
            assert "excluded" in groups[b.name]["neutral_residual"].attrs["description"]


@pytest.mark.parametrize("matrix_free", [False, True])
def test_newton_from_a_start_off_the_family_of_rotated_orbits_converges(stay_branches, matrix_free):
    """The first orbit of a branch solved from a start near, not on, a nonplanar orbit (turned by
    0.3 rad about the chord and enlarged by 2 %): the family of rotated orbits makes the
    periodicity condition's Jacobian singular along the generator, and Newton's method without
    the phase condition ended at its iteration limit, dense and matrix-free (it could not meet
    its correction test along the family). With it both converge in a few steps, to an orbit the
    independent reference flow closes after two forcing periods."""
    from cablesim.orbits.matrixfree import MatrixFreeShooting, solve_orbit_mf
    from cablesim.orbits.shooting import Shooting, SolveStatus, solve_orbit
    from cablesim.orbits.systems import cable_system

    case, omega, res = stay_branches
    (branch,) = [b for b in res.branches if b.period == 2 and not b.planar]
    k = branch.parameter.size // 2
    gamma, x = float(branch.parameter[k]), branch.state[k]
    system = cable_system(build_equations(case, run_static(case), omega=omega, load_scale=gamma), gamma=1.0)
    e = system.rotation.axis
    start = rotated(x, e, 0.3) * 1.02
    scale = np.full(x.size, np.abs(x).max())
    if matrix_free:
        sol = solve_orbit_mf(MatrixFreeShooting(system, period=2, scheme="rk8"), start, scale=scale)
    else:
        sol = solve_orbit(Shooting(system, period=2), start, scale=scale)
    assert sol.status == SolveStatus.CONVERGED and sol.iterations <= 10
    motion = Motion(cable_from_case(case), omega, gamma)
    x0 = np.concatenate([motion.y0 + sol.u[:3], sol.u[3:]])
    assert np.abs(flow(motion, x0, periods=2.0)[0] - x0).max() < 1e-7 * np.abs(x0[3:]).max()


def test_the_pitchfork_direction_is_not_the_generator_of_the_rotation():
    """At a pitchfork of a planar orbit the rotation moves, the out-of-plane block holds two
    multipliers at +1: the generator's ``g`` and the critical ``v``. Here the generator's is
    the nearer (exactly 1 against the located ``1 - 1e-9``), and the eigenvector nearest +1,
    taken without deflation, is ``g``: it leads to the rotated planar orbit. With the rotation's
    phase the direction is the critical null vector without its component along ``g``: in the
    odd subspace, orthogonal to ``g``, a null vector of ``Phi_o - I`` to the located 1e-9."""
    from types import SimpleNamespace

    from cablesim.orbits.switching import pitchfork_direction
    from cablesim.orbits.symmetry import Mirror

    rng = np.random.default_rng(7)
    mirror = Mirror(Q=np.linalg.qr(rng.standard_normal((6, 6)))[0], n_odd=2)
    g_o, v_o = np.array([1.0, 0.3]), np.array([0.2, 1.0])
    V = np.column_stack([g_o, v_o])
    Po = V @ np.diag([1.0, 1.0 - 1e-9]) @ np.linalg.inv(V)
    Pe = np.diag([0.5, -0.3, 0.2, 0.1]) + 0.05 * rng.standard_normal((4, 4))
    B = np.zeros((6, 6))
    B[:4, :4], B[4:, 4:] = Pe, Po
    ev = SimpleNamespace(monodromy=mirror.Q @ B @ mirror.Q.T)
    g = mirror.odd @ g_o
    q = g / np.linalg.norm(g)
    scale = np.ones(6)

    plain, _ = pitchfork_direction(ev, mirror, 1, scale, 1e-3)
    assert abs(plain @ q) / np.linalg.norm(plain) > 1.0 - 1e-12  # the hazard: the generator itself

    w, eps = pitchfork_direction(ev, mirror, 1, scale, 1e-3, phase=q)
    assert eps * np.linalg.norm(w) == pytest.approx(1e-3, rel=1e-12)
    assert np.linalg.norm(mirror.even.T @ w) <= 1e-14 * np.linalg.norm(w)
    assert abs(w @ q) <= 1e-14 * np.linalg.norm(w)
    w_o = mirror.odd.T @ w
    assert np.linalg.norm(Po @ w_o - w_o) <= 1e-8 * np.linalg.norm(w_o)
