"""Stability charts of spatial cables: the curves of a planar response's out-of-plane
bifurcations in (omega, gamma), against the independent out-of-plane linearisation of
``tests/test_orbits_whirl.py`` (the planar motion and the string's Hill equation across the plane,
integrated by scipy)."""

from __future__ import annotations

import copy

import h5py
import numpy as np

from cablesim.analyses.continuation import run_continuation
from cablesim.case import case_from_dict
from cablesim.io.continuation import write_continuation
from cablesim.plots.charts import plot_stability_chart
from test_orbits_whirl import BEAD, bead, equations, located_crossing

LEVELS = (0.5, 1.2)


def tongue_chart():
    data = copy.deepcopy(BEAD)
    data.update(spatial=True, name="bead-tongue")
    data["loads"]["FL"] = [0.0, 0.6]
    data["continuation"] = {"omega": {"start": 12.0, "stop": 13.2}, "switch_branches": False, "loci": True,
                            "gamma": {"start": 0.2, "stop": 3.0, "at": 1.0, "levels": list(LEVELS)}}
    return run_continuation(case_from_dict(data))


def test_parametric_tongue_of_a_bead_is_one_out_of_plane_period_doubling_curve(tmp_path):
    """The two out-of-plane period doublings of the bead's planar response (the edges of its
    parametric tongue at gamma = 1) lie on one curve in (omega, gamma), the tongue's boundary,
    labelled out-of-plane in the result, the HDF5 file and the chart; where it crosses gamma =
    0.5 and 1.2 the independent linearisation's multiplier passes -1 at the same omega (1e-6
    rad/s), at both edges; its least gamma (the tip: the threshold of parametric resonance) lies
    below both levels."""
    res = tongue_chart()
    assert [(b.kind, b.plane) for b in res.bifurcations] == [("period-doubling", "out-of-plane")] * 2
    (curve,) = res.loci
    assert curve.kind == "period-doubling" and curve.plane == "out-of-plane"
    for level in LEVELS:
        at = [k for k, sp in enumerate(curve.special) if sp == "level" and abs(curve.gamma[k] - level) < 1e-9]
        assert len(at) == 2, (level, curve.special)
        for k in at:
            eom = equations(bead(0.6 * level), curve.omega[k])
            w_ref = located_crossing(eom, curve.omega[k], curve.state[k], -1.0)
            assert abs(w_ref - curve.omega[k]) < 1e-6, (level, w_ref, curve.omega[k])
    tip = int(np.argmin(curve.gamma))
    assert curve.special[tip] == "turning point" and curve.gamma[tip] < min(LEVELS)
    path = tmp_path / "chart.h5"
    write_continuation(path, res)
    with h5py.File(path) as f:
        (name,) = list(f["continuation/loci"])
        plane = f["continuation/loci"][name].attrs["plane"]
        assert (plane.decode() if isinstance(plane, bytes) else plane) == "out-of-plane"
    png = plot_stability_chart(path, tmp_path / "chart.png")
    assert png.exists() and png.stat().st_size > 20_000
