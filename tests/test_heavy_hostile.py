"""Independent checks of the heavy-cable features: the case-file shorthand, the banded operators,
modal analysis of many nodes, node channels and snapshots, and a short dynamic consistency test.

Every reference here is computed from first principles in this file (segment geometry, the
tension law T = EA (l - S) / S, nodal equilibrium, a dense assembly of the tangent stiffness,
scipy's dense generalized eigensolver, scipy's solve_ivp on the second-order equations of
motion), never from cablesim's own earlier output.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import sparse
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import case_from_dict, parse_case
from cablesim.channels import channel_index
from cablesim.mechanics import banded as bd
from cablesim.errors import CablesimError
from cablesim.modal import modal_analysis_banded
from cablesim.statics import band_to_dense, tangent_stiffness, tangent_stiffness_band

G = 9.81


# ----------------------------------------------------------------------------------------------
# Independent mechanics of a chain of elastic segments (node 0 = A at (0, 0), node n+1 = B at (L, H))
# ----------------------------------------------------------------------------------------------
def geometry(L, H, S, EA, y):
    """Segment lengths, unit vectors and tensions (EA (l - S) / S, sign kept) of configuration y."""
    pts = np.vstack([[0.0, 0.0], np.reshape(y, (-1, 2)), [L, H]])
    d = pts[1:] - pts[:-1]
    length = np.sqrt((d**2).sum(axis=1))
    e = d / length[:, None]
    T = EA * (length - S) / S
    return length, e, T


def my_P(L, H, S, EA, y):
    """Internal resisting nodal forces: P_r = T_r e_r - T_{r+1} e_{r+1}."""
    _, e, T = geometry(L, H, S, EA, y)
    n = len(S) - 1
    P = np.zeros((n, 2))
    for r in range(n):  # node r+1 (1-based) ends segment r+1 and starts segment r+2 (1-based)
        P[r] = T[r] * e[r] - T[r + 1] * e[r + 1]
    return P.reshape(-1)


def my_K(L, H, S, EA, y):
    """Dense tangent stiffness: sum over segments of EA/S e e^T + T/l (I - e e^T) in node blocks."""
    length, e, T = geometry(L, H, S, EA, y)
    n = len(S) - 1
    K = np.zeros((2 * n, 2 * n))
    for r in range(n + 1):  # segment r (0-based) joins node r-1 and node r (0-based interior index)
        ee = np.outer(e[r], e[r])
        k = EA / S[r] * ee + T[r] / length[r] * (np.eye(2) - ee)
        a, b = r - 1, r
        if a >= 0:
            K[2 * a:2 * a + 2, 2 * a:2 * a + 2] += k
        if b < n:
            K[2 * b:2 * b + 2, 2 * b:2 * b + 2] += k
        if a >= 0 and b < n:
            K[2 * a:2 * a + 2, 2 * b:2 * b + 2] -= k
            K[2 * b:2 * b + 2, 2 * a:2 * a + 2] -= k
    return K


def lower_band(A, width=3):
    """band[d, j] = A[j + d, j] for d = 0..width."""
    m = A.shape[0]
    band = np.zeros((width + 1, m))
    for d in range(width + 1):
        for j in range(m - d):
            band[d, j] = A[j + d, j]
    return band


def heavy(n=30, L=60.0, H=3.0, length=61.5, EA=2.0e6, mu=1.5, point=None, **extra):
    """A heavy cable case dictionary using the shorthand."""
    d = {
        "name": "hostile-heavy",
        "cable": {"L": L, "H": H, "length": length, "nodes": n, "EA": EA, "mass_per_length": mu},
        "loads": {"gravity": G},
        "damping": {"ratio": 0.02},
    }
    if point is not None:
        d["loads"]["point"] = point
    d.update(extra)
    return d


def cable_arrays(case):
    c = case.cable
    return c.L, c.H, np.array(c.S, float), float(c.EA), np.array(c.masses, float)


# ----------------------------------------------------------------------------------------------
# 1. The shorthand
# ----------------------------------------------------------------------------------------------
def test_shorthand_expansion_matches_hand_lumping():
    n, length, mu = 7, 41.0, 2.5
    point = [{"node": 3, "mass": 4.0, "F": [10.0, -20.0]},
             {"node": 7, "FL": [1.0, 30.0]},
             {"node": 1, "mass": 0.5}]
    case = case_from_dict(heavy(n=n, L=40.0, H=-2.0, length=length, mu=mu, point=point))
    seg = length / (n + 1)
    assert np.allclose(case.cable.S, [seg] * (n + 1), rtol=0, atol=1e-12)
    m = np.full(n, mu * seg)  # half of each of the two adjacent equal segments
    m[2] += 4.0
    m[0] += 0.5
    assert np.allclose(case.cable.masses, m, rtol=1e-14)
    F0 = np.zeros(2 * n)
    F0[1::2] = G * m
    F0[4] += 10.0
    F0[5] += -20.0
    assert np.allclose(case.F0, F0, rtol=1e-14, atol=1e-12)
    FL = np.zeros(2 * n)
    FL[12], FL[13] = 1.0, 30.0
    assert np.allclose(case.FL, FL, rtol=0, atol=0)
    # total vertical sustained load: the nodes carry all but the two half segments at the supports
    weight_on_nodes = G * (mu * length * n / (n + 1) + 4.0 + 0.5)
    assert math.isclose(case.F0[1::2].sum(), weight_on_nodes - 20.0, rel_tol=1e-13)
    # horizontal loads only from the point F
    assert math.isclose(case.F0[0::2].sum(), 10.0, rel_tol=1e-14)


def test_mass_per_length_on_explicit_unequal_segments():
    S = [3.0, 5.0, 2.0, 7.0, 4.0]
    d = {"cable": {"L": 19.0, "H": 1.0, "S": S, "EA": 1e7, "mass_per_length": 3.0},
         "loads": {"gravity": 2.0, "F0": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]}}
    case = case_from_dict(d)
    m = [3.0 * (S[i] + S[i + 1]) / 2 for i in range(4)]
    assert np.allclose(case.cable.masses, m, rtol=1e-14)
    F0 = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0])
    F0[1::2] += 2.0 * np.array(m)
    assert np.allclose(case.F0, F0, rtol=1e-14)


def test_duplicate_point_nodes_add_up_and_their_mass_weighs():
    point = [{"node": 2, "mass": 1.0, "F": [3.0, 4.0]}, {"node": 2, "mass": 2.0, "F": [-1.0, 1.0]}]
    case = case_from_dict(heavy(n=4, L=10.0, H=0.0, length=10.5, mu=1.0, point=point))
    seg = 10.5 / 5
    assert math.isclose(case.cable.masses[1], seg + 3.0, rel_tol=1e-14)
    assert math.isclose(case.F0[2], 2.0, rel_tol=1e-14)
    assert math.isclose(case.F0[3], G * (seg + 3.0) + 5.0, rel_tol=1e-14)


def test_stored_text_reruns_as_the_same_explicit_case():
    case = case_from_dict(heavy(n=12, point=[{"node": 5, "mass": 2.0, "FL": [0.0, 7.0]}]))
    again = parse_case(case.text, source="(stored)")
    for key in ("S", "masses"):
        assert getattr(again.cable, key) == getattr(case.cable, key)
    assert np.array_equal(again.F0, case.F0) and np.array_equal(again.FL, case.FL)
    # the stored text holds explicit lists, not only the shorthand
    body = yaml.safe_load(case.text)
    assert len(body["cable"]["S"]) == 13 and len(body["loads"]["F0"]) == 24


def _static_equilibrium_checks(case, st):
    L, H, S, EA, m = cable_arrays(case)
    y = st.exact.y
    F0 = case.F0
    # nodal equilibrium from the tension law and the geometry, computed here
    P = my_P(L, H, S, EA, y)
    scale = np.abs(F0).max() + np.abs(geometry(L, H, S, EA, y)[2]).max()
    assert np.abs(P - F0).max() < 1e-9 * scale
    # support reactions: A pulls the cable with -T1 e1, B with +T_{n+1} e_{n+1}
    _, e, T = geometry(L, H, S, EA, y)
    RA, RB = -T[0] * e[0], T[-1] * e[-1]
    total = F0.reshape(-1, 2).sum(axis=0)
    assert np.allclose(total + RA + RB, 0.0, atol=1e-9 * scale)
    # vertical reactions carry exactly the load on the nodes: g * (sum of lumped + point masses)
    assert math.isclose(-(RA[1] + RB[1]), G * m.sum(), rel_tol=1e-9)
    # vertical loads only: the horizontal component of the tension is the same in every segment
    Th = T * e[:, 0]
    assert np.ptp(Th) < 1e-9 * Th.max()
    # cablesim's tensions are those of its own geometry
    assert np.allclose(st.exact.T, T, rtol=1e-9)
    assert np.all(T > 0)


def test_static_of_heavy_cable_is_in_equilibrium_and_reactions_carry_the_weight():
    case = case_from_dict(heavy(n=40, point=[{"node": 17, "mass": 6.0}]))
    st = run_static(case, all_models=False)
    _static_equilibrium_checks(case, st)


def test_pretensioned_heavy_cable_static_and_exact_dynamics_only():
    # natural length shorter than the chord: exact analysis only (dynamics too, without a natural state)
    d = heavy(n=20, L=60.0, H=3.0, length=59.9)
    case = case_from_dict(d)
    assert sum(case.cable.S) < math.hypot(60.0, 3.0)
    st = run_static(case, all_models=True)
    assert st.inextensible is None and st.approximate is None
    _static_equilibrium_checks(case, st)
    # the chord is stretched: every segment longer than its natural length
    L, H, S, EA, _ = cable_arrays(case)
    assert np.all(geometry(L, H, S, EA, st.exact.y)[0] > S)
    eom = build_equations(case, st, omega=1.0)  # no natural state: the configuration is measured from y0
    assert np.array_equal(eom.x0, st.exact.y) and np.all(eom.u0 == 0.0)
    d["analysis"] = "approximate"
    with pytest.raises(CablesimError, match="cable.S"):
        run_static(case_from_dict(d), all_models=False)


# Bad shorthand inputs: each must raise CablesimError naming the field, in one paragraph.
BAD = [
    ("point node 0", lambda d: d["loads"].update(point=[{"node": 0, "mass": 1.0}]), "loads.point[1].node"),
    ("point node > n", lambda d: d["loads"].update(point=[{"node": 1, "mass": 1.0}, {"node": 9, "mass": 1.0}]),
     "loads.point[2].node"),
    ("point node float", lambda d: d["loads"].update(point=[{"node": 2.5, "mass": 1.0}]), "loads.point[1].node"),
    ("point mass negative", lambda d: d["loads"].update(point=[{"node": 2, "mass": -1.0}]), "loads.point[1].mass"),
    ("point mass nan", lambda d: d["loads"].update(point=[{"node": 2, "mass": float("nan")}]), "loads.point[1].mass"),
    ("point F inf", lambda d: d["loads"].update(point=[{"node": 2, "F": [0.0, float("inf")]}]), "loads.point[1].F"),
    ("point F four values", lambda d: d["loads"].update(point=[{"node": 2, "F": [0.0, 1.0, 2.0, 3.0]}]),
     "loads.point[1].F"),
    ("point FL one value", lambda d: d["loads"].update(point=[{"node": 2, "FL": [1.0]}]), "loads.point[1].FL"),
    ("point unknown key", lambda d: d["loads"].update(point=[{"node": 2, "masse": 1.0}]), "loads.point[1].masse"),
    ("gravity negative", lambda d: d["loads"].update(gravity=-9.81), "loads.gravity"),
    ("gravity nan", lambda d: d["loads"].update(gravity=float("nan")), "loads.gravity"),
    ("gravity inf", lambda d: d["loads"].update(gravity=float("inf")), "loads.gravity"),
    ("mass_per_length zero", lambda d: d["cable"].update(mass_per_length=0.0), "cable.mass_per_length"),
    ("mass_per_length negative", lambda d: d["cable"].update(mass_per_length=-1.0), "cable.mass_per_length"),
    ("mass_per_length nan", lambda d: d["cable"].update(mass_per_length=float("nan")), "cable.mass_per_length"),
    ("length zero", lambda d: d["cable"].update(length=0.0), "cable.length"),
    ("length negative", lambda d: d["cable"].update(length=-3.0), "cable.length"),
    ("length inf", lambda d: d["cable"].update(length=float("inf")), "cable.length"),
    ("nodes zero", lambda d: d["cable"].update(nodes=0), "cable.nodes"),
    ("nodes negative", lambda d: d["cable"].update(nodes=-4), "cable.nodes"),
    ("nodes fractional", lambda d: d["cable"].update(nodes=4.5), "cable.nodes"),
    ("nodes huge", lambda d: d["cable"].update(nodes=10**9), "cable.nodes"),
    ("nodes 2001", lambda d: d["cable"].update(nodes=2001), "cable.nodes"),
    ("segments below 1 mm", lambda d: d["cable"].update(nodes=2000, length=1.5), "cable.length"),
    ("S with length", lambda d: d["cable"].update(S=[2.0] * 9), "cable.S"),
    ("S with nodes only", lambda d: (d["cable"].pop("length"), d["cable"].update(S=[2.0] * 9)), "cable.S"),
    ("length without nodes", lambda d: d["cable"].pop("nodes"), "cable.nodes"),
    ("nodes without length", lambda d: d["cable"].pop("length"), "cable.length"),
    ("mass_per_length with masses", lambda d: d["cable"].update(masses=[1.0] * 8), "cable.masses"),
    ("F0 wrong length", lambda d: d["loads"].update(F0=[0.0] * 15), "loads.F0"),
    ("FL wrong length", lambda d: d["loads"].update(FL=[0.0] * 17), "loads.FL"),
    ("FL wrong length with point FL", lambda d: d["loads"].update(FL=[0.0] * 3, point=[{"node": 2, "FL": [0.0, 1.0]}]),
     "loads.FL"),
    ("summed point loads beyond range", lambda d: d["loads"].update(
        point=[{"node": 2, "F": [0.0, 9e11]}, {"node": 2, "F": [0.0, 9e11]}]), "loads.F0"),
    ("point mass beyond range after lumping", lambda d: (d["cable"].update(mass_per_length=1e6, length=20000.0),
                                                         d["loads"].update(point=[{"node": 3, "mass": 1e10}])),
     "masses"),
]


@pytest.mark.parametrize("label, change, field", BAD, ids=[b[0] for b in BAD])
def test_bad_shorthand_is_refused_naming_the_field(label, change, field):
    d = heavy(n=8, L=16.0, H=0.5, length=16.8, mu=1.0)
    change(d)
    with pytest.raises(CablesimError) as exc:
        case_from_dict(d)
    msg = str(exc.value)
    assert field in msg, msg
    assert "\n" not in msg.strip() and "Traceback" not in msg


def _cli(args, cwd):
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100")
    script = Path(sys.executable).with_name("cablesim")
    cmd = [str(script)] if script.exists() else [sys.executable, "-m", "cablesim.cli"]
    return subprocess.Popen([*cmd, *map(str, args)], cwd=cwd, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def test_cli_refuses_bad_shorthand_with_status_2_and_no_traceback(tmp_path):
    cases = {
        "node.yaml": ("loads.point[1].node", lambda d: d["loads"].update(point=[{"node": 31, "mass": 1.0}])),
        "mix.yaml": ("cable.S", lambda d: d["cable"].update(S=[2.0] * 31)),
        "nan.yaml": ("cable.mass_per_length", lambda d: d["cable"].update(mass_per_length=float("nan"))),
    }
    procs = []
    for name, (field, change) in cases.items():
        d = heavy(n=30)
        change(d)
        (tmp_path / name).write_text(yaml.safe_dump(d))
        procs.append((field, name, _cli(["static", name, "--no-plot", "-o", f"{name}.h5"], tmp_path)))
    for field, name, p in procs:
        out, err = p.communicate(timeout=120)
        assert p.returncode == 2, (name, err)
        assert "Traceback" not in err and field in err, err
        assert not (tmp_path / f"{name}.h5").exists()


# ----------------------------------------------------------------------------------------------
# 2. Banded operators
# ----------------------------------------------------------------------------------------------
def test_own_stiffness_is_the_jacobian_of_own_forces():
    """Validates the reference itself: central differences of P(y)."""
    case = case_from_dict(heavy(n=6, L=12.0, H=1.0, length=12.6, mu=1.0))
    L, H, S, EA, _ = cable_arrays(case)
    y = run_static(case, all_models=False).exact.y + np.random.default_rng(0).normal(0, 0.05, 12)
    K = my_K(L, H, S, EA, y)
    h = 1e-6
    J = np.column_stack([(my_P(L, H, S, EA, y + h * ei) - my_P(L, H, S, EA, y - h * ei)) / (2 * h)
                         for ei in np.eye(12)])
    assert np.abs(J - K).max() < 1e-6 * np.abs(K).max()


@pytest.fixture(scope="module")
def big():
    """A 400-node heavy cable at its exact equilibrium, with the dense reference stiffness."""
    case = case_from_dict(heavy(n=400, L=300.0, H=10.0, length=300.7, EA=3.3e7, mu=1.628,
                                point=[{"node": 200, "mass": 15.0}], modal={"modes": 12}))
    st = run_static(case, all_models=False)
    L, H, S, EA, m = cable_arrays(case)
    K, mm = my_K(L, H, S, EA, st.exact.y), np.repeat(m, 2)
    # the lowest 12 frequencies and the highest, by sparse shift-invert Lanczos on the own K
    # (single-threaded SuperLU: quick even on a busy machine)
    from scipy.sparse.linalg import eigsh
    Mi = sparse.diags(1.0 / np.sqrt(mm))
    A = (Mi @ sparse.csc_matrix(K) @ Mi).tocsc()
    low = np.sort(eigsh(A, k=12, sigma=0.0, return_eigenvectors=False))
    top = eigsh(A, k=1, sigma=abs(A).sum(axis=1).max(), return_eigenvectors=False)
    BIG_W.clear()
    BIG_W.extend(np.sqrt(np.concatenate([low, top])))
    return case, st, K, mm


BIG_W: list = []  # the lowest 12 frequencies and then the highest of the `big` cable


def test_band_stiffness_of_400_nodes_is_the_dense_assembly(big):
    case, st, K, _ = big
    L, H, S, EA, _ = cable_arrays(case)
    band = tangent_stiffness_band(st.cable, st.exact.y)
    scale = np.abs(K).max()
    assert band.shape == (4, 800)
    assert np.abs(band - lower_band(K)).max() < 1e-12 * scale
    assert np.abs(band_to_dense(band) - K).max() < 1e-12 * scale
    assert np.abs(tangent_stiffness(st.cable, st.exact.y) - K).max() < 1e-12 * scale
    assert np.abs(st.K0_band - lower_band(K)).max() < 1e-12 * scale
    # nothing outside the block-tridiagonal band
    i, j = np.indices(K.shape)
    assert np.all(K[np.abs(i - j) > 3] == 0.0)


@pytest.mark.parametrize("n", [1, 2, 3, 7])
def test_band_stiffness_small_and_off_equilibrium(n):
    case = case_from_dict(heavy(n=n, L=10.0, H=-1.5, length=10.8, mu=1.0))
    L, H, S, EA, _ = cable_arrays(case)
    st = run_static(case, all_models=False)
    y = st.exact.y + np.random.default_rng(n).normal(0, 0.2, 2 * n)
    K = my_K(L, H, S, EA, y)
    scale = np.abs(K).max()
    assert np.abs(band_to_dense(tangent_stiffness_band(st.cable, y)) - K).max() < 1e-12 * scale
    assert np.abs(tangent_stiffness(st.cable, y) - K).max() < 1e-12 * scale


def test_band_storage_product_row_and_solve_against_dense():
    rng = np.random.default_rng(3)
    nd = 40
    A = np.zeros((nd, nd))
    for d in range(4):
        v = rng.normal(size=nd - d)
        A += np.diag(v, -d) + (np.diag(v, d) if d else 0)
    A += np.diag(np.full(nd, 20.0))  # diagonally dominant: SPD, no pivoting needed
    C = bd.band_storage(lower_band(A))
    assert C.shape == (bd.band_rows(2), nd)
    for i in range(nd):
        for j in range(max(0, i - 3), min(nd, i + 4)):
            assert C[3 + i - j, j] == A[i, j]
    x = rng.normal(size=nd)
    assert np.allclose(bd.band_product(C, x), A @ x, rtol=0, atol=1e-12 * np.abs(A @ x).max())
    for i in (0, 1, 2, 3, 17, nd - 2, nd - 1):
        assert math.isclose(bd.damping_row(C, x, 0, i), (A @ x)[i], rel_tol=1e-12, abs_tol=1e-12)
        assert math.isclose(bd.damping_row(A, x, 0, i), (A @ x)[i], rel_tol=1e-12, abs_tol=1e-12)
    # offset into a longer state vector
    s = np.concatenate([rng.normal(size=nd), x])
    assert math.isclose(bd.damping_row(C, s, nd, 5), (A @ x)[5], rel_tol=1e-12)
    b = rng.normal(size=nd)
    out, LU = np.empty(nd), np.empty_like(C)
    assert bd.solve_band(C, b, out, LU)
    assert np.allclose(out, np.linalg.solve(A, b), rtol=1e-10, atol=1e-12)


def test_solve_band_on_a_heavy_cable_newton_matrix(big):
    case, st, K, m = big
    A = 4.0 / 1e-6 * np.diag(m) + 2.0 / 1e-3 * K  # the shape of an implicit scheme's Newton matrix
    C = bd.band_storage(lower_band(A))
    b = np.random.default_rng(4).normal(size=m.size)
    out, LU = np.empty(m.size), np.empty_like(C)
    assert bd.solve_band(C, b, out, LU)
    assert np.abs(A @ out - b).max() < 1e-10 * np.abs(b).max()


def _rayleigh(K, m, i, j, xi):
    w = np.sqrt(eigh(K, np.diag(m), eigvals_only=True))
    a0 = 2 * xi * w[i - 1] * w[j - 1] / (w[i - 1] + w[j - 1])
    a1 = 2 * xi / (w[i - 1] + w[j - 1])
    return a0, a1, w


@pytest.mark.parametrize("modes", [(1, 2), (2, 5)])
def test_exact_equations_damping_is_rayleigh_of_own_matrices(modes):
    d = heavy(n=25, point=[{"node": 9, "FL": [0.0, 20.0]}])
    d["damping"] = {"ratio": 0.03, "modes": list(modes)}
    case = case_from_dict(d)
    st = run_static(case, all_models=False)
    eom = build_equations(case, st, omega=1.7)
    L, H, S, EA, m1 = cable_arrays(case)
    m = np.repeat(m1, 2)
    K = my_K(L, H, S, EA, st.exact.y)
    a0, a1, _ = _rayleigh(K, m, *modes, 0.03)
    assert math.isclose(eom.a0, a0, rel_tol=1e-9) and math.isclose(eom.a1, a1, rel_tol=1e-9)
    C = a0 * np.diag(m) + a1 * K
    scale = np.abs(C).max()
    assert np.abs(eom.K0 - K).max() < 1e-12 * np.abs(K).max()
    assert np.abs(eom.C - C).max() < 1e-9 * scale
    assert eom.C_band is not None and eom.C_band.shape == (7, 50)
    assert np.abs(band_to_dense(eom.K0_band) - K).max() < 1e-12 * np.abs(K).max()
    i, j = np.indices(C.shape)
    near = np.abs(i - j) <= 3
    assert np.abs(eom.C_band[3 + i[near] - j[near], j[near]] - C[near]).max() < 1e-9 * scale
    rng = np.random.default_rng(5)
    v, a = rng.normal(size=50), rng.normal(size=50)
    assert np.abs(eom.damping_force(v) - C @ v).max() < 1e-9 * np.abs(C @ v).max()
    t = 0.37
    F = case.F0 + case.FL * np.sin(1.7 * t)
    s = np.concatenate([rng.normal(size=50), v, a])
    P = eom.internal_force(t, s)
    terms = max(np.abs(F).max(), np.abs(C @ v).max(), np.abs(m * a).max())  # round-off of their difference
    assert np.abs(P - (F - C @ v - m * a)).max() < 1e-9 * terms
    # eq. 19: the initial acceleration from rest at the equilibrium is zero (F(0) = F0 = P(y0))
    s0 = eom.initial_state()
    assert np.abs(s0[100:]).max() < 1e-7 * np.abs(case.F0).max() / m.min()


def test_approximate_equations_damping_is_dense_rayleigh():
    d = heavy(n=8, L=16.0, H=0.5, length=16.8, mu=1.0, analysis="approximate")
    d["damping"] = {"ratio": 0.05, "modes": [1, 3]}
    case = case_from_dict(d)
    st = run_static(case, all_models=False)
    eom = build_equations(case, st, omega=2.0)
    assert eom.K0_band is None and eom.C_band is not None  # banded part; the rest is rank 2
    m = np.repeat(cable_arrays(case)[4], 2)
    # the approximate tangent stiffness is the inverse of dy/dP, y = x + u; finite differences of
    # the approximate equilibrium, column by column
    from cablesim.statics import approximate_equilibrium
    P0 = case.F0
    h = 1e-4 * np.abs(P0).max()
    N = np.column_stack([(approximate_equilibrium(st.cable, P0 + h * ei).y
                          - approximate_equilibrium(st.cable, P0 - h * ei).y) / (2 * h) for ei in np.eye(16)])
    K_fd = np.linalg.inv(0.5 * (N + N.T))
    assert np.abs(eom.K0 - K_fd).max() < 1e-5 * np.abs(K_fd).max()
    K = eom.K0
    assert np.allclose(K, K.T, rtol=0, atol=1e-10 * np.abs(K).max())
    a0, a1, w = _rayleigh(K, m, 1, 3, 0.05)
    assert math.isclose(eom.a0, a0, rel_tol=1e-9) and math.isclose(eom.a1, a1, rel_tol=1e-9)
    C = a0 * np.diag(m) + a1 * K
    assert np.abs(eom.C - C).max() < 1e-9 * np.abs(C).max()
    v = np.random.default_rng(6).normal(size=16)
    assert np.abs(eom.damping_force(v) - C @ v).max() < 1e-9 * np.abs(C @ v).max()
    # the modes damped as asked, the others by Rayleigh's rule
    xi = a0 / (2 * w) + a1 * w / 2
    assert math.isclose(xi[0], 0.05, rel_tol=1e-9) and math.isclose(xi[2], 0.05, rel_tol=1e-9)
    assert np.allclose(st.damping_ratios, xi, rtol=1e-8)


# ----------------------------------------------------------------------------------------------
# 3. Modal analysis of many nodes
# ----------------------------------------------------------------------------------------------
def _check_modes(K, m, omega, shapes, k_shapes, top=None, rtol=1e-9, w_all=None):
    if w_all is None:
        w_all = np.sqrt(eigh(K, np.diag(m), eigvals_only=True))
    k = omega.size
    assert np.allclose(omega, w_all[:k], rtol=rtol, atol=0)
    if top is not None:
        assert math.isclose(top, w_all[-1], rel_tol=rtol)
    phi = shapes[:, :k_shapes]
    assert phi.shape == (m.size, k_shapes)
    # mass-orthonormal, and each an eigenvector of K phi = w^2 M phi
    assert np.abs(phi.T @ (m[:, None] * phi) - np.eye(k_shapes)).max() < 1e-8
    R = K @ phi - (m[:, None] * phi) * omega[:k_shapes] ** 2
    assert np.abs(R).max() < 1e-7 * np.abs(K).max() * np.abs(phi).max()


def test_banded_lowest_modes_of_400_nodes_against_own_reference(big):
    case, st, K, m = big
    modes = modal_analysis_banded(lower_band(K), m, n_modes=10, n_shapes=10)
    assert modes.omega.size == 10 and modes.omega_max is not None
    # 800 DOF > 600: shapes by inverse iteration
    assert modes.shapes.shape == (800, 10)
    _check_modes(K, m, modes.omega, modes.shapes, 10, top=modes.omega_max, w_all=np.array(BIG_W))
    # without n_shapes above 600 DOF: frequencies only (documented)
    assert modal_analysis_banded(lower_band(K), m, n_modes=3).shapes.shape == (800, 0)


def test_static_run_of_400_nodes_keeps_lowest_modes_and_the_highest(big):
    case, st, K, m = big
    # case asks for 12 modes; the damping names modes 1 and 2
    assert st.modes.omega.size == 12
    w = np.array(BIG_W)
    _check_modes(K, m, st.modes.omega, st.modes.shapes, min(12, st.modes.shapes.shape[1]), top=st.modes.omega_max,
                 w_all=w)
    a0, a1 = 2 * 0.02 * w[0] * w[1] / (w[0] + w[1]), 2 * 0.02 / (w[0] + w[1])
    assert math.isclose(st.a0, a0, rel_tol=1e-9) and math.isclose(st.a1, a1, rel_tol=1e-9)
    assert np.allclose(st.damping_ratios, a0 / (2 * w[:12]) + a1 * w[:12] / 2, rtol=1e-9)


def test_banded_modes_with_every_shape_up_to_600_dof():
    case = case_from_dict(heavy(n=40, point=[{"node": 11, "mass": 3.0}]))
    st = run_static(case, all_models=False)
    L, H, S, EA, m1 = cable_arrays(case)
    K, m = my_K(L, H, S, EA, st.exact.y), np.repeat(m1, 2)
    assert st.modes.omega.size == 80 and st.modes.omega_max is None
    _check_modes(K, m, st.modes.omega, st.modes.shapes, 80)
    assert math.isclose(st.modes.highest, np.sqrt(eigh(K, np.diag(m), eigvals_only=True)[-1]), rel_tol=1e-9)


def test_inextensible_frequencies_are_the_stiff_limit_of_own_exact_ones():
    """n - 1 finite inextensible frequencies = the limit EA -> inf of the lowest n - 1 exact ones
    (own K and eigh), approached as 1/EA."""
    point = [{"node": 3, "mass": 2.0}]
    st = run_static(case_from_dict(heavy(n=40, EA=2e6, point=point)), all_models=True)
    wi = st.inextensible_omega
    assert wi.size == 39
    errors = []
    for EA in (1e9, 1e11):
        case = case_from_dict(heavy(n=40, EA=EA, point=point))
        L, H, S, EA_, m1 = cable_arrays(case)
        y = run_static(case, all_models=False).exact.y
        assert np.abs(my_P(L, H, S, EA_, y) - case.F0).max() < 2 * EA_ / S.min() * 1e-12 * sum(S)
        w = np.sqrt(eigh(my_K(L, H, S, EA_, y), np.diag(np.repeat(m1, 2)), eigvals_only=True))
        errors.append(np.abs(w[:39] / wi - 1).max())
        assert w[39] > 5 * wi[-1]  # the next one is elastic, far above
    assert errors[1] < 1e-6 and 50 < errors[0] / errors[1] < 200


def test_modes_never_fewer_than_the_damping_names():
    d = heavy(n=40, modal={"modes": 1})
    d["damping"] = {"ratio": 0.01, "modes": [2, 4]}
    case = case_from_dict(d)
    st = run_static(case, all_models=False)
    L, H, S, EA, m1 = cable_arrays(case)
    K, m = my_K(L, H, S, EA, st.exact.y), np.repeat(m1, 2)
    assert st.modes.omega.size >= 4
    a0, a1, _ = _rayleigh(K, m, 2, 4, 0.01)
    assert math.isclose(st.a0, a0, rel_tol=1e-9) and math.isclose(st.a1, a1, rel_tol=1e-9)
    # more modes than the cable has: refused, naming the field
    for key, value, field in (("modal", {"modes": 81}, "modal.modes"),
                              ("damping", {"ratio": 0.01, "modes": [1, 81]}, "damping.modes")):
        bad = heavy(n=40, **{key: value})
        with pytest.raises(CablesimError, match=field.replace(".", r"\.")):
            case_from_dict(bad)



def my_K_sparse(L, H, S, EA, y):
    """The same assembly as my_K, in sparse storage (for 2000 nodes)."""
    length, e, T = geometry(L, H, S, EA, y)
    n = len(S) - 1
    rows, cols, vals = [], [], []
    for r in range(n + 1):
        ee = np.outer(e[r], e[r])
        k = EA / S[r] * ee + T[r] / length[r] * (np.eye(2) - ee)
        a, b = r - 1, r
        for i, j, sign in ((a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)):
            if 0 <= i < n and 0 <= j < n:
                for p in range(2):
                    for q in range(2):
                        rows.append(2 * i + p)
                        cols.append(2 * j + q)
                        vals.append(sign * k[p, q])
    return sparse.csc_matrix((vals, (rows, cols)), shape=(2 * n, 2 * n))


def test_2000_nodes_lowest_100_and_highest_mode_against_sparse_reference():
    from scipy.sparse.linalg import eigsh
    case = case_from_dict(heavy(n=2000, L=300.0, H=10.0, length=300.7, EA=3.3e7, mu=1.628,
                                point=[{"node": 1000, "mass": 15.0}]))
    st = run_static(case, all_models=False)
    L, H, S, EA, m1 = cable_arrays(case)
    m = np.repeat(m1, 2)
    # equilibrium by own force balance, to what the solver's closure tolerance (1e-12 of the
    # length, docs/theory.md section 3) allows: a position error d gives a force error EA/S d
    closure = 1e-12 * max(sum(S), math.hypot(L, H))
    assert np.abs(my_P(L, H, S, EA, st.exact.y) - case.F0).max() < 2 * EA / S.min() * closure
    K = my_K_sparse(L, H, S, EA, st.exact.y)
    assert np.abs(st.K0_band - np.vstack([np.concatenate([K.diagonal(-d), np.zeros(d)]) for d in range(4)])).max() \
        < 1e-12 * abs(K).max()
    # default above 300 nodes: the lowest 100 frequencies, 20 shapes, and the highest frequency
    assert st.modes.omega.size == 100 and st.modes.shapes.shape == (4000, 20)
    Mi = sparse.diags(1.0 / np.sqrt(m))
    A = (Mi @ K @ Mi).tocsc()
    lam = np.sort(eigsh(A, k=40, sigma=0.0, which="LM", return_eigenvectors=False))
    assert np.allclose(st.modes.omega[:40], np.sqrt(lam), rtol=1e-7)
    assert np.all(np.diff(st.modes.omega) >= 0)
    # the highest: between the largest Rayleigh quotient of a unit vector (the largest diagonal
    # entry) and Gershgorin's bound (checked exactly at 400 nodes above)
    assert A.diagonal().max() <= st.modes.omega_max**2 <= abs(A).sum(axis=1).max()
    phi = st.modes.shapes
    assert np.abs(phi.T @ (m[:, None] * phi) - np.eye(20)).max() < 1e-8
    R = K @ phi - (m[:, None] * phi) * st.modes.omega[:20] ** 2
    assert np.abs(R).max() < 1e-9 * abs(K).max() * np.abs(phi).max()


# ----------------------------------------------------------------------------------------------
# 5. Dynamics of a 30-node heavy cable against an independent second-order integration
# ----------------------------------------------------------------------------------------------
OMEGA_F = 2.5
DURATION = 0.5
FORCED = heavy(n=30, point=[{"node": 20, "mass": 4.0, "FL": [8.0, 60.0]}, {"node": 7, "FL": [0.0, -25.0]}])


def my_forces_vectorised(L, H, S, EA):
    def P(y):
        pts = np.empty((S.size + 1, 2))
        pts[0] = 0.0
        pts[1:-1] = y.reshape(-1, 2)
        pts[-1] = (L, H)
        d = np.diff(pts, axis=0)
        length = np.sqrt((d**2).sum(axis=1))
        F = (EA * (length - S) / S / length)[:, None] * d  # T e
        return (F[:-1] - F[1:]).reshape(-1)
    return P


@pytest.fixture(scope="module")
def reference():
    """z(t) of M z'' + C z' + P(y0 + z) = F0 + FL sin(w t) from rest, with own P, K, C and y0
    checked for equilibrium; scipy's Radau at rtol 1e-9 (agrees with DOP853 at rtol 1e-11 to 3e-12)."""
    case = case_from_dict(FORCED)
    st = run_static(case, all_models=False)
    L, H, S, EA, m1 = cable_arrays(case)
    m = np.repeat(m1, 2)
    y0 = st.exact.y.copy()
    P = my_forces_vectorised(L, H, S, EA)
    F0, FL = case.F0, case.FL
    assert np.abs(P(y0) - F0).max() < 1e-9 * np.abs(F0).max()
    assert np.allclose(P(y0), my_P(L, H, S, EA, y0), rtol=1e-12, atol=1e-9)
    K = my_K(L, H, S, EA, y0)
    a0, a1, _ = _rayleigh(K, m, 1, 2, 0.02)
    C = a0 * np.diag(m) + a1 * K
    Cs = sparse.csr_matrix(C)  # block-tridiagonal; sparse products and LU keep the reference fast
    nd = m.size

    def rhs(t, s):
        z, v = s[:nd], s[nd:]
        return np.concatenate([v, (F0 + FL * np.sin(OMEGA_F * t) - Cs @ v - P(y0 + z)) / m])

    # the Jacobian at the equilibrium serves Radau's Newton iterations (accuracy comes from the
    # residual of rhs, evaluated exactly)
    J = sparse.csc_matrix(np.block([[np.zeros((nd, nd)), np.eye(nd)], [-K / m[:, None], -C / m[:, None]]]))
    sol = solve_ivp(rhs, (0.0, DURATION), np.zeros(2 * nd), method="Radau", jac=J, rtol=1e-9, atol=1e-13,
                    dense_output=True)
    assert sol.success
    return case, sol, m, C, P, y0


