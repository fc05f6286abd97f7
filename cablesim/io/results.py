"""Any cablesim result file read as one object: :func:`load_result`.

A :class:`ResultFile` holds every dataset of the file with its units and named axes (time x
DOF for a history, omega x channel for a sweep, ...), the group and root attributes (the
command line, the versions, every effective option), the stored case, and the object the file's
own reader builds (a :class:`~cablesim.dynamics.result.HistoryResult`, a
:class:`~cablesim.io.sweeps.StoredSweep`, the dicts of continuation and backbone files).
:meth:`ResultFile.to_xarray` gives one of its groups as an ``xarray.Dataset`` (xarray is an
optional extra: ``pip install 'cablesim[xarray]'``); :mod:`cablesim.io.export` writes tidy CSV
files from the same axes.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from ..case import parse_case
from ..errors import CablesimError
from .charts import read_backbone
from .continuation import read_continuation
from .hdf5 import attr_text, inspect_result, read_history
from .sweeps import read_sweep

#: The first axis of a group's datasets, by group (the first prefix that matches).
MAIN_AXES = (("history/events", "event"), ("history/segments", "segment"), ("history", "time"), ("sweep", "omega"),
             ("continuation/branches/", "point"), ("continuation/bifurcations", "bifurcation"),
             ("backbone/resonances", "resonance"), ("backbone", "point"), ("modal", "mode"))
#: Axes after the first, by dataset name.
TRAILING_AXES = {"z": ("dof",), "v": ("dof",), "zc": ("dof",), "ze": ("dof",), "T": ("segment",),
                 "amplitude": ("channel",), "halfrange": ("channel",), "response_frequency": ("channel",),
                 "peak_tension": ("segment",), "slack_fraction": ("segment",), "multipliers": ("multiplier",),
                 "multiplier_plane": ("multiplier",), "state": ("component",), "ratios": ("ratio",),
                 "whirl_area": ("node",), "max_w": ("node",), "whirl_sense": ("node",), "peak_time": ("segment",),
                 "slack_episodes": ("segment",), "least_tension": ("segment",),
                 "multipliers_before": ("multiplier",), "multipliers_after": ("multiplier",)}
#: Datasets whose axes are not the group's main axis, by dataset name.
OWN_AXES = {"y0": ("dof",), "T0": ("segment",), "dof": ("dof",), "shapes": ("dof", "mode"),
            "inextensible_omega": ("inextensible_mode",), "P": ("dof",), "x": ("dof",), "u": ("dof",),
            "y": ("dof",), "l": ("segment",), "B": ("segment", "dof"), "D": ("dof", "dof_j"), "f": ("dof", "dof_j"),
            "N": ("dof", "dof_j"), "K": ("dof", "dof_j"), "K_band": ("band", "dof"),
            "support_amplitude": ("moving_support", "component"), "slack_onset": ("slack_episode",),
            "slack_end": ("slack_episode",)}
#: Where an axis's coordinate values are stored (datasets of the file), and their units.
COORDINATES = {"time": ("history/t", "s"), "omega": ("sweep/omega", "rad/s"), "gamma": ("sweep/gamma", "1"),
               "dof": ("history/dof", "")}


@dataclass(frozen=True)
class StoredArray:
    """One dataset of a result file.

    Attributes
    ----------
    path : str
        Its place in the file, e.g. ``"history/z"``.
    values : ndarray
        The data (strings decoded).
    units : str
        Its ``units`` attribute (``""`` if it has none).
    description : str
        Its ``description`` attribute.
    axes : tuple of str
        A name for each axis (``("time", "dof")``); the same name means the same axis throughout
        the group.
    """

    path: str
    values: np.ndarray
    units: str
    description: str
    axes: tuple[str, ...]

    @property
    def name(self) -> str:
        """The dataset's name inside its group (``"z"``)."""
        return self.path.rsplit("/", 1)[-1]

    @property
    def group(self) -> str:
        """Its group (``"history"``; ``""`` at the root)."""
        return self.path.rsplit("/", 1)[0] if "/" in self.path else ""


