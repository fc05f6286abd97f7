"""Backbones of spatial cables: the free, undamped periodic orbits of an out-of-plane mode.

References written here, sharing no code with the orbit kernels: the elastic chain in three
dimensions (segment tensions ``EA (l - S) / S`` along the segments, scipy's DOP853), of which
the stored orbits must be free periodic orbits; and the out-of-plane frequency of the lumped
string, the eigenvalue of ``M^-1 K_w`` with ``K_w`` the tridiagonal of the equilibrium's segment
tensions over their lengths ``T_r / l_r``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

import cablesim
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
TIGHT = dict(method="DOP853", rtol=1e-12, atol=1e-12)


def chain(eom):
    """``(z, v) -> (v, v')`` of the undamped, unforced elastic chain in three dimensions."""
    c = eom.cable
    A, B = np.asarray(c.support_A, float), np.asarray(c.support_B, float)
    S, EA = np.asarray(c.S, float), float(c.EA)
    y0, m, F0 = np.asarray(eom.y0, float), np.asarray(eom.mass, float), np.asarray(eom.F0, float)
    nd = y0.size

    def rhs(t, s):
        pts = np.vstack([A, (y0 + s[:nd]).reshape(-1, 3), B])
        d = np.diff(pts, axis=0)
        l = np.linalg.norm(d, axis=1)
        pull = (EA * np.maximum(l - S, 0.0) / S / l)[:, None] * d  # each segment's tension along it
        force = (pull[1:] - pull[:-1]).ravel() + F0
        return np.concatenate([s[nd:], force / m])

    return rhs, nd


def string_frequencies(eom) -> np.ndarray:
    """Out-of-plane frequencies of the lumped string at equilibrium (the plane's normal is z)."""
    c = eom.cable
    pts = np.vstack([c.support_A, np.reshape(eom.y0, (-1, 3)), c.support_B])
    l = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    k = c.EA * (l - np.asarray(c.S)) / np.asarray(c.S) / l
    n = l.size - 1
    K = np.diag(k[:-1] + k[1:]) - np.diag(k[1:-1], 1) - np.diag(k[1:-1], -1)
    return np.sqrt(eigh(K, np.diag(np.asarray(eom.mass)[2::3]), eigvals_only=True))[:n]


@pytest.fixture(scope="module")
def out_of_plane_backbone():
    case = cablesim.load_case(CONFIG, overrides=["spatial=true", "backbone={channels: [node1.v, node1.w, node2.w]}"])
    static = run_static(case)
    eom = build_equations(case, static, omega=float(static.modes.omega[0]))
    run = cablesim.backbone(case, mode=1, amplitude=3.0)
    return case, eom, run.result


def test_an_out_of_plane_mode_starts_at_the_strings_frequency(out_of_plane_backbone):
    _, eom, r = out_of_plane_backbone
    w_string = string_frequencies(eom)
    assert r.linear_omega == pytest.approx(w_string[0], rel=1e-9)  # mode 1 of the paper's cable in space
    assert r.complete and r.amplitude.max() >= 3.0 and np.abs(r.delta).max() < 1e-9
    # the orbits move out of the plane: node 1's w is the largest channel; the frequency leaves
    # the linear one as the square of the amplitude (a quadratic fit through the first orbits)
    w1 = r.amplitude[:, 1]
    assert np.all(w1 >= r.amplitude[:, 0])
    small = w1 < 0.5
    assert small.sum() >= 3
    shift = (r.omega[small] - r.linear_omega) / w1[small] ** 2
    assert np.ptp(shift) < 0.2 * np.abs(shift).max() + 1e-9


def test_the_orbits_are_free_periodic_orbits_of_the_independent_chain(out_of_plane_backbone):
    _, eom, r = out_of_plane_backbone
    rhs, nd = chain(eom)
    assert np.abs(rhs(0.0, np.zeros(2 * nd))[nd:]).max() < 1e-6  # the equilibrium is one of the chain
    for j in (r.omega.size // 2, r.omega.size - 1):
        s0 = r.state[j]
        size = np.abs(s0[:nd]).max()
        T = 2 * np.pi / r.omega[j]
        scaled = np.r_[np.ones(nd), np.full(nd, 1.0 / r.omega[j])]

        def miss(t):
            sol = solve_ivp(rhs, (0.0, t), s0, **TIGHT)
            assert sol.success
            return np.abs((sol.y[:, -1] - s0) * scaled).max() / size

        assert np.abs(s0[2:nd:3]).max() > 0.1 * size  # out of the plane
        assert miss(T) < 1e-7
        assert miss(1.001 * T) > 1e-4


def test_backbone_and_sweep_files_of_a_spatial_cable_label_their_channels_in_space(invoke_cli, tmp_path):
    """The files say how many components a node has, so that z3 is node 1 out of the plane, not
    node 2 horizontal (as the planar numbering would have it)."""
    from cablesim.io.charts import read_backbone
    from cablesim.io.sweeps import read_sweep
    from cablesim.plots.sweep import channel_label

    res = invoke_cli("backbone", CONFIG, "--set", "spatial=true", "--set", "backbone={channels: [node1.v, node1.w]}",
                     "--mode", "1", "--amplitude", "0.3", "-o", tmp_path / "bb.h5")
    assert res.returncode == 0, res.stderr
    bb = read_backbone(tmp_path / "bb.h5")
    assert bb["channels"] == ["z2", "z3"] and bb["components"] == 3
    assert "node 1, out of plane" in channel_label("z3", components=bb["components"])
    res = invoke_cli("sweep", CONFIG, "--set", "spatial=true", "--set",
                     "sweep={omega: {start: 2.0, stop: 2.2, num: 2}, duration: 60, window: 30, refine: 0}",
                     "--set", "history.channels=[node1.w]", "-o", tmp_path / "sw.h5")
    assert res.returncode == 0, res.stderr
    sw = read_sweep(tmp_path / "sw.h5")
    assert sw.attrs["components"] == 3 and "out of plane" in channel_label(sw.channels[-1], components=3)


def test_a_spatial_cable_has_three_modes_per_node_to_choose_from(invoke_cli, tmp_path):
    res = invoke_cli("backbone", CONFIG, "--set", "spatial=true", "--mode", "7", "-o", tmp_path / "x.h5")
    assert res.returncode == 2 and "3n = 6 modes" in res.stderr and "Traceback" not in res.stderr
    assert not (tmp_path / "x.h5").exists()


HEAVY = Path(__file__).resolve().parents[1] / "configs" / "heavy-span.yaml"


def test_a_backbone_beyond_the_limits_is_refused_before_it_starts(invoke_cli, tmp_path):
    """The most a backbone can take (every orbit of backbone.max_points, each a few flows over the
    mode's period) is checked before it starts, as for the other commands."""
    res = invoke_cli("backbone", HEAVY, "--set", "backbone={max_points: 100000}", "-o", tmp_path / "x.h5")
    assert res.returncode == 2 and "Traceback" not in res.stderr
    for words in ("Runge-Kutta steps", "backbone.max_points", "--force"):
        assert words in res.stderr, res.stderr
    assert not (tmp_path / "x.h5").exists()
    from cablesim import api

    cost = api.backbone_cost(cablesim.load_case(CONFIG), mode=1)
    assert cost.samples == 2000 and cost.excess() is None and "at most" in cost.text()
