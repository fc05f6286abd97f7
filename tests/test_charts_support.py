"""Stability charts in (omega, s): bifurcation curves continued in the forcing frequency and the
support motion multiplier s (``continuation.loci`` with ``continuation.support`` a range).

The reference is the one-parameter continuation in s at fixed omega (``parameter: support``):
it follows the response branch and locates its period doubling by the test functions of the
multipliers along the branch, while the curve is the solution set of the minimally augmented
system in (omega, s). On a sagging stay (with gravity the in-plane and out-of-plane frequencies
differ, so that each period doubling is a simple multiplier -1; the taut stay's double -1 makes
its curve degenerate) the period doublings found at fixed omegas lie on the continued curve.
With no harmonic loads, gamma and s both scale the supports' motion alone: the curve in
(omega, gamma) at s = 0.4 is the curve in (omega, s) at gamma = 1 with gamma = s / 0.4 (an
identity through the kernel's other parameter derivative).
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest
import yaml

import cablesim

#: A sagging stay: natural length 99.85 m on a 100 m chord, sagging under gravity; anchorage A
#: moving 5 mm along the chord at s = 1.
SAGGING_STAY = """\
name: sagging-stay
spatial: {spatial}
cable:
  L: 80.0                  # m
  H: -60.0                 # B 60 m above A: a 100 m chord
  length: 99.85            # natural length, m
  nodes: {nodes}
  EA: 2.0e9                # N
  mass_per_length: 80.0    # kg/m
loads:
  gravity: 9.81            # the stay sags (in-plane and out-of-plane frequencies differ)
supports:
  A:
    amplitude: {amplitude}   # m: 5 mm along the chord at s = 1
analysis: exact
damping:
  ratio: 0.002
  modes: [1, 2]
"""


def stay_data(nodes: int, continuation: dict, spatial: bool = False) -> dict:
    data = yaml.safe_load(SAGGING_STAY.format(nodes=nodes, spatial=str(spatial).lower(),
                                              amplitude=[0.004, -0.003, 0.0] if spatial else [0.004, -0.003]))
    data["continuation"] = {"switch_branches": False, **continuation}
    return data


def stay(nodes: int, continuation: dict, spatial: bool = False):
    return cablesim.load_case(stay_data(nodes, continuation, spatial))


def period_doubling_in_s(nodes: int, omega: float, spatial: bool = False, plane: str = "in-plane") -> float:
    """The period doubling of the response continued in s from 0 to 1 at fixed omega."""
    res = cablesim.continuation(stay(nodes, {"parameter": "support", "omega": omega,
                                             "support": {"start": 0.0, "stop": 1.0}}, spatial)).result
    (pd,) = [b for b in res.bifurcations if b.kind == "period-doubling" and b.plane == plane]
    assert pd.located and pd.trusted and pd.omega == omega
    return float(pd.support)


def crossings(curve, level: float) -> list:
    """omega of the curve's located crossings of ``s = level``."""
    return [float(curve.omega[k]) for k, sp in enumerate(curve.special)
            if sp == "level" and abs(curve.support[k] - level) < 1e-9]


#: Fixed omegas either side of the tip of the tongue near 2 w1 of the two-node stay (11.818).
OMEGAS = (11.76, 11.80, 11.87)