@dataclass(frozen=True)
class ResultFile:
    """A cablesim result file, read: see :func:`load_result`.

    Attributes
    ----------
    path : Path
    command : str
        The command that wrote it (``static``, ``history``, ``free-vibration``, ``sweep``,
        ``continue``, ``backbone``).
    kind : str
        ``static``, ``history`` (also free vibrations), ``sweep``, ``continuation`` or ``backbone``.
    case_text : str
        The case as it ran (YAML): ``cablesim.load_case(result.case_text)`` rebuilds it.
    attributes : dict
        The root attributes: the command line, every effective option, versions, git commit.
    group_attributes : dict
        Each group's attributes (``"history"`` -> its settings, ``"sweep"`` -> ...).
    arrays : dict
        Every dataset, by its path in the file, as a :class:`StoredArray`.
    data : object
        What the file's own reader returns (:attr:`data`, read on first use).
    """

    path: Path
    command: str
    kind: str
    case_text: str
    attributes: dict
    group_attributes: dict
    arrays: dict

    def __repr__(self) -> str:
        line = attr_text(self.attributes.get("command_line", "")) or f"cablesim {self.command}"
        return (f"<ResultFile {str(self.path)!r}: {self.kind}, written by `{line}`; {len(self.arrays)} datasets in "
                f"{', '.join(self.groups)}>")

    @functools.cached_property
    def data(self):
        """What the file's own reader returns (read on first use): a ``HistoryResult`` (history,
        free vibration), a ``StoredSweep`` (sweep), the dicts of ``read_continuation`` and
        ``read_backbone``; None for a static file (its arrays are in :attr:`arrays`)."""
        readers = {"history": read_history, "sweep": read_sweep, "continuation": read_continuation,
                   "backbone": read_backbone}
        return readers[self.kind](self.path) if self.kind in readers else None

    def __getitem__(self, path: str) -> np.ndarray:
        """The values of the dataset at ``path`` (``result["history/z"]``)."""
        key = path.strip("/")
        if key not in self.arrays:
            raise KeyError(f"{self.path} has no dataset {key!r}; it has {', '.join(self.arrays)}")
        return self.arrays[key].values

    @property
    def case(self):
        """The stored case (:class:`~cablesim.case.Case`), as it ran."""
        return parse_case(self.case_text, source=f"the case stored in {self.path}")

    @property
    def groups(self) -> list[str]:
        """The groups that hold datasets, in file order (``["history", "history/events", ...]``)."""
        return list(dict.fromkeys(a.group for a in self.arrays.values()))

    @property
    def main_group(self) -> str:
        """The group :meth:`to_xarray` gives by default: ``history``, ``sweep``, ``backbone``, the
        first continuation branch, or the exact (else the first) model of a static file."""
        for name in ("history", "sweep", "backbone", "static/exact"):
            if name in self.groups:
                return name
        first = [g for g in self.groups if g.startswith(("continuation/branches/", "static/"))]
        return first[0] if first else self.groups[0]

    def coordinate(self, axis: str, group: str, size: int):
        """``(values, units)`` labelling ``size`` positions along ``axis`` in ``group``: stored
        values (times, frequencies, DOF numbers), a group's channel names, else positions counted
        from 1 (DOF, segments, modes) or 0."""
        path, units = COORDINATES.get(axis, ("", ""))
        if path in self.arrays and self.arrays[path].values.shape == (size,):
            return self.arrays[path].values, units
        if axis == "channel":
            names = self.group_attributes.get(group, {}).get("channels")
            top = self.group_attributes.get(group.split("/")[0], {}).get("channels")
            for value in (names, top):
                if value is not None and np.size(value) == size:
                    return np.array([attr_text(v) for v in np.ravel(value)]), ""
        first = 1 if axis in ("dof", "dof_j", "segment", "mode", "inextensible_mode", "channel", "node") else 0
        return np.arange(first, first + size), ""

    def to_xarray(self, group: str | None = None):
        """One group of the file as an ``xarray.Dataset``.

        Parameters
        ----------
        group : str, optional
            A group of :attr:`groups` (default :attr:`main_group`).

        Returns
        -------
        xarray.Dataset
            Every dataset of the group as a variable over its named axes, with coordinates
            (``time`` in s, ``omega`` in rad/s, ``dof``, ``channel``, ``segment``, ...), each
            variable's ``units`` and ``description`` as attributes, and the group's and the
            file's attributes (command line, versions) as the Dataset's.

        Raises
        ------
        CablesimError
            If xarray is not installed (the message says how to install it) or the group has no
            datasets.
        """
        try:
            import xarray
        except ImportError:
            raise CablesimError("to_xarray needs xarray, which is not installed: pip install 'cablesim[xarray]' "
                                "(or pip install xarray). The arrays are in result.arrays without it.") from None
        group = self.main_group if group is None else group.strip("/")
        members = [a for a in self.arrays.values() if a.group == group]
        if not members:
            raise CablesimError(f"{self.path} has no datasets in the group {group!r}; its groups: {', '.join(self.groups)}.")
        variables, coords = {}, {}
        for a in members:
            for axis, size in zip(a.axes, a.values.shape):
                if axis not in coords:
                    values, units = self.coordinate(axis, group, size)
                    coords[axis] = xarray.Variable(axis, values, {"units": units} if units else {})
            if a.axes == (a.name,) or (len(a.axes) == 1 and COORDINATES.get(a.axes[0], ("",))[0] == a.path):
                continue  # the axis's own coordinate (history/t, sweep/omega, sweep/gamma, history/dof)
            variables[a.name] = xarray.Variable(a.axes, a.values, {"units": a.units, "description": a.description})
        attrs = {k: _attribute(v) for k, v in {**self.attributes, **self.group_attributes.get(group, {})}.items()}
        attrs.update(result_file=str(self.path), group=group)
        return xarray.Dataset(variables, coords=coords, attrs=attrs)


