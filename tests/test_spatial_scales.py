"""The continuation's state scales of a spatial cable symmetric about its plane: the in-plane
velocities scaled as on the planar cable, the out-of-plane ones by the lowest out-of-plane
frequency. References: the lowest eigenvalues of ``K0 q = w^2 M q`` of each block, solved here
with scipy on the equations' own stiffness and masses."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg

from cablesim import api
from cablesim.analyses.continuation import prepare_continuation
from cablesim.orbits.starting import cable_scales

CASE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
RANGE = "continuation={omega: {start: 0.5, stop: 6.0}, channels: [node1.v, node2.v]}"


def lowest_frequency(K: np.ndarray, mass: np.ndarray) -> float:
    return float(np.sqrt(scipy.linalg.eigh(K, np.diag(mass), eigvals_only=True, subset_by_index=[0, 0])[0]))


def test_in_plane_velocities_of_a_symmetric_spatial_cable_are_scaled_as_on_the_planar_cable():
    planar = prepare_continuation(api.load_case(CASE, overrides=[RANGE])).eom
    spatial = prepare_continuation(api.load_case(CASE, overrides=[RANGE, "spatial=true"])).eom
    nd2, nd3 = planar.n_dof, spatial.n_dof
    # the plane's normal: the axis along which no node of the spatial equilibrium has moved
    nodes = np.reshape(spatial.y0, (-1, 3))
    normal = int(np.argmin(np.ptp(nodes, axis=0)))
    odd = np.arange(normal, nd3, 3)
    even = np.setdiff1d(np.arange(nd3), odd)
    w_in = lowest_frequency(planar.K0, planar.mass)
    w_out = lowest_frequency(spatial.K0[np.ix_(odd, odd)], spatial.mass[odd])
    assert w_out < w_in  # the paper's cable: its first out-of-plane mode is below the in-plane one
    s2, _ = cable_scales(planar, "omega", 0.5, 6.0)
    s3, _ = cable_scales(spatial, "omega", 0.5, 6.0)
    amp = s2[0]
    assert np.allclose(s3[:nd3], amp, rtol=1e-12)
    assert np.allclose(s2[nd2:], amp * w_in, rtol=1e-10)
    assert np.allclose(s3[nd3 + even], amp * w_in, rtol=1e-10)
    assert np.allclose(s3[nd3 + odd], amp * w_out, rtol=1e-10)
