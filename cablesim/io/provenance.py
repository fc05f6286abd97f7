"""What a result file records about the run that wrote it, so that it can be reproduced.

Every HDF5 file cablesim writes carries, as root attributes, the command line and every
effective option (:func:`set_invocation`, called by the command line; a Python script leaves
them empty), the versions of Python, numpy, scipy, numba and h5py, the platform and, when
cablesim runs from a git checkout, the commit (with ``-dirty`` if the checkout has changes).
"""

from __future__ import annotations

import functools
import json
import platform
import subprocess
import sys
from enum import Enum
from importlib import metadata
from pathlib import Path

from ..version import __version__

_INVOCATION = {"command_line": "", "options": {}}


def set_invocation(command_line: str, options: dict) -> None:
    """Record the command line and the effective options of this run (for every file written)."""
    _INVOCATION["command_line"] = command_line
    _INVOCATION["options"] = dict(options)


def invocation() -> dict:
    """``{"command_line": str, "options": dict}`` of this run."""
    return dict(_INVOCATION)


def plain(value):
    """A parameter value as JSON-friendly data (enums by value, paths as text)."""
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


def command_words(ctx, drop=()) -> list[str]:
    """The command line that reproduces a click invocation ``ctx`` (long option names, defaults
    left out, ``drop`` parameters omitted)."""
    words = ["cablesim", ctx.info_name or ""]
    for p in ctx.command.params:
        value = ctx.params.get(p.name)
        if p.name in drop or value is None:
            continue
        if getattr(p, "param_type_name", "") == "argument":
            words += [str(plain(v)) for v in (value if isinstance(value, (list, tuple)) else [value])]
            continue
        if value == p.default or (isinstance(value, (list, tuple)) and not value):
            continue
        long = max(p.opts, key=len)
        if p.is_flag:
            if p.secondary_opts:
                words.append(long if value else max(p.secondary_opts, key=len))
            elif value:
                words.append(long)
        elif p.multiple:
            for v in value:
                words += [long, str(plain(v))]
        else:
            words += [long, str(plain(value))]
    return words


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "not installed"


@functools.lru_cache(maxsize=1)
def git_commit() -> str:
    """The commit of the git checkout cablesim runs from (``""`` if not a checkout)."""
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        return ""
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=5)
        if head.returncode != 0:
            return ""
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return ""
    return head.stdout.strip() + ("-dirty" if dirty.returncode == 0 and dirty.stdout.strip() else "")


@functools.lru_cache(maxsize=1)
def environment() -> dict:
    """Versions of cablesim and its numerical libraries, the platform and the git commit."""
    return {
        "cablesim_version": __version__,
        "python_version": sys.version.split()[0],
        "numpy_version": _version("numpy"),
        "scipy_version": _version("scipy"),
        "numba_version": _version("numba"),
        "h5py_version": _version("h5py"),
        "platform": platform.platform(),
        "git_commit": git_commit(),
    }


def record() -> dict:
    """Root attributes of a result file: the environment, the command line and the options (JSON)."""
    inv = invocation()
    return {**environment(), "command_line": inv["command_line"],
            "options": json.dumps(inv["options"], sort_keys=True, default=str)}