def _attribute(value):
    """An HDF5 attribute as a value xarray keeps (str, number, or a list of them)."""
    if isinstance(value, (bytes, str)):
        return attr_text(value)
    arr = np.asarray(value)
    if arr.dtype.kind in "SO":
        return [attr_text(v) for v in arr.ravel()] if arr.ndim else attr_text(arr.item())
    return arr.item() if arr.ndim == 0 else arr


def axes_of(group: str, name: str, shape: tuple[int, ...]) -> tuple[str, ...]:
    """Names for the axes of the dataset ``group/name`` of this shape (see :data:`MAIN_AXES`)."""
    if name in OWN_AXES and len(OWN_AXES[name]) == len(shape) and group != "history/segments":
        return OWN_AXES[name]
    if (group, name) == ("sweep", "gamma"):
        return ("gamma",)
    main = next((axis for prefix, axis in MAIN_AXES if group.startswith(prefix)), None)
    rule = (main, *TRAILING_AXES.get(name, ())) if main else TRAILING_AXES.get(name, ())
    if group.startswith("sweep") and len(shape) == len(rule) + 1:
        rule = ("gamma", *rule)  # a sweep with gamma: a leading gamma axis
    if len(rule) != len(shape):
        rule = (*rule[:1], *(f"{name}_axis{k}" for k in range(1, len(shape)))) if rule and shape else ()
        rule = rule if len(rule) == len(shape) else tuple(f"{name}_axis{k}" for k in range(len(shape)))
    return rule


def _values(ds: h5py.Dataset) -> np.ndarray:
    arr = np.asarray(ds[()])
    if arr.dtype.kind in "SO":
        return np.array([attr_text(v) for v in arr.ravel()], dtype=str).reshape(arr.shape)
    return arr


def _consistent(arrays: dict) -> dict:
    """Rename an axis that has another length elsewhere in its group (``name_axisK``)."""
    sizes: dict = {}
    out = {}
    for path, a in arrays.items():
        axes = list(a.axes)
        for k, (axis, size) in enumerate(zip(a.axes, a.values.shape)):
            if sizes.setdefault((a.group, axis), size) != size:
                axes[k] = f"{a.name}_axis{k}"
        out[path] = StoredArray(a.path, a.values, a.units, a.description, tuple(axes))
    return out


def load_result(path: str | Path) -> ResultFile:
    """Read any cablesim result file (static, history, free vibration, sweep, continuation,
    backbone).

    Parameters
    ----------
    path : str or Path
        An HDF5 file a cablesim command wrote.

    Returns
    -------
    ResultFile
        Its datasets with units and named axes, its attributes, the stored case and the object
        the file's own reader builds (``data``); ``to_xarray()`` gives a group as an
        ``xarray.Dataset``.

    Raises
    ------
    CablesimError
        If the file is missing, not HDF5, not a cablesim result, or malformed.
    """
    info = inspect_result(path)
    arrays, groups = {}, {}
    try:
        with h5py.File(info.path, "r") as f:
            root = {k: v for k, v in f.attrs.items()}

            def visit(name, obj):
                group = name.rsplit("/", 1)[0] if "/" in name else ""
                if isinstance(obj, h5py.Group):
                    groups[name] = dict(obj.attrs.items())
                    return
                values = _values(obj)
                arrays[name] = StoredArray(name, values, attr_text(obj.attrs.get("units", "")),
                                           attr_text(obj.attrs.get("description", "")),
                                           axes_of(group, name.rsplit("/", 1)[-1], values.shape))

            f.visititems(visit)
    except (OSError, KeyError, ValueError, TypeError) as exc:
        raise CablesimError(f"The result file {info.path} cannot be read ({exc}); rerun the command that wrote it.") from None
    return ResultFile(info.path, info.command, info.family, info.case_text, root, groups, _consistent(arrays))


def attribute_units(attrs: dict) -> dict:
    """The units of a group's attributes (its JSON attribute ``units``), ``{}`` if none."""
    try:
        units = json.loads(attr_text(attrs["units"])) if "units" in attrs else {}
    except ValueError:
        return {}
    return units if isinstance(units, dict) else {}


def stored_command_line(path: str | Path) -> str:
    """The command line a result file records (root attribute ``command_line``; "" if none)."""
    with h5py.File(path, "r") as f:
        return attr_text(f.attrs.get("command_line", ""))
