"""Spatial cables (three components per node) against the planar analysis, rotations of the
span, Irvine's out-of-plane frequencies and the taut beaded string's closed form."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import case_from_dict, parse_case
from cablesim.dynamics.integrators import RK4
from cablesim.dynamics.simulate import simulate
from cablesim.modal import IN_PLANE, OUT_OF_PLANE

from helpers_mechanics import rotation_about_vertical

PAPER = {
    "cable": {"L": 300.0, "H": 20.0, "S": [130.0, 100.0, 110.0], "EA": 1.0e9, "masses": [8000.0, 14000.0]},
    "loads": {"F0": [300.0e3, 1100.0e3, 450.0e3, 2000.0e3], "FL": [-6.0e3, 22.0e3, -18.0e3, 120.0e3]},
    "damping": {"ratio": 0.01, "modes": [1, 2]},
}


def paper(**changes):
    data = copy.deepcopy(PAPER)
    for key, value in changes.items():
        section, _, field = key.partition(".")
        if field:
            data[section][field] = value
        else:
            data[section] = value
    return case_from_dict(data)


def history(case, omega=2.4, duration=40.0):
    """A history by rk4 at a fixed step: the same steps whatever the number of components (an
    adaptive scheme's error norm counts the out-of-plane components, and would choose other
    steps for the same motion)."""
    st = run_static(case)
    eom = build_equations(case, st, omega=omega)
    return st, eom, simulate(eom, RK4(dt=0.005), duration, 0.05)


def test_a_planar_case_run_in_space_gives_its_planar_results():
    flat, space = paper(), paper(spatial=True)
    assert flat.dim == 2 and space.dim == 3
    st2, eom2, h2 = history(flat)
    st3, eom3, h3 = history(space)
    np.testing.assert_allclose(st3.T0, st2.T0, rtol=1e-12)
    np.testing.assert_allclose(st3.y0.reshape(-1, 3)[:, :2].ravel(), st2.y0, rtol=0, atol=1e-10)
    assert np.all(st3.y0.reshape(-1, 3)[:, 2] == 0.0)
    inplane = [w for w, k in zip(st3.modes.omega, st3.modes.kinds) if k == IN_PLANE]
    np.testing.assert_allclose(inplane, st2.modes.omega, rtol=1e-10)
    assert st3.modes.kinds.count(OUT_OF_PLANE) == 2
    assert (st3.a0, st3.a1) == pytest.approx((st2.a0, st2.a1), rel=1e-10)  # damping by the in-plane modes
    z3 = h3.z.reshape(h3.z.shape[0], -1, 3)
    assert np.all(z3[:, :, 2] == 0.0)  # exactly planar forever
    scale = np.abs(h2.z).max()
    assert np.abs(z3[:, :, :2].reshape(h2.z.shape) - h2.z).max() < 1e-10 * scale
    np.testing.assert_allclose(h3.T, h2.T, rtol=0, atol=1e-10 * np.abs(h2.T).max())


def test_the_span_turned_about_the_vertical_gives_the_turned_results():
    a = 0.6
    R = rotation_about_vertical(a)
    base = paper(spatial=True)
    B = R @ np.array([300.0, 20.0, 0.0])
    F0 = (np.column_stack([np.reshape(PAPER["loads"]["F0"], (-1, 2)), np.zeros(2)]) @ R.T).ravel()
    FL = (np.column_stack([np.reshape(PAPER["loads"]["FL"], (-1, 2)), np.zeros(2)]) @ R.T).ravel()
    turned = paper(**{"cable.L": float(B[0]), "cable.H": float(B[1]), "cable.W": float(B[2]),
                      "loads.F0": F0.tolist(), "loads.FL": FL.tolist()})
    assert turned.dim == 3
    st0, _, h0 = history(base, duration=20.0)
    st1, _, h1 = history(turned, duration=20.0)
    np.testing.assert_allclose(st1.modes.omega, st0.modes.omega, rtol=1e-9)
    np.testing.assert_allclose(st1.T0, st0.T0, rtol=1e-9)
    np.testing.assert_allclose(h1.T, h0.T, rtol=0, atol=1e-9 * np.abs(h0.T).max())
    z_turned = (h0.z.reshape(h0.z.shape[0], -1, 3) @ R.T).reshape(h0.z.shape)
    assert np.abs(h1.z - z_turned).max() < 1e-9 * np.abs(h0.z).max()


def level_cable(nodes: int, sag_ratio: float = 1 / 200):
    """A level heavy cable (span 100 m, 10 kg/m) sagging about ``sag_ratio`` of its span."""
    L = 100.0
    length = L * (1 + 8 / 3 * sag_ratio**2)  # parabola: s = L (1 + 8/3 (d/L)^2)
    text = (f"spatial: true\ncable: {{L: {L}, H: 0.0, length: {length!r}, nodes: {nodes}, EA: 1.0e12, "
            f"mass_per_length: 10.0}}\nloads: {{gravity: 9.81}}\n")
    return parse_case(text)


@pytest.mark.slow
def test_out_of_plane_frequencies_approach_irvines_at_second_order():
    """Out-of-plane modes of a shallow level cable: w_k = k pi / L sqrt(H / m) (Irvine), H the
    horizontal tension; the discrete cable approaches its own limit at order 2 in the spacing,
    and that limit is Irvine's to the shallow theory's error (sag/span)^2."""
    errs, limits = [], []
    for n in (9, 19, 39):
        case = level_cable(n)
        st = run_static(case)
        H = st.exact.segments.F[0][0]  # horizontal tension (the same in every segment)
        w = np.array([om for om, k in zip(st.modes.omega, st.modes.kinds) if k == OUT_OF_PLANE][:3])
        irvine = np.arange(1, 4) * np.pi / 100.0 * np.sqrt(H / 10.0)
        limits.append(irvine)
        errs.append(w / irvine - 1.0)
    errs = np.array(errs)
    order = np.log2(np.abs(errs[0] - errs[1]) / np.abs(errs[1] - errs[2]))
    assert np.all((order > 1.8) & (order < 2.2)), order
    richardson = errs[2] + (errs[2] - errs[1]) / 3.0
    assert np.abs(richardson).max() < 1e-3, richardson  # (1/200)^2 = 2.5e-5 times a few


def test_out_of_plane_modes_of_a_taut_beaded_string_are_the_closed_form():
    """A straight pretensioned cable of n equal masses: transverse modes (in-plane and out of
    the plane alike) w_k = 2 sqrt(T / (m a)) sin(k pi / (2 (n + 1))), a the spacing."""
    n, m, L = 7, 5.0, 40.0
    S = L / (n + 1) / 1.001  # 0.1 % pretension strain
    EA = 1.0e6
    case = parse_case(f"spatial: true\ncable: {{L: {L}, H: 0.0, S: {[S] * (n + 1)}, EA: {EA}, masses: {[m] * n}}}\n"
                      f"loads: {{F0: {[0.0] * (3 * n)}}}\n")
    st = run_static(case)
    T = st.T0[0]
    assert T == pytest.approx(EA * 0.001, rel=1e-9)
    a = L / (n + 1)
    k = np.arange(1, n + 1)
    closed = 2.0 * np.sqrt(T / (m * a)) * np.sin(k * np.pi / (2 * (n + 1)))
    out = np.array([w for w, kind in zip(st.modes.omega, st.modes.kinds) if kind == OUT_OF_PLANE])
    np.testing.assert_allclose(out, closed, rtol=1e-10)
    axial = 2.0 * np.sqrt((EA / S) / m) * np.sin(k * np.pi / (2 * (n + 1)))
    inplane = np.sort([w for w, kind in zip(st.modes.omega, st.modes.kinds) if kind == IN_PLANE])
    np.testing.assert_allclose(inplane, np.sort(np.concatenate([closed, axial])), rtol=1e-10)


def test_spatial_case_file_rules():
    assert paper().dim == 2
    assert paper(**{"cable.W": 10.0}).dim == 3
    assert paper(**{"loads.F0": [300e3, 1100e3, 5e3, 450e3, 2000e3, 0.0]}).dim == 3
    sp = paper(spatial=True)
    np.testing.assert_array_equal(sp.F0, [300e3, 1100e3, 0.0, 450e3, 2000e3, 0.0])  # planar list padded
    moving = paper(supports={"B": {"amplitude": [0.0, 0.1, 0.2]}})
    assert moving.dim == 3
    uA, uB, _, _ = moving.support_motion()
    np.testing.assert_array_equal(uB, [0.0, 0.1, 0.2])
    with pytest.raises(Exception, match="F0 has 5 values"):
        paper(**{"loads.F0": [1.0, 2.0, 3.0, 4.0, 5.0]})
    with pytest.raises(Exception, match="exact analysis"):
        paper(analysis="approximate", supports={"A": {"amplitude": [0.1, 0.0]}})
    with pytest.raises(Exception, match=r"\.w"):
        paper(history={"channels": ["node1.w"]})  # a planar case has no w
    assert paper(spatial=True, history={"channels": ["node2.w"]}).history.channels == ("node2.w",)
