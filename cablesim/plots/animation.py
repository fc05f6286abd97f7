"""The cable moving: ``cablesim animate RESULT.h5`` (an animated GIF, or MP4 where ffmpeg is).

Each frame draws the cable at one saved instant of a time history, at true scale (equal axes):
the static equilibrium dashed, the envelope of the vertical motion over the animated window
shaded, the segments coloured by their tension, and below a strip with the waveform of the node
that moves most and a marker at the frame's instant (with the phase of the forcing when the
response is periodic). A spatial cable also gets its end view (``w``, ``v``, from support A).

Which instants: one steady period of a forced response that is periodic at its end (the GIF
then loops without a jump); else a window of :data:`FRAMES_PER_PERIOD` frames per period of
interest (the forcing's, or the lowest mode's for a free vibration): from the start of a free
vibration, at the end of a forced response; or the window ``start``-``stop`` given. The count
of frames and the frame rate are bounded (:data:`FRAMES_RANGE`, :data:`FPS_RANGE`), and the
animation states both, and its length, in its title.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..analyses.dynamic import plan_orbit
from ..cable import Cable, nodes_with_supports
from ..channels import channel_description
from ..case import parse_case
from ..errors import CablesimError
from ..io.continuation import read_continuation
from ..io.hdf5 import FAMILY_TEXT, inspect_result, read_history
from ..io.paths import part_path, remove_stale_parts, write_error
from .base import pyplot, title_line
from .snapshots import steady_period
from .style import COLOURS, FIGURE_WIDTH, force_unit, styled, to_resolution

#: Default number of frames and frame rate (frames per second).
DEFAULT_FRAMES, DEFAULT_FPS = 120, 20
#: Allowed numbers of frames and frame rates.
FRAMES_RANGE, FPS_RANGE = (2, 600), (1, 50)
#: Frames per period of interest when the window is not one steady period.
FRAMES_PER_PERIOD = 20
#: Resolution of the frames (dots per inch; 7 in wide: 700 pixels).
ANIMATION_DPI = 100
#: Up to this many nodes each node is marked (more would hide the tension colours).
MARKED_NODES = 40
#: Suffixes of the files written.
ANIMATION_SUFFIXES = (".gif", ".mp4")


@dataclass(frozen=True)
class FramePlan:
    """The instants an animation draws.

    Attributes
    ----------
    indices : ndarray of int
        Saved instants drawn, one per frame, in time order.
    start, stop : float
        The window, s.
    periodic : bool
        Whether the window is one steady period (the animation loops seamlessly).
    period : float or None
        The steady period, s, when periodic.
    what : str
        The window in words.
    """

    indices: np.ndarray
    start: float
    stop: float
    periodic: bool
    period: float | None
    what: str


def check_frames(frames: int, fps: float) -> None:
    """Refuse a frame count or frame rate outside :data:`FRAMES_RANGE` and :data:`FPS_RANGE`."""
    if not (isinstance(frames, (int, np.integer)) and FRAMES_RANGE[0] <= frames <= FRAMES_RANGE[1]):
        raise CablesimError(f"--frames {frames}: give the number of frames, a whole number from {FRAMES_RANGE[0]} "
                            f"to {FRAMES_RANGE[1]} (default {DEFAULT_FRAMES}).", field="frames")
    if not (math.isfinite(fps) and FPS_RANGE[0] <= fps <= FPS_RANGE[1]):
        raise CablesimError(f"--fps {fps:g}: give the frame rate in frames per second, from {FPS_RANGE[0]} to "
                            f"{FPS_RANGE[1]} (default {DEFAULT_FPS}).", field="fps")


def _window(t: np.ndarray, start, stop) -> tuple[float, float]:
    t0, t1 = float(t[0]), float(t[-1])
    a = t0 if start is None else float(start)
    b = t1 if stop is None else float(stop)
    if not (math.isfinite(a) and math.isfinite(b) and t0 <= a < b <= t1):
        raise CablesimError(f"--start {a:g} s and --stop {b:g} s: give a window inside the record, "
                            f"{t0:g} to {t1:g} s, with start before stop.", field="start")
    return a, b


def plan_frames(t, z, omega: float | None, modal_omega, frames: int = DEFAULT_FRAMES,
                start: float | None = None, stop: float | None = None, period: float | None = None) -> FramePlan:
    """Choose the saved instants of a history an animation of ``frames`` frames draws.

    Parameters
    ----------
    t : ndarray, shape (m,)
        Saved instants, s.
    z : ndarray, shape (m, k)
        Displacements, m (to find a steady period).
    omega : float or None
        Forcing frequency, rad/s (None: a free vibration).
    modal_omega : ndarray
        Linear modal frequencies, rad/s (a free vibration's period of interest: the lowest).
    frames : int
        Frames wanted; fewer when the window holds fewer saved instants.
    start, stop : float, optional
        The window, s (default: see the module's docstring).
    period : float, optional
        The record's last ``period`` s are known to be one period of the motion (an orbit):
        the frames loop over them.

    Returns
    -------
    FramePlan
    """
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        raise CablesimError("The history holds a single instant; there is nothing to animate.")
    known = period is not None
    if period is None and start is None and stop is None:
        period = steady_period(t, np.asarray(z, dtype=float), omega)
    if period is not None:
        a, b = t[-1] - period, t[-1]
        targets = a + period * np.arange(frames) / frames  # the end is the start again
        p = round(period * omega / (2 * np.pi)) if omega else 1
        what = (f"one {'period of the orbit' if known else 'steady period of the response'} ({period:.4g} s, {p} "
                f"forcing period{'s' if p > 1 else ''}), looping")
    else:
        if start is None and stop is None:
            w = omega if omega else float(np.asarray(modal_omega, dtype=float)[0]) if np.size(modal_omega) else 0.0
            length = t[-1] - t[0] if not w > 0 else min(t[-1] - t[0], frames * 2 * np.pi / w / FRAMES_PER_PERIOD)
            a, b = (t[0], t[0] + length) if omega is None else (t[-1] - length, t[-1])
            what = "the whole record" if length >= t[-1] - t[0] else \
                ("the start of the free vibration" if omega is None else "the end of the record")
        else:
            a, b = _window(t, start, stop)
            what = "the window asked for"
        targets = np.linspace(a, b, frames)
    idx = np.clip(np.round(np.interp(targets, t, np.arange(t.size))).astype(int), 0, t.size - 1)  # the nearest
    return FramePlan(np.unique(idx), float(a), float(b), period is not None, period, what)


def _moving_most(hist, cable: Cable, idx: np.ndarray) -> int:
    """Column of ``z`` of the vertical component that moves most over the frames."""
    vertical = np.arange(1, cable.n_dof, cable.dim)
    span = np.ptp(np.asarray(hist.z)[idx][:, vertical], axis=0)
    return int(vertical[int(np.argmax(span))])


def _axes(plt, spatial: bool):
    fig = plt.figure(figsize=(FIGURE_WIDTH, 5.4 if spatial else 5.0), layout="constrained")
    grid = fig.add_gridspec(2, 2 if spatial else 1, height_ratios=(3.0, 1.0),
                            width_ratios=(2.2, 1.0) if spatial else None)
    ax = fig.add_subplot(grid[0, 0])
    end = fig.add_subplot(grid[0, 1]) if spatial else None
    strip = fig.add_subplot(grid[1, :])
    return fig, ax, end, strip


def _segments(pts: np.ndarray, cols) -> np.ndarray:
    p = pts[:, cols]
    return np.stack([p[:-1], p[1:]], axis=1)


def _end_view(end, base: np.ndarray, shapes: np.ndarray):
    """The end view (w, v, from A) of a spatial cable; the line that moves."""
    end.plot(base[:, 2], base[:, 1], "--", color=COLOURS["reference"], lw=1.0)
    line = end.plot(shapes[0, :, 2], shapes[0, :, 1], "-o", color=COLOURS["response"], ms=2, lw=1.2)[0]
    end.update_datalim(shapes[:, :, [2, 1]].reshape(-1, 2))
    end.autoscale_view()
    end.invert_yaxis()
    end.invert_xaxis()  # looking from A towards B, w points to the left
    end.set_aspect("equal", adjustable="datalim")
    end.set_title("end view (from A)", fontsize="small")
    end.set_xlabel("$w$ (m)")
    return line


def _strip(strip, t: np.ndarray, z: np.ndarray, idx: np.ndarray, col: int):
    """The waveform of DOF column ``col`` over the frames' window; the time marker."""
    lo, hi = int(idx[0]), int(idx[-1]) + 1
    strip.plot(t[lo:hi], z[lo:hi, col], "-", color=COLOURS["response"], lw=0.9)
    strip.set_xlabel("time $t$ (s)")
    strip.set_ylabel(f"$z_{{{col + 1}}}$ (m)")
    return strip.axvline(t[idx[0]], color=COLOURS["annotation"], lw=1.2)


@styled
def animate_history(hist, cable: Cable, title: str, frames: int = DEFAULT_FRAMES, fps: float = DEFAULT_FPS,
                    start: float | None = None, stop: float | None = None, period: float | None = None):
    """The animation of a time history (not saved: :func:`save_animation` writes it).

    Parameters
    ----------
    hist : cablesim.dynamics.result.HistoryResult
        It must have kept every DOF (``outputs.channels`` unset).
    cable : Cable
        The cable of the run.
    title : str
        First title line (the case name).
    frames : int
        Frames, within :data:`FRAMES_RANGE` (fewer if the window holds fewer saved instants).
    fps : float
        Frames per second, within :data:`FPS_RANGE`.
    start, stop : float, optional
        The window, s (default: one steady period, else see :func:`plan_frames`).
    period : float, optional
        The record ends with one period of this length, s (an orbit's): the frames loop over it.

    Returns
    -------
    matplotlib.animation.FuncAnimation
        With the attributes ``frame_plan`` (:class:`FramePlan`), ``frame_times`` (s),
        ``fps`` and ``summary`` (what it shows, in words).
    """
    from matplotlib.animation import FuncAnimation
    from matplotlib.collections import LineCollection

    check_frames(frames, fps)
    every = list(range(1, cable.n_dof + 1))
    if sorted(set(hist.dof_numbers)) != every:
        raise CablesimError(f"An animation of the cable needs every DOF, but this history kept only "
                            f"{len(set(hist.dof_numbers))} of {cable.n_dof} (outputs.channels); rerun it without "
                            "outputs.channels.", field="outputs.channels")
    if list(hist.dof_numbers) != every:
        hist = hist.keep(every)
    plan = plan_frames(hist.t, hist.z, hist.omega, hist.modal_omega, frames, start, stop, period)
    idx, t, z, T = plan.indices, np.asarray(hist.t, dtype=float), np.asarray(hist.z, dtype=float), np.asarray(hist.T)
    y0 = np.asarray(hist.y0, dtype=float)
    plt = pyplot()
    spatial = cable.dim == 3
    fig, ax, end, strip = _axes(plt, spatial)
    base = nodes_with_supports(cable, y0)
    shapes = np.stack([nodes_with_supports(cable, y0 + z[i]) for i in idx])  # frames x (n + 2) x dim
    ax.plot(base[:, 0], base[:, 1], "--", color=COLOURS["reference"], lw=1.0, label="static equilibrium")
    ax.fill_between(base[:, 0], shapes[:, :, 1].min(axis=0), shapes[:, :, 1].max(axis=0), color="0.88",
                    lw=0, label="envelope of the vertical motion")
    ax.plot([0, cable.L], [0, cable.H], "^", color="k", ms=8, zorder=4)
    div, unit = force_unit(T[idx])
    norm = plt.Normalize(float(T[idx].min()) / div, float(max(T[idx].max(), T[idx].min() * (1 + 1e-9) + 1e-9)) / div)
    cable_lines = LineCollection(_segments(shapes[0], [0, 1]), cmap="viridis", norm=norm, lw=2.4, zorder=3)
    ax.add_collection(cable_lines)
    nodes = ax.plot(shapes[0, 1:-1, 0], shapes[0, 1:-1, 1], "o", color="k", ms=2.5 if cable.n_nodes <= MARKED_NODES else 0,
                    zorder=4)[0]
    fig.colorbar(cable_lines, ax=[ax] + ([end] if end is not None else []), label=f"segment tension $T$ ({unit})",
                 shrink=0.9, pad=0.01)
    ax.update_datalim(shapes[:, :, :2].reshape(-1, 2))
    ax.autoscale_view()
    ax.invert_yaxis()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("horizontal coordinate (m)")
    ax.set_ylabel("vertical (m), down")
    ax.legend(loc="lower left", fontsize=7.5, framealpha=0.9)
    end_line = None if end is None else _end_view(end, base, shapes)
    col = _moving_most(hist, cable, idx)
    marker = _strip(strip, t, z, idx, col)
    strip.set_title(f"$z_{{{col + 1}}}$: {channel_description(col, cable.dim)}, the DOF that moves most", fontsize=8.5)
    step = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    clock = ax.text(0.99, 0.97, "", transform=ax.transAxes, ha="right", va="top", fontsize=9,
                    bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="0.6", lw=0.6))
    duration = idx.size / fps
    fewer = f" (the window holds {idx.size} saved instants)" if idx.size < frames else ""
    summary = (f"{idx.size} frames{fewer} at {fps:g} fps ({duration:.3g} s), t = {to_resolution(plan.start, step)} to "
               f"{to_resolution(plan.stop, step)} s: {plan.what}")
    title_line(fig, f"{title}: the cable moving (true scale)", summary)

    def draw(k: int):
        i = idx[k]
        cable_lines.set_segments(_segments(shapes[k], [0, 1]))
        cable_lines.set_array(T[i] / div)
        nodes.set_data(shapes[k, 1:-1, 0], shapes[k, 1:-1, 1])
        if end_line is not None:
            end_line.set_data(shapes[k, :, 2], shapes[k, :, 1])
        marker.set_xdata([t[i], t[i]])
        text = f"t = {to_resolution(t[i], step)} s"
        if plan.periodic and hist.omega:
            text += f"\nforcing phase {((hist.omega * t[i]) / (2 * np.pi)) % 1.0:.2f} × 2π"
        clock.set_text(text)
        return (cable_lines, nodes, marker, clock) + ((end_line,) if end_line is not None else ())

    moving = draw(0)
    fig.set_dpi(ANIMATION_DPI)
    fig.canvas.draw()  # lay the figure out once; the frames keep that layout (else each is laid out again)
    fig.set_layout_engine("none")
    anim = FuncAnimation(fig, draw, frames=idx.size, interval=1000.0 / fps, blit=False, repeat=True)
    anim.frame_plan, anim.frame_times, anim.fps, anim.summary = plan, t[idx], float(fps), summary
    anim.draw_frame, anim.moving_artists = draw, moving
    return anim


def animate_file(path: str | Path, frames: int = DEFAULT_FRAMES, fps: float = DEFAULT_FPS,
                 start: float | None = None, stop: float | None = None, branch: str | None = None,
                 omega: float | None = None):
    """:func:`animate_history` of the time history stored in ``path`` (a file of ``cablesim
    history`` or ``free-vibration``), with the cable and name of the case stored in it; or of
    one orbit of a continuation file (:func:`orbit_history`: ``branch`` and ``omega`` choose it).

    Raises
    ------
    CablesimError
        If the file is neither, or as :func:`animate_history`.
    """
    check_frames(frames, fps)
    info = inspect_result(path)
    case = parse_case(info.case_text, source=f"(the case stored in {info.path})", default_name=info.path.stem)
    if info.family == "continuation":
        hist, title, period = orbit_history(info.path, case, branch, omega)
        return animate_history(hist, case.to_cable(), title, frames, fps, period=period)
    if info.family != "history":
        raise CablesimError(
            f"{info.path} is {FAMILY_TEXT[info.family]}; cablesim animate draws a time history (a file of cablesim "
            "history or free-vibration) or an orbit of a continuation (a file of cablesim continue).", field="result")
    if branch is not None or omega is not None:
        raise CablesimError("--branch and --omega choose an orbit of a continuation file; a time history is "
                            "animated over --start to --stop.", field="branch")
    return animate_history(read_history(info.path), case.to_cable(), case.name, frames, fps, start, stop)


def pick_orbit(branches: list[dict], branch: str | None, omega: float | None) -> tuple[dict, int]:
    """The branch named ``branch`` (default: the first) and its orbit nearest to ``omega``
    (default: the orbit of the largest amplitude in the first channel)."""
    names = [b["name"] for b in branches]
    if not branches:
        raise CablesimError("The continuation file holds no branch; there is no orbit to animate.", field="branch")
    if branch is not None and branch not in names:
        raise CablesimError(f"--branch {branch}: the continuation file has the branches {', '.join(names)}; "
                            "give one of them.", field="branch")
    b = branches[names.index(branch) if branch is not None else 0]
    w = np.asarray(b["omega"], dtype=float)
    if omega is not None and not (math.isfinite(omega) and w.min() * 0.99 <= omega <= w.max() * 1.01):
        raise CablesimError(f"--omega {omega:g}: branch {b['name']} runs from {w.min():.6g} to {w.max():.6g} rad/s; "
                            "give a forcing frequency on it.", field="omega")
    k = int(np.argmin(np.abs(w - omega))) if omega is not None else int(np.argmax(np.asarray(b["amplitude"])[:, 0]))
    return b, k


def orbit_history(path: Path, case, branch: str | None = None, omega: float | None = None):
    """Two periods of one orbit of a continuation file, integrated from its stored state:
    ``(history, title, orbit period in s)``; the animation then loops over the second one."""
    res = read_continuation(path)
    b, k = pick_orbit(res["branches"], branch, omega)
    w, gamma, support = float(b["omega"][k]), float(b["gamma"][k]), float(b["support"][k])
    hist = plan_orbit(case, w, gamma, b["state"][k], b["period"], analysis=res["analysis"], support=support).run()[1]
    stability = "stable" if bool(b["stable"][k]) else "unstable"
    title = (f"{case.name}: orbit {k + 1} of branch {b['name']} (period {b['period']}, {stability}), "
             f"ω = {w:.6g} rad/s, γ = {gamma:g}" + (f", s = {support:g}" if res["parameter"] == "support" else ""))
    return hist, title, b["period"] * 2.0 * np.pi / w


def ffmpeg_available() -> bool:
    """Whether matplotlib finds ffmpeg (for MP4 files)."""
    from matplotlib import animation

    return animation.writers.is_available("ffmpeg")


@styled
def save_animation(anim, path: str | Path) -> Path:
    """Write an animation of :func:`animate_history` as a GIF (pillow) or, for a ``.mp4`` path
    and where ffmpeg is installed, an MP4; atomically (through ``NAME.part``).

    Raises
    ------
    CablesimError
        For another suffix, or an MP4 without ffmpeg.
    """
    from matplotlib import animation

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in ANIMATION_SUFFIXES:
        raise CablesimError(f"-o {path}: an animation is written as .gif (or .mp4 where ffmpeg is installed); "
                            f"give, for example, -o {path.with_suffix('.gif')}.", field="output")
    if suffix == ".mp4" and not ffmpeg_available():
        raise CablesimError(f"-o {path}: MP4 files need ffmpeg, which is not installed here; install it "
                            f"(apt-get install ffmpeg) or write a GIF: -o {path.with_suffix('.gif')}.", field="output")
    remove_stale_parts(path)
    tmp = part_path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if suffix == ".gif":
            images = gif_frames(anim)
            anim._draw_was_started = True  # it was drawn, frame by frame (matplotlib warns of one never drawn)
            images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                           duration=int(round(1000 / anim.fps)), loop=0)
        else:
            writer = animation.FFMpegWriter(fps=anim.fps, codec="h264", extra_args=["-pix_fmt", "yuv420p", "-f", "mp4"])
            anim.save(tmp, writer=writer, dpi=ANIMATION_DPI)
        tmp.replace(path)
    except OSError as exc:
        raise write_error(path, exc) from None
    finally:
        tmp.unlink(missing_ok=True)
        pyplot().close(anim._fig)
    return path


def gif_frames(anim) -> list:
    """The frames of an animation of :func:`animate_history` as PIL images: the still parts of
    the figure drawn once, the moving ones (cable, nodes, marker, clock) drawn over them per frame."""
    from PIL import Image

    fig, canvas = anim._fig, anim._fig.canvas
    moving = anim.moving_artists
    for a in moving:
        a.set_animated(True)
    try:
        canvas.draw()
        background = canvas.copy_from_bbox(fig.bbox)
        images = []
        for k in range(anim.frame_times.size):
            canvas.restore_region(background)
            for a in anim.draw_frame(k):
                fig.draw_artist(a)
            images.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy()))
    finally:
        for a in moving:
            a.set_animated(False)
    anim.draw_frame(0)
    return images
