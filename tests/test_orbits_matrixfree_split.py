"""Matrix-free continuation of the planar orbits of symmetric spatial cables: the leading
multipliers of the in-plane and out-of-plane blocks computed apart, the out-of-plane
bifurcations located and switched at, against the dense path on cables small enough for both.

References (none from the matrix-free code under test): the dense shooting
(:class:`~cablesim.orbits.shooting.Shooting`), which integrates the variational equations of
every state variable, forms the whole monodromy and splits it in the plane's basis
(:func:`~cablesim.orbits.symmetry.split_multipliers`: all eigenvalues of each block), and the
planar branch's own properties (a pitchfork is no turning point: the parameter grows
monotonically through it).
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import case_from_dict, parse_case
from cablesim.orbits import Shooting, cable_system, continue_branches, linear_response_state, solve_orbit
from cablesim.orbits import floquet
from cablesim.orbits.matrixfree import MatrixFreeShooting
from cablesim.orbits.problems import PlanarOrbitProblem
from cablesim.orbits.starting import cable_scales
from cablesim.orbits.splitleading import split_leading
from cablesim.orbits.symmetry import split_multipliers

#: A single mass on two segments, forced vertically (the bead of tests/test_orbits_whirl.py).
BEAD = {
    "spatial": True,
    "cable": {"L": 2.0, "H": 0.0, "S": [1.02, 1.02], "EA": 2000.0, "masses": [1.0]},
    "loads": {"F0": [0.0, 9.81], "FL": [0.0, 5.0]},
    "damping": {"ratio": 0.005, "modes": [1, 2]},
}
#: A heavy span of eight nodes made spatial (48 states: blocks of 32 and 16), forced in its plane.
HEAVY = """\
spatial: true
cable: {L: 300.0, H: 10.0, length: 300.7, nodes: 8, EA: 3.3e7, mass_per_length: 1.628}
loads: {gravity: 9.81, point: [{node: 1, FL: [0.0, 200.0, 0.0]}]}
analysis: exact
damping: {ratio: 0.005, modes: [1, 2]}
"""


@pytest.fixture(autouse=True)
def dense_steps_on_the_multipliers(monkeypatch):
    """The matrix-free path forms no monodromy block, so it judges a step on the leading
    multipliers of both blocks together; the dense path it is compared with takes its steps by
    that rule too (its own judges the out-of-plane block on its matrix,
    :func:`~cablesim.orbits.stability.interpolated_step_ratio`), so that both visit the same
    points."""
    monkeypatch.setattr(PlanarOrbitProblem, "block_step_rule", False)


def bead(FL: float, omega: float):
    data = copy.deepcopy(BEAD)
    data["loads"]["FL"] = [0.0, FL]
    case = case_from_dict(data)
    return build_equations(case, run_static(case), omega=omega)


def heavy(omega: float):
    case = parse_case(HEAVY)
    return build_equations(case, run_static(case), omega=omega)


def both(eom, *args, **kw):
    return continue_branches(eom, *args, matrix_free=False, **kw), continue_branches(eom, *args, matrix_free=True, **kw)


def block(planes, mu, plane):
    return np.asarray(mu)[np.array(planes) == plane]


def assert_kept_are_the_block(kept, dense, bound, tol=1e-8):
    """Every kept multiplier is one of the dense block's, and every dense one clearly above the
    bound is kept."""
    assert kept.size and all(np.abs(dense - m).min() < tol for m in kept), (kept, dense)
    wanted = dense[np.abs(dense) > bound + 1e-6]
    assert all(np.abs(kept - m).min() < tol for m in wanted), (wanted, kept)


@pytest.mark.parametrize("dense_limit, bound", [(floquet.DENSE_LIMIT, floquet.DEFAULT_BOUND), (2, 0.9)])
def test_split_leading_multipliers_are_the_dense_blocks(monkeypatch, dense_limit, bound):
    """A planar orbit of an eight-node spatial heavy span: the leading multipliers of each block
    from the action alone are the eigenvalues of the dense monodromy's blocks to 1e-8, each block
    with its own count and largest discarded modulus, and their joined subspace is invariant.
    The in-plane block (32) by the subspace iteration: at the bound 0.5 its 16 transverse
    multipliers (the axial ones are below 1e-3), at 0.9 the 8 of moduli 0.944 to 0.905, the
    next (0.877) discarded; the out-of-plane block (16, all between 0.82 and 0.97) formed from
    its products or, below the dense limit, iterated until its whole spectrum is kept."""
    monkeypatch.setattr(floquet, "DENSE_LIMIT", dense_limit)
    w = 1.5
    eom = heavy(w)
    sysm = cable_system(eom)
    mirror = sysm.mirror
    assert mirror is not None and mirror.n_odd == 16
    scale, _ = cable_scales(eom, "omega", 1.0, 3.0)
    sol = solve_orbit(Shooting(sysm), linear_response_state(eom, w), w, scale=scale)
    assert sol.converged and mirror.is_planar(sol.u, scale)
    mu_in, mu_out = split_multipliers(mirror, sol.evaluation.monodromy)
    mf = MatrixFreeShooting(sysm, scheme="rk8")
    ev = mf.evaluate(sol.u, w)
    s = split_leading(mf, ev, mirror, scale, bound=bound)
    for lead, dense in ((s.in_plane, mu_in), (s.out_of_plane, mu_out)):
        assert_kept_are_the_block(lead.multipliers, dense, lead.bound)
        assert lead.residual < 1e-8
        if not lead.complete:  # the largest discarded modulus is below the bound, and it is one of the block's
            assert lead.discarded < lead.bound
            assert np.abs(np.abs(dense) - lead.discarded).min() < 1e-3
    assert not s.in_plane.complete and s.out_of_plane.complete
    assert (s.in_plane.multipliers.size, s.out_of_plane.multipliers.size) == ((16, 16) if bound == 0.5 else (8, 16))
    assert ev.leading.discarded == s.in_plane.discarded
    assert ev.leading.multipliers.size == s.in_plane.multipliers.size + s.out_of_plane.multipliers.size
    # the joined subspace is invariant under the scaled action: M' V = V S
    lead = ev.leading
    d = scale[:, None]
    MV = mf.monodromy_apply(ev, lead.basis * d) / d
    assert np.abs(MV - lead.basis @ lead.schur).max() < 1e-8
    # an out-of-plane eigenvector has no in-plane part
    v = s.vector("out-of-plane", mu_out[0]) * scale
    assert np.abs(mirror.even.T @ v).max() < 1e-12 * np.abs(v).max()


def assert_same_bifurcations(dense, free):
    assert [(b.kind, b.plane) for b in free.bifurcations] == [(b.kind, b.plane) for b in dense.bifurcations]
    for a, b in zip(dense.bifurcations, free.bifurcations):
        assert b.located and b.trusted
        assert abs(b.parameter - a.parameter) <= 1e-8 * abs(a.parameter), (a.parameter, b.parameter)
        assert abs(b.multiplier - a.multiplier) < 1e-8


def assert_same_split_points(dense_branch, free_branch):
    """Point by point (the same steps: the whole spectrum is kept on so small a cable), each
    block's multipliers to 1e-8."""
    assert free_branch.planar and dense_branch.planar
    assert len(free_branch.points) == len(dense_branch.points)
    for p, q in zip(dense_branch.points, free_branch.points):
        assert abs(q.parameter - p.parameter) <= 1e-8 * abs(p.parameter)
        for plane in ("in-plane", "out-of-plane"):
            a, b = block(p.planes, p.multipliers, plane), block(q.planes, q.multipliers, plane)
            assert a.size == b.size and all(np.abs(a - m).min() < 1e-8 for m in b)


