"""Output paths: checked before any computation, written atomically, never destroying a result.

- :func:`check_output` refuses, before anything is computed, an output that could not be
  written or would destroy something: a folder, a device, one of the run's inputs, a name with
  the wrong suffix, a place inside a file, a folder that cannot be written, a disk without room.
- :func:`part_path` names the temporary file a writer fills before renaming it into place
  (``NAME.part``); :func:`remove_stale_parts` deletes the one a killed writer left, on the next
  start (two runs never write the same output at once: sweeps hold :class:`OutputLock`).
- :func:`beside` names where an incomplete run writes when a complete result already has its
  name (``history-w2.4.partial.h5``): an interrupted run never replaces a complete one.
- :class:`OutputLock` keeps two sweeps from writing the same file: the second is refused with
  a message naming the first.

None of this imports h5py: the command line checks its outputs before loading anything heavy.
"""

from __future__ import annotations

import errno
import functools
import json
import os
import shutil
import socket
import stat
import tempfile
import time
from pathlib import Path

from ..errors import CablesimError

#: Suffixes of result files.
HDF5_SUFFIXES = (".h5", ".hdf5")


def _fail(flag: str, path: Path, why: str, fix: str, owner: Path | None = None) -> CablesimError:
    if owner is None:
        return CablesimError(f"{flag} {path}: {why}. {fix}", field="output")
    return CablesimError(f"{flag} {owner}: the file {path} written beside it {why}. Move {path} away, or give "
                         f"another {flag}.", field="output")


def _existing_ancestor(folder: Path) -> Path:
    p = folder if str(folder) else Path(".")
    while not os.path.lexists(p):
        if p.parent == p:
            break
        p = p.parent
    return p


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _check_target(path: Path, flag: str, inputs, owner: Path | None = None) -> None:
    """One file to be written: not a folder, device or input; its folder writable."""
    fail = functools.partial(_fail, owner=owner)
    if os.path.lexists(path):
        try:
            st = os.stat(path)
        except OSError as exc:
            raise fail(flag, path, f"cannot be examined ({exc.strerror})", "Give another file name.") from None
        if stat.S_ISDIR(st.st_mode):
            raise fail(flag, path, "is a folder", f"Give a file name, for example {path / ('result' + path.suffix)}.")
        if not stat.S_ISREG(st.st_mode):
            raise fail(flag, path, "is a device or special file, not a regular file, and would be replaced",
                        "Give the name of an ordinary file.")
        for inp in inputs:
            if inp is not None and _same_file(path, Path(inp)):
                raise fail(flag, path, f"is this run's input {inp}, which writing the results would destroy",
                            "Give another output name.")
    folder = path.parent
    base = _existing_ancestor(folder)
    if not base.is_dir():
        raise fail(flag, path, f"{base} is a file, so no folder can be made inside it",
                    "Give an output path in a folder.")
    try:
        readonly = bool(os.statvfs(base).f_flag & os.ST_RDONLY)
    except OSError:
        readonly = False
    if readonly or not os.access(base, os.W_OK | os.X_OK) or not _probe(base):
        raise fail(flag, path, f"the folder {base} cannot be written"
                    + (" (a read-only file system)" if readonly else " (no permission)"),
                    f"Give {flag} in a folder you can write to.")


def _probe(folder: Path) -> bool:
    """Whether a file can really be created in ``folder`` (permissions can say yes and be wrong)."""
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".cablesim-probe-"):
            return True
    except OSError:
        return False


def check_output(path, *, inputs=(), flag: str = "-o", suffixes=HDF5_SUFFIXES, companions=(),
                 need_bytes: float = 0.0) -> Path:
    """Refuse an output (and the files written beside it) that cannot or must not be written.

    Parameters
    ----------
    path : str or Path
        The output file.
    inputs : iterable of paths
        The run's inputs (case file, result files read); the output must be none of them.
    flag : str
        How messages name the option (``"-o"``, ``"--md"``).
    suffixes : tuple of str
        Allowed suffixes (lower case).
    companions : iterable of paths, or a function of ``path`` giving them
        Other files the run writes beside it (PNGs), checked the same way.
    need_bytes : float
        Estimated size of what is written; refused if the disk has less room.

    Returns
    -------
    Path

    Raises
    ------
    CablesimError
        Naming the path, why, and what to give instead.
    """
    path = Path(path)
    inputs = [Path(i) for i in inputs if i is not None]
    if not path.name or path.name in (".", ".."):
        raise _fail(flag, path, "names a folder, not a file", f"Give a file name, for example {flag} result{suffixes[0]}.")
    if path.suffix.lower() not in suffixes:
        named = [x for x in suffixes if x]
        what = ("an HDF5 result" if suffixes == HDF5_SUFFIXES else f"a {named[0]} file" if len(named) == 1
                else "a figure")
        extra = " (the plots are written beside it as PNG files)" if suffixes == HDF5_SUFFIXES else ""
        ends = (", ".join(named[:-1]) + " or " if len(named) > 1 else "") + named[-1]
        ends += " (or have no suffix: a prefix for several files)" if "" in suffixes else ""
        other = f"; {path.suffix} files are not written" if path.suffix else ""
        raise _fail(flag, path, f"this option names {what}{extra}, so its name must end in {ends}{other}",
                    f"Give, for example, {flag} {path.with_suffix(suffixes[0])}.")
    if callable(companions):
        companions = companions(path)
    for p in (path, *map(Path, companions)):
        _check_target(p, flag, inputs, owner=None if p == path else path)
        remove_stale_parts(p)
    check_room(path, need_bytes, flag)
    return path


