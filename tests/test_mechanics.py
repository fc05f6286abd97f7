"""The mechanics core (cablesim/mechanics/) at two and three components per node, against the
independent reference of helpers_mechanics.py (own assembly, scipy closure solves, complex steps
and central differences), and the source check that its laws are written nowhere else."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from cablesim.cable import Cable
from cablesim.mechanics import assembly as asm
from cablesim.mechanics import banded as bd
from cablesim.mechanics import flexibility as fx
from cablesim.mechanics import segments as sg
from cablesim.statics import approximate_equilibrium, exact_equilibrium, inextensible_equilibrium

import helpers_mechanics as ref

ROOT = Path(__file__).resolve().parents[1] / "cablesim"


def spatial_cable(n: int, seed: int, dim: int = 3):
    """A cable of n nodes with B out of the plane (dim 3) and its loads with sideways parts."""
    rng = np.random.default_rng(seed)
    L, H = 100.0, 15.0 * rng.uniform(-1, 1)
    W = 20.0 * rng.uniform(0.2, 1.0) if dim == 3 else 0.0
    chord = np.sqrt(L * L + H * H + W * W)
    S = rng.uniform(0.5, 1.5, n + 1)
    S *= 1.08 * chord / S.sum()
    P = np.zeros((n, dim))
    P[:, 1] = rng.uniform(500.0, 2000.0, n)  # downwards
    P[:, 0] = rng.uniform(-200.0, 200.0, n)
    if dim == 3:
        P[:, 2] = rng.uniform(-300.0, 300.0, n)  # sideways (wind)
    return Cable(L, H, S, 2.0e7, np.ones(n), W=W, dim=dim), P.ravel()


def perturbed_configuration(cable, P, seed, size=0.05):
    inext = inextensible_equilibrium(cable, P)
    rng = np.random.default_rng(seed)
    return inext.x + size * rng.standard_normal(inext.x.size)


# ----------------------------------------------------------------------------------------------
# Segment law and assembly
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("n", [1, 2, 6])
def test_forces_and_tangents_against_own_assembly_and_differences(dim, n):
    cable, P = spatial_cable(n, seed=10 * n + dim, dim=dim)
    y = perturbed_configuration(cable, P, seed=n)
    S, EA, A, B = cable.S, cable.EA, cable.support_A, cable.support_B
    chord = cable.chord
    taut = np.ones(n + 1)
    nd = cable.n_dof
    P_ref = ref.resisting_force(y, S, EA, chord, dim)
    K_ref = ref.jacobian(lambda q: ref.resisting_force(q, S, EA, chord, dim), y, 1e-5)
    scale = np.abs(K_ref).max()
    Pa, Kv, K = np.empty(nd), np.empty(nd), np.empty((nd, nd))
    v = np.random.default_rng(3).standard_normal(nd)
    zero = (0.0,) * dim
    asm.force_and_rate(y, v, S, EA, A, B, zero, zero, taut, Pa, Kv)
    np.testing.assert_allclose(Pa, P_ref, rtol=0, atol=1e-12 * np.abs(P_ref).max())
    np.testing.assert_allclose(Kv, K_ref @ v, rtol=0, atol=1e-7 * scale * np.abs(v).max())
    asm.force_and_stiffness(y, S, EA, A, B, taut, Pa, K)
    np.testing.assert_allclose(K, K_ref, rtol=0, atol=1e-7 * scale)
    assert np.array_equal(K, K.T)  # exactly symmetric
    np.testing.assert_allclose(K @ v, Kv, rtol=0, atol=1e-12 * np.abs(Kv).max())
    Kb = np.empty((bd.band_rows(dim), nd))
    asm.force_and_stiffness_band(y, S, EA, A, B, taut, Pa, Kb)
    hb = bd.band_half(dim)
    dense = np.zeros((nd, nd))
    for i in range(nd):
        for j in range(max(0, i - hb), min(nd, i + hb + 1)):
            dense[i, j] = Kb[hb + i - j, j]
    assert np.array_equal(dense, K)
    np.testing.assert_allclose(bd.band_product(Kb, v), K @ v, rtol=0, atol=1e-12 * np.abs(K @ v).max())
    # a slack segment contributes nothing
    taut[n // 2] = 0.0
    asm.force_and_rate(y, v, S, EA, A, B, zero, zero, taut, Pa, Kv)
    np.testing.assert_allclose(Pa, ref.resisting_force(y, S, EA, chord, dim, taut), rtol=0, atol=1e-12 * np.abs(P_ref).max())


@pytest.mark.parametrize("dim", [2, 3])
def test_the_displaced_form_is_the_configuration_form(dim):
    cable, P = spatial_cable(4, seed=5, dim=dim)
    y0 = exact_equilibrium(cable, P).y
    z = 1e-3 * np.random.default_rng(2).standard_normal(cable.n_dof)
    nd, zero = cable.n_dof, (0.0,) * dim
    x = np.concatenate([z, np.zeros(nd)])  # the orbits' state (z, v)
    P1, J = np.empty(nd), np.zeros((2 * nd, 2 * nd))
    # every segment taut, and one in the slack mode (no force, no stiffness: the orbits through slack)
    for taut in (np.ones(5), np.array([1.0, 1.0, 0.0, 1.0, 1.0])):
        assert asm.displaced_force_and_stiffness(x, y0, cable.S, cable.EA, cable.support_A, cable.support_B,
                                                 zero, zero, taut, P1, J, nd, 0) == -1
        P2, K = np.empty(nd), np.empty((nd, nd))
        asm.force_and_stiffness(y0 + z, cable.S, cable.EA, cable.support_A, cable.support_B, taut, P2, K)
        np.testing.assert_allclose(P1, P2, rtol=0, atol=1e-9 * np.abs(P2).max())
        np.testing.assert_allclose(J[nd:, :nd], K, rtol=1e-12, atol=1e-12 * np.abs(K).max())


@pytest.mark.parametrize("dim", [2, 3])
def test_support_velocities_enter_the_rate_of_the_force(dim):
    """With supports moving, force_and_rate's product is the whole ``dP/dt``: the derivative of
    P(y(t), B(t)) along node and support velocities, checked by central differences."""
    cable, P = spatial_cable(3, seed=8, dim=dim)
    y = perturbed_configuration(cable, P, seed=4)
    rng = np.random.default_rng(6)
    v, vA, vB = rng.standard_normal(cable.n_dof), rng.standard_normal(dim), rng.standard_normal(dim)
    A0, B0 = np.zeros(dim), cable.chord

    def force(tau):
        A, B = A0 + tau * vA, B0 + tau * vB
        d = np.diff(np.vstack([A, np.reshape(y + tau * v, (-1, dim)), B]), axis=0)
        l = np.sqrt((d * d).sum(axis=1))
        F = (cable.EA * (l - cable.S) / cable.S / l)[:, None] * d
        return (F[:-1] - F[1:]).ravel()

    h = 1e-5
    rate_ref = (force(h) - force(-h)) / (2 * h)
    Pa, Kv = np.empty(cable.n_dof), np.empty(cable.n_dof)
    asm.force_and_rate(y, v, cable.S, cable.EA, tuple(A0), tuple(B0), tuple(vA), tuple(vB), np.ones(4), Pa, Kv)
    np.testing.assert_allclose(Kv, rate_ref, rtol=0, atol=1e-6 * np.abs(rate_ref).max())


def test_tension_law_and_gaps():
    cable, P = spatial_cable(3, seed=2)
    y = perturbed_configuration(cable, P, seed=3)
    n1 = cable.n_segments
    l, e, T = np.empty(n1), np.empty((n1, 3)), np.empty(n1)
    sg.segment_states(y, cable.S, cable.EA, cable.support_A, cable.support_B, l, e, T)
    d = np.diff(ref.nodes(y, cable.chord, 3), axis=0)
    np.testing.assert_allclose(l, np.linalg.norm(d, axis=1), rtol=1e-15)
    np.testing.assert_allclose(e, d / l[:, None], rtol=1e-15)
    np.testing.assert_allclose(T, cable.EA * (l - cable.S) / cable.S, rtol=1e-13)
    g = np.empty(n1)
    sg.gaps(y, cable.S, cable.support_A, cable.support_B, g)
    np.testing.assert_allclose(g, l - cable.S, rtol=1e-13)


# ----------------------------------------------------------------------------------------------
# Closure
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [1, 3, 8])
def test_spatial_inextensible_closure_against_an_independent_solve(n):
    cable, P = spatial_cable(n, seed=n)
    got = inextensible_equilibrium(cable, P)
    F1 = ref.solve_closure(P, cable.S, cable.chord, 3)
    x_ref, T_ref, _ = ref.inextensible_state(P, cable.S, cable.chord, 3, F_start=F1)
    np.testing.assert_allclose(got.segments.F[0], F1, rtol=0, atol=1e-10 * np.abs(F1).max())
    np.testing.assert_allclose(got.T, T_ref, rtol=1e-10)
    np.testing.assert_allclose(got.x, x_ref, rtol=0, atol=1e-10 * cable.chord_length)
    assert got.segments.closure_error < 1e-11 * cable.chord_length


@pytest.mark.parametrize("n", [2, 5])
def test_spatial_exact_equilibrium_against_an_independent_solve(n):
    cable, P = spatial_cable(n, seed=20 + n)
    got = exact_equilibrium(cable, P)
    y_ref = ref.exact_equilibrium(P, cable.S, cable.EA, cable.chord, 3, inextensible_equilibrium(cable, P).x)
    np.testing.assert_allclose(got.y, y_ref, rtol=0, atol=1e-9 * cable.chord_length)
    np.testing.assert_allclose(ref.resisting_force(got.y, cable.S, cable.EA, cable.chord, 3), P, rtol=0,
                               atol=1e-6 * np.abs(P).max())
    # dy/dP by implicit differentiation is the inverse of the assembled tangent
    np.testing.assert_allclose(got.dydP @ got.K, np.eye(cable.n_dof), rtol=0, atol=1e-8)


def test_a_planar_case_posed_in_space_stays_in_its_plane():
    planar, P2 = spatial_cable(5, seed=3, dim=2)
    space = planar.spatial()
    P3 = np.column_stack([P2.reshape(-1, 2), np.zeros(5)]).ravel()
    for solve in (inextensible_equilibrium, exact_equilibrium):
        a, b = solve(planar, P2), solve(space, P3)
        ya = a.x if hasattr(a, "x") else a.y
        yb = b.x if hasattr(b, "x") else b.y
        yb = yb.reshape(-1, 3)
        assert np.abs(yb[:, 2]).max() == 0.0
        np.testing.assert_allclose(yb[:, :2].ravel(), ya, rtol=0, atol=1e-12 * planar.chord_length)
        np.testing.assert_allclose(b.T, a.T, rtol=1e-12)


def test_rotating_the_span_about_the_vertical_rotates_the_solution():
    planar, P2 = spatial_cable(4, seed=9, dim=2)
    a = 0.7
    R = ref.rotation_about_vertical(a)
    B = R @ np.array([planar.L, planar.H, 0.0])
    turned = Cable(B[0], B[1], planar.S, planar.EA, planar.masses, W=B[2], dim=3)
    P3 = (np.column_stack([P2.reshape(-1, 2), np.zeros(4)]) @ R.T).ravel()
    base = exact_equilibrium(planar.spatial(), np.column_stack([P2.reshape(-1, 2), np.zeros(4)]).ravel())
    rot = exact_equilibrium(turned, P3)
    np.testing.assert_allclose(rot.T, base.T, rtol=1e-11)
    np.testing.assert_allclose(rot.y.reshape(-1, 3), base.y.reshape(-1, 3) @ R.T, rtol=0, atol=1e-9)


# ----------------------------------------------------------------------------------------------
# The approximate analysis' flexibility
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [1, 2, 5])
def test_spatial_flexibility_against_differences_of_the_independent_states(n):
    """x(P), u(P), T(P) of the reference (scipy closure, complex-step u = dOmega_e/dP);
    D = dx/dP, N = dy/dP = D + f, B = dT/dP by central differences; and the factored K."""
    cable, P = spatial_cable(n, seed=40 + n)
    S, EA, chord = cable.S, cable.EA, cable.chord
    app = approximate_equilibrium(cable, P)
    x_ref, T_ref, F1 = ref.inextensible_state(P, S, chord, 3)
    u_ref = ref.elastic_displacement(P, S, EA, chord, 3, F1)
    np.testing.assert_allclose(app.x, x_ref, rtol=0, atol=1e-10 * cable.chord_length)
    np.testing.assert_allclose(app.u, u_ref, rtol=0, atol=1e-9 * np.abs(u_ref).max())
    h = 1e-4 * np.abs(P).max()

    def state(Pq):
        x, T, F = ref.inextensible_state(Pq, S, chord, 3, F_start=F1)
        return x, T, ref.elastic_displacement(Pq, S, EA, chord, 3, F)

    D_ref = ref.jacobian(lambda q: state(q)[0], P, h)
    B_ref = ref.jacobian(lambda q: state(q)[1], P, h)
    N_ref = ref.jacobian(lambda q: state(q)[0] + state(q)[2], P, h)
    tol = 1e-6
    np.testing.assert_allclose(app.D, D_ref, rtol=0, atol=tol * np.abs(D_ref).max())
    np.testing.assert_allclose(app.B, B_ref, rtol=0, atol=tol * np.abs(B_ref).max())
    np.testing.assert_allclose(app.N, N_ref, rtol=0, atol=tol * np.abs(N_ref).max())
    np.testing.assert_allclose(app.f, N_ref - D_ref, rtol=0, atol=tol * np.abs(N_ref).max())
    np.testing.assert_allclose(app.K @ app.N, np.eye(cable.n_dof), rtol=0, atol=1e-8)
    # identities of homogeneity (docs/theory.md, section 4.1), at three components per node
    scale = np.abs(app.D).max() * np.abs(P).max()
    assert np.abs(app.D @ P).max() < 1e-12 * scale
    np.testing.assert_allclose(app.B @ P, app.T, rtol=1e-12)
    np.testing.assert_allclose(app.N @ P, app.u, rtol=0, atol=1e-11 * np.abs(app.u).max())
    np.testing.assert_allclose(app.B.T @ (app.T * S / EA), app.u, rtol=0, atol=1e-12 * np.abs(app.u).max())
    assert P @ app.u == pytest.approx(2.0 * app.omega_e, rel=1e-11)


def test_spatial_factored_products_are_the_inverse_of_the_forward_one():
    cable, P = spatial_cable(9, seed=77)
    app = approximate_equilibrium(cable, P)
    fac, gi = app.factors.fac, app.factors.gi
    like = (0.0, 0.0, 0.0)
    nd = cable.n_dof
    rng = np.random.default_rng(1)
    v = rng.standard_normal(nd)
    out, scratch = np.empty(nd), fx.factor_workspace(9, 3)[2]
    fx.stiffness_product(fac, gi, v, out, scratch, like)
    np.testing.assert_allclose(app.N @ out, v, rtol=0, atol=1e-10 * np.abs(v).max())
    Kb, U = np.empty((bd.band_rows(3), nd)), np.empty((nd, 3))
    fx.stiffness_band(fac, gi, Kb, U, like)
    K = bd.band_product(Kb, v) - U @ (gi[:9].reshape(3, 3) @ (U.T @ v))
    np.testing.assert_allclose(K, out, rtol=0, atol=1e-9 * np.abs(out).max())


# ----------------------------------------------------------------------------------------------
# Each law written once
# ----------------------------------------------------------------------------------------------
#: ``EA (l - S) / S`` and its variants (``EA * stretch / S``, ``EA * max(g, 0) / S``).
TENSION_LAW = re.compile(r"\bEA\b\s*\*\s*[^\n#]*/\s*[\w.\[\]]*\bS\w*\b")
#: The complementary energy's segment term ``S |F| (1 + eps |F| / 2)``.
ENERGY_TERM = re.compile(r"0\.5\s*\*\s*eps\s*\*")


def test_the_segment_law_and_the_closure_are_written_only_in_mechanics():
    found = []
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith("mechanics/"):
            continue
        for i, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0]
            if '"""' in line or "``" in line:
                continue  # documentation quotes the law
            if TENSION_LAW.search(code) or ENERGY_TERM.search(code):
                found.append(f"{rel}:{i}: {line.strip()}")
    assert not found, "\n".join(found)


def test_the_check_finds_a_tension_law():
    """The pattern of the source check matches the forms the law was written in."""
    for line in ("T = EA * (l - S[k]) / S[k]", "T = cable.EA * (length - cable.S) / cable.S",
                 "T = EA * max(g[k], 0.0) / S[k]", "T = EA * stretch / Sk"):
        assert TENSION_LAW.search(line), line
    assert ENERGY_TERM.search("phi += S[k] * T * (1.0 + 0.5 * eps * T)")
