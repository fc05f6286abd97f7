"""`cablesim animate` and `cablesim.animate`: the GIF holds the frames asked for at the frame rate
asked for, each frame draws the stored state (read back with h5py) and tensions, a periodic
response loops over one steady period, and the bounds are enforced."""

from __future__ import annotations

import math
import shutil
import subprocess

import h5py
import numpy as np
import pytest
from PIL import Image

import cablesim
from cablesim.plots.animation import FPS_RANGE, FRAMES_RANGE, ffmpeg_available
from helpers_cli import assert_refused

#: Animations drawn and inspected, not shown or saved (matplotlib warns of those).
pytestmark = pytest.mark.filterwarnings("ignore:Animation was deleted without rendering")


@pytest.fixture(scope="module")
def histories(tmp_path_factory):
    """A forced response damped until periodic (30 s), and a free vibration (1 s), as files."""
    root = tmp_path_factory.mktemp("anim")
    forced = cablesim.load_case(None, ["damping.ratio=0.3"])
    h = cablesim.history(forced, omega=2.4, duration=30.0).to_hdf5(root / "forced.h5")
    fv = cablesim.free_vibration(cablesim.load_case(), duration=1.0).to_hdf5(root / "free.h5")
    return root, h, fv


def stored(path):
    with h5py.File(path, "r") as f:
        return {k: f[f"history/{k}"][()] for k in ("t", "z", "T", "y0")}


def test_gif_has_the_frames_and_rate_asked_for(invoke_cli, histories, tmp_path):
    root, h, _ = histories
    res = invoke_cli("animate", h, "-o", "a.gif", "--frames", "25", "--fps", "10")
    assert res.returncode == 0, res.stdout + res.stderr
    assert "25 frames at 10 fps (2.5 s)" in res.stdout
    with Image.open(tmp_path / "a.gif") as im:
        assert im.n_frames == 25
        assert im.info["duration"] == 100  # ms per frame
        assert im.size[0] == 700  # 7 in at 100 dpi
        frames = []
        for k in (0, 12):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB"), dtype=int))
    assert np.abs(frames[0] - frames[1]).sum() > 0  # the cable moves


def test_each_frame_draws_the_stored_state(histories):
    _, h, _ = histories
    data = stored(h)
    anim = cablesim.animate(h, frames=12)
    n = data["y0"].size // 2
    idx = np.searchsorted(data["t"], anim.frame_times)
    np.testing.assert_array_equal(data["t"][idx], anim.frame_times)
    for k in (0, 5, 11):
        lines, nodes = anim.draw_frame(k)[:2]
        y = data["y0"] + data["z"][idx[k]]
        np.testing.assert_allclose(np.column_stack(nodes.get_data()).ravel(), y, rtol=1e-12)
        seg = np.asarray(lines.get_segments())
        assert seg.shape == (n + 1, 2, 2)
        np.testing.assert_allclose(seg[1:, 0].ravel(), y, rtol=1e-12)  # each segment starts at a node
        np.testing.assert_allclose(seg[0, 0], [0.0, 0.0], atol=0)  # support A
        T = np.asarray(lines.get_array())
        scale = data["T"][idx[k]] / T
        np.testing.assert_allclose(scale, scale[0], rtol=1e-12)  # colours are the tensions (kN)
        assert scale[0] == pytest.approx(1e3) or scale[0] == pytest.approx(1e6)


def test_a_periodic_response_loops_over_one_period(histories):
    _, h, _ = histories
    anim = cablesim.animate(h, frames=20)
    plan = anim.frame_plan
    assert plan.periodic
    t = stored(h)["t"]
    step = t[1] - t[0]
    assert plan.stop - plan.start == pytest.approx(2 * math.pi / 2.4, abs=step)
    assert plan.stop == pytest.approx(t[-1])
    assert anim.frame_times.size == 20 and np.all(np.diff(anim.frame_times) > 0)
    assert anim.frame_times[-1] < plan.stop  # the last frame is not the first one again
    assert "one steady period" in anim.summary


def test_a_free_vibration_is_shown_from_its_start(histories, tmp_path):
    _, _, fv = histories
    anim = cablesim.animate(fv, tmp_path / "fv.gif", frames=10, fps=5)
    t = stored(fv)["t"]
    assert anim.frame_times[0] == t[0] and not anim.frame_plan.periodic
    with Image.open(tmp_path / "fv.gif") as im:
        assert im.n_frames == 10 and im.info["duration"] == 200
    # a window asked for
    anim = cablesim.animate(fv, frames=5, start=0.5, stop=0.9)
    assert anim.frame_times[0] == pytest.approx(0.5, abs=t[1] - t[0])
    assert anim.frame_times[-1] == pytest.approx(0.9, abs=t[1] - t[0])


