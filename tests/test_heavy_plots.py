"""Many nodes: channels named by node and direction, node labels, snapshots of the moving cable."""

from __future__ import annotations

import numpy as np
import pytest

import cablesim
from cablesim.cable import nodes_with_supports
from cablesim.case import parse_case
from cablesim.channels import channel_index, node_channel_name, normalise_channel, parse_channels
from cablesim.errors import CablesimError
from cablesim.plots.snapshots import labelled_nodes, snapshot_figure, snapshot_indices

CABLE = "cable: {L: 60.0, H: 2.0, length: 61.5, nodes: 8, EA: 2.0e7, mass_per_length: 2.0}\n"
LOADS = "loads: {gravity: 9.81, point: [{node: 3, FL: [0.0, 300.0]}]}\n"


def test_node_channels_round_trip_to_z_names():
    """node k .h is z(2k-1) and .v is z(2k) for every DOF of a 40-node cable, both ways."""
    n_dof = 80
    for i in range(n_dof):
        name = node_channel_name(i)
        assert channel_index(name, n_dof) == i == channel_index(f"z{i + 1}", n_dof)
        assert normalise_channel(name) == f"z{i + 1}"
    assert node_channel_name(39) == "node20.v" and node_channel_name(38) == "node20.h"
    assert normalise_channel("node20.v") == "z40" and normalise_channel("node20.h") == "z39"
    assert normalise_channel(" Node 20 . V ") == "z40" and normalise_channel("NODE3.h") == "z5"
    assert normalise_channel("node3.x") is None and normalise_channel("node0.v") is None


@pytest.mark.parametrize("name, needles", [
    ("node0.v", ["'node0.v'", "names node 0", "numbered from 1"]),
    ("node9999.v", ["'node9999.v'", "node 9999", "n = 40 interior nodes"]),
    ("node3.x", ["'node3.x'", "direction 'x'", ".h (horizontal) or .v"]),
    ("node3", ["'node3'", "malformed"]),
])
def test_node_channel_errors_say_what_is_wrong(name, needles):
    with pytest.raises(CablesimError) as err:
        channel_index(name, 80)
    msg = str(err.value)
    assert all(n in msg for n in needles), msg
    assert "node1.h to node40.v" in msg  # what is allowed
    with pytest.raises(CablesimError) as err:  # the command-line option names itself
        parse_channels(f"z2,{name}", None, 80)
    assert str(err.value).startswith("--channels: ")


@pytest.mark.parametrize("section", ["history", "sweep", "outputs"])
def test_case_file_channels_by_node(section):
    extra = "{omega: [1.0], channels: [%s]}" if section == "sweep" else "{channels: [%s]}"
    ok = parse_case(CABLE + LOADS + f"{section}: " + extra % "node3.v, node8.h")
    chosen = getattr(ok, section).channels
    assert [channel_index(c, 16) for c in chosen] == [5, 14]
    with pytest.raises(CablesimError) as err:
        parse_case(CABLE + LOADS + f"{section}: " + extra % "node9.v")
    assert f"{section}.channels" in str(err.value) and "node 9" in str(err.value)


def test_node_labels_are_a_readable_subset():
    assert labelled_nodes(7) == list(range(1, 8))
    for n in (13, 40, 100, 400, 2000):
        nodes = labelled_nodes(n)
        assert nodes[0] == 1 and nodes[-1] == n and len(nodes) <= 12 and nodes == sorted(set(nodes))
        gaps = np.diff(nodes)
        assert gaps.min() >= 0.5 * gaps.max() - 1  # evenly spread, none crowded
    assert labelled_nodes(2000)[1:-1] == list(range(200, 2000, 200))


@pytest.fixture(scope="module")
def short_history():
    case = parse_case(CABLE + LOADS)
    run = cablesim.history(case, omega=3.0, duration=2.0, output_step=0.05)
    return case, run.history


def test_snapshot_lines_are_equilibrium_plus_displacement(short_history):
    """The drawn shapes, read back from the figure's lines, are the supports and y0 + z(t_k) at
    the chosen instants; the lower panel holds the vertical displacements, zero at the supports."""
    case, hist = short_history
    cable = case.to_cable()
    fig = snapshot_figure(hist, cable, "test", 4)
    shape_ax, disp_ax = fig.axes[:2]
    picks = snapshot_indices(hist.t.size, 4)
    assert list(picks) == [0, 13, 27, 40] and hist.t.size == 41
    lines = shape_ax.get_lines()
    np.testing.assert_allclose(np.column_stack(lines[0].get_data()), nodes_with_supports(cable, hist.y0))
    assert np.abs(hist.z[picks[1:]]).max() > 1e-4  # the cable moved: the check below is not trivial
    for line, i in zip(lines[1:5], picks):
        x, y = line.get_data()
        expected = np.vstack([[0.0, 0.0], (hist.y0 + hist.z[i]).reshape(-1, 2), [cable.L, cable.H]])
        np.testing.assert_allclose(np.column_stack([x, y]), expected, rtol=0, atol=1e-12)
        assert line.get_label() == f"t = {hist.t[i]:.4g} s"
    for line, i in zip(disp_ax.get_lines(), picks):
        np.testing.assert_allclose(line.get_ydata(), np.concatenate([[0.0], hist.z[i, 1::2], [0.0]]), atol=1e-15)
    cablesim.plots.base.pyplot().close(fig)


def test_snapshots_from_the_command_line(short_history, invoke_cli, tmp_path):
    from helpers_cli import assert_refused

    case, _ = short_history
    (tmp_path / "c.yaml").write_text(CABLE + LOADS)
    rc, _, err, _ = invoke_cli("history", "c.yaml", "--omega", "3", "--duration", "2", "--channels", "node3.v,node4.h",
                               "-o", "run.h5")
    assert rc == 0, err
    rc, out, err, _ = invoke_cli("plot", "run.h5", "--snapshots", "5")
    assert rc == 0, err
    assert (tmp_path / "run-snapshots.png").stat().st_size > 10_000
    rc, _, err, _ = invoke_cli("static", "c.yaml", "--no-plot", "-o", "s.h5")
    assert rc == 0, err
    keep = tuple(p for p in tmp_path.rglob("*") if p.suffix in (".h5", ".png"))
    assert_refused(invoke_cli("plot", "s.h5", "--snapshots", "3"), tmp_path, "--snapshots", "static", keep=keep)
    res = invoke_cli("history", "c.yaml", "--omega", "3", "--duration", "1", "--channels", "node9.v", "-o", "x.h5")
    assert_refused(res, tmp_path, "--channels", "node 9", keep=keep)
