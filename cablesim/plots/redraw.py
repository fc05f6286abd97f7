"""Redraw figures from stored result files, without recomputing anything.

``cablesim plot RESULT.h5 [MORE.h5 ...]`` reads HDF5 files written by ``cablesim static``,
``history``, ``free-vibration``, ``sweep`` or ``continue``. If the case stored in the first
file (root attribute ``case_yaml``) has a ``figure:`` section, or ``--figure FILE.yaml`` gives
one, one composite PNG is drawn from all the files (one column per file); otherwise each file
gets the standard plots of its command. A continuation file given with a sweep file is drawn
with the sweep's points on top, as ``cablesim continue --overlay`` draws it; a continuation file
with bifurcation curves also gets its stability chart (``<name>-chart.png``); a backbone file
given with continuation files is drawn over their frequency responses.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from ..case import parse_case, read_figure
from ..case.files import name_from_stem
from ..channels import normalise_channel
from ..errors import CablesimError
from ..io.charts import has_loci
from ..io.hdf5 import FAMILY_TEXT, ResultInfo, inspect_result, read_history, read_static_drawing
from ..io.results import load_result
from .base import kept_figures, stamp_figures
from .cable import plot_cable
from .charts import plot_backbone, plot_stability_chart
from .composite import draw_figure
from .continuation import plot_continuation
from .history import plot_history
from .modes import modes_drawable, modes_png, plot_modes
from .snapshots import plot_snapshots
from .sweep import plot_sweep


def redraw(paths, output=None, figure=None, stamp: str | None = None,
           snapshots: int | None = None) -> list[Path]:
    """Redraw figures from stored result files; nothing is recomputed.

    Parameters
    ----------
    paths : list of Path
        Result files of cablesim static, history, free-vibration, sweep or continue; all of one
        type (history and free-vibration files count as one type: time histories), except one
        continuation file with one sweep file, whose points are drawn on the continuation.
    output : Path, optional
        With a ``figure:`` section: the PNG (default: the first file with suffix ``.png``).
        Without one (one file only): the PNG of a static or sweep file, or the prefix of the
        five time-history PNGs (``output`` without its suffix).
    figure : Path or FigureSpec, optional
        A composite figure to draw instead of the stored case's ``figure:`` section: a YAML
        file with a ``figure:`` section (see :func:`read_figure`), or the spec itself.
    stamp : str, optional
        Text drawn in a corner of every figure and recorded in the PNG metadata, e.g.
        ``"preview: coarse grid"``.
    snapshots : int, optional
        Instead: the cable drawn at this many instants of each time history
        (:func:`~cablesim.plots.snapshots.plot_snapshots`), as ``<file>-snapshots.png`` or ``output``.

    Returns
    -------
    list of Path
        The PNG files written.

    Raises
    ------
    CablesimError
        If a file is missing, not HDF5 or not a cablesim result, the files mix types, the
        figure does not fit the files (e.g. ``fdr`` from time histories, ``split`` without
        z_c/z_e), or a channel, segment or label list does not fit.
    """
    with stamp_figures(stamp):
        return _redraw([Path(p) for p in paths], output, figure, snapshots)


def _redraw(paths: list[Path], output, figure, snapshots: int | None) -> list[Path]:
    if not paths:
        raise CablesimError("Give at least one result file (.h5) to plot.")
    infos = [inspect_result(p) for p in paths]
    families = {i.family for i in infos}
    if families == {"continuation", "sweep"} and figure is None:
        return [_continuation_with_sweep(infos, output)]
    if families == {"backbone", "continuation"} and figure is None:
        return [_backbone_over_responses(infos, output)]
    if len(families) > 1:
        listing = "; ".join(f"{i.path} is {FAMILY_TEXT[i.family]}" for i in infos)
        raise CablesimError(
            f"The result files mix types ({listing}); plot files of one type together (history and "
            "free-vibration files count as one)."
        )
    family = infos[0].family
    if snapshots is not None:
        return _snapshots(infos, output, snapshots)
    case = parse_case(infos[0].case_text, source=f"(the case stored in {paths[0]})", default_name=name_from_stem(paths[0].stem))
    output = None if output is None else Path(output)

    if figure is not None:  # asked for explicitly: it must fit the files
        spec = figure if hasattr(figure, "kind") else read_figure(figure)
        png = output if output is not None else paths[0].with_suffix(".png")
        return [draw_figure(spec, infos, png, case.name)]
    if case.figure is not None and family in ("history", "sweep"):
        png = output if output is not None else paths[0].with_suffix(".png")
        return [draw_figure(case.figure, infos, png, case.name)]

    if output is not None and len(paths) > 1:
        raise CablesimError(
            "-o names one output, but several files were given and no figure: section of the stored "
            "case applies to them; drop -o (each file's plots go beside it) or plot the files one at a time."
        )
    written: list[Path] = []
    for info in infos:
        written += _standard(info, output)
    return written


def _continuation_with_sweep(infos, output) -> Path:
    """One continuation file drawn with one sweep file's points on top (as ``continue --overlay``)."""
    conts = [i for i in infos if i.family == "continuation"]
    sweeps = [i for i in infos if i.family == "sweep"]
    if len(conts) != 1 or len(sweeps) != 1:
        raise CablesimError(
            f"A continuation file is drawn with at most one sweep file on top; got {len(conts)} continuation "
            f"and {len(sweeps)} sweep files. Plot one continuation file and the sweep of the same case."
        )
    png = Path(output) if output is not None else conts[0].path.with_suffix(".png")
    return plot_continuation(conts[0].path, png, overlay=sweeps[0].path)


