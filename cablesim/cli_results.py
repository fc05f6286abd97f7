"""The command line's commands on stored results: ``cablesim export`` (tidy CSV files) and
``cablesim rerun`` (the stored case with the stored command).

:func:`register` adds them to the application of :mod:`cablesim.cli`; like it, this module
imports its machinery only when a command runs, so that ``cablesim --help`` starts at once.
"""

from __future__ import annotations

import shlex
from enum import Enum
from pathlib import Path
from typing import Optional

import typer

from .errors import CablesimError
from .io.terminal import quiet_outputs

#: The commands whose files ``cablesim rerun`` reruns.
RERUNNABLE = ("static", "history", "free-vibration", "sweep", "continue", "backbone")
#: Parameters of the stored command that a rerun sets itself: the case (the stored text), the
#: output, and a sweep's --resume (a rerun starts afresh).
RESET = {"case_file": None, "output": None, "resume": False}


def rerun_case_text(case_text: str) -> tuple[str, bool]:
    """The case file a rerun runs, from the stored case text, and whether the stored command's
    ``--set`` overrides are to be given again. A text with explicit lists (the shorthand
    expanded) has every override applied: it runs as it is, without them. Otherwise the text
    is the case file with the overrides the command applied (its --set and the flags that set
    case values, such as a sweep's --omega) recorded after it: they are left out, and the
    command, given its --set again, records them as they were."""
    from .case.files import EXPANDED_MARK, OVERRIDES_MARK

    if case_text.startswith(EXPANDED_MARK):
        return case_text, False
    kept = [line for line in case_text.splitlines(keepends=True) if not line.startswith(OVERRIDES_MARK)]
    return "".join(kept), True


class ExportFormat(str, Enum):
    csv = "csv"


def run_export(ctx, result_path: Path, fmt: ExportFormat, output: Optional[Path]) -> None:
    """``cablesim export`` (see :func:`register`)."""
    from .io.export import INDEX, check_export_folder, default_export_folder, export_csv
    from .io.results import load_result

    echo, note = quiet_outputs(bool(ctx.find_root().params.get("quiet")))
    result = load_result(result_path)
    folder = output if output is not None else default_export_folder(result.path)
    check_export_folder(folder)
    if (folder / INDEX).is_file():
        note(f"replacing the CSV export in {folder}")
    files = export_csv(result, folder)
    echo(f"Wrote {len(files) - 2} CSV files, one per dataset of {result.path} ({result.kind}), into {folder}; "
         f"{INDEX} lists them with their units, attributes.csv holds the file's attributes.")


def rerun_words(ctx, info, case_path: Path, out: Path, keep_sets: bool) -> list[str]:
    """The command line that reruns the stored one of ``info``
    (:class:`~cablesim.io.hdf5.ResultInfo`) on the case file ``case_path``, writing ``out``
    (with the stored ``--set`` overrides if ``keep_sets``)."""
    from .io.provenance import command_words
    from .io.results import stored_command_line

    line = stored_command_line(info.path)
    words = shlex.split(line)
    if len(words) < 2 or words[0] != "cablesim" or words[1] != info.command:
        raise CablesimError(f"{info.path} records no command line of 'cablesim {info.command}' (it has {line!r}), so "
                            "it cannot be rerun; run the command on its case instead (cablesim plot and the case_yaml "
                            "attribute hold what it ran).")
    group = ctx.find_root().command
    command = group.get_command(ctx, info.command)
    try:
        stored = command.make_context(info.command, words[2:], parent=ctx.find_root(), resilient_parsing=True)
    except Exception as exc:  # click's UsageError and the like: the line is not this version's
        raise CablesimError(f"The command line stored in {info.path} ({line}) is not one this cablesim reads "
                            f"({exc}); rerun it by hand on its case.") from None
    stored.params.update({k: v for k, v in RESET.items() if k in stored.params})
    if not keep_sets and "overrides" in stored.params:
        stored.params["overrides"] = []
    stored.params.update(case_file=case_path, output=out)
    return command_words(stored)[1:]


def run_rerun(ctx, result_path: Path, output: Optional[Path]) -> None:
    """``cablesim rerun`` (see :func:`register`)."""
    from .io.hdf5 import inspect_result
    from .io.naming import rerun_output
    from .io.paths import check_output

    root = ctx.find_root()
    echo, note = quiet_outputs(bool(root.params.get("quiet")))
    info = inspect_result(result_path)
    if info.command not in RERUNNABLE:
        raise CablesimError(f"{info.path} was written by 'cablesim {info.command}', which cablesim rerun does not "
                            f"rerun; it reruns the files of {', '.join(RERUNNABLE)}.")
    out = output if output is not None else rerun_output(info.path)
    if out.resolve() == info.path.resolve():
        raise CablesimError(f"-o {out} is the result being rerun; a rerun never replaces it: give another file with "
                            "-o, or leave -o out (the rerun then goes beside it, as NAME-rerun.h5).")
    check_output(out, inputs=[info.path])
    case_path = out.with_suffix(".case.yaml")
    text, keep_sets = rerun_case_text(info.case_text)
    if case_path.exists() and case_path.read_text() != text:
        raise CablesimError(f"{case_path}, where the rerun keeps its case, exists with another case; give another "
                            "file with -o, or remove it.")
    words = rerun_words(ctx, info, case_path, out, keep_sets)
    case_path.parent.mkdir(parents=True, exist_ok=True)
    case_path.write_text(text)
    flags = [f"--{k}" for k in ("quiet", "verbose") if root.params.get(k)]
    note(f"rerunning {info.path} with its stored case ({case_path}): {shlex.join(['cablesim', *words])}")
    code = root.command.main(args=[*flags, *words], prog_name="cablesim", standalone_mode=False)
    if code:
        raise typer.Exit(code)
    echo(f"Rerun of {info.path}: {out}")


def register(app, user_errors) -> None:
    """Add ``cablesim export`` and ``cablesim rerun`` to the application ``app`` (``user_errors``
    turns a :class:`~cablesim.errors.CablesimError` into a one-paragraph message and exit status 2)."""

    @app.command()
    @user_errors
    def export(
        ctx: typer.Context,
        result: Path = typer.Argument(..., metavar="RESULT.h5", show_default=False,
                                      help="HDF5 result file of any cablesim command."),
        fmt: ExportFormat = typer.Option(ExportFormat.csv, "--format", help="Export format."),
        output: Optional[Path] = typer.Option(None, "-o", "--output", metavar="FOLDER",
                                              help="Folder for the files (default: RESULT-csv beside the file; an "
                                              "earlier export there is replaced)."),
    ):
        """Export a result file as tidy CSV files: one per dataset (one row per value, a column per
        axis, units in the header), with index.csv (the datasets, their units and descriptions)
        and attributes.csv (command line, versions, settings)."""
        run_export(ctx, result, fmt, output)

    @app.command()
    @user_errors
    def rerun(
        ctx: typer.Context,
        result: Path = typer.Argument(..., metavar="RESULT.h5", show_default=False,
                                      help="HDF5 result file of static, history, free-vibration, sweep, continue "
                                      "or backbone."),
        output: Optional[Path] = typer.Option(None, "-o", "--output",
                                              help="HDF5 file for the rerun (default: RESULT-rerun.h5 beside it, "
                                              "never over a file); the case it ran goes beside it as .case.yaml."),
    ):
        """Rerun a result file's stored case with its stored command and options (the file holds
        both), writing a new file beside it (never over it) unless -o is given."""
        run_rerun(ctx, result, output)
