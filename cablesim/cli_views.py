"""The command-line parts that show results: the mode shapes ``cablesim static`` draws,
``cablesim animate`` (the cable moving, as a GIF) and ``cablesim report`` (one HTML page of a run).

:func:`register` adds the commands to the application of :mod:`cablesim.cli`; like it, this
module imports its machinery only when a command runs, so that ``cablesim --help`` starts at once.
"""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Optional

import typer

from .io.terminal import quiet_outputs


def static_figures(modes_drawn: int):
    """The PNGs ``cablesim static`` writes beside its result (a function of the result's path)."""
    def figures(out: Path) -> list[Path]:
        png = out.with_suffix(".png")
        return [png, png.with_name(png.stem + "-modes.png")] if modes_drawn else [png]

    return figures


def draw_static(result, out: Path, name: str, modes_drawn: int) -> str:
    """Draw the cable (and its lowest ``modes_drawn`` modes) beside ``out``; the PNGs written."""
    from .plots.cable import plot_cable
    from .plots.modes import modes_drawable, modes_png, plot_modes

    png = plot_cable(result, out.with_suffix(".png"), name)
    written = [png]
    if modes_drawn and modes_drawable(result):
        written.append(plot_modes(result, modes_png(png), name, modes_drawn))
    return " and ".join(str(p) for p in written)


def _begin(ctx) -> tuple:
    """Record the invocation (for the figures' metadata); ``(echo, note)`` honouring --quiet."""
    from .io.provenance import command_words, plain, set_invocation

    set_invocation(shlex.join(command_words(ctx)), {k: plain(v) for k, v in ctx.params.items()})
    return quiet_outputs(bool(ctx.find_root().params.get("quiet")))


def run_animate(ctx, result: Path, output, frames: int, fps: float, start, stop, branch=None, omega=None) -> None:
    """``cablesim animate`` (see :func:`register`)."""
    from .errors import CablesimError
    from .io.naming import animation_file
    from .io.paths import check_output
    from .plots.animation import ANIMATION_SUFFIXES, animate_file, check_frames, ffmpeg_available, save_animation

    echo, note = _begin(ctx)
    check_frames(frames, fps)
    out = Path(output) if output is not None else animation_file(result)
    check_output(out, inputs=[result], suffixes=ANIMATION_SUFFIXES)
    if out.suffix.lower() == ".mp4" and not ffmpeg_available():
        raise CablesimError(f"-o {out}: MP4 files need ffmpeg, which is not installed here; install it "
                            f"(apt-get install ffmpeg) or write a GIF: -o {out.with_suffix('.gif')}.", field="output")
    anim = animate_file(result, frames, fps, start, stop, branch, omega)
    if out.is_file():
        note(f"note: replacing the animation {out}; give -o to keep it")
    save_animation(anim, out)
    echo(f"Wrote {out}: {anim.summary}")


def run_report(ctx, results: list[Path], output) -> None:
    """``cablesim report`` (see :func:`register`)."""
    from .io.naming import report_file
    from .io.paths import check_output
    from .plots.run_report import write_run_report

    echo, note = _begin(ctx)
    out = Path(output) if output is not None else report_file(results[0])
    check_output(out, inputs=results, suffixes=(".html", ".htm"))
    if out.is_file():
        note(f"note: replacing the report {out}; give -o to keep it")
    write_run_report(results, out)
    echo(f"Wrote {out} ({out.stat().st_size / 1e6:.3g} MB, self-contained: open it in any browser)")


def register(app, user_errors) -> None:
    """Add ``cablesim animate`` and ``cablesim report`` to the application ``app``
    (``user_errors`` turns a :class:`~cablesim.errors.CablesimError` into a one-paragraph
    message and exit status 2)."""

    @app.command()
    @user_errors
    def animate(
        ctx: typer.Context,
        result: Path = typer.Argument(..., metavar="RESULT.h5", show_default=False,
                                      help="A file of cablesim history, free-vibration or continue."),
        output: Optional[Path] = typer.Option(None, "-o", "--output", metavar="GIF|MP4",
                                              help="Animation file, .gif, or .mp4 where ffmpeg is installed "
                                              "(default: RESULT-animation.gif beside the file)."),
        frames: int = typer.Option(120, "--frames", min=2, max=600, help="Number of frames, 2 to 600 (fewer when "
                                   "the window holds fewer saved instants)."),
        fps: float = typer.Option(20.0, "--fps", min=1.0, max=50.0, help="Frames per second, 1 to 50."),
        start: Optional[float] = typer.Option(None, "--start", metavar="S", help="Start of the window, s (default: "
                                              "one steady period, else 20 frames per period; see the README)."),
        stop: Optional[float] = typer.Option(None, "--stop", metavar="S", help="End of the window, s."),
        branch: Optional[str] = typer.Option(None, "--branch", metavar="NAME", help="A continuation file: the branch "
                                             "(default: the first, b0-p1)."),
        omega: Optional[float] = typer.Option(None, "--omega", metavar="W", help="A continuation file: the orbit "
                                              "nearest this forcing frequency, rad/s (default: the largest response)."),
    ):
        """The cable moving, as an animated GIF (or MP4): a time history, or one orbit of a
        continuation, at true scale with the static shape, the envelope of the motion, a time
        marker and the tensions in colour; one steady period of a periodic response, looping.
        The frames, the frame rate and the length are stated."""
        run_animate(ctx, result, output, frames, fps, start, stop, branch, omega)

    @app.command()
    @user_errors
    def report(
        ctx: typer.Context,
        results: list[Path] = typer.Argument(..., metavar="RESULT.h5", show_default=False,
                                             help="Result files of any cablesim command (one section each)."),
        output: Optional[Path] = typer.Option(None, "-o", "--output", metavar="HTML",
                                              help="The page (default: FIRST-report.html beside the first file)."),
    ):
        """One self-contained HTML page of a run (or several): the case, how it was run (command,
        versions, commit), tables of results (tensions and reactions, modes, peaks,
        bifurcations), every figure embedded, and the warnings. No network needed to read it."""
        run_report(ctx, results, output)
