"""Point loads and masses placed by position (``loads.point`` items with ``x`` or ``s``): on
the nearest node, with the snap distance stated; the heavy-span example keeps its loads where
they were whatever ``cable.nodes``.

The reference positions are computed here from the expanded case alone: the node that carries
the extra mass (its lumped mass minus the cable's own share) or the harmonic load, and its
natural length from support A.
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from cablesim.case import load_case, parse_case
from cablesim.errors import CablesimError
from helpers_cli import assert_refused

REPO_HEAVY = "configs/heavy-span.yaml"
MARKER, MARKER_KG, DRIVE = 150.0, 15.0, 60.0  # the example's x of the marker ball and of the harmonic load


def _node_positions(case) -> np.ndarray:
    """Each interior node's position along the span, m: its share of the natural length times L."""
    S = np.asarray(case.cable.S)
    return np.cumsum(S)[:-1] / S.sum() * case.cable.L


@pytest.mark.parametrize("nodes", [7, 40, 100, 333])
def test_heavy_span_keeps_its_point_loads_within_half_a_segment(nodes):
    from conftest import REPO

    case = load_case(REPO / REPO_HEAVY, [f"cable.nodes={nodes}"])[0]
    x = _node_positions(case)
    S = np.asarray(case.cable.S)
    half = 0.5 * S.max() * case.cable.L / S.sum()
    own = 0.5 * 1.628 * (S[:-1] + S[1:])
    marker = int(np.flatnonzero(np.abs(np.asarray(case.cable.masses) - own - MARKER_KG) < 1e-9)[0])
    drive = int(np.flatnonzero(case.FL[1::2])[0])
    assert case.FL[1::2][drive] == pytest.approx(200.0)
    assert abs(x[marker] - MARKER) <= half + 1e-9
    assert abs(x[drive] - DRIVE) <= half + 1e-9
    placed = {p.given: p for p in case.placements}
    assert placed["x = 150 m"].node == marker + 1 and placed["x = 60 m"].node == drive + 1
    assert placed["x = 150 m"].snap == pytest.approx(abs(x[marker] - MARKER), abs=1e-9)
    assert placed["x = 60 m"].snap == pytest.approx(abs(x[drive] - DRIVE), abs=1e-9)
    assert np.min(np.abs(x - DRIVE)) == pytest.approx(placed["x = 60 m"].snap, abs=1e-9)  # the nearest node


TWO = """\
cable: {L: 100.0, H: 0.0, S: [30.0, 50.0, 22.0], EA: 1.0e8, masses: [10.0, 10.0]}
loads: {F0: [0.0, 100.0, 0.0, 100.0], point: [POINT]}
"""


def test_s_is_a_fraction_of_the_natural_length():
    case = parse_case(TWO.replace("POINT", "{s: 0.45, F: [0.0, 50.0], mass: 3.0}"))
    # node 1 at s = 30/102, node 2 at 80/102: 0.45 is nearer node 1 (0.294) than node 2 (0.784)
    assert case.placements[0].node == 1
    assert case.placements[0].snap == pytest.approx(abs(0.45 - 30.0 / 102.0) * 102.0)
    assert case.F0.tolist() == pytest.approx([0.0, 150.0, 0.0, 100.0])
    assert case.cable.masses == pytest.approx((13.0, 10.0))


@pytest.mark.parametrize("point, needles", [
    ("{x: 120.0, F: [0.0, 1.0]}", ["loads.point[1].x", "beyond the span L = 100 m"]),
    ("{node: 1, x: 10.0, F: [0.0, 1.0]}", ["loads.point", "gives node and x", "exactly one of"]),
    ("{F: [0.0, 1.0]}", ["loads.point", "gives no position"]),
    ("{s: 1.5, F: [0.0, 1.0]}", ["loads.point", ".s"]),
])
def test_bad_positions_are_refused(point, needles):
    with pytest.raises(CablesimError) as err:
        parse_case(TWO.replace("POINT", point))
    for needle in needles:
        assert needle in " ".join(str(err.value).split())


def test_static_states_the_snap_distance(invoke_cli, write_case, tmp_path):
    path = write_case(TWO.replace("POINT", "{x: 70.0, F: [0.0, 50.0]}"))
    res = invoke_cli("static", str(path), "-o", "out.h5", "--no-plot")
    assert res[0] == 0, res
    x_node = 80.0 / 102.0 * 100.0  # node 2, the nearer to x = 70 m
    assert "loads.point[1] at x = 70 m: node 2" in res[1] and f"snap distance {abs(x_node - 70.0):.4g} m" in res[1]
    with h5py.File(tmp_path / "out.h5") as f:
        st = f["static"]
        assert list(st.attrs["point_load_node"]) == [2]
        assert st.attrs["point_load_snap"][0] == pytest.approx(abs(x_node - 70.0))
        assert st.attrs["point_load_x"][0] == pytest.approx(x_node)
        assert '"point_load_snap": "m"' in st.attrs["units"]
        assert f["static/P"][3] == pytest.approx(150.0)  # the 50 N went onto node 2, vertical
    check = invoke_cli("check", str(path))
    assert check[0] == 0 and "snap distance" in check[1]


def test_a_position_beyond_the_span_is_refused_on_the_command_line(invoke_cli, write_case, tmp_path):
    path = write_case(TWO.replace("POINT", "{x: 101.0, F: [0.0, 50.0]}"))
    assert_refused(invoke_cli("static", str(path)), tmp_path, "loads.point[1].x", "beyond the span")


def test_the_stored_case_states_its_placements_again(invoke_cli, tmp_path):
    """The text stored with results has the shorthand expanded into explicit lists; it records
    where the point loads went, so that a rerun states the placements and their snap distances."""
    from conftest import REPO

    case = load_case(REPO / REPO_HEAVY, ["cable.nodes=9"])[0]
    again = parse_case(case.text)
    assert again.placements == case.placements and again == case
    assert parse_case(case.text, overrides=["damping.ratio=0.02"]).placements == ()  # changed: not claimed
    (tmp_path / "heavy.yaml").write_text((REPO / REPO_HEAVY).read_text())
    assert invoke_cli("static", "heavy.yaml", "--set", "cable.nodes=9", "-o", "s.h5", "--no-plot")[0] == 0
    rerun = invoke_cli("rerun", "s.h5")
    assert rerun[0] == 0 and "snap distance" in rerun[1]
    with h5py.File(tmp_path / "s.h5") as f, h5py.File(tmp_path / "s-rerun.h5") as g:
        for key in ("point_load_node", "point_load_snap", "point_load_x"):
            assert np.array_equal(f["static"].attrs[key], g["static"].attrs[key])
        assert np.array_equal(f["static/P"][()], g["static/P"][()])