def _error(run, sol):
    h = run.history
    assert h.status.name == "COMPLETED", h.message
    zref = sol.sol(h.t)[: h.z.shape[1]].T
    return np.abs(h.z - zref).max() / np.abs(zref).max(), zref


def test_compiled_third_order_rate_is_the_own_jerk(reference):
    """eq. 17: y''' = M^-1 (w FL cos(w t) - K(y) y' - C y''), with the banded C, taut and slack modes."""
    from cablesim.dynamics import field as eq
    case = reference[0]
    st = run_static(case, all_models=False)
    eom = build_equations(case, st, omega=OMEGA_F)
    L, H, S, EA, m1 = cable_arrays(case)
    m = np.repeat(m1, 2)
    nd = m.size
    C = eom.a0 * np.diag(m) + eom.a1 * my_K(L, H, S, EA, eom.y0)
    rng = np.random.default_rng(11)
    s = np.concatenate([rng.normal(0, 0.01, nd), rng.normal(0, 0.3, nd), rng.normal(0, 1.0, nd)])
    y = eom.y0 + s[:nd]
    length, e, T = geometry(L, H, S, EA, y)
    t = 0.3
    for slack in ((), (4, 17)):
        wk, awk = eom.workspaces()
        for k in slack:
            wk.taut[k] = 0.0  # segment k+1 slack: no force, no stiffness
        ds = np.empty(3 * nd)
        assert eq.rate(eom.model(), t, s, eom.F1.copy(), ds, wk, awk) == 0
        K = my_K(L, H, S, EA, y)
        for k in slack:  # remove that segment's block from the own assembly
            ee = np.outer(e[k], e[k])
            kb = EA / S[k] * ee + T[k] / length[k] * (np.eye(2) - ee)
            for a, b, sign in ((k - 1, k - 1, 1), (k, k, 1), (k - 1, k, -1), (k, k - 1, -1)):
                K[2 * a:2 * a + 2, 2 * b:2 * b + 2] -= sign * kb
        jerk = (case.FL * OMEGA_F * np.cos(OMEGA_F * t) - K @ s[nd:2 * nd] - C @ s[2 * nd:]) / m
        assert np.array_equal(ds[:nd], s[nd:2 * nd]) and np.array_equal(ds[nd:2 * nd], s[2 * nd:])
        assert np.abs(ds[2 * nd:] - jerk).max() < 1e-10 * np.abs(jerk).max(), slack


