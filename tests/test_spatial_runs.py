"""Spatial cases run end to end: histories and sweeps with out-of-plane channels, forcing by a
moving support alone, and the out-of-plane disturbance that lets a planar response leave its
plane."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml

from cablesim.analyses.dynamic import run_history
from cablesim.analyses.sweep import run_sweep
from cablesim.case import case_from_dict, parse_case
from cablesim.errors import CablesimError
from cablesim.modal import out_of_plane_shape, plane_basis

PAPER = {
    "cable": {"L": 300.0, "H": 20.0, "S": [130.0, 100.0, 110.0], "EA": 1.0e9, "masses": [8000.0, 14000.0]},
    "loads": {"F0": [300.0e3, 1100.0e3, 450.0e3, 2000.0e3], "FL": [-6.0e3, 22.0e3, -18.0e3, 120.0e3]},
    "damping": {"ratio": 0.01, "modes": [1, 2]},
    "spatial": True,
}


def spatial(**sections):
    data = copy.deepcopy(PAPER)
    data.update(sections)
    return data


def test_a_spatial_history_takes_out_of_plane_channels_on_the_command_line(invoke_cli, tmp_path):
    """`cablesim history` refused node2.w of a spatial case (its channels were checked as planar)."""
    case = tmp_path / "space.yaml"
    case.write_text(yaml.safe_dump(spatial(history={"omega": 2.4, "duration": 4.0, "disturbance": 0.01})))
    r = invoke_cli("history", case, "--channels", "node2.w,node2.v", "-o", tmp_path / "h.h5", "--no-plot")
    assert r.returncode == 0, r.stderr
    assert "z6" in r.stdout and "z5" in r.stdout  # node2.w is z6, node2.v is z5 in a spatial cable


def test_a_history_forced_only_by_a_moving_support_runs():
    """A case whose only forcing is a support's motion was refused as having no forcing."""
    data = spatial(loads={"F0": PAPER["loads"]["F0"]}, analysis="exact",
                   supports={"B": {"amplitude": [0.0, 0.05, 0.0]}})
    case = case_from_dict(data)
    assert case.forced and not np.any(case.FL)
    _, hist, _ = run_history(case, omega=2.4, duration=20.0)
    assert hist.completed and np.abs(hist.z).max() > 1e-3  # the support drives the cable
    assert hist.omega == 2.4  # a forced response (it was reported as a free vibration)


def test_the_disturbance_is_out_of_the_plane_of_a_turned_span_with_its_stated_size():
    from cablesim.analyses.static import run_static

    theta = 0.7
    data = spatial()
    data["cable"] = dict(data["cable"], W=300.0 * np.tan(theta))  # B moved out of the x-v plane
    data["loads"] = {"gravity": 9.81}
    data["cable"]["masses"] = [8000.0, 14000.0]
    case = case_from_dict(data)
    st = run_static(case)
    cable = st.cable
    d = out_of_plane_shape(st.y0, np.asarray(cable.support_A), np.asarray(cable.support_B))
    assert np.abs(d).max() == pytest.approx(1.0, abs=1e-15)
    nodes = np.vstack([cable.support_A, st.y0.reshape(-1, 3), cable.support_B])
    normal = np.cross(nodes[-1] - nodes[0], nodes[1] - nodes[0])
    normal /= np.linalg.norm(normal)
    R = plane_basis(normal, nodes[-1] - nodes[0])
    inplane = d.reshape(-1, 3) @ R[:, :2]
    assert np.abs(inplane).max() < 1e-12  # wholly along the plane's normal


def test_a_history_starts_disturbed_by_the_setting_and_a_stable_planar_response_recovers():
    case = case_from_dict(spatial(history={"omega": 2.4, "duration": 60.0, "disturbance": 0.05}))
    _, hist, _ = run_history(case)
    w = hist.z.reshape(hist.z.shape[0], -1, 3)[:, :, 2]
    assert np.abs(w[0]).max() == pytest.approx(0.05, rel=1e-12)
    assert np.abs(w[-20:]).max() < 0.5 * 0.05  # the out-of-plane motion decays: this orbit is stable there
    _, still, _ = run_history(case_from_dict(spatial(history={"omega": 2.4, "duration": 5.0})))
    assert np.all(still.z.reshape(still.z.shape[0], -1, 3)[:, :, 2] == 0.0)  # no disturbance: exactly planar


