"""Default names of result files, and the files a new result replaces.

A default name says what differs between runs of one case: the command, the forcing frequency
and duration of a history, the mode and velocity of a free vibration, and what a flag chooses:
a free vibration's damping ratio, a sweep's frequencies, the analysis and the integrator (``runs/<case>/history-w2.4-d600-rk4.h5``). A complete result is still replaced
when a run has its name (the same command twice), but never silently: :func:`replacing_note`
names it first. The figures of a result go with it: before a new result is written under a
name, :func:`remove_figures` deletes the PNGs the old one drew (``--no-plot`` would otherwise
leave them beside a file they no longer describe).

No h5py here (the command line names its outputs before loading anything heavy); the note on a
replaced file reads it through :func:`cablesim.io.hdf5.describe_result` when there is one.
"""

from __future__ import annotations

from pathlib import Path

#: The figures each kind of result draws beside ``NAME.h5``: ``NAME.png``, or ``NAME-<kind>.png``.
HISTORY_FIGURES = ("waveforms", "phase", "lissajous", "tensions", "fft", "snapshots", "across")


def _number(x: float) -> str:
    return f"{float(x):g}"


def _choices(analysis: str | None, integrator: str | None) -> str:
    """The parts a flag adds: ``-approximate``, ``-rk4``."""
    return "".join(f"-{v}" for v in (analysis, integrator) if v)


def history_stem(omega: float, duration: float, analysis=None, integrator=None) -> str:
    """``history-w2.4-d600`` (and ``-approximate``, ``-rk4`` when flags choose them)."""
    return f"history-w{_number(omega)}-d{_number(duration)}" + _choices(analysis, integrator)


def free_vibration_stem(mode, peak_velocity, damping_ratio=None, analysis=None, integrator=None) -> str:
    """``free-vibration-mode3-v1`` (then ``-xi0.2`` for ``--damping-ratio``, and the flags' choices)."""
    stem = "free-vibration" + (f"-mode{mode}" if mode is not None else "")
    stem += f"-v{_number(peak_velocity)}" if peak_velocity is not None and mode else ""
    stem += f"-xi{_number(damping_ratio)}" if damping_ratio is not None else ""
    return stem + _choices(analysis, integrator)


def sweep_stem(omega_flag: str | None = None, analysis=None, integrator=None) -> str:
    """``sweep`` for the case's frequencies; ``sweep-w1,2`` or ``sweep-w0.5-6-n56`` for those of
    ``--omega``; then the flags' choices."""
    stem = "sweep"
    if omega_flag:
        text = omega_flag.replace(" ", "")
        if ":" in text:
            start, stop, num = text.split(":")
            text = f"{_number(start)}-{_number(stop)}-n{int(num)}"
        else:
            text = ",".join(_number(w) for w in text.split(",") if w)
        stem += f"-w{text}"[:80]
    return stem + _choices(analysis, integrator)


def figures(out: Path, kind: str) -> list[Path]:
    """The PNGs a result of ``kind`` (``static``, ``history``, ``sweep``, ``continuation``,
    ``backbone``) written at ``out`` draws beside it."""
    out = Path(out)
    if kind == "history":
        prefix = str(out.with_suffix(""))
        return [Path(f"{prefix}-{k}.png") for k in HISTORY_FIGURES]
    if kind == "continuation":  # and the stability chart of its bifurcation curves
        return [out.with_suffix(".png"), out.with_name(out.stem + "-chart.png")]
    if kind == "static":  # and its mode shapes
        return [out.with_suffix(".png"), out.with_name(out.stem + "-modes.png")]
    return [out.with_suffix(".png")]


def remove_figures(out: Path, kind: str) -> list[Path]:
    """Delete the figures an earlier result at ``out`` drew, in any format (PNG, PDF, SVG; a new
    result is about to take its place); the paths removed."""
    gone = []
    for png in figures(out, kind):
        for path in (png, png.with_suffix(".pdf"), png.with_suffix(".svg")):
            if path.is_file():
                path.unlink()
                gone.append(path)
    return gone


def replacing_note(out: Path, describe) -> str | None:
    """``"replacing the complete result ... (its figures too)"`` if ``out`` holds a complete
    result (``describe(out)`` says what it is, or None when it is not one), else None."""
    out = Path(out)
    if not out.is_file():
        return None
    what = describe(out)
    if what is None:
        return None
    return (f"replacing {out}, {what}; give -o to keep it (the default names differ by the command's "
            "frequency, duration, mode, analysis and integrator flags)")


def animation_file(out: Path) -> Path:
    """Where ``cablesim animate`` writes the animation of the result ``out`` by default
    (``NAME-animation.gif`` beside it)."""
    out = Path(out)
    return out.with_name(out.stem + "-animation.gif")


def report_file(out: Path) -> Path:
    """Where ``cablesim report`` writes the page of the result ``out`` by default
    (``NAME-report.html`` beside it)."""
    out = Path(out)
    return out.with_name(out.stem + "-report.html")


def rerun_output(original: Path) -> Path:
    """Where a rerun of ``original`` goes by default: ``NAME-rerun.h5`` beside it (``-rerun2``, ...
    if that exists), never over a file."""
    k = 1
    while True:
        out = original.with_name(f"{original.stem}-rerun{'' if k == 1 else k}{original.suffix}")
        if not out.exists() and not out.with_suffix(".case.yaml").exists():
            return out
        k += 1