def test_default_integrator_matches_independent_reference(reference):
    import cablesim
    case, sol, *_ = reference
    run = cablesim.history(case, omega=OMEGA_F, duration=DURATION, output_step=0.01)
    err, zref = _error(run, sol)
    assert np.abs(zref).max() > 1e-3  # a visible response
    # the default for this stiff cable is implicit; documented error 6e-6 to 5e-5
    assert err < 1e-4, (run.history.integrator, err)


def test_dopri5_matches_independent_reference(reference):
    import cablesim
    case, sol, *_ = reference
    run = cablesim.history(case, omega=OMEGA_F, duration=DURATION, output_step=0.01, integrator="dopri5")
    err, _ = _error(run, sol)
    assert err < 1e-6, err  # rtol 1e-8 by default
    # velocities too
    h = run.history
    vref = sol.sol(h.t)[h.z.shape[1]:].T
    assert np.abs(h.v - vref).max() < 1e-5 * np.abs(vref).max()


# ----------------------------------------------------------------------------------------------
# 4. Node channels and snapshots
# ----------------------------------------------------------------------------------------------
def test_node_channel_names_map_to_dof_numbers():
    n = 30
    for k in range(1, n + 1):
        assert channel_index(f"node{k}.v", 2 * n) == 2 * k - 1  # 0-based: z_{2k}
        assert channel_index(f"node{k}.h", 2 * n) == 2 * k - 2  # z_{2k-1}
        assert channel_index(f"z{2 * k}", 2 * n) == channel_index(f"node{k}.v", 2 * n)
    assert channel_index("Node 20.V", 60) == 39