def test_the_disturbance_is_refused_where_it_cannot_apply():
    planar = copy.deepcopy(PAPER)
    planar.pop("spatial")
    with pytest.raises(CablesimError, match="history.disturbance"):
        parse_case(yaml.safe_dump(dict(planar, history={"omega": 2.4, "disturbance": 0.01})))
    case = case_from_dict(spatial(history={"omega": 2.4, "duration": 1.0, "disturbance": 0.01}))
    with pytest.raises(CablesimError, match="only the exact analysis") as err:
        run_history(case, analysis="approximate")
    assert err.value.field == "history.disturbance"


def test_a_spatial_sweep_records_out_of_plane_channels_and_its_disturbance():
    """A spatial sweep sized its per-segment columns as if the cable were planar."""
    sweep = {"omega": [1.5, 2.4], "duration": 30.0, "window": 10.0, "channels": ["node2.w", "node2.v"],
             "accelerate": False, "floquet": False}
    case = case_from_dict(spatial(sweep=sweep))
    res = run_sweep(case, case.text, n_jobs=1)
    assert res.complete and res.n_segments == 3 and res.dim == 3
    chord = float(np.hypot(300.0, 20.0))
    assert res.settings["disturbance"] == pytest.approx(1e-6 * chord)
    table = res.table(0)
    assert table.peak_tension.shape == (2, 3)
    assert np.all(table.amplitude[:, 0] < 1e-3 * table.amplitude[:, 1])  # w stays small: stable planar points


def test_spatial_figures_draw_the_motion_across_the_span_and_the_plan_view(tmp_path):
    from cablesim.plots.cable import plot_cable
    from cablesim.plots.history import plot_history
    from cablesim.plots.spatial import across_nodes

    data = spatial(history={"omega": 2.4, "duration": 6.0})
    data["loads"] = {"F0": [300.0e3, 1100.0e3, 0.0, 450.0e3, 2000.0e3, 50.0e3],
                     "FL": [-6.0e3, 22.0e3, 5.0e3, -18.0e3, 120.0e3, 0.0]}
    st, hist, _ = run_history(case_from_dict(data))
    nodes = across_nodes(hist)
    assert [n for n, _, _ in nodes] == [1, 2]
    for node, jv, jw in nodes:  # the columns are the node's v and w
        assert hist.dof_numbers[jv] == 3 * node - 1 and hist.dof_numbers[jw] == 3 * node
    paths = plot_history(hist, tmp_path / "h", "spatial")
    assert paths[-1].name == "h-across.png" and paths[-1].stat().st_size > 0
    assert plot_cable(st, tmp_path / "s.png", "spatial").stat().st_size > 0
    _, flat, _ = run_history(case_from_dict(dict(copy.deepcopy(PAPER), spatial=False, history={"omega": 2.4,
                                                                                               "duration": 2.0})))
    assert across_nodes(flat) == []  # a planar history has no motion across the span


def taut_string(nodes=6, **extra):
    """A weightless stay 100 m long between its supports, 15 cm shorter than that: taut, with no
    inextensible natural state."""
    data = {"spatial": True, "analysis": "exact",
            "cable": {"L": 80.0, "H": -60.0, "length": 99.85, "nodes": nodes, "EA": 2.0e9, "mass_per_length": 80.0},
            "loads": {"gravity": 0.0}, "damping": {"a0": 0.0, "a1": 0.0}}
    data.update(extra)
    return data