def test_whirling_onset_is_a_pitchfork_on_the_matrix_free_path_too():
    """The bead forced near its out-of-plane frequency: both pitchforks located where the dense
    path locates them (1e-8 relative), with their plane; no fold or branch point of the planar
    branch there, which goes straight through (the matrix-free multipliers, unsplit, once read
    the out-of-plane +1 as a fold)."""
    eom = bead(5.0, 5.0)
    dense, free = both(eom, "omega", 5.0, 6.6, switch_branches=False)
    assert [(b.kind, b.plane) for b in dense.bifurcations] == [("pitchfork", "out-of-plane")] * 2
    assert_same_bifurcations(dense, free)
    assert not any(b.kind in ("fold", "branch-point") for b in free.bifurcations)
    assert np.all(np.diff(free.branches[0].values) > 0)
    assert_same_split_points(dense.branches[0], free.branches[0])


def test_out_of_plane_period_doubling_pair_on_the_matrix_free_path():
    """The bead's parametric tongue near twice its out-of-plane frequency: both out-of-plane
    period doublings, and inside them no point is stable, as on the dense path."""
    eom = bead(0.6, 12.0)
    dense, free = both(eom, "omega", 12.0, 13.2, switch_branches=False)
    assert [(b.kind, b.plane) for b in dense.bifurcations] == [("period-doubling", "out-of-plane")] * 2
    assert_same_bifurcations(dense, free)
    assert_same_split_points(dense.branches[0], free.branches[0])
    assert [p.stable for p in free.branches[0].points] == [p.stable for p in dense.branches[0].points]


