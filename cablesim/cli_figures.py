"""The figure options of every command that draws: ``--format png|pdf|svg``, ``--width`` (in)
and ``--dpi``.

:func:`register` adds them to the commands of :mod:`cablesim.cli` that draw figures (``static``,
``history``, ``free-vibration``, ``sweep``, ``continue``, ``backbone``, ``plot``): each runs
inside :func:`cablesim.plots.style.figure_output`, so that every figure it draws is that wide
(the text keeps its sizes) and saved in that format, beside its result with the format's suffix.
``cablesim plot -o FIG.pdf`` takes the format from the suffix. Like :mod:`cablesim.cli`, this
module imports its machinery only when a command runs.
"""

from __future__ import annotations

import functools
import inspect
import math
from enum import Enum
from pathlib import Path
from typing import Optional

import typer

from .errors import CablesimError

#: The commands that draw figures.
DRAWING_COMMANDS = ("static", "history", "free-vibration", "sweep", "continue", "backbone", "plot")


class FigureFormat(str, Enum):
    png = "png"
    pdf = "pdf"
    svg = "svg"


FORMAT_OPT = typer.Option(None, "--format", help="Figure format: png, pdf or svg (vector, fonts embedded in PDF); "
                          "default: the suffix of -o for cablesim plot, else png.", show_default=False)
WIDTH_OPT = typer.Option(None, "--width", metavar="INCHES", help="Figure width in inches, e.g. 3.5 for one journal "
                         "column (default 7, two columns; from 3 to 14); the text keeps its sizes.", show_default=False)
DPI_OPT = typer.Option(None, "--dpi", help="Resolution of PNG figures, dots per inch (default 200; from 50 to 1200).",
                       show_default=False)


def check_figure_options(fmt: Optional[FigureFormat], width: Optional[float], dpi: Optional[int],
                         output: Optional[Path] = None) -> Optional[str]:
    """The figure format to use (None: each output's suffix, else PNG), or a
    :class:`~cablesim.errors.CablesimError` naming the option out of range or the clash of
    ``--format`` with the suffix of ``output``."""
    from .plots.style import DPI_RANGE, FIGURE_FORMATS, WIDTH_RANGE

    if width is not None and not (math.isfinite(width) and WIDTH_RANGE[0] <= width <= WIDTH_RANGE[1]):
        raise CablesimError(f"--width {width:g}: give the figure width in inches, from {WIDTH_RANGE[0]:g} to "
                            f"{WIDTH_RANGE[1]:g} (e.g. --width 3.5 for one journal column, 7 for two).")
    if dpi is not None and not DPI_RANGE[0] <= dpi <= DPI_RANGE[1]:
        raise CablesimError(f"--dpi {dpi}: give the resolution of PNG figures in dots per inch, from {DPI_RANGE[0]} "
                            f"to {DPI_RANGE[1]} (e.g. --dpi 300).")
    suffix = output.suffix.lower().lstrip(".") if output is not None else ""
    if fmt is not None and suffix in FIGURE_FORMATS and suffix != fmt.value:
        raise CablesimError(f"--format {fmt.value} and -o {output} name different formats; give one of them "
                            f"(-o {output.with_suffix('.' + fmt.value)}, or leave --format out).")
    return fmt.value if fmt is not None else None


def with_figure_options(command, user_errors):
    """The command ``command`` (as registered: wrapped by ``user_errors``) with ``--format``,
    ``--width`` and ``--dpi`` added, run inside :func:`~cablesim.plots.style.figure_output`; a
    bad value is refused as any bad input is (``user_errors``: one paragraph, exit status 2)."""
    raw = inspect.unwrap(command)
    signature = inspect.signature(raw)
    added = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=kind)
             for name, default, kind in (("figure_format", FORMAT_OPT, Optional[FigureFormat]),
                                         ("figure_width", WIDTH_OPT, Optional[float]),
                                         ("figure_dpi", DPI_OPT, Optional[int]))]

    @functools.wraps(raw)
    def drawing(*args, figure_format=None, figure_width=None, figure_dpi=None, **kwargs):
        from .plots.style import figure_output

        fmt = check_figure_options(figure_format, figure_width, figure_dpi, kwargs.get("output"))
        with figure_output(fmt, figure_width, figure_dpi):
            return raw(*args, **kwargs)

    drawing.__signature__ = signature.replace(parameters=[*signature.parameters.values(), *added])
    return user_errors(drawing)


def register(app, user_errors) -> None:
    """Add ``--format``, ``--width`` and ``--dpi`` to every command of ``app`` that draws
    (:data:`DRAWING_COMMANDS`); ``user_errors`` turns a bad value into the one-paragraph message
    and exit status 2 of every command."""
    for info in app.registered_commands:
        name = info.name or info.callback.__name__.replace("_", "-")
        if name in DRAWING_COMMANDS:
            info.callback = with_figure_options(info.callback, user_errors)