@pytest.mark.parametrize("name, needle", [
    ("node0.v", "node 0"), ("node31.v", "31"), ("node31.h", "31"), ("node5.z", "'z'"), ("node5", "node1.h to node30.v"),
    ("node.v", "malformed"), ("node-1.v", "malformed"), ("nodes5.v", "malformed"), ("z0", "out of range"),
    ("z61", "out of range"), ("node5.v.h", "malformed"), ("", "malformed"),
])
def test_bad_node_channels_are_refused_clearly(name, needle):
    with pytest.raises(CablesimError) as exc:
        channel_index(name, 60)
    msg = str(exc.value)
    assert needle in msg and repr(name) in msg and "\n" not in msg


def test_cli_node_channels_store_the_right_dofs_and_snapshots_draw_them(reference, tmp_path):
    import h5py
    case, sol, m, C, P, y0 = reference
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(FORCED))
    common = ["history", "c.yaml", "--omega", OMEGA_F, "--duration", DURATION, "--output-step", 0.01,
              "--integrator", "dopri5", "--no-plot"]
    # z40 is node20.v again: stored once
    p1 = _cli([*common, "--set", "outputs.channels=[node20.v, node20.h, node7.v, z40]", "-o", "part.h5"], tmp_path)
    p2 = _cli([*common, "--channels", "node20.v,node7.h", "--full", "-o", "full.h5"], tmp_path)
    outs = []
    for p in (p1, p2):
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        outs.append(out)
    # --full: the summary lists every DOF, each with its peak |z| (5 digits), as the reference has it
    # (the summary locates the peak between the saved instants, so the reference's peak is that of
    # its continuous solution, sampled 100 times finer than the record)
    peaks = {}
    for line in outs[1].splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0][:1] == "z" and parts[0][1:].isdigit():
            peaks.setdefault(int(parts[0][1:]), float(parts[1]))
    assert sorted(peaks) == list(range(1, 61))
    t_all = np.linspace(0.0, DURATION, 5001)
    zmax = np.abs(sol.sol(t_all)[:60]).max(axis=1)
    for k, value in peaks.items():
        assert math.isclose(value, zmax[k - 1], rel_tol=2e-4), (k, value, zmax[k - 1])
    with h5py.File(tmp_path / "part.h5") as f:
        t, z, dof = f["history/t"][:], f["history/z"][:], list(f["history/dof"][:])
    zref = sol.sol(t)[:60].T
    assert z.shape == (t.size, 3) and dof == [40, 39, 14]
    for name, want in (("node20.v", 39), ("node20.h", 38), ("node7.v", 13)):
        col = dof.index(want + 1)
        assert np.abs(z[:, col] - zref[:, want]).max() < 1e-6 * np.abs(zref).max(), name
    # node 20 carries the large vertical harmonic load: its vertical motion is the column that
    # agrees with the reference's DOF 40, not with any other DOF
    col = dof.index(40)
    others = [j for j in range(60) if j != 39]
    assert min(np.abs(z[:, col] - zref[:, j]).max() for j in others) > 100 * np.abs(z[:, col] - zref[:, 39]).max()

    # snapshots of the full record: exit 0 and a PNG; errors for bad requests, no traceback
    procs = [(args, _cli(args, tmp_path)) for args in (
        ["plot", "full.h5", "--snapshots", "4"], ["plot", "part.h5", "--snapshots", "4"])]
    results = []
    for args, p in procs:
        _, err = p.communicate(timeout=120)
        results.append((args, p.returncode, err))
    assert results[0][1] == 0 and (tmp_path / "full-snapshots.png").stat().st_size > 10_000
    for args, rc, err in results[1:]:
        assert rc == 2, (args, err)
        assert "Traceback" not in err and "snapshots" in err.lower(), err
    assert "outputs.channels" in results[1][2]


