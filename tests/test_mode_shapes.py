"""Mode shapes drawn by `cablesim static` (NAME-modes.png) and `StaticRun.plot_modes`: the lines
of the figure are the static equilibrium and the shapes stored in the result file, read back
with h5py."""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np
import pytest

import cablesim
from cablesim.plots.modes import SHAPE_FRACTION

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def lines_by_gid(fig) -> dict:
    """Every line of the figure with a gid, by gid."""
    return {ln.get_gid(): ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid()}


def drawn_shape(fig, k: int, columns: int) -> np.ndarray:
    """The displacement drawn for mode k (1-based) at the interior nodes, (n, 2): the mode's
    line minus the static line, in the panel's two coordinates."""
    ax = next(a for a in fig.axes if any(ln.get_gid() == f"mode {k}" for ln in a.get_lines()))
    got = {ln.get_gid(): np.column_stack([ln.get_xdata(), ln.get_ydata()]) for ln in ax.get_lines() if ln.get_gid()}
    return (got[f"mode {k}"] - got["static"])[1:-1]


def test_static_draws_the_modes_stored_in_its_file(invoke_cli, tmp_path):
    res = invoke_cli("static", "-o", "st.h5", "--modes-drawn", "3")
    assert res.returncode == 0, res.stdout + res.stderr
    png = tmp_path / "st-modes.png"
    assert png.read_bytes()[:8] == PNG_MAGIC
    assert f"and {png.name}" in res.stdout.replace("st-modes.png", png.name)
    with h5py.File(tmp_path / "st.h5", "r") as f:
        shapes = f["modal/shapes"][()]
        omega = f["modal/omega"][()]
        xi = f["modal/damping_ratio"][()]
        y0 = f["static/exact/y"][()]
    run = cablesim.static(cablesim.load_case())
    fig = run.plot_modes(count=3)
    lines = lines_by_gid(fig)
    assert {"mode 1", "mode 2", "mode 3"} <= set(lines) and "mode 4" not in lines
    static = np.column_stack([lines["static"].get_xdata(), lines["static"].get_ydata()])[1:-1]
    np.testing.assert_allclose(static.ravel(), y0, rtol=1e-12)
    span = run.case.cable.L
    for k in (1, 2, 3):
        d = drawn_shape(fig, k, 2).ravel()
        phi = shapes[:, k - 1]
        scale = d @ phi / (phi @ phi)  # the drawing's factor: displacement = scale x shape
        np.testing.assert_allclose(d, scale * phi, atol=1e-9 * span)
        assert np.hypot(*d.reshape(-1, 2).T).max() == pytest.approx(SHAPE_FRACTION * span, rel=1e-9)
        title = next(a.get_title() for a in fig.axes if lines[f"mode {k}"] in a.get_lines())
        assert f"{omega[k - 1]:.4g} rad/s" in title
        assert f"{omega[k - 1] / (2 * math.pi):.4g} Hz" in title
        assert f"{100 * xi[k - 1]:.3g} %" in title


def test_modes_drawn_zero_draws_none_and_a_bad_count_is_refused(invoke_cli, tmp_path):
    res = invoke_cli("static", "-o", "a.h5")
    assert res.returncode == 0 and (tmp_path / "a-modes.png").is_file()
    res = invoke_cli("static", "-o", "a.h5", "--modes-drawn", "0")  # replaces the result: its old figures go
    assert res.returncode == 0, res.stdout + res.stderr
    assert (tmp_path / "a.png").is_file() and not (tmp_path / "a-modes.png").exists()
    res = invoke_cli("static", "-o", "b.h5", "--modes-drawn", "21")
    assert res.returncode == 2 and "--modes-drawn" in res.stderr
    assert not (tmp_path / "b.h5").exists()
    with pytest.raises(cablesim.api.CablesimError, match="modes-drawn"):
        cablesim.static(cablesim.load_case()).plot_modes(count=0)


def test_out_of_plane_modes_are_drawn_in_plan_view(tmp_path):
    case = cablesim.load_case(None, ["spatial=true"])
    run = cablesim.static(case)
    kinds = run.result.modes.kinds
    assert "out-of-plane" in kinds and "in-plane" in kinds
    path = tmp_path / "m.png"
    fig = run.plot_modes(path, count=len(kinds))
    assert path.read_bytes()[:8] == PNG_MAGIC
    shapes = run.result.modes.shapes.reshape(case.cable.n_nodes, 3, -1)
    for k, kind in enumerate(kinds, start=1):
        d = drawn_shape(fig, k, 2)
        plan = kind == "out-of-plane"
        phi = shapes[:, [0, 2 if plan else 1], k - 1]
        scale = d.ravel() @ phi.ravel() / (phi.ravel() @ phi.ravel())
        np.testing.assert_allclose(d, scale * phi, atol=1e-9 * case.cable.L)
        title = next(a.get_title() for a in fig.axes if lines_by_gid(fig)[f"mode {k}"] in a.get_lines())
        assert kind in title
        ax = next(a for a in fig.axes if lines_by_gid(fig)[f"mode {k}"] in a.get_lines())
        assert ("$w$" in ax.get_ylabel()) == plan


def test_plot_redraws_the_mode_figure_from_the_file(tmp_path):
    run = cablesim.static(cablesim.load_case())
    h5 = run.to_hdf5(tmp_path / "s.h5")
    written = cablesim.plot([h5])
    assert Path(tmp_path / "s-modes.png") in [Path(p) for p in written]


@pytest.mark.parametrize("overrides, count", [([], 4), (["spatial=true"], 6)])
def test_no_text_of_the_mode_figure_overlaps(overrides, count):
    from helpers_figures import text_problems

    from cablesim.plots.style import journal_style

    fig = cablesim.static(cablesim.load_case(None, overrides)).plot_modes(count=count)
    with journal_style():
        assert text_problems(fig) == []