def assert_same_orbits_or_mirrored(eom, dense_branch, free_branch):
    """The same orbits (1e-6 of their size), or all of them the mirror images ``w -> -w`` (the
    critical eigenvector's sign is arbitrary)."""
    mirror = cable_system(eom).mirror
    gaps = [[], []]
    for p, q in zip(dense_branch.points, free_branch.points):
        assert abs(q.parameter - p.parameter) < 1e-8 * abs(p.parameter)
        size = np.abs(p.state).max()
        gaps[0].append(np.abs(q.state - p.state).max() / size)
        gaps[1].append(np.abs(q.state - mirror.reflect(p.state)).max() / size)
    assert min(max(gaps[0]), max(gaps[1])) < 1e-6, gaps


def test_pitchfork_switching_follows_the_same_nonplanar_branch():
    """Switched at the upper pitchfork, the matrix-free whirling branch is the dense one: its
    mirror image reported, well out of the plane, the same orbits (1e-6 of their size) or their
    mirror images."""
    eom = bead(5.0, 6.0)
    dense, free = both(eom, "omega", 6.0, 6.6)
    assert_same_bifurcations(dense, free)
    pf_d, pf_f = dense.bifurcations[0], free.bifurcations[0]
    assert pf_f.kind == "pitchfork" and pf_f.child is not None
    wd, wf = dense.branches[pf_d.child], free.branches[pf_f.child]
    assert wf.mirror_image and not wf.planar and len(wf.points) == len(wd.points) > 3
    assert_same_orbits_or_mirrored(eom, wd, wf)
    for p, q in zip(wd.points[1:], wf.points[1:]):  # whirling measures (the mirror image goes the other way round)
        assert abs(abs(q.whirl.area[0]) - abs(p.whirl.area[0])) <= 1e-6 * abs(p.whirl.area[0])
        assert abs(q.whirl.max_w[0] - p.whirl.max_w[0]) <= 1e-6 * p.whirl.max_w[0]
        assert abs(q.whirl.tilt - p.whirl.tilt) < 1e-4
    assert np.abs(wf.points[-1].state[[2, 5]]).max() > 0.01  # w and w' of the bead