def test_period_doublings_found_in_s_at_fixed_omegas_lie_on_the_continued_curve():
    """At three fixed omegas the continuation in s locates the period doubling at s_k; the curve
    continued in (omega, s) from the response's period doublings at s = 1 crosses s = s_k at
    omega_k (1e-6 rad/s), on the left edge of the tongue for the omegas below its tip and on
    the right edge for the one above; both ends of the curve are the response's two period
    doublings at s = 1 (the second found independently of the first, from which the curve
    started)."""
    s_k = [period_doubling_in_s(2, w) for w in OMEGAS]
    case = stay(2, {"omega": {"start": 11.6, "stop": 12.2}, "loci": True,
                    "support": {"start": 0.05, "stop": 1.0, "levels": s_k}})
    res = cablesim.continuation(case).result
    assert res.loci_parameter == "support" and res.loci_range == (0.05, 1.0) and res.fixed_support == 1.0
    (curve,) = res.loci
    assert curve.kind == "period-doubling" and curve.second == "support" and curve.plane == "in-plane"
    np.testing.assert_array_equal(curve.values2, curve.support)
    assert np.all(curve.gamma == 1.0) and curve.support.min() < min(s_k)
    for w, s in zip(OMEGAS, s_k):
        near = min(crossings(curve, s), key=lambda x: abs(x - w))
        assert abs(near - w) < 1e-6, (w, s, near)  # measured 3.4e-11 rad/s at most
    pds = sorted(b.omega for b in res.bifurcations if b.kind == "period-doubling")
    assert [b.support for b in res.bifurcations] == [1.0, 1.0]
    np.testing.assert_allclose([curve.support[0], curve.support[-1]], 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sorted((curve.omega[0], curve.omega[-1])), pds, rtol=0, atol=1e-6)
    tip = int(np.argmin(curve.support))
    assert curve.special[tip] == "turning point" and OMEGAS[1] < curve.omega[tip] < OMEGAS[2]


def test_out_of_plane_period_doubling_curve_of_a_spatial_sagging_stay():
    """The one-node stay made spatial: the planar response's out-of-plane period doubling near
    twice the out-of-plane frequency has its own curve in (omega, s), labelled out-of-plane; the
    out-of-plane period doubling found in s at a fixed omega lies on it (1e-6 rad/s)."""
    w = 11.0
    s_c = period_doubling_in_s(1, w, spatial=True, plane="out-of-plane")
    case = stay(1, {"omega": {"start": 10.8, "stop": 11.3}, "loci": True,
                    "support": {"start": 0.1, "stop": 1.0, "levels": [s_c]}}, spatial=True)
    res = cablesim.continuation(case).result
    out = [L for L in res.loci if L.plane == "out-of-plane"]
    assert [L.kind for L in out] == ["period-doubling"]
    near = min(crossings(out[0], s_c), key=lambda x: abs(x - w))
    assert abs(near - w) < 1e-6, (s_c, near)


def test_gamma_and_s_curves_agree_when_only_the_supports_force_the_cable():
    """No FL: the supports move by gamma s times their amplitudes, so the curve in (omega, gamma)
    at s = 0.4 crosses gamma = x / 0.4 where the curve in (omega, s) at gamma = 1 crosses s = x
    (1e-8 rad/s; measured 4.5e-12); its points have s = 0.4, the other's gamma = 1."""
    base = {"omega": {"start": 10.9, "stop": 11.4}, "loci": True}
    levels = (0.3, 0.45)
    in_s = cablesim.continuation(stay(1, {**base, "support": {"start": 0.1, "stop": 1.0, "levels": list(levels)}}))
    in_g = cablesim.continuation(stay(1, {**base, "support": 0.4, "gamma": {
        "start": 0.25, "stop": 2.5, "levels": [x / 0.4 for x in levels]}}))
    (cs,), (cg,) = in_s.result.loci, in_g.result.loci
    assert cs.second == "support" and cg.second == "gamma"
    assert np.all(cg.support == 0.4) and np.all(cs.gamma == 1.0)
    for x in levels:
        a = crossings(cs, x)
        b = [float(cg.omega[k]) for k, sp in enumerate(cg.special)
             if sp == "level" and abs(cg.gamma[k] - x / 0.4) < 1e-9]
        assert len(a) == len(b) == 2
        np.testing.assert_allclose(sorted(a), sorted(b), rtol=0, atol=1e-8)


