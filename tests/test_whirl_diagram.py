"""Whirling measures on every spatial orbit, the summary lines of nonplanar branches and the
response diagram of a spatial case (nonplanar branches in their own style, a panel of the
out-of-plane amplitude).

References written here: circular and straight paths of known radius, orientation and tilt fed
to the measure function, the sense of rotation judged from the angular momentum about the chord
(counter-clockwise seen from A when it points back towards A); and, for a real continuation of
the one-node whirling case (``helpers_whirl_cases.WHIRL_CASE``, across its pitchfork near 4.59
rad/s), its orbits integrated again from their stored states with scipy's DOP853 and the
segment forces written out below, whose densely sampled ``|w|`` and angular momentum give the
largest ``|w|`` and the sense to compare with the file.
"""

from __future__ import annotations

import re

import h5py
import numpy as np
import pytest
import yaml
from matplotlib.figure import Figure
from scipy.integrate import solve_ivp
from typer.testing import CliRunner

from cablesim.cli import app
from cablesim.orbits.symmetry import rotation_sense, state_mirror, whirling_measures
from helpers_figures import text_problems
from helpers_whirl_cases import WHIRL_CASE

RANGE = {"start": 4.55, "stop": 4.75}  # rad/s: both pitchforks (4.591, 4.713)


# ------------------------------------------------------------------------------------------------
# The measure function on paths of known shape
# ------------------------------------------------------------------------------------------------
def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


#: A chord A -> B that is not along an axis, and a normal to it (the cable's plane: neither a
#: coordinate plane).
CHORD = np.array([300.0, 20.0, -40.0])
NORMAL = unit(np.cross(CHORD, [0.2, 1.0, 0.3]))


def sampled_path(position, velocity, samples=256, period=2.0):
    """States ``(z, y')`` of nodes moving on closed paths, sampled uniformly over one period
    (first and last samples the same instant); ``position(t)``, ``velocity(t)``: (nodes, 3)."""
    t = np.linspace(0.0, period, samples + 1)
    x = np.array([np.concatenate([np.ravel(position(s)), np.ravel(velocity(s))]) for s in t])
    return x, t[1] - t[0]


def circle(radius, a, b, omega, phase=0.0, centre=(0.0, 0.0, 0.0)):
    """``r(t) = c + R (cos(wt + p) a + sin(wt + p) b)`` and its rate (a, b orthonormal)."""
    c = np.asarray(centre, dtype=float)
    pos = lambda t: c + radius * (np.cos(omega * t + phase) * a + np.sin(omega * t + phase) * b)  # noqa: E731
    vel = lambda t: radius * omega * (-np.sin(omega * t + phase) * a + np.cos(omega * t + phase) * b)  # noqa: E731
    return pos, vel


def seen_from_a(angular_momentum_along_chord: float) -> str:
    """The sense a viewer at A looking towards B sees (right-hand rule: an angular momentum
    pointing back at the viewer turns counter-clockwise)."""
    return "counter-clockwise" if angular_momentum_along_chord < 0 else "clockwise"


def test_circles_give_pi_r_squared_and_the_sense_seen_from_a():
    """Two nodes on circles across the cable's plane going round opposite ways, phases chosen so
    that no sample falls on the largest |w|: areas +-pi r^2, the senses the angular momentum
    about the chord gives, the radius as the largest |w| (between the samples)."""
    u = unit(CHORD)
    a, b = NORMAL, np.cross(u, NORMAL)  # a x b = u: angular velocity along A -> B
    omega, r1, r2 = np.pi, 0.3, 0.05
    p1, v1 = circle(r1, a, b, omega, phase=0.1234)
    p2, v2 = circle(r2, a, -b, omega, phase=0.777, centre=5.0 * b + 2.0 * u)  # the other way
    x, dt = sampled_path(lambda t: np.array([p1(t), p2(t)]), lambda t: np.array([v1(t), v2(t)]))
    m = whirling_measures(state_mirror(NORMAL, CHORD, 2), x, dt)
    expected = [seen_from_a(np.cross(a, b) @ u), seen_from_a(np.cross(a, -b) @ u)]
    assert expected == ["clockwise", "counter-clockwise"]
    np.testing.assert_allclose(np.abs(m.area), [np.pi * r1**2, np.pi * r2**2], rtol=1e-12)
    assert list(rotation_sense(m.area, m.max_w)) == expected
    np.testing.assert_allclose(m.max_w, [r1, r2], rtol=1e-8)  # a sample would be off by up to 7.5e-5
    assert m.max_w[0] > np.abs(x[:, 0:3] @ NORMAL).max()  # found between the samples


