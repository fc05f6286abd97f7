"""``cablesim report``: one self-contained HTML page of one or more result files, with every
figure of each run embedded.

A result's figures are the PNGs its command drew beside it (and its animation, if
``cablesim animate`` made one); a file whose figures are not there (``--no-plot``, moved) gets
them drawn for the page from the stored data, into a temporary folder, and says so.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from ..errors import CablesimError
from ..io.html_report import render_report, write_report_html
from ..io.naming import animation_file, figures
from ..io.report_tables import FileReport, read_file_report
from .redraw import redraw

#: Figure captions by the end of the file name.
CAPTIONS = {"-modes.png": "the lowest mode shapes", "-waveforms.png": "waveforms", "-phase.png": "phase plots",
            "-lissajous.png": "Lissajous figure", "-tensions.png": "tension waveforms", "-fft.png": "spectrum",
            "-snapshots.png": "the cable at several instants", "-across.png": "motion across the span",
            "-chart.png": "stability chart", "-animation.gif": "animation"}
MIME = {".png": "image/png", ".gif": "image/gif"}


def caption(path: Path, result: Path) -> str:
    """A figure's caption: its file name and what it shows."""
    for end, words in CAPTIONS.items():
        if path.name.endswith(end):
            return f"{path.name}: {words}"
    return f"{path.name}: the {'cable under F0' if result.stem.startswith('static') else 'main figure'}"


def run_figures(rep: FileReport) -> list[tuple[str, str, bytes]]:
    """Every figure of the run of ``rep`` as (caption, MIME type, bytes): those beside its file,
    else drawn now from the stored data (a warning says so)."""
    beside = [p for p in (*figures(rep.path, rep.family), animation_file(rep.path)) if p.is_file()]
    if any(p.suffix == ".png" for p in beside):
        return [(caption(p, rep.path), MIME[p.suffix], p.read_bytes()) for p in beside]
    with tempfile.TemporaryDirectory(prefix="cablesim-report-") as tmp:
        try:
            drawn = redraw([rep.path], Path(tmp) / f"{rep.path.stem}.png")
        except CablesimError as exc:
            rep.warnings.append(f"The figures could not be drawn from the file: {exc}")
            drawn = []
        else:
            rep.warnings.append("No figures were beside the file; those shown were drawn for this report from "
                                "the stored data (cablesim plot draws them beside it).")
        out = [(caption(Path(p), rep.path), MIME[Path(p).suffix], Path(p).read_bytes()) for p in drawn]
    return out + [(caption(p, rep.path), MIME[p.suffix], p.read_bytes()) for p in beside]


def write_run_report(results, output: str | Path) -> Path:
    """Write the report of the result files ``results`` as one HTML page at ``output``.

    Parameters
    ----------
    results : list of str or Path
        Files of cablesim static, history, free-vibration, sweep, continue or backbone.
    output : str or Path
        The ``.html`` file.

    Returns
    -------
    Path

    Raises
    ------
    CablesimError
        If a file is missing or not a cablesim result.
    """
    if not results:
        raise CablesimError("Give at least one result file (.h5) to report on.")
    reports = [read_file_report(p) for p in results]
    pictures = [run_figures(r) for r in reports]
    names = list(dict.fromkeys(r.case_name for r in reports))
    return write_report_html(output, render_report(reports, pictures, ", ".join(names)))
