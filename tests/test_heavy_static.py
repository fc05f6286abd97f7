"""Static analysis of heavy cables: banded stiffness and modes, and output that scales with n."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

import cablesim
from cablesim.case import parse_case
from cablesim.io.report import static_summary
from cablesim.modal import modal_analysis, modal_analysis_banded
from cablesim.statics import band_to_dense, exact_equilibrium, tangent_stiffness, tangent_stiffness_band


def heavy(n: int, extra: str = "") -> cablesim.case.Case:
    return parse_case(
        f"cable: {{L: 300.0, H: 10.0, length: 306.0, nodes: {n}, EA: 2.0e8, mass_per_length: 2.0}}\n"
        f"loads: {{gravity: 9.81, point: [{{node: {max(1, n // 3)}, F: [2.0e2, 1.0e2], mass: 5.0}}]}}\n{extra}"
    )


@pytest.mark.parametrize("n", [1, 2, 7, 60])
def test_banded_stiffness_is_the_dense_one(n):
    case = heavy(n)
    cab = case.to_cable()
    ex = exact_equilibrium(cab, case.F0)
    K = tangent_stiffness(cab, ex.y)
    np.testing.assert_allclose(band_to_dense(tangent_stiffness_band(cab, ex.y)), K, rtol=0, atol=1e-12 * abs(K).max())


@pytest.mark.parametrize("n, n_shapes", [(7, None), (150, None), (150, 12)])
def test_banded_modes_are_the_dense_ones(n, n_shapes, monkeypatch):
    case = heavy(n)
    cab = case.to_cable()
    ex = exact_equilibrium(cab, case.F0)
    m = cab.mass_diagonal
    dense = modal_analysis(ex.K, m)
    if n_shapes is not None:  # the inverse-iteration route of large cables
        monkeypatch.setattr(cablesim.modal, "ALL_SHAPES_DOF", 0)
    band = modal_analysis_banded(tangent_stiffness_band(cab, ex.y), m, n_shapes=n_shapes)
    np.testing.assert_allclose(band.omega, dense.omega, rtol=1e-8)
    k = band.shapes.shape[1]
    assert k == (2 * n if n_shapes is None else n_shapes)
    np.testing.assert_allclose(band.shapes, dense.shapes[:, :k], atol=1e-7 * abs(dense.shapes).max())
    np.testing.assert_allclose(band.shapes.T @ (m[:, None] * band.shapes), np.eye(k), atol=1e-9)
    low = modal_analysis_banded(tangent_stiffness_band(cab, ex.y), m, n_modes=5)
    np.testing.assert_allclose(low.omega, dense.omega[:5], rtol=1e-8)


def test_static_of_2000_nodes_writes_a_small_file_and_a_short_summary(tmp_path):
    case = heavy(2000)
    run = cablesim.static(case)
    assert run.result.approximate is None  # the dense models are left out above 300 nodes
    text = static_summary(case, run.result)
    assert len(text.splitlines()) < 80 and "--full" in text
    assert len(static_summary(case, run.result, full=True).splitlines()) > 6000  # every DOF and segment
    path = run.to_hdf5(tmp_path / "heavy.h5")
    assert path.stat().st_size < 50e6
    with h5py.File(path, "r") as f:
        assert not f["static"].attrs["matrices_stored"]
        assert "K" not in f["static/exact"] and f["static/exact/K_band"].shape == (4, 4000)
        assert f["modal/omega"].shape == (100,)  # the lowest 100 modes by default above 300 nodes
        assert f["modal"].attrs["modes_computed"] == 100 and f["modal"].attrs["omega_max"] > 1e3
        assert 20 <= f["modal/shapes"].shape[1] < 100
        np.testing.assert_allclose(f["modal/omega"][:], run.result.modes.omega)


def test_matrices_on_request_and_below_the_size(tmp_path):
    small = cablesim.static(heavy(5))
    with h5py.File(small.to_hdf5(tmp_path / "small.h5"), "r") as f:
        assert f["static"].attrs["matrices_stored"] and f["static/exact/K"].shape == (10, 10)
        assert f["modal/shapes"].shape == (10, 10)
    with h5py.File(small.to_hdf5(tmp_path / "none.h5", matrices=False), "r") as f:
        assert "K" not in f["static/exact"] and "D" not in f["static/approximate"]
        np.testing.assert_allclose(f["static/exact/K_band"][:], small.result.K0_band)
    big = cablesim.static(heavy(250))
    with h5py.File(big.to_hdf5(tmp_path / "big.h5", matrices=True), "r") as f:
        assert f["static/exact/K"].shape == (500, 500) and f["static/approximate/N"].shape == (500, 500)
        assert f["static/exact/K"].compression == "gzip"


def test_heavy_span_example_parses_and_expands():
    from pathlib import Path

    from cablesim.case import load_case

    case, text = load_case(Path(__file__).resolve().parents[1] / "configs" / "heavy-span.yaml")
    assert case.cable.n_nodes == 100 and len(case.cable.S) == 101
    carried = 1.628 * 300.7 * 100 / 101 + 15.0  # the end half-segments hang on the supports
    assert sum(case.cable.masses) == pytest.approx(carried, rel=1e-12)
    assert sum(case.F0[1::2]) == pytest.approx(9.81 * carried, rel=1e-12)
    assert case.FL[2 * 19 + 1] == 200.0 and "length: 300.7" in text and "\nloads:\n  F0:" in text


def test_free_vibration_along_a_mode_beyond_the_kept_shapes(monkeypatch):
    from cablesim.analyses.setup import mode_velocity
    from cablesim.analyses.static import run_static

    case = heavy(30)
    full = run_static(case, all_models=False)
    monkeypatch.setattr(cablesim.modal, "ALL_SHAPES_DOF", 0)  # as for a large cable
    monkeypatch.setattr(cablesim.analyses.static, "ALL_SHAPES_DOF", 0)
    kept = run_static(case, all_models=False)
    assert kept.modes.shapes.shape[1] == 20
    v = mode_velocity(kept, 25, 1.0)
    np.testing.assert_allclose(v, mode_velocity(full, 25, 1.0), atol=1e-7)


def test_the_default_static_path_builds_no_dense_matrix(tmp_path, monkeypatch):
    """n = 400 (above the sizes that store matrices and compute every model): neither the dense
    tangent stiffness nor a dense eigensolver nor the O(n^2) slack test of the closure runs."""
    import cablesim.analyses.static
    import cablesim.mechanics.equilibrium
    import cablesim.statics

    def dense(*args, **kwargs):
        raise AssertionError("a dense O(n^2) computation ran")

    monkeypatch.setattr(cablesim.statics, "tangent_stiffness", dense)
    monkeypatch.setattr(cablesim.analyses.static, "modal_analysis", dense)
    monkeypatch.setattr(cablesim.mechanics.equilibrium, "slack_segment", dense)
    case = heavy(400)
    run = cablesim.static(case)
    static_summary(case, run.result)
    with h5py.File(run.to_hdf5(tmp_path / "heavy.h5"), "r") as f:
        assert "K" not in f["static/exact"] and f["static/exact/K_band"].shape == (4, 800)
    assert "K" not in vars(run.result.exact)  # the lazy dense stiffness was never asked for
    assert run.result.K0_band.shape == (4, 800) and run.result.exact.T.min() > 0


def test_banded_and_dense_static_results_agree():
    """The dense stiffness built on request equals the banded one the analysis used, and the
    modes of the dense eigensolver equal the banded ones."""
    from cablesim.analyses.static import run_static

    case = heavy(40)
    r = run_static(case, all_models=False)
    K = r.K0  # built now, from the equilibrium
    np.testing.assert_allclose(band_to_dense(r.K0_band), K, rtol=0, atol=1e-12 * abs(K).max())
    np.testing.assert_allclose(K, tangent_stiffness(r.cable, r.exact.y), rtol=0, atol=1e-12 * abs(K).max())
    dense = modal_analysis(K, r.cable.mass_diagonal)
    np.testing.assert_allclose(r.modes.omega, dense.omega, rtol=1e-9)
    np.testing.assert_allclose(r.modes.shapes, dense.shapes, atol=1e-7 * abs(dense.shapes).max())


def test_a_slack_segment_is_still_found_when_newton_runs_first():
    """The slack test now runs only after Newton fails or ends next to a kink. Segment 11 made
    400 m long, nodes 10 and 11 loaded with 1 MN down: with it removed, both halves hang nearly
    straight down from their supports, about 320 m apart, closer than 400 m (slack)."""
    from cablesim.cable import Cable
    from cablesim.errors import SlackSegmentError
    from cablesim.statics import inextensible_equilibrium

    case = heavy(30)
    c = case.to_cable()
    S = c.S.copy()
    S[10] = 400.0
    cable = Cable(c.L, c.H, S, c.EA, c.masses)
    P = case.F0.copy()
    P[2 * 9 + 1] += 1e6
    P[2 * 10 + 1] += 1e6
    for solve in (inextensible_equilibrium, exact_equilibrium):
        with pytest.raises(SlackSegmentError) as err:
            solve(cable, P)
        assert err.value.segment == 11


@pytest.mark.parametrize("analysis", ["exact", "approximate"])
def test_lowest_modes_are_those_of_the_full_eigendecomposition(analysis):
    """``n_modes = 10`` on a 40-node cable: the 10 lowest frequencies and shapes and the highest
    frequency of the full dense eigen-decomposition (scipy's eigh of K0 and M)."""
    from cablesim.analyses.static import run_static

    case = heavy(40)
    part = run_static(case, analysis, all_models=False, n_modes=10)
    K = part.exact.K if analysis == "exact" else part.approximate.K
    full = modal_analysis(K, part.cable.mass_diagonal)
    assert part.modes.omega.size == 10 and not part.modes.complete
    np.testing.assert_allclose(part.modes.omega, full.omega[:10], rtol=1e-9)
    k = part.modes.shapes.shape[1]
    np.testing.assert_allclose(part.modes.shapes, full.shapes[:, :k], atol=1e-7 * abs(full.shapes).max())
    assert part.modes.highest == pytest.approx(full.omega[-1], rel=1e-9)
    np.testing.assert_allclose(part.modes.omega_with_highest(), np.append(full.omega[:10], full.omega[-1]), rtol=1e-9)


def test_lowest_modes_keep_the_damping_and_the_dynamics_right():
    """With only the lowest modes the Rayleigh coefficients, the fastest damped root and so the
    default integrator are those of the complete spectrum (the highest frequency is kept)."""
    from cablesim.analyses.setup import build_equations, make_integrator
    from cablesim.analyses.static import run_static
    from cablesim.modal import fastest_rate

    case = heavy(60, "damping: {ratio: 0.01, modes: [1, 3]}")
    full = run_static(case, all_models=False, n_modes=None)
    assert full.modes.complete
    part = run_static(case, all_models=False, n_modes=2)
    assert part.modes.omega.size == 3  # raised to the damping's mode 3
    assert (part.a0, part.a1) == pytest.approx((full.a0, full.a1), rel=1e-12)
    eq_full, eq_part = build_equations(case, full, omega=2.0), build_equations(case, part, omega=2.0)
    assert fastest_rate(eq_part.frequencies, part.a0, part.a1) == pytest.approx(
        fastest_rate(eq_full.frequencies, full.a0, full.a1), rel=1e-9)
    assert make_integrator(case.integrator, eq_part, 2.0) == make_integrator(case.integrator, eq_full, 2.0)


def test_modal_modes_from_the_case_and_the_command_line(invoke_cli, tmp_path):
    """``modal: {modes: k}`` in the case and ``static --modes k``; a k beyond 2n or below 1 is
    refused naming the field."""
    from helpers_cli import assert_refused

    text = ("cable: {L: 300.0, H: 10.0, length: 306.0, nodes: 12, EA: 2.0e8, mass_per_length: 2.0}\n"
            "loads: {gravity: 9.81}\n")
    (tmp_path / "c.yaml").write_text(text + "modal: {modes: 4}\n")
    rc, out, err, _ = invoke_cli("static", "c.yaml", "--no-plot", "-o", "a.h5")
    assert rc == 0, err
    assert "the lowest 4 of 24" in out
    rc, out, err, _ = invoke_cli("static", "c.yaml", "--no-plot", "-o", "b.h5", "--modes", "6")
    assert rc == 0, err
    with h5py.File(tmp_path / "a.h5", "r") as fa, h5py.File(tmp_path / "b.h5", "r") as fb:
        assert fa["modal/omega"].shape == (4,) and fb["modal/omega"].shape == (6,)
        np.testing.assert_allclose(fb["modal/omega"][:4], fa["modal/omega"][:], rtol=1e-12)
        assert fa["modal"].attrs["omega_max"] == pytest.approx(fb["modal"].attrs["omega_max"], rel=1e-12)
    (tmp_path / "d.yaml").write_text(text + "modal: {modes: 25}\n")
    assert_refused(invoke_cli("static", "d.yaml", "--no-plot", "-o", "d.h5"), tmp_path, "modal.modes", "24",
                   keep=(tmp_path / "a.h5", tmp_path / "b.h5"))
    res = invoke_cli("static", "c.yaml", "--no-plot", "-o", "e.h5", "--modes", "0")
    assert res[0] == 2 and "--modes" in res[2]