def test_snapshot_lines_are_the_reference_shapes(reference):
    import cablesim
    from cablesim.plots.snapshots import snapshot_figure
    case, sol, m, C, P, y0 = reference
    run = cablesim.history(case, omega=OMEGA_F, duration=DURATION, output_step=0.01, integrator="dopri5")
    h = run.history
    fig = snapshot_figure(h, case.to_cable(), "t", count=5)
    shape_ax, disp_ax = fig.axes[:2]
    zref = sol.sol(h.t)[:60].T
    L, H = case.cable.L, case.cable.H
    lines = [ln for ln in shape_ax.get_lines() if len(ln.get_xdata()) == 32]
    # equilibrium + 5 instants, each drawn with the supports at its ends
    assert len(lines) == 6
    picks = np.unique(np.round(np.linspace(0, h.t.size - 1, 5)).astype(int))
    for ln, i in zip(lines[1:], picks):
        pts = np.vstack([[0, 0], (y0 + zref[i]).reshape(-1, 2), [L, H]])
        assert np.abs(np.column_stack([ln.get_xdata(), ln.get_ydata()]) - pts).max() < 1e-6
    base = np.vstack([[0, 0], y0.reshape(-1, 2), [L, H]])
    dlines = [ln for ln in disp_ax.get_lines() if len(ln.get_xdata()) == 32]
    assert len(dlines) == 5
    for ln, i in zip(dlines, picks):
        assert np.allclose(ln.get_xdata(), base[:, 0])
        want = np.concatenate([[0.0], zref[i, 1::2], [0.0]])
        assert np.abs(ln.get_ydata() - want).max() < 1e-6 * np.abs(zref).max()
    import matplotlib.pyplot as plt
    plt.close(fig)