@pytest.mark.parametrize("args, needle", [
    (["--frames", str(FRAMES_RANGE[1] + 1)], "--frames"),
    (["--frames", "1"], "--frames"),
    (["--fps", str(FPS_RANGE[1] + 1)], "--fps"),
    (["--fps", "0.5"], "--fps"),
    (["--start", "25", "--stop", "20"], "--start"),
    (["-o", "a.png"], "must end in .gif"),
])
def test_bounds_and_bad_options_are_refused(invoke_cli, histories, tmp_path, args, needle):
    _, h, _ = histories
    assert_refused(invoke_cli("animate", h, "-o", "a.gif", *args), tmp_path, needle)
    assert not (tmp_path / "a.gif").exists()


def test_a_static_file_is_refused_and_the_api_checks_bounds(invoke_cli, tmp_path):
    cablesim.static(cablesim.load_case()).to_hdf5(tmp_path / "s.h5")
    keep = (tmp_path / "s.h5",)
    assert_refused(invoke_cli("animate", "s.h5"), tmp_path, "s.h5 is a static file", "cablesim history", keep=keep)
    with pytest.raises(cablesim.api.CablesimError, match="--frames"):
        cablesim.animate(tmp_path / "s.h5", frames=FRAMES_RANGE[1] + 1)


def test_mp4_without_ffmpeg_is_refused(invoke_cli, histories, tmp_path, monkeypatch):
    import cablesim.plots.animation as animation

    monkeypatch.setattr(animation, "ffmpeg_available", lambda: False)  # as on a machine without it
    _, h, _ = histories
    assert_refused(invoke_cli("animate", h, "-o", "a.mp4"), tmp_path, "ffmpeg", "a.gif")
    with pytest.raises(cablesim.api.CablesimError, match="ffmpeg"):
        cablesim.animate(h, tmp_path / "b.mp4", frames=4)
    assert not (tmp_path / "b.mp4").exists()


@pytest.mark.skipif(not ffmpeg_available(), reason="ffmpeg is not installed (apt-get install ffmpeg)")
def test_mp4_where_ffmpeg_is_installed(histories, tmp_path):
    _, h, _ = histories
    cablesim.animate(h, tmp_path / "a.mp4", frames=10, fps=5)
    assert (tmp_path / "a.mp4").stat().st_size > 1000
    if shutil.which("ffprobe"):
        probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                                "stream=nb_read_frames,r_frame_rate,width", "-of", "csv=p=0", str(tmp_path / "a.mp4")],
                               capture_output=True, text=True, timeout=60).stdout.strip()
        assert probe.split(",") == ["700", "5/1", "10"], probe


@pytest.fixture(scope="module")
def continuation(tmp_path_factory):
    """A short continuation of the paper example's response near its 1/2 subharmonic."""
    root = tmp_path_factory.mktemp("orbit")
    case = cablesim.load_case(None, ["continuation={omega: {start: 5.0, stop: 5.04}, channels: [z2, z4]}"])
    return cablesim.continuation(case).to_hdf5(root / "cont.h5")


def test_an_orbit_of_a_continuation_loops_over_its_period(continuation, invoke_cli, tmp_path):
    with h5py.File(continuation, "r") as f:
        names = sorted(f["continuation/branches"], key=lambda b: int(f["continuation/branches"][b].attrs["index"]))
        g = f["continuation/branches"][names[0]]
        omega, state, amp, period = g["omega"][()], g["state"][()], g["amplitude"][()], int(g.attrs["period"])
    k = int(np.argmax(amp[:, 0]))  # the default orbit: the largest response
    anim = cablesim.animate(continuation, frames=30)
    T = period * 2 * math.pi / omega[k]
    assert anim.frame_plan.periodic and "one period of the orbit" in anim.summary
    assert anim.frame_plan.stop - anim.frame_plan.start == pytest.approx(T, rel=1e-9)
    assert anim.frame_times[0] == pytest.approx(T, rel=1e-6)  # phase 0 of the second period
    nodes = anim.draw_frame(0)[1]
    y = np.column_stack(nodes.get_data()).ravel()
    y0 = cablesim.static(cablesim.load_case()).result.y0
    n = y0.size
    # after one period the orbit is back at the state the file stores (z at phase 0)
    np.testing.assert_allclose(y - y0, state[k, :n], atol=1e-4 * np.abs(state[k, :n]).max())
    res = invoke_cli("animate", continuation, "-o", "o.gif", "--frames", "12", "--branch", names[0],
                     "--omega", f"{omega[0]:.6g}")
    assert res.returncode == 0, res.stdout + res.stderr
    with Image.open(tmp_path / "o.gif") as im:
        assert im.n_frames == 12
    assert_refused(invoke_cli("animate", continuation, "-o", "x.gif", "--branch", "nope"), tmp_path,
                   "--branch nope", names[0], keep=(tmp_path / "o.gif",))


def test_a_history_of_some_channels_is_refused(invoke_cli, tmp_path):
    res = invoke_cli("history", "--set", "outputs.channels=[z2]", "--set", "history.channels=[z2]", "--duration", "2",
                     "-o", "some.h5", "--no-plot")
    assert res.returncode == 0, res.stdout + res.stderr
    assert_refused(invoke_cli("animate", "some.h5"), tmp_path, "every DOF", "outputs.channels",
                   keep=(tmp_path / "some.h5",))