def test_a_motion_along_a_line_goes_nowhere_round_and_gives_its_tilt():
    """A node moving back and forth along a line at 30 deg from the cable's plane (in the
    cross-section): no area, sense none, tilt 30 deg, largest |w| its amplitude times sin 30."""
    u = unit(CHORD)
    across = np.cross(NORMAL, u)  # in the plane, across the chord
    line = np.cos(np.radians(30.0)) * across + np.sin(np.radians(30.0)) * NORMAL
    amp, omega = 0.2, 2.0
    x, dt = sampled_path(lambda t: (amp * np.sin(omega * t + 0.3) * line)[None],
                         lambda t: (amp * omega * np.cos(omega * t + 0.3) * line)[None], period=np.pi)
    m = whirling_measures(state_mirror(NORMAL, CHORD, 1), x, dt)
    assert abs(m.area[0]) < 1e-15
    assert list(rotation_sense(m.area, m.max_w)) == ["none"]
    assert m.tilt == pytest.approx(30.0, abs=1e-9)
    assert m.max_w[0] == pytest.approx(amp * 0.5, rel=1e-8)


def test_a_planar_orbit_has_no_sense_and_nan_is_not_measured():
    assert list(rotation_sense([0.0, np.nan, 1e-3, -1e-3], [0.0, np.nan, 0.1, 0.1])) == [
        "none", "not measured", "counter-clockwise", "clockwise"]


# ------------------------------------------------------------------------------------------------
# A real continuation across the whirling pitchfork: file, summary, figure
# ------------------------------------------------------------------------------------------------
def case_file(tmp, spatial: bool):
    data = yaml.safe_load(WHIRL_CASE)
    if not spatial:
        data.pop("spatial")
        data["name"] = "flat-one-node"
        data["loads"]["point"] = [{"node": 1, "FL": [0.0, 0.05]}]
        data["history"]["channels"] = ["node1.v"]
    data["continuation"] = {"omega": dict(RANGE), "channels": ["node1.v", "node1.w"] if spatial else ["node1.v"]}
    path = tmp / f"{data['name']}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path, data


def run_continue(tmp, spatial: bool, monkeypatch):
    """``cablesim continue`` on the case; its stdout, file and the Figure objects it saved."""
    path, data = case_file(tmp, spatial)
    out = tmp / f"{data['name']}.h5"
    saved = []
    real = Figure.savefig

    def keep(self, *args, **kwargs):
        self.text_problems = text_problems(self)  # while its canvas can draw (helpers_figures)
        saved.append(self)
        return real(self, *args, **kwargs)

    with monkeypatch.context() as mp:
        mp.setattr(Figure, "savefig", keep)
        res = CliRunner().invoke(app, ["continue", str(path), "-o", str(out)])
    assert res.exit_code == 0, (res.stdout, res.exception)
    return res.stdout, out, saved, data