def test_out_of_plane_period_doubling_switches_onto_the_period_two_branch():
    """At the lower edge of the tongue the matrix-free path starts the nonplanar period-2 branch
    that the dense path follows (the same orbits, 1e-6 of their size, or their mirror images)."""
    eom = bead(0.6, 12.1)
    dense, free = both(eom, "omega", 12.1, 12.3)
    assert_same_bifurcations(dense, free)
    cd, cf = (d.branches[d.bifurcations[0].child] for d in (dense, free))
    assert cf.period == 2 and not cf.planar and len(cf.points) == len(cd.points) > 3
    assert_same_orbits_or_mirrored(eom, cd, cf)


#: The paper's example cable made spatial (two nodes, 12 states: blocks of 8 and 4).
PAPER = {
    "spatial": True,
    "cable": {"L": 300.0, "H": 20.0, "S": [130.0, 100.0, 110.0], "EA": 1.0e9, "masses": [8000.0, 14000.0]},
    "loads": {"F0": [300.0e3, 1100.0e3, 450.0e3, 2000.0e3], "FL": [-6.0e3, 22.0e3, -18.0e3, 120.0e3]},
    "damping": {"ratio": 0.01, "modes": [1, 2]},
}


def test_paper_example_made_spatial_loses_planar_stability_at_the_same_doublings():
    """The paper's cable made spatial: its harmonic response's out-of-plane period doublings
    (5.473 and 5.556 rad/s) where the dense path finds them (1e-8 relative), no in-plane
    special point between them, each block's multipliers at every point to 1e-8."""
    case = case_from_dict(copy.deepcopy(PAPER))
    eom = build_equations(case, run_static(case), omega=5.4)
    dense, free = both(eom, "omega", 5.4, 5.6, switch_branches=False)
    assert [(b.kind, b.plane) for b in dense.bifurcations] == [("period-doubling", "out-of-plane")] * 2
    assert_same_bifurcations(dense, free)
    assert_same_split_points(dense.branches[0], free.branches[0])


def continue_file(tmp_path, monkeypatch, matrix_free: bool):
    """`cablesim continue` on the bead across its whirling onset, shot matrix-free or dense (the
    size above which the continuation shoots matrix-free set below or above the bead's 6 states)."""
    import yaml
    from typer.testing import CliRunner

    from cablesim.cli import app
    from cablesim.orbits import mfproblem

    monkeypatch.setattr(mfproblem, "MATRIX_FREE_DOF", 0 if matrix_free else 10**6)
    data = copy.deepcopy(BEAD)
    data.update(name="bead", continuation={"omega": {"start": 5.0, "stop": 6.6}, "switch_branches": False})
    path = tmp_path / "bead.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / f"bead-{'mf' if matrix_free else 'dense'}.h5"
    res = CliRunner().invoke(app, ["continue", str(path), "-o", str(out)])
    assert res.exit_code == 0, (res.stdout, res.exception)
    return out, res.stdout


def test_result_file_of_a_matrix_free_planar_branch_is_laid_out_as_the_dense_one(tmp_path, monkeypatch):
    """The matrix-free run's file holds the datasets and attributes of the dense run's, the
    bifurcations' kinds and planes and every multiplier's block the same, and the summary names
    the pitchforks out of the plane."""
    import h5py

    files = {mf: continue_file(tmp_path, monkeypatch, mf) for mf in (False, True)}
    assert "pitchfork" in files[True][1] and "out-of-plane" in files[True][1]

    def layout(path):
        items = {}
        with h5py.File(path) as f:
            f["continuation"].visititems(
                lambda name, obj: items.setdefault(name, (type(obj).__name__, sorted(obj.attrs))))
            bif = f["continuation/bifurcations"]
            kinds = [(k.decode(), p.decode()) for k, p in zip(bif["kind"][()], bif["plane"][()])]
            planes = f["continuation/branches/b0-p1/multiplier_plane"][()]
            parameter = bif["parameter"][()]
        return items, kinds, planes, parameter

    (ld, kd, pd, wd), (lf, kf, pf, wf) = layout(files[False][0]), layout(files[True][0])
    assert lf == ld
    assert kf == kd == [("pitchfork", "out-of-plane")] * 2
    assert pf.shape == pd.shape and np.array_equal(pf, pd)
    np.testing.assert_allclose(wf, wd, rtol=1e-8)