def check_room(path, need_bytes: float, flag: str = "-o") -> None:
    """Refuse if the disk holding ``path`` has less free space than ``need_bytes``."""
    if not need_bytes > 0:
        return
    path = Path(path)
    base = _existing_ancestor(path.parent)
    try:
        free = shutil.disk_usage(base).free
    except OSError:
        return
    if need_bytes > free:
        raise _fail(flag, path, f"the results need about {need_bytes / 1e6:.3g} MB but {base} has "
                    f"{free / 1e6:.3g} MB free", "Free some space, or give -o on another disk.")


def part_path(path: Path) -> Path:
    """The temporary name a writer fills before renaming it to ``path``."""
    return path.with_name(f"{path.name}.part")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_parts(path: Path) -> None:
    """Delete the temporary of ``path`` that a killed writer left behind."""
    tmp = part_path(Path(path))
    try:
        if tmp.is_file():
            tmp.unlink()
    except OSError:
        pass


def beside(path: Path) -> Path:
    """Where an incomplete run writes when a complete result already holds ``path``."""
    path = Path(path)
    return path.with_name(f"{path.stem}.partial{path.suffix}")


def discard(path: Path) -> None:
    """Remove a temporary file if it is there; a file system that refuses (read-only) leaves it."""
    try:
        Path(path).unlink(missing_ok=True)
    except OSError:
        pass


def write_error(path: Path, exc: Exception) -> CablesimError:
    """A message for a write that failed (disk full, permissions changed during the run): an
    OSError, or the RuntimeError the HDF5 library raises when it cannot flush or extend a file."""
    if isinstance(exc, OSError):
        why = os.strerror(exc.errno) if exc.errno else (exc.strerror or str(exc))
        full = exc.errno == errno.ENOSPC
    else:
        lines = str(exc).strip().splitlines()
        full = _low_on_room(path)
        why = ("the disk is full (the HDF5 library could not flush the file)" if full else
               f"the HDF5 library could not complete the file ({lines[0] if lines else type(exc).__name__})")
    fix = "Free some space, or give -o on another disk" if full else "Give -o somewhere writable"
    return CablesimError(f"Could not write {path}: {why}. Nothing was written under that name. {fix}.", field="output")


def _low_on_room(path: Path, margin: float = 1e6) -> bool:
    """Whether the disk holding ``path`` has less than ``margin`` bytes free."""
    try:
        return shutil.disk_usage(_existing_ancestor(Path(path).parent)).free < margin
    except OSError:
        return False


class OutputLock:
    """An exclusive claim on an output file (``OUT.lock``) for the length of a run.

    The lock file records the owner's process id, host, start time and command line; a lock
    whose owner is no longer running on this host is taken over.
    """

    def __init__(self, out: Path, command: str = ""):
        self.out = Path(out)
        self.path = self.out.with_name(self.out.name + ".lock")
        self.command = command
        self.held = False

    def owner(self) -> dict | None:
        """The live owner's record, or None if the file is free (or its lock is stale)."""
        try:
            rec = json.loads(self.path.read_text())
            pid, host = int(rec["pid"]), str(rec["host"])
        except (OSError, ValueError, KeyError, TypeError):
            return None
        if host == socket.gethostname() and not _alive(pid):
            return None
        if host == socket.gethostname() and pid == os.getpid() and not self.held:
            return None
        return rec

    def refuse_if_taken(self) -> None:
        """Raise if another live run holds the lock."""
        rec = self.owner()
        if rec is not None and not self.held:
            started = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(float(rec.get("time", 0))))
            cmd = rec.get("command") or "cablesim"
            raise CablesimError(
                f"{self.out} is being written by another run (process {rec['pid']} on {rec['host']}, started "
                f"{started}: {cmd}). Wait for it to finish, or give another -o; if that process is gone, "
                f"delete {self.path}.",
                field="output",
            )

    def acquire(self) -> None:
        """Take the lock (refusing if another live run holds it)."""
        self.refuse_if_taken()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        rec = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "time": time.time(),
                          "command": self.command})
        for _ in range(2):
            try:
                fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                self.refuse_if_taken()  # stale: remove and retry once
                self.path.unlink(missing_ok=True)
                continue
            with os.fdopen(fd, "w") as f:
                f.write(rec)
            self.held = True
            return
        self.refuse_if_taken()

    def release(self) -> None:
        if self.held:
            self.path.unlink(missing_ok=True)
            self.held = False