@pytest.fixture(scope="module")
def whirl(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        return run_continue(tmp_path_factory.mktemp("whirl"), True, mp)


@pytest.fixture(scope="module")
def flat(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        return run_continue(tmp_path_factory.mktemp("flat"), False, mp)


def one_node_rhs(data: dict, omega: float, C: np.ndarray):
    """The one-node spatial cable of the case: ``m y'' + C y' + P(y) = F0 + FL sin(omega t)``
    for the state ``(z, y')`` about the equilibrium, the segment forces written out here
    (supports at (0, 0, 0) and (L, H, 0), tension ``EA max(l - S, 0) / S``); the equilibrium
    solved here too."""
    from scipy.optimize import fsolve

    cab = data["cable"]
    A, B = np.zeros(3), np.array([cab["L"], cab["H"], 0.0])
    S, EA, m = np.asarray(cab["S"], dtype=float), float(cab["EA"]), float(cab["masses"][0])
    F0 = np.array([0.0, m * data["loads"]["gravity"], 0.0])
    FL = np.array(data["loads"]["point"][0]["FL"], dtype=float)

    def force(y):
        d = np.array([y - A, B - y])
        l = np.linalg.norm(d, axis=1)
        f = (EA * np.maximum(l - S, 0.0) / S / l)[:, None] * d
        return f[0] - f[1]

    y0 = fsolve(lambda y: force(y) - F0, np.array([cab["L"] / 2, 0.01, 0.0]), xtol=1e-14)

    def rhs(t, s):
        z, v = s[:3], s[3:]
        return np.concatenate([v, (F0 + FL * np.sin(omega * t) - C @ v - force(y0 + z)) / m])

    return rhs


def damping_matrix(case_path):
    from cablesim import api
    from cablesim.analyses.setup import build_equations
    from cablesim.analyses.static import run_static

    case = api.load_case(case_path)
    return build_equations(case, run_static(case, all_models=False), omega=4.6).C


def test_stored_largest_w_and_sense_are_those_of_the_orbit_integrated_again(whirl, tmp_path):
    """For orbits of the nonplanar branch: the largest |w| in the file (m) is the largest of the
    orbit integrated again from its stored state and sampled densely, and the stored sense is
    the one its angular momentum about the chord gives; the planar branch stores zeros."""
    _, out, _, data = whirl
    C = damping_matrix(case_file(tmp_path, True)[0])
    with h5py.File(out) as f:
        branches = [f["continuation/branches"][k] for k in f["continuation/branches"]]
        assert f[branches[0].name + "/max_w"].attrs["units"] == "m"
        planar = [b for b in branches if b.attrs["planar"]]
        whirling = [b for b in branches if not b.attrs["planar"]]
        assert planar and whirling
        for b in planar:
            assert np.all(b["max_w"][()] == 0.0) and set(b["whirl_sense"][()].ravel()) == {b"none"}
        b = whirling[0]
        omega, state, max_w = b["omega"][()], b["state"][()], b["max_w"][()]
        area, sense = b["whirl_area"][()], b["whirl_sense"][()].astype(str)
    for k in (state.shape[0] // 2, state.shape[0] - 1):
        T = 2 * np.pi / omega[k]
        t = np.linspace(0.0, T, 20001)
        y = solve_ivp(one_node_rhs(data, omega[k], C), (0.0, T), state[k], method="DOP853", rtol=1e-12,
                      atol=1e-14, t_eval=t).y
        assert np.abs(y[:, -1] - state[k]).max() < 1e-6 * np.abs(state[k]).max()  # it is the orbit
        v, w, dv, dw = y[1], y[2], y[4], y[5]
        assert max_w[k, 0] == pytest.approx(np.abs(w).max(), rel=1e-6)
        spin = np.trapezoid(v * dw - w * dv, t)  # angular momentum about the chord (1, 0, 0), integrated
        assert abs(area[k, 0]) == pytest.approx(0.5 * abs(spin), rel=1e-5)
        assert sense[k, 0] == seen_from_a(spin)


def test_summary_has_a_line_per_nonplanar_branch_and_none_for_planar_ones(whirl, flat):
    stdout, out, _, _ = whirl
    with h5py.File(out) as f:
        g = f["continuation/branches"]
        rows = {k: (bool(g[k].attrs["planar"]), g[k]["max_w"][()], g[k]["tilt"][()],
                    set(g[k]["whirl_sense"][()].astype(str).ravel()) - {"none"}) for k in g}
    lines = [line for line in stdout.splitlines() if "nonplanar (whirling)" in line]
    assert len(lines) == sum(not p for p, *_ in rows.values()) >= 1
    for name, (planar, max_w, tilt, senses) in rows.items():
        mine = [line for line in lines if line.strip().startswith(f"{name}:")]
        if planar:
            assert not mine
            continue
        (line,) = mine
        assert f"largest |w| {np.nanmax(max_w):.4g} m" in line
        assert f"tilted {np.nanmin(tilt):.3g} - {np.nanmax(tilt):.3g} deg" in line
        assert re.search(r"goes round (counter-)?clockwise", line)
        assert len(senses) == 1 and f"round {senses.pop()};" in line
        assert "mirror image" in line
    assert "nonplanar" not in flat[0] and "|w|" not in flat[0]


def _lines(ax):
    return [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 1]


def test_spatial_diagram_has_an_out_of_plane_panel_and_its_own_style_for_nonplanar_branches(whirl):
    _, out, saved, data = whirl
    (fig,) = [f for f in saved if len(f.axes) > 0]
    chans = data["continuation"]["channels"]
    assert len(fig.axes) == len(chans) + 1
    w_ax = fig.axes[-1]
    assert "|w|" in w_ax.get_ylabel() and "(mm)" in w_ax.get_ylabel()
    assert all(ax.get_shared_x_axes().joined(ax, w_ax) for ax in fig.axes[:-1])
    assert "out of plane" in fig.axes[1].get_ylabel()  # node1.w is z3: node 1, not "node 2, horizontal"
    assert "vertical" in fig.axes[0].get_ylabel()
    with h5py.File(out) as f:
        top = max(float(np.max(f["continuation/branches"][k]["max_w"][()])) for k in f["continuation/branches"])
    # lines of the out-of-plane panel: the planar branch on zero, the whirling one off it, in mm
    on_zero = [ln for ln in _lines(w_ax) if np.all(np.asarray(ln.get_ydata()) == 0.0)]
    off_zero = [ln for ln in _lines(w_ax) if np.any(np.asarray(ln.get_ydata()) > 0.0)]
    assert on_zero and off_zero
    assert max(np.max(ln.get_ydata()) for ln in off_zero) == pytest.approx(1e3 * top, rel=1e-12)
    style = lambda ln: (ln.get_color(), ln.get_linestyle(), ln.get_linewidth())  # noqa: E731
    assert not {style(ln) for ln in on_zero} & {style(ln) for ln in off_zero}
    assert not {ln.get_color() for ln in on_zero} & {ln.get_color() for ln in off_zero}
    # stable and unstable whirling orbits told apart (the upper branch born unstable)
    assert len({ln.get_linestyle() for ln in off_zero}) == 2
    legend = fig.legends[0]
    entries = {t.get_text(): h for t, h in zip(legend.get_texts(), legend.legend_handles)}
    (label,) = [t for t in entries if t.startswith("nonplanar (whirling)")]
    assert "mirror image" in label
    assert entries[label].get_color() in {ln.get_color() for ln in off_zero}
    assert "nonplanar" in fig.get_suptitle()
    assert not fig.text_problems, fig.text_problems  # no label over another or off the figure


def test_planar_diagram_keeps_its_single_panel(flat):
    _, _, saved, data = flat
    (fig,) = [f for f in saved if len(f.axes) > 0]
    assert len(fig.axes) == len(data["continuation"]["channels"]) == 1
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "stable" in texts and "unstable" in texts and not any("nonplanar" in t for t in texts)


# ------------------------------------------------------------------------------------------------
# Out-of-plane round-off on a planar branch
# ------------------------------------------------------------------------------------------------
def test_tiny_out_of_plane_parts_of_a_planar_orbit_are_zero_to_the_shooting_map(tmp_path):
    """Newton's corrections shrink the out-of-plane round-off of a planar branch's states into
    subnormal numbers (the paper's planar period-2 branch, made spatial, reached 1e-322), whose
    arithmetic made every flow of the branch twenty times slower: the shooting map now takes
    components below 1e-100 of the state's largest as zero, so such a state gives the residual,
    Jacobian and extremes of the state with exact zeros there, bit for bit."""
    from cablesim import api
    from cablesim.analyses.setup import build_equations
    from cablesim.analyses.static import run_static
    from cablesim.orbits import Shooting, cable_system, linear_response_state, solve_orbit

    case = api.load_case(case_file(tmp_path, True)[0])
    eom = build_equations(case, run_static(case, all_models=False), omega=4.5)
    sh = Shooting(cable_system(eom))
    u = solve_orbit(sh, linear_response_state(eom, 4.5), 4.5).u
    w = np.array([2, 5])  # w and w' of the node
    assert np.all(u[w] == 0.0) and np.abs(u).max() > 1e-3
    tiny = u.copy()
    tiny[w] = [3e-318, -7e-312]  # subnormal
    a, b = sh.evaluate(u, 4.5), sh.evaluate(tiny, 4.5)
    for key in ("r", "J_u", "J_lam", "xmax", "xmin", "multipliers"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key
    # a component within reach of the others' round-off is kept
    small = u.copy()
    small[w] = [1e-20, 0.0]
    assert not np.array_equal(sh.evaluate(small, 4.5).r, a.r)


def test_readme_spatial_continuation_example_runs_and_says_what_it_prints(tmp_path, monkeypatch):
    """The README's block on spatial continuation runs as written, and its numbers are the run's."""
    import shlex
    from pathlib import Path

    from cablesim.case import example_text

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    section = readme.split("**Spatial cases: where the response leaves its plane.**")[1]
    block = section.split("```sh\n")[1].split("```")[0]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my-case.yaml").write_text(example_text())
    (command,) = [line for line in block.splitlines() if line.strip()]
    args = shlex.split(command)
    assert args[0] == ".venv/bin/cablesim"
    res = CliRunner().invoke(app, args[1:])
    assert res.exit_code == 0, (res.stdout, res.exception)
    with h5py.File(tmp_path / "runs/my-case/spatial-continuation.h5") as f:
        bif = f["continuation/bifurcations"]
        found = sorted(zip(bif["kind"][()].astype(str), bif["plane"][()].astype(str), bif["parameter"][()]),
                       key=lambda b: b[2])
        whirl = [f["continuation/branches"][k] for k in f["continuation/branches"]
                 if not f["continuation/branches"][k].attrs["planar"]]
        assert len(whirl) == 1
        max_w, area = whirl[0]["max_w"][()], whirl[0]["whirl_area"][()]
    assert np.all(np.isfinite(max_w))  # its last orbit, the parent's period doubling it merges at, too
    text = " ".join(section.split("```sh")[0].split())
    (fold,) = [b for b in found if b[0] == "fold"]
    doublings = [b for b in found if b[0] == "period-doubling" and b[1] == "out-of-plane"]
    assert len(doublings) == 2
    assert f"between {doublings[0][2]:.3f} and {doublings[1][2]:.3f} rad/s" in text
    assert f"fold at {fold[2]:.3f} rad/s" in text
    assert f"up to {np.max(max_w):.1f} m across the plane" in text
    # a period-2 whirl with w(t + T) = -w(t) encloses no net area: the figure of eight
    assert np.abs(area).max() < 1e-9 * np.max(max_w) ** 2
    assert "no net rotation" in res.stdout


def test_a_cable_forced_out_of_its_plane_has_its_whirling_measured_in_the_equilibrium_plane():
    """With a harmonic load across the plane there is no mirror symmetry and no planar branch:
    every orbit leaves the plane of the (planar) equilibrium, and its measures are taken there;
    the largest |w| is the w channel's amplitude found by the flow kernel's own extremes."""
    from cablesim import api
    from cablesim.analyses.continuation import run_continuation

    data = yaml.safe_load(WHIRL_CASE)
    data["loads"]["point"] = [{"node": 1, "FL": [0.0, 0.05, 0.01]}]
    data["continuation"] = {"omega": {"start": 4.4, "stop": 4.5}, "channels": ["node1.v", "node1.w"]}
    res = run_continuation(api.load_case(data))
    assert res.branches and not any(b.planar for b in res.branches)
    b = res.branches[0]
    assert b.nonplanar and np.all(np.isfinite(b.max_w)) and np.all(b.max_w > 0)
    np.testing.assert_allclose(b.max_w[:, 0], b.amplitude[:, 1], rtol=1e-12)  # the same quintic interpolant
    assert set(b.whirl_sense.ravel()) <= {"clockwise", "counter-clockwise", "none"}


def test_whirling_measures_read_as_arrays_over_point_and_node(whirl):
    import cablesim

    _, out, _, _ = whirl
    r = cablesim.load_result(out)
    with h5py.File(out) as f:
        name = next(k for k in f["continuation/branches"] if not f["continuation/branches"][k].attrs["planar"])
        stored = f["continuation/branches"][name]["max_w"][()]
    x = r.to_xarray(f"continuation/branches/{name}")
    for key in ("max_w", "whirl_area", "whirl_sense"):
        assert x[key].dims == ("point", "node"), key
    assert list(x["node"].values) == [1] and x["max_w"].attrs["units"] == "m"
    np.testing.assert_array_equal(x["max_w"].values, stored)