def test_continue_writes_the_curves_in_s_and_plot_redraws_the_chart(tmp_path, invoke_cli, monkeypatch):
    """case file -> `cablesim continue` -> HDF5 -> `cablesim plot`: the curve's support column
    and what s = 1 stands for, the summary naming the parameter, the chart's axes (s, and the
    anchorage amplitude s |u_A| in m) and the response line at its s (0.8)."""
    from matplotlib.figure import Figure

    data = stay_data(1, {"omega": {"start": 10.9, "stop": 11.4}, "loci": True,
                         "support": {"start": 0.1, "stop": 1.0, "at": 0.8}})
    (tmp_path / "stay.yaml").write_text(yaml.safe_dump(data))
    res = invoke_cli("continue", "stay.yaml", "-o", "c.h5")
    assert res.returncode == 0, (res.stdout, res.stderr, res.exception)
    assert "Bifurcation curves in (omega, s), support motion multiplier s from 0.1 to 1" in res.stdout
    assert "s = 1: |u_A| = 5.0 mm" in res.stdout and "response at s = 0.8, gamma = 1" in res.stdout
    with h5py.File(tmp_path / "c.h5") as f:
        lg = f["continuation/loci"]
        assert lg.attrs["parameter"] == "support" and lg.attrs["support_response"] == 0.8
        assert (lg.attrs["support_start"], lg.attrs["support_stop"]) == (0.1, 1.0)
        np.testing.assert_array_equal(lg.attrs["amplitude_A"], [0.004, -0.003])
        (name,) = list(lg)
        h = lg[name]
        assert h.attrs["parameter"] == "support" and h.attrs["origin_support"] == 0.8
        s = h["support"]
        assert s.attrs["units"] == "1" and s.attrs["amplitude_units"] == "m"
        assert s[()].min() < 0.3 and np.all(h["gamma"][()] == 1.0)
        np.testing.assert_array_equal(f["continuation/branches/b0-p1/support"][()], 0.8)
    drawn = {}
    real = Figure.savefig

    def spy(self, fname, *args, **kwargs):
        ax = self.axes[0]
        drawn[str(fname)] = (ax.get_ylabel(), [a.get_ylabel() for a in ax.child_axes],
                             [ln.get_ydata() for ln in ax.lines if list(ln.get_xdata()) == [0, 1]])
        return real(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    res = invoke_cli("plot", "c.h5", "-o", "again.png")
    assert res.returncode == 0, (res.stdout, res.stderr, res.exception)
    chart = tmp_path / "again-chart.png"
    assert chart.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and chart.stat().st_size > 20_000
    (left, right, dashed), = [v for k, v in drawn.items() if "again-chart" in k]
    assert left == "support motion multiplier $s$ (s = 1: $|u_A|$ = 5.0 mm)"
    assert right == ["support amplitude $s\\,|u_A|$ (m)"]
    assert [list(y) for y in dashed] == [[0.8, 0.8]]  # the response line at its s


def _polylines_cross(p, q) -> bool:
    """Whether two curves, given by their points (x, y), have crossing segments."""
    def side(o, a, b):
        return np.sign((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))
    P, Q = np.column_stack(p), np.column_stack(q)
    for i in range(len(P) - 1):
        for j in range(len(Q) - 1):
            if side(P[i], P[i + 1], Q[j]) * side(P[i], P[i + 1], Q[j + 1]) < 0 and \
                    side(Q[j], Q[j + 1], P[i]) * side(Q[j], Q[j + 1], P[i + 1]) < 0:
                return True
    return False


def test_where_an_in_plane_and_an_out_of_plane_curve_cross_no_resonance_is_reported():
    """The one-node stay made spatial: its in-plane and out-of-plane period-doubling curves
    cross (two multipliers at -1, one in each block of the monodromy). That is two curves
    crossing, not a 1:2 resonance (a double multiplier -1 of one block): the codimension-two
    tests of a curve of planar orbits look at its own block only."""
    case = stay(1, {"omega": {"start": 10.8, "stop": 11.3}, "loci": True,
                    "support": {"start": 0.1, "stop": 1.0}}, spatial=True)
    res = cablesim.continuation(case).result
    planes = {L.plane: L for L in res.loci if L.kind == "period-doubling"}
    assert set(planes) == {"in-plane", "out-of-plane"}
    a, b = planes["in-plane"], planes["out-of-plane"]
    assert _polylines_cross((a.omega, a.support), (b.omega, b.support))
    assert not [c for c in res.codim2 if c.kind == "1:2 resonance"], [(c.kind, c.omega, c.support) for c in res.codim2]