def _backbone_over_responses(infos, output) -> Path:
    """One backbone file drawn over the frequency responses of continuation files."""
    bbs = [i for i in infos if i.family == "backbone"]
    if len(bbs) != 1:
        raise CablesimError(f"A backbone is drawn over continuation files one at a time; got {len(bbs)} backbone "
                            "files. Plot each backbone with the continuation files of its cable.")
    png = Path(output) if output is not None else bbs[0].path.with_suffix(".png")
    return plot_backbone(bbs[0].path, png, responses=[i.path for i in infos if i.family == "continuation"])


def _standard(info: ResultInfo, output: Path | None) -> list[Path]:
    """The plots the command that wrote the file draws."""
    case = parse_case(info.case_text, source=f"(the case stored in {info.path})", default_name=name_from_stem(info.path.stem))
    if info.family == "static":
        result = read_static_drawing(info.path, case)
        png = output if output is not None else info.path.with_suffix(".png")
        return [plot_cable(result, png, case.name), *([plot_modes(result, modes_png(png), case.name)]
                                                      if modes_drawable(result) else [])]
    if info.family == "continuation":
        png = output if output is not None else info.path.with_suffix(".png")
        out = [plot_continuation(info.path, png)]
        if has_loci(info.path):  # and its stability chart beside it
            out.append(plot_stability_chart(info.path, Path(png).with_name(Path(png).stem + "-chart.png")))
        return out
    if info.family == "backbone":
        return [plot_backbone(info.path, output if output is not None else info.path.with_suffix(".png"))]
    if info.family == "sweep":
        return [plot_sweep(info.path, output if output is not None else info.path.with_suffix(".png"))]
    hist = read_history(info.path)
    if hist.t.size < 2:
        raise CablesimError(f"The history in {info.path} holds a single instant; there is nothing to plot.")
    wanted = case.history.channels if info.command == "history" else case.free_vibration.channels
    stored = {f"z{d}" for d in hist.dof_numbers}
    channels = None
    if wanted:  # the case's plotted channels, among those the file kept
        channels = [c for c in wanted if normalise_channel(c) in stored] or None
    prefix = output.with_suffix("") if output is not None else info.path.with_suffix("")
    return plot_history(hist, prefix, case.name, channels=channels)




def _snapshots(infos: list[ResultInfo], output, count: int) -> list[Path]:
    """The snapshot figure of each time history."""
    if infos[0].family != "history":
        raise CablesimError(f"--snapshots draws time histories, but {infos[0].path} is {FAMILY_TEXT[infos[0].family]}.",
                            field="snapshots")
    if output is not None and len(infos) > 1:
        raise CablesimError("-o names one output, but --snapshots was given several files; drop -o "
                            "(each figure goes beside its file as <file>-snapshots.png).")
    written = []
    for info in infos:
        case = parse_case(info.case_text, source=f"(the case stored in {info.path})", default_name=name_from_stem(info.path.stem))
        png = Path(output) if output is not None else info.path.with_name(info.path.stem + "-snapshots.png")
        written.append(plot_snapshots(read_history(info.path), case.to_cable(), png, case.name, count))
    return written


class LabelledArrays:
    """``to_xarray()`` for a run: its file, as ``to_hdf5`` writes it, read back as an
    ``xarray.Dataset`` (:meth:`cablesim.io.results.ResultFile.to_xarray`; needs xarray); and
    ``figures()``, its standard figures as matplotlib ``Figure`` objects."""

    def to_xarray(self, group: str | None = None):
        """The run's results as an ``xarray.Dataset`` with named axes, coordinates and units:
        the same labels as ``cablesim.load_result(file).to_xarray(group)`` on its file."""
        with tempfile.TemporaryDirectory() as folder:
            ds = load_result(self.to_hdf5(Path(folder) / "run.h5")).to_xarray(group)
        ds.attrs.pop("result_file", None)  # a file that no longer exists
        return ds

    def figures(self) -> list:
        """The run's standard figures, those its command draws, as matplotlib ``Figure`` objects
        (in a notebook each shows itself; ``fig.savefig`` writes it in any format)."""
        with tempfile.TemporaryDirectory() as folder, kept_figures() as kept:
            redraw([self.to_hdf5(Path(folder) / "run.h5")])
        return kept
