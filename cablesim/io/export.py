"""Result files exported as tidy CSV files (``cablesim export RESULT.h5 --format csv``).

One CSV file per dataset, named by its place in the file (``/history/z`` -> ``history_z.csv``),
in tidy form: one row per value, a column per axis holding that axis's label (time in s, omega
in rad/s, the DOF, channel, segment or mode number; a position from 0 where nothing labels it)
and a column for the value, each header naming its units: ``time (s),dof,z (m)``. Complex values
take two columns (``multipliers real (1)``, ``multipliers imag (1)``). Numbers are written to
the 17 significant digits that read back to the same double. ``index.csv`` lists every
dataset (file, dataset, shape, units, description) and ``attributes.csv`` every attribute of
the file and its groups (the command line, the versions, the settings, with their units).
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import numpy as np

from ..errors import CablesimError
from .hdf5 import attr_text
from .results import COORDINATES, ResultFile, StoredArray, attribute_units

#: The file that marks a folder as a cablesim CSV export (it may be replaced).
INDEX = "index.csv"


def csv_name(array: StoredArray) -> str:
    """The CSV file a dataset goes to: its path with ``/`` as ``_`` (``history_z.csv``)."""
    return array.path.replace("/", "_") + ".csv"


def _heading(name: str, units: str) -> str:
    return f"{name} ({units})" if units else name


def _text(values: np.ndarray) -> list:
    """Cells: floats to the digits that read back exactly, the rest as they print."""
    if values.dtype.kind == "f":
        return [repr(float(v)) for v in values]
    if values.dtype.kind in "iub":
        return values.tolist()
    return [str(v) for v in values]


def _axis_columns(result: ResultFile, a: StoredArray) -> tuple[list[str], list]:
    """The headers and cells of the axis columns of a dataset, one row per value (C order)."""
    headers, columns = [], []
    grid = np.indices(a.values.shape).reshape(len(a.values.shape), -1)
    for k, (axis, size) in enumerate(zip(a.axes, a.values.shape)):
        labels, units = result.coordinate(axis, a.group, size)
        if a.values.ndim == 1 and COORDINATES.get(axis, ("",))[0] == a.path or a.axes == (a.name,):
            labels, units, axis = np.arange(size), "", "index"  # the axis's own coordinate
        headers.append(_heading(axis, units))
        columns.append(_text(np.asarray(labels)[grid[k]]))
    return headers, columns


def write_dataset_csv(result: ResultFile, a: StoredArray, path: Path) -> Path:
    """Write one dataset of ``result`` as a tidy CSV file at ``path``."""
    headers, columns = _axis_columns(result, a)
    flat = a.values.reshape(-1)
    if flat.dtype.kind == "c":
        headers += [_heading(f"{a.name} real", a.units), _heading(f"{a.name} imag", a.units)]
        columns += [_text(flat.real), _text(flat.imag)]
    else:
        headers.append(_heading(a.name, a.units))
        columns.append(_text(flat))
    with open(path, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh)
        out.writerow(headers)
        out.writerows(zip(*columns))
    return path


def _attribute_rows(result: ResultFile) -> list[list[str]]:
    rows = []
    for group, attrs in [("/", result.attributes), *result.group_attributes.items()]:
        units = attribute_units(attrs)
        for name, value in attrs.items():
            if name == "units":
                continue
            arr = np.asarray(value)
            if isinstance(value, (bytes, str)) or arr.ndim == 0:
                text = attr_text(value)
            else:
                text = json.dumps([attr_text(v) if arr.dtype.kind in "SOU" else v.item() for v in arr.ravel()])
            rows.append([group, name, text, units.get(name, "")])
    return rows


def check_export_folder(folder: Path) -> None:
    """Refuse a folder that exists but is not an earlier export (it would be replaced)."""
    if folder.exists() and not (folder.is_dir() and (folder / INDEX).is_file()):
        raise CablesimError(f"-o {folder} exists and is not a cablesim CSV export (no {INDEX} in it); give a new "
                            "folder with -o, or remove it.")


def default_export_folder(result: str | Path) -> Path:
    """Where a result file's CSV export goes by default: ``RESULT-csv`` beside it."""
    result = Path(result)
    return result.with_name(result.stem + "-csv")


def export_csv(result: ResultFile, folder: str | Path) -> list[Path]:
    """Write every dataset of a result file as a tidy CSV file into ``folder``.

    Parameters
    ----------
    result : ResultFile
        A result file read by :func:`~cablesim.io.results.load_result`.
    folder : str or Path
        Created (with its parents); an earlier export there is replaced as a whole, through
        ``folder.part`` renamed into place.

    Returns
    -------
    list of Path
        The CSV files written: one per dataset, then ``index.csv`` and ``attributes.csv``.

    Raises
    ------
    CablesimError
        If ``folder`` exists and is not an earlier export, or cannot be written.
    """
    folder = Path(folder)
    check_export_folder(folder)
    part = folder.with_name(folder.name + ".part")
    shutil.rmtree(part, ignore_errors=True)
    try:
        part.mkdir(parents=True)
        names = []
        for a in result.arrays.values():
            write_dataset_csv(result, a, part / csv_name(a))
            names.append(csv_name(a))
        with open(part / INDEX, "w", newline="", encoding="utf-8") as fh:
            out = csv.writer(fh)
            out.writerow(["file", "dataset", "shape", "axes", "units", "description"])
            for a in result.arrays.values():
                out.writerow([csv_name(a), "/" + a.path, "x".join(map(str, a.values.shape)), " x ".join(a.axes),
                              a.units, a.description])
        with open(part / "attributes.csv", "w", newline="", encoding="utf-8") as fh:
            out = csv.writer(fh)
            out.writerow(["group", "attribute", "value", "units"])
            out.writerows(_attribute_rows(result))
        if folder.exists():
            shutil.rmtree(folder)
        part.rename(folder)
    except OSError as exc:
        shutil.rmtree(part, ignore_errors=True)
        raise CablesimError(f"Cannot write the CSV files into {folder}: {exc.strerror or exc}. Give another folder "
                            "with -o.") from None
    return [folder / n for n in (*names, INDEX, "attributes.csv")]
