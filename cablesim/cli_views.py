"""The command-line parts that show results: the mode shapes ``cablesim static`` draws,
``cablesim animate`` (the cable moving, as a GIF) and ``cablesim report`` (one HTML page of a run).

:func:`register` adds the commands to the application of :mod:`cablesim.cli`; like it, this
module imports its machinery only when a command runs, so that ``cablesim --help`` starts at once.
"""

from __future__ import annotations

from pathlib import Path


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


def register(app, user_errors) -> None:
    """Add ``cablesim animate`` and ``cablesim report`` to the application ``app``
    (``user_errors`` turns a :class:`~cablesim.errors.CablesimError` into a one-paragraph
    message and exit status 2)."""