def test_undamped_free_vibration_conserves_own_energy():
    """No damping, no forcing: 1/2 v.M.v + sum EA (l - S)^2 / (2 S) - F0.y is constant."""
    import cablesim
    d = heavy(n=30, point=[{"node": 20, "mass": 4.0}])
    d["damping"] = {"a0": 0.0, "a1": 0.0}
    case = case_from_dict(d)
    L, H, S, EA, m1 = cable_arrays(case)
    m = np.repeat(m1, 2)
    st = run_static(case, all_models=False)
    lam, phi = eigh(my_K(L, H, S, EA, st.exact.y), np.diag(m), subset_by_index=[2, 2])
    for integrator, tol in ((None, 1e-4), ("dopri5", 1e-6)):
        h = cablesim.free_vibration(case, mode=3, peak_velocity=0.5, duration=2.0, output_step=0.01,
                                    integrator=integrator).history
        assert h.status.name == "COMPLETED", h.message
        # the start is along mode 3 of the own eigenproblem, largest component 0.5 m/s
        p = phi[:, 0] * 0.5 / phi[np.argmax(np.abs(phi[:, 0])), 0]
        assert np.abs(h.v[0] - p).max() < 1e-8
        E = []
        for k in range(h.t.size):
            y = h.y0 + h.z[k]
            length, _, _ = geometry(L, H, S, EA, y)
            E.append(0.5 * m @ h.v[k] ** 2 + np.sum(EA * np.maximum(length - S, 0.0) ** 2 / (2 * S)) - case.F0 @ y)
        E = np.array(E)
        kinetic0 = 0.5 * m @ h.v[0] ** 2
        assert np.abs(h.z).max() > 0.01
        assert np.abs(E - E[0]).max() < tol * kinetic0, (h.integrator, np.abs(E - E[0]).max() / kinetic0)


