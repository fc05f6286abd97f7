"""The ``cablesim`` command line: a thin layer over the analyses and the writers.

Every problem a user can fix is reported as one paragraph on standard error with exit status
2 and no traceback; Ctrl-C exits with status 130 and keeps whatever was already written.
"""

from __future__ import annotations

import functools
import sys
import textwrap
from enum import Enum
from pathlib import Path
from typing import Optional

import typer

from . import __version__
from .errors import CablesimError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Nonlinear statics and dynamics of weightless sagging elasto-flexible cables. "
    "Each command reads a YAML case file (or, given none, the paper's example: see "
    "`cablesim example`) and writes HDF5 results and PNG plots under runs/<case name>/.",
)


class Analysis(str, Enum):
    exact = "exact"
    approximate = "approximate"


def _say_error(message: str) -> None:
    width = 100
    sys.stderr.write(textwrap.fill("error: " + message, width=width) + "\n")


def user_errors(func):
    """Turn CablesimError into a one-paragraph message and exit status 2."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except CablesimError as exc:
            _say_error(str(exc))
            raise typer.Exit(2)
        except KeyboardInterrupt:
            _say_error("interrupted; files already completed were kept.")
            raise typer.Exit(130)

    return wrapper


def _version(value: bool):
    if value:
        typer.echo(f"cablesim {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version."),
):
    pass


CASE_ARG = typer.Argument(None, help="YAML case file; omit it to run the paper's example.", show_default=False)


def _output(case, out: Optional[Path], stem: str) -> Path:
    return out if out is not None else Path("runs") / case.name / f"{stem}.h5"


@app.command()
@user_errors
def example():
    """Print the paper's example as a commented case file to start from."""
    from .case import example_text

    typer.echo(example_text(), nl=False)


@app.command()
@user_errors
def static(
    case_file: Optional[Path] = CASE_ARG,
    output: Optional[Path] = typer.Option(None, "-o", "--output", help="HDF5 file [default: runs/<name>/static.h5]"),
    analysis: Optional[Analysis] = typer.Option(None, "--analysis", help="Override the case file's analysis."),
    plot: bool = typer.Option(True, "--plot/--no-plot", help="Also draw the cable as a PNG beside the HDF5 file."),
):
    """Static equilibrium under F0 (inextensible, approximate and exact), modes and damping."""
    from .analyses.static import run_static
    from .case import load_case
    from .io_hdf5 import write_static
    from .report import static_summary

    case, text = load_case(case_file)
    result = run_static(case, analysis.value if analysis else None)
    typer.echo(static_summary(case, result))
    out = _output(case, output, "static")
    write_static(out, result, text)
    msg = f"\nWrote {out}"
    if plot:
        from .plotting import plot_cable

        png = plot_cable(result, out.with_suffix(".png"), case.name)
        msg += f" and {png}"
    typer.echo(msg)


def main():
    """Entry point of the ``cablesim`` console script."""
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
