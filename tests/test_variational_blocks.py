"""The variational equations of a planar orbit of a spatial cable carried on their in-plane and
out-of-plane blocks alone (:func:`cablesim.orbits.kernels.flow_segment` with two blocks).

On an orbit in a plane whose normal is a coordinate axis the Jacobian never couples the in-plane
and the out-of-plane components, so the blocked flow must give exactly (bit for bit) the map,
the monodromy, the parameter derivative and the Liouville data of the whole Jacobian's flow;
the references here are the whole flow itself and the structure of the mirror's basis.
"""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.orbits import Shooting, cable_system, linear_response_state, solve_orbit
from cablesim.orbits.symmetry import cable_mirror, state_mirror

from test_orbits_whirl import BEAD, PAPER, case_of, equations


def test_blocks_of_a_plane_whose_normal_is_an_axis():
    n = 3
    chord = np.array([0.8, 0.6, 0.0])
    blocks = state_mirror(np.array([0.0, 0.0, 1.0]), chord, n).coordinate_blocks()
    assert blocks is not None
    rows, bounds = blocks
    odd = rows[bounds[1]:]
    # the normal's component of every node's displacement and velocity: indices 2 mod 3
    np.testing.assert_array_equal(odd, np.arange(2, 6 * n, 3))
    np.testing.assert_array_equal(np.sort(rows), np.arange(6 * n))
    assert all(np.all(np.diff(rows[bounds[k]:bounds[k + 1]]) > 0) for k in range(2))


def test_no_blocks_for_a_tilted_plane():
    tilted = np.array([0.0, np.sin(0.3), np.cos(0.3)])
    assert state_mirror(tilted, np.array([1.0, 0.0, 0.0]), 2).coordinate_blocks() is None


@pytest.mark.parametrize("base,omega", [(PAPER, 2.4), (BEAD, 5.0)])
@pytest.mark.parametrize("parameter", ["omega", "gamma"])
def test_blocked_flow_is_the_whole_flow_bit_for_bit(base, omega, parameter):
    eom = equations(case_of(base, spatial=True), omega)
    mirror = cable_mirror(eom)
    blocks = mirror.coordinate_blocks()
    assert blocks is not None
    system = cable_system(eom)
    sh = Shooting(system, segments=2, parameter=parameter)
    lam = omega if parameter == "omega" else 1.0
    sol = solve_orbit(Shooting(system), linear_response_state(eom, omega), omega)
    assert sol.converged and mirror.is_planar(sol.u, np.ones(sol.u.size))
    u = sh.spread(sol.u, lam)
    whole = sh.evaluate(u, lam)
    split = sh.evaluate(u, lam, blocks=blocks)
    for name in ("r", "J_u", "J_lam", "monodromy", "multipliers", "ends", "xmax", "xmin"):
        np.testing.assert_array_equal(getattr(split, name), getattr(whole, name), err_msg=name)
    assert split.logdet == whole.logdet and split.divergence == whole.divergence
    _, _, off = mirror.blocks(split.monodromy)
    assert off == 0.0