def test_static_full_summary_and_modes_k_from_the_command_line(tmp_path):
    d = heavy(n=30, point=[{"node": 20, "mass": 4.0}])
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(d))
    procs = [_cli(["static", "c.yaml", "--no-plot", "-o", f"{k}.h5", *extra], tmp_path)
             for k, extra in (("full", ["--full"]), ("short", []), ("s", ["--modes", "5"]))]
    outs = []
    for p in procs:
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        outs.append(out)
    full, short, _ = outs
    case = case_from_dict(d)
    L, H, S, EA, m1 = cable_arrays(case)
    st = run_static(case, all_models=False)
    w = np.sqrt(eigh(my_K(L, H, S, EA, st.exact.y), np.diag(np.repeat(m1, 2)), eigvals_only=True))

    def rows(text, first_word):
        block = text.split(first_word, 1)[1].splitlines()[2:]
        out = []
        for line in block:
            parts = line.split()
            if not parts or not parts[0].isdigit():
                break
            out.append(parts)
        return out

    modes = rows(full, "Linear modes about the equilibrium")
    assert [int(r[0]) for r in modes] == list(range(1, 61))
    assert np.allclose([float(r[1]) for r in modes], w, rtol=1e-6)
    assert [int(r[0]) for r in rows(full, "Segment tensions")] == list(range(1, 32))
    dof_rows = [line for line in full.splitlines() if line.strip().startswith(("x", "y")) and "(" in line]
    assert len(dof_rows) == 60
    # the exact coordinates printed are those of the equilibrium (checked by own force balance above)
    y = np.array([float(line.split()[-1]) for line in dof_rows])
    assert np.abs(y - st.exact.y).max() < 1e-6 * np.abs(y).max()
    # without --full: shortened, and says so
    assert len([line for line in short.splitlines() if line.strip().startswith(("x", "y")) and "(" in line]) < 60
    assert "--full" in short
    _check_modes_file(tmp_path / "s.h5", case, w)


