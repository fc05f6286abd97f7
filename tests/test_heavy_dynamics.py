"""Heavy cables in the time loop: banded damping products agree with the dense ones."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.mechanics import banded as bd
from cablesim.mechanics import assembly as asm
from cablesim.dynamics.field import rate
from cablesim.dynamics.integrators import DOPRI5, GeneralizedAlpha, RK4
from cablesim.dynamics.simulate import simulate
from cablesim.statics import band_to_dense

N = 24


@pytest.fixture(scope="module")
def equations():
    case = parse_case(
        f"cable: {{L: 100.0, H: 5.0, length: 102.5, nodes: {N}, EA: 2.0e8, mass_per_length: 10.0}}\n"
        "loads: {gravity: 9.81, point: [{node: 8, F: [0.0, 5.0e3], FL: [300.0, 1.0e3]}]}\n"
    )
    banded = build_equations(case, run_static(case, all_models=False), omega=2.0)
    dense = dataclasses.replace(banded, K0_band=None, K0_dense=band_to_dense(banded.K0_band))
    assert dense.C_band is None
    return banded, dense


def test_band_storage_holds_the_dense_damping(equations):
    banded, _ = equations
    assert banded.C_band is not None and banded.C_band.shape == (bd.band_rows(2), 2 * N)
    lower = np.zeros((4, 2 * N))
    for d in range(4):
        lower[d, : 2 * N - d] = banded.C_band[bd.band_half(2) + d, : 2 * N - d]
    np.testing.assert_allclose(band_to_dense(lower), banded.C, rtol=0, atol=1e-12 * abs(banded.C).max())
    v = np.random.default_rng(3).standard_normal(2 * N)
    for C in (banded.C, banded.C_band):
        got = np.array([bd.damping_row(np.ascontiguousarray(C), v, 0, i) for i in range(2 * N)])
        np.testing.assert_allclose(got, banded.C @ v, rtol=1e-12, atol=1e-12 * abs(banded.C @ v).max())


def test_band_product_and_internal_force_match_the_dense_products(equations):
    banded, dense = equations
    rng = np.random.default_rng(11)
    v = rng.standard_normal(2 * N)
    ref = dense.C @ v
    np.testing.assert_allclose(bd.band_product(banded.C_band, v), ref, rtol=0, atol=1e-13 * abs(ref).max())
    np.testing.assert_allclose(banded.damping_force(v), ref, rtol=0, atol=1e-13 * abs(ref).max())
    s = rng.standard_normal(6 * N)
    P_dense = dense.F0 + dense.FL * np.sin(dense.omega * 0.7) - dense.C @ s[2 * N : 4 * N] - dense.mass * s[4 * N :]
    np.testing.assert_allclose(banded.internal_force(0.7, s), P_dense, rtol=0, atol=1e-12 * abs(P_dense).max())
    with pytest.raises(ValueError, match="exactly one"):
        dataclasses.replace(banded, K0_dense=dense.K0)


def test_time_loop_of_the_exact_analysis_builds_no_dense_matrix():
    """At set-up and in the time loop the exact analysis keeps K0 and C banded: neither the
    static result's dense tangent stiffness nor the equations' dense K0 or C is ever built."""
    case = parse_case(
        "cable: {L: 100.0, H: 0.0, length: 102.5, nodes: 60, EA: 2.0e8, mass_per_length: 10.0}\n"
        "loads: {gravity: 9.81, point: [{node: 20, FL: [0.0, 1.0e3]}]}\n"
    )
    static = run_static(case, all_models=False)
    eom = build_equations(case, static, omega=2.0)
    for integ in (make_integrator(case.integrator, eom, 2.0), RK4(dt=1e-5)):
        assert simulate(eom, integ, 2e-3, 1e-3).completed
    assert eom.initial_state().shape == (6 * 60,)
    built = [name for obj, name in ((static.exact, "K"), (eom, "K0"), (eom, "C")) if name in vars(obj)]
    assert built == []
    assert eom.model().Cr.shape == (120, 0)  # no low-rank damping part in the exact analysis


def test_rate_is_the_same_with_banded_and_dense_damping(equations):
    rng = np.random.default_rng(0)
    banded, dense = equations
    s = banded.initial_state() + np.concatenate([1e-6 * rng.standard_normal(2 * N), 1e-2 * rng.standard_normal(4 * N)])
    got = []
    for eom in (banded, dense):
        ds = np.empty_like(s)
        assert rate(eom.model(), 0.3, s, np.array(eom.F1), ds, *eom.workspaces()) == 0
        got.append(ds)
    np.testing.assert_allclose(got[0], got[1], rtol=1e-12, atol=1e-12 * abs(got[1]).max())


@pytest.mark.parametrize("integrator", [DOPRI5(rtol=1e-8, atol=1e-9), RK4(dt=2e-4), GeneralizedAlpha(dt=2e-3)],
                         ids=["dopri5", "rk4", "generalized-alpha"])
def test_histories_agree(equations, integrator):
    banded, dense = equations
    hb, hd = (simulate(e, integrator, 1.0, 0.1) for e in (banded, dense))
    assert hb.completed and hd.completed
    scale = abs(hd.z).max()
    assert scale > 1e-3
    np.testing.assert_allclose(hb.z, hd.z, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(hb.residual, hd.residual, rtol=0, atol=1e-8)


def test_default_for_a_fine_heavy_cable_is_implicit_and_accurate():
    """The default rule: implicit once the fastest damped root exceeds STIFF_RATIO times the
    frequency of interest (here a1 w_max^2 ~ 3200 1/s against 2 rad/s); error < 1e-4."""
    case = parse_case(
        "cable: {L: 100.0, H: 0.0, length: 102.5, nodes: 10, EA: 2.0e8, mass_per_length: 10.0}\n"
        "loads: {gravity: 9.81, point: [{node: 3, FL: [0.0, 1.0e3]}]}\n"
    )
    eom = build_equations(case, run_static(case, all_models=False), omega=2.0)
    assert eom.C_band is not None
    default = make_integrator(case.integrator, eom, 2.0)
    assert default.name == "generalized-alpha"
    ref = simulate(eom, DOPRI5(rtol=1e-10, atol=1e-12 * eom.cable.chord_length), 6.0, 0.05, split=False)
    got = simulate(eom, default, 6.0, 0.05, split=False)
    assert got.completed and ref.completed
    assert np.abs(got.z - ref.z).max() < 1e-4 * np.abs(ref.z).max()


def test_banded_stiffness_kernel_and_solve(equations):
    eom, _ = equations
    cab = eom.cable
    y = eom.y0 + 1e-6 * np.random.default_rng(5).standard_normal(2 * N)
    P, K, Pb, Kb = np.empty(2 * N), np.empty((2 * N, 2 * N)), np.empty(2 * N), np.empty((bd.band_rows(2), 2 * N))
    taut = np.ones(N + 1)  # every segment in its taut mode
    asm.force_and_stiffness(y, cab.S, cab.EA, cab.support_A, cab.support_B, taut, P, K)
    asm.force_and_stiffness_band(y, cab.S, cab.EA, cab.support_A, cab.support_B, taut, Pb, Kb)
    dense = np.zeros_like(K)
    for i in range(2 * N):
        for j in range(max(0, i - 3), min(2 * N, i + 4)):
            dense[i, j] = Kb[bd.band_half(2) + i - j, j]
    np.testing.assert_allclose(Pb, P, rtol=0, atol=1e-12 * abs(P).max())
    np.testing.assert_allclose(dense, K, rtol=0, atol=1e-12 * abs(K).max())
    J, Jb = K + 1e4 * np.diag(eom.mass), Kb.copy()
    Jb[bd.band_half(2)] += 1e4 * eom.mass
    b, x = np.arange(2.0 * N), np.empty(2 * N)
    assert bd.solve_band(Jb, b, x, np.empty_like(Jb))
    np.testing.assert_allclose(x, np.linalg.solve(J, b), rtol=1e-10, atol=0)


def test_split_is_skipped_by_default_above_100_nodes():
    from cablesim.analyses.dynamic import split_outputs

    text = "cable: {L: 100.0, H: 0.0, length: 102.5, nodes: %d, EA: 2.0e8, mass_per_length: 10.0}\nloads: {gravity: 9.81}\n"
    assert split_outputs(parse_case(text % 100)) and not split_outputs(parse_case(text % 101))
    assert split_outputs(parse_case(text % 101 + "outputs: {split: true}\n"))
    assert not split_outputs(parse_case(text % 10 + "outputs: {split: false}\n"))
    assert split_outputs(parse_case(text % 101), split=True)