def test_a_taut_cable_vibrates_out_of_its_line_at_the_beaded_string_frequency():
    """Dynamics refused every cable not longer than its chord; the exact analysis needs no
    natural state. Reference: the beaded string, omega_1 = 2 sqrt(T / (m a)) sin(pi / (2 (n + 1)))."""
    from cablesim.analyses.dynamic import run_free_vibration

    n = 6
    T = 2.0e9 * (100.0 - 99.85) / 99.85
    m, a = 80.0 * 99.85 / (n + 1), 100.0 / (n + 1)
    w1 = 2.0 * np.sqrt(T / (m * a)) * np.sin(np.pi / (2 * (n + 1)))
    z0 = np.zeros(3 * n)
    z0[2::3] = 1e-3 * np.sin(np.pi * np.arange(1, n + 1) / (n + 1))  # first out-of-plane shape, 1 mm
    period = 2 * np.pi / w1
    case = case_from_dict(taut_string(n, free_vibration={"z0": z0.tolist(), "duration": 6 * period,
                                                         "output_step": period / 400}))
    _, hist, _ = run_free_vibration(case)
    assert hist.completed and hist.zc is None  # no configurational/elastic split without a natural state
    w = hist.z[:, 3 * 3 - 1]  # node 3's w
    up = np.flatnonzero((w[:-1] < 0) & (w[1:] >= 0))
    t_up = hist.t[up] - w[up] * (hist.t[up + 1] - hist.t[up]) / (w[up + 1] - w[up])
    measured = (t_up[-1] - t_up[0]) / (t_up.size - 1)
    assert measured == pytest.approx(period, rel=1e-5)


def test_a_taut_cable_refuses_the_split_and_the_approximate_analysis():
    case = case_from_dict(taut_string(3, history={"omega": 12.0, "duration": 1.0},
                                      supports={"A": {"amplitude": [0.004, -0.003, 0.0]}},
                                      outputs={"split": True}))
    with pytest.raises(CablesimError, match="outputs.split"):
        run_history(case)
    with pytest.raises(CablesimError, match="the approximate analysis"):
        run_history(case_from_dict(taut_string(3, history={"omega": 12.0, "duration": 1.0},
                                               loads={"gravity": 0.0, "point": [{"node": 1, "FL": [0, 1.0, 0]}]})),
                    analysis="approximate")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["spatial-span", "stay-anchorage"])
def test_the_shipped_spatial_examples_run(invoke_cli, tmp_path, name):
    """The README's spatial and support-motion examples, shortened: the stay's was refused (no
    forcing but its support) and its out-of-plane channel was refused on the command line."""
    from pathlib import Path

    case = Path(__file__).resolve().parents[1] / "configs" / f"{name}.yaml"
    r = invoke_cli("history", case, "--duration", "2", "-o", tmp_path / "h.h5")
    assert r.returncode == 0, r.stderr
    assert "forcing w =" in r.stdout and (tmp_path / "h-across.png").is_file()


def test_snapshots_of_a_spatial_history_draw_its_plan_and_end_views():
    """The snapshots of a spatial cable showed its elevation only: motion across the span, and a
    cable swung out of its plane, were not drawn."""
    from cablesim.cable import nodes_with_supports
    from cablesim.plots.snapshots import snapshot_figure

    loads = {"F0": [300.0e3, 1100.0e3, 80.0e3, 450.0e3, 2000.0e3, 120.0e3],
             "FL": [-6.0e3, 22.0e3, 5.0e3, -18.0e3, 120.0e3, 9.0e3]}
    case = case_from_dict(spatial(loads=loads))
    _, hist, _ = run_history(case, omega=2.4, duration=6.0)
    fig = snapshot_figure(hist, case.to_cable(), "space", count=3)
    shape, disp, plan, end = fig.axes[:4]
    assert "plan view" in plan.get_title() and "end view" in end.get_title()
    drawn_plan = [ln.get_xydata() for ln in plan.get_lines()]
    drawn_end = [ln.get_xydata() for ln in end.get_lines()]
    states = [nodes_with_supports(case.to_cable(), hist.y0 + hist.z[i]) for i in range(hist.t.size)]
    for xy in drawn_plan[2:]:  # after the static shape and its supports: the instants, (x, w)
        assert any(np.allclose(xy, p[:, [0, 2]]) for p in states)
    for xy in drawn_end[2:]:  # (w, v)
        assert any(np.allclose(xy, p[:, [2, 1]]) for p in states)
    assert len(drawn_plan) == len(drawn_end) == 2 + 3
    w = np.array([p[1:-1, 2] for p in states])
    assert np.abs(w).max() > 1e-3  # the out-of-plane loads swing the cable: something to see