def _check_modes_file(path, case, w):
    """`cablesim static --modes 5`: the lowest 5 and the highest frequency, against dense eigh."""
    import h5py
    L, H, S, EA, m1 = cable_arrays(case)
    with h5py.File(path) as f:
        omega = f["modal/omega"][:]
        attrs = dict(f["modal"].attrs)
        y = f["static/exact/y"][:]
        shapes = f["modal/shapes"][:]
    # the stored equilibrium is one (own force balance), then own K and eigh
    assert np.abs(my_P(L, H, S, EA, y) - case.F0).max() < 1e-8 * np.abs(case.F0).max()
    K, m = my_K(L, H, S, EA, y), np.repeat(m1, 2)
    assert int(attrs["modes_computed"]) == 5 and omega.size == 5
    assert np.allclose(omega, w[:5], rtol=1e-9)
    assert math.isclose(float(attrs["omega_max"]), w[-1], rel_tol=1e-9)
    shapes = shapes if shapes.shape[0] == 60 else shapes.T
    _check_modes(K, m, omega, shapes, 5, w_all=w)


# ----------------------------------------------------------------------------------------------
# Defects found by these checks (each failed before its fix)
# ----------------------------------------------------------------------------------------------
def test_band_product_of_a_one_node_cable():
    A = np.array([[2.0, 0.5], [0.5, 3.0]])
    C = bd.band_storage(lower_band(A))
    assert np.allclose(bd.band_product(C, np.array([1.0, -2.0])), A @ [1.0, -2.0])


def test_history_of_a_one_node_heavy_cable_against_own_reference():
    import cablesim
    d = heavy(n=1, L=10.0, H=1.0, length=10.5, mu=2.0, point=[{"node": 1, "FL": [2.0, 5.0]}])
    d["integrator"] = {"rtol": 1e-11, "atol": 1e-15}  # the default atol (1e-10 of the chord) is 1e-5 of this response
    case = case_from_dict(d)
    st = run_static(case, all_models=False)
    L, H, S, EA, m1 = cable_arrays(case)
    m = np.repeat(m1, 2)
    y0 = st.exact.y
    assert np.abs(my_P(L, H, S, EA, y0) - case.F0).max() < 1e-9 * np.abs(case.F0).max()
    K = my_K(L, H, S, EA, y0)
    a0, a1, _ = _rayleigh(K, m, 1, 2, 0.02)
    C = a0 * np.diag(m) + a1 * K

    def rhs(t, s):
        return np.concatenate([s[2:], (case.F0 + case.FL * np.sin(3.0 * t) - C @ s[2:] - my_P(L, H, S, EA, y0 + s[:2])) / m])

    sol = solve_ivp(rhs, (0.0, 1.0), np.zeros(4), method="DOP853", rtol=1e-11, atol=1e-14, dense_output=True)
    h = cablesim.history(case, omega=3.0, duration=1.0, output_step=0.05, integrator="dopri5").history
    zref = sol.sol(h.t)[:2].T
    assert np.abs(h.z - zref).max() < 1e-6 * np.abs(zref).max()


def test_free_vibration_along_a_mode_above_the_computed_ones():
    import cablesim
    case = case_from_dict(heavy(n=30, modal={"modes": 5}))
    L, H, S, EA, m1 = cable_arrays(case)
    m = np.repeat(m1, 2)
    st = run_static(case, all_models=False)
    lam, phi = eigh(my_K(L, H, S, EA, st.exact.y), np.diag(m), subset_by_index=[7, 7])
    h = cablesim.free_vibration(case, mode=8, peak_velocity=0.1, duration=0.2).history
    p = phi[:, 0] * 0.1 / phi[np.argmax(np.abs(phi[:, 0])), 0]
    assert np.abs(h.v[0] - p).max() < 1e-8


def test_near_degenerate_modes_of_400_nodes_are_mass_orthonormal():
    case = case_from_dict(heavy(n=400, L=100.0, H=0.0, length=100.3, EA=4381066.0, mu=10.0, modal={"modes": 4}))
    st = run_static(case, all_models=False)
    L, H, S, EA, m1 = cable_arrays(case)
    from scipy.sparse.linalg import eigsh
    K, m = my_K_sparse(L, H, S, EA, st.exact.y), np.repeat(m1, 2)
    w = np.sqrt(np.sort(eigsh(K, k=4, M=sparse.diags(m).tocsc(), sigma=0.0, return_eigenvectors=False)))
    assert np.allclose(st.modes.omega, w, rtol=1e-8)
    assert (w[1] - w[0]) / w[0] < 1e-6  # the nearly degenerate pair
    phi = st.modes.shapes
    assert phi.shape == (800, 4)
    assert np.abs(phi.T @ (m[:, None] * phi) - np.eye(4)).max() < 1e-9


def test_case_from_a_mapping_with_numpy_numbers():
    d = heavy(n=10)
    d["cable"]["nodes"] = np.int64(10)
    d["cable"]["EA"] = np.float64(2.0e6)
    try:
        case = case_from_dict(d)
    except CablesimError:
        return  # a clear refusal would do
    assert case.cable.n_nodes == 10 and case.cable.EA == 2.0e6


def test_continuation_node_channels_are_checked_with_the_case():
    d = heavy(n=3, L=12.0, H=0.5, length=12.6, mu=1.5, point=[{"node": 2, "FL": [0.0, 5.0]}])
    d["continuation"] = {"omega": {"start": 1.0, "stop": 2.0}, "channels": ["node9.v"]}
    with pytest.raises(CablesimError, match=r"continuation\.channels"):
        case_from_dict(d)


def test_cable_as_long_as_its_chord_is_solved_or_refused_naming_the_field():
    case = case_from_dict(heavy(n=30, L=60.0, H=0.0, length=60.0, mu=1.5))
    try:
        st = run_static(case, all_models=False)
    except CablesimError as exc:
        assert "cable.length" in str(exc) or "cable.S" in str(exc), str(exc)
        return
    L, H, S, EA, _ = cable_arrays(case)
    assert np.abs(my_P(L, H, S, EA, st.exact.y) - case.F0).max() < 1e-6 * np.abs(case.F0).max()


def test_snapshots_of_a_history_keeping_every_dof_in_another_order():
    import cablesim
    from cablesim.plots.snapshots import snapshot_figure
    d = heavy(n=3, L=12.0, H=0.5, length=12.6, mu=1.5, point=[{"node": 2, "FL": [0.0, 5.0]}])
    case = case_from_dict(d)
    h = cablesim.history(case, omega=2.0, duration=0.5, output_step=0.05, integrator="dopri5").history
    # what `cablesim history` keeps for outputs.channels: [node3.v, node3.h, node2.v, node2.h, node1.v, node1.h]
    order = [channel_index(c, 6) + 1 for c in ("node3.v", "node3.h", "node2.v", "node2.h", "node1.v", "node1.h")]
    kept = h.keep(order)
    assert sorted(kept.dof_numbers) == [1, 2, 3, 4, 5, 6]
    fig = snapshot_figure(kept, case.to_cable(), "t", count=3)
    lines = [ln for ln in fig.axes[0].get_lines() if len(ln.get_xdata()) == 5]
    i = h.t.size - 1  # the last snapshot: equilibrium + z at the end, node by node
    pts = np.vstack([[0, 0], (h.y0 + h.z[i]).reshape(-1, 2), [12.0, 0.5]])
    assert np.abs(np.column_stack([lines[-1].get_xdata(), lines[-1].get_ydata()]) - pts).max() < 1e-12
