"""Curves of symmetry-breaking pitchforks in (omega, gamma): where a planar response of a spatial
cable symmetric about its plane gives birth to whirling (an out-of-plane multiplier +1).

Reference, independent of the orbit code: the planar periodic response of the one-node case and
its out-of-plane (Hill) multipliers written in ``helpers_whirl_cases`` (the planar orbit by its
own shooting, the out-of-plane linearisation integrated by scipy), located by brentq at fixed
gamma. Every point of the continued curve where it crosses a requested level of gamma must be the
reference's pitchfork there, on its side of the curve's turning point.
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest
import yaml

import cablesim
from helpers_whirl_cases import WHIRL_CASE, pitchfork_omega

LEVELS = (0.8, 0.9)


@pytest.fixture(scope="module")
def pitchfork_curves():
    data = yaml.safe_load(WHIRL_CASE)
    data["continuation"] = {"omega": {"start": 4.45, "stop": 4.7}, "loci": True, "channels": ["node1.v", "node1.w"],
                            "gamma": {"start": 0.6, "stop": 1.0, "levels": list(LEVELS)}}
    case = cablesim.load_case(data)
    return case, cablesim.continuation(case)


def test_the_pitchfork_curve_passes_through_the_references_pitchforks(pitchfork_curves):
    case, run = pitchfork_curves
    res = run.result
    (curve,) = [L for L in res.loci if L.kind == "pitchfork"]
    assert curve.plane == "out-of-plane"
    assert curve.origin[1] == 1.0 and curve.gamma.max() == pytest.approx(1.0)
    assert curve.gamma.min() < min(LEVELS)  # the curve turns below the levels: two crossings each
    levels = [(w, g) for w, g, s in zip(curve.omega, curve.gamma, curve.special) if s == "level"]
    assert len(levels) == 2 * len(LEVELS), levels
    # both sides of the turning point at 0.8, the left one at 0.9 (at 0.9 on the right, 4.666
    # rad/s, the reference's own shooting from its linear guess does not converge: near the
    # planar response's resonance)
    checked = [(w, g) for w, g in levels if abs(g - 0.8) < 1e-6 or w < 4.6]
    assert len(checked) == 3
    for w, g in checked:
        ref = pitchfork_omega(case, bracket=(w - 2e-3, w + 2e-3), gamma=g)
        assert abs(w - ref.value) < 1e-6, (w, g, ref.value)
    # the orbits on the curve stay in the plane
    w_amp = curve.amplitude[:, 1]
    assert np.abs(w_amp).max() == 0.0
    assert np.all(curve.trusted)


def test_the_pitchfork_curve_is_stored_and_drawn(pitchfork_curves, tmp_path):
    _, run = pitchfork_curves
    out = run.to_hdf5(tmp_path / "pf.h5")
    with h5py.File(out) as f:
        (name,) = [k for k in f["continuation/loci"] if f["continuation/loci"][k].attrs["kind"] == "pitchfork"]
        assert name.startswith("pf") and f["continuation/loci"][name].attrs["plane"] == "out-of-plane"
    from cablesim.plots.charts import KIND_STYLE, style_key
    assert style_key("pitchfork", "out-of-plane") in KIND_STYLE
