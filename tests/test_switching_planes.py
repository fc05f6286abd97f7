"""The direction into a period-doubled branch at a period doubling of a planar orbit of a
spatial cable, taken from the block of the monodromy that holds the critical multiplier.

The taut stay without gravity is symmetric about its chord: its in-plane and out-of-plane
transverse modes have one frequency, and at the threshold of parametric resonance an in-plane and
an out-of-plane multiplier pass -1 together. The whole monodromy's eigenvectors at -1 then mix the
planes; the direction for the in-plane doubling must lie in the plane and the one for the
out-of-plane doubling across it, each an eigenvector of the whole monodromy with multiplier -1
(checked here on the monodromy itself, independently of the split).
"""

from __future__ import annotations

import numpy as np
import yaml

import cablesim
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.orbits import Shooting, cable_system
from cablesim.orbits.switching import doubling_direction
from cablesim.orbits.symmetry import cable_mirror
from helpers_whirl_cases import STAY_CASE

OMEGA = 12.0835669


def test_each_plane_has_its_own_doubling_direction_at_a_double_minus_one():
    data = yaml.safe_load(STAY_CASE.format(nodes=6, omega=OMEGA))
    data["continuation"] = {"parameter": "support", "omega": OMEGA, "switch_branches": False,
                            "support": {"start": 0.05, "stop": 0.5}}
    case = cablesim.load_case(data)
    res = cablesim.continuation(case).result
    pds = {b.plane: b for b in res.bifurcations if b.kind == "period-doubling"}
    assert set(pds) == {"in-plane", "out-of-plane"}, [(b.kind, b.plane) for b in res.bifurcations]
    s_c = pds["out-of-plane"].parameter
    assert abs(pds["in-plane"].parameter - s_c) < 1e-6  # the double multiplier -1
    eom = build_equations(case, run_static(case), omega=OMEGA)
    mirror = cable_mirror(eom)
    b = res.branches[0]
    k = int(np.argmin(np.abs(b.parameter - s_c)))
    sh = Shooting(cable_system(eom, support=s_c), parameter="support")
    ev = sh.evaluate(b.state[k], s_c)
    M = ev.monodromy
    assert np.sum(np.abs(ev.multipliers + 1) < 1e-5) == 2  # two multipliers at -1
    scale = np.ones(M.shape[0])
    for plane, inside, across in (("in-plane", mirror.even, mirror.odd), ("out-of-plane", mirror.odd, mirror.even)):
        d, _ = doubling_direction(ev, 1, scale, 1e-3, mirror, plane)
        w = d[: M.shape[0]]
        np.testing.assert_array_equal(d[M.shape[0]:], -w)
        assert np.linalg.norm(across.T @ w) <= 1e-14 * np.linalg.norm(w), plane
        assert np.linalg.norm(inside.T @ w) > 0.0
        assert np.linalg.norm(M @ w + w) < 1e-5 * np.linalg.norm(w), plane