def test_each_plane_has_its_own_matrix_free_doubling_direction_at_a_double_minus_one():
    """The taut stay at its threshold of parametric resonance, where an in-plane and an
    out-of-plane multiplier pass -1 together: the matrix-free direction of each plane's doubling
    lies in that plane's block and is an eigenvector of the dense monodromy with multiplier -1."""
    import yaml

    import cablesim
    from cablesim.orbits.switching import doubling_direction
    from helpers_whirl_cases import STAY_CASE

    omega = 12.0835669
    data = yaml.safe_load(STAY_CASE.format(nodes=6, omega=omega))
    case = cablesim.load_case(data)
    eom = build_equations(case, run_static(case), omega=omega)
    sysm = cable_system(eom, support=0.2)
    mirror = sysm.mirror
    dense = Shooting(sysm, parameter="support")
    sol = solve_orbit(dense, linear_response_state(eom, omega, 1.0, 0.2), 0.2)
    assert sol.converged
    # the threshold: where the largest |mu| of the planar orbit is 1, by bisection in s
    lo, hi, u = 0.05, 0.5, sol.u
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        s_mid = solve_orbit(dense, u, mid)
        assert s_mid.converged
        u = s_mid.u
        lo, hi = (lo, mid) if np.abs(s_mid.evaluation.multipliers).max() > 1.0 else (mid, hi)
    ev_d = dense.evaluate(u, mid)
    M = ev_d.monodromy
    assert np.sum(np.abs(ev_d.multipliers + 1) < 1e-5) == 2  # two multipliers at -1
    mf = MatrixFreeShooting(sysm, parameter="support", scheme="rk8")
    ev = mf.evaluate(u, mid)
    scale = np.ones(M.shape[0])
    split_leading(mf, ev, mirror, scale)
    for plane, inside, across in (("in-plane", mirror.even, mirror.odd), ("out-of-plane", mirror.odd, mirror.even)):
        d, _ = doubling_direction(ev, 1, scale, 1e-3, mirror, plane)
        w = d[: M.shape[0]]
        assert np.linalg.norm(across.T @ w) <= 1e-14 * np.linalg.norm(w), plane
        assert np.linalg.norm(inside.T @ w) > 0.0
        assert np.linalg.norm(M @ w + w) < 1e-5 * np.linalg.norm(w), plane


@pytest.mark.parametrize("FL, start, stop, kind", [(5.0, 6.0, 6.6, "pitchfork"), (0.6, 12.1, 12.3, "period-doubling")])
def test_a_two_segment_matrix_free_branch_is_switched_at_as_the_dense_one(FL, start, stop, kind):
    """On two shooting segments the critical eigenvector is carried from the first segment to the
    second by the action of its Jacobian (``G_0 w``); the matrix-free path was refused there
    with an error. At the bead's upper pitchfork and at the lower edge of its parametric tongue
    it starts the nonplanar branch the dense two-segment path follows (its segment Jacobians
    formed): the same bifurcation, the same orbits to 1e-6 of their size or their mirror images,
    on the period-1 and on the period-2 (four-segment) child."""
    eom = bead(FL, start)
    dense, free = (continue_branches(eom, "omega", start, stop, segments=2, matrix_free=mf) for mf in (False, True))
    assert [b.kind for b in dense.bifurcations] == [kind]
    assert_same_bifurcations(dense, free)
    cd, cf = (d.branches[d.bifurcations[0].child] for d in (dense, free))
    assert cf.segments == cd.segments == (2 if kind == "pitchfork" else 4)
    assert not cf.planar and len(cf.points) == len(cd.points) > 3
    assert_same_orbits_or_mirrored(eom, cd, cf)
