"""The sweep journal: every finished point on disk at once, and the HDF5 file kept current.

Every completed point is appended to a journal (``OUT.h5.journal``, one JSON record per line,
flushed to disk), and the HDF5 file is rewritten atomically from the results every few seconds
and at the end. A killed run therefore loses no completed point and never leaves a corrupt
file; resuming reads the journal and computes only what is missing. The journal is removed
when the sweep completes.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path

from ..errors import CablesimError
from .sweeps import write_sweep


def fingerprint(case_text: str, analysis, integrator) -> str:
    """What makes two sweeps the same: the case text and the analysis and integrator flags."""
    h = hashlib.sha256()
    for part in (case_text, str(analysis), str(integrator)):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


def read_journal(path: Path, fingerprint: str) -> list[dict]:
    """The records of a journal, after checking that it belongs to this sweep; a torn last
    record (a kill mid-write) is cut off the file."""
    records = []
    with open(path) as f:
        lines = f.read().split("\n")
    if not lines or not lines[0].strip():
        return records
    head = json.loads(lines[0])
    if head.get("fingerprint") != fingerprint:
        raise CablesimError(
            f"The journal {path} belongs to a different case or different settings, so --resume "
            "cannot continue it. Run without --resume to start afresh (the journal is replaced), "
            "or give another output file with -o.",
            field="sweep",
        )
    good = len(lines[0]) + 1
    for line in lines[1:]:
        if not line.strip():
            good += len(line) + 1
            continue
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            break  # a record torn by a kill: everything before it is intact
        good += len(line) + 1
    # Cut a torn tail off, so that new records start on a line of their own.
    with open(path, "r+b") as f:
        f.truncate(min(good, os.path.getsize(path)))
    return records


class _Journal:
    """An append-only file of JSON records, each flushed to disk as it is written."""

    def __init__(self, path: Path, fingerprint: str, fresh: bool):
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        if fresh:
            with open(path, "w") as f:
                f.write(json.dumps({"fingerprint": fingerprint}) + "\n")
                f.flush()
                os.fsync(f.fileno())
        self.f = open(path, "a")

    def append(self, rec: dict) -> None:
        self.f.write(json.dumps(rec) + "\n")
        self.f.flush()
        os.fsync(self.f.fileno())

    def close(self, remove: bool) -> None:
        self.f.close()
        if remove:
            self.path.unlink(missing_ok=True)


class SweepFile:
    """A sweep's HDF5 file and journal: the recorder :func:`cablesim.analyses.sweep.run_sweep`
    reports to.

    Parameters
    ----------
    out : Path
        The HDF5 file; the journal is ``out`` + ``.journal``.
    fingerprint : str
        From :func:`fingerprint`; a journal of other settings is refused on resume.
    resume : bool
        Continue from the journal of an interrupted run.
    snapshot_every : float
        Seconds between atomic rewrites of the HDF5 file.
    """

    def __init__(self, out: Path, fingerprint: str, resume: bool = False, snapshot_every: float = 3.0):
        self.out = Path(out)
        self.journal_path = self.out.with_name(self.out.name + ".journal")
        self.fingerprint = fingerprint
        self.resume = resume
        self.snapshot_every = snapshot_every
        self._journal = None
        self._last = time.monotonic()

    def previous(self) -> list[dict]:
        """Records of the interrupted run (empty unless resuming)."""
        if not self.resume:
            return []
        if not self.journal_path.exists():
            if self.out.exists():
                raise CablesimError(f"{self.out} is already complete (no journal to resume); nothing to do.")
            raise CablesimError(f"There is no interrupted sweep to resume at {self.out} (no {self.journal_path.name}).")
        return read_journal(self.journal_path, self.fingerprint)

    def begin(self) -> None:
        """Open the journal (a fresh one unless resuming)."""
        self._journal = _Journal(self.journal_path, self.fingerprint, fresh=not self.resume)
        self._last = time.monotonic()

    def point(self, record: dict, result) -> None:
        """Journal one point; rewrite the HDF5 file if the last snapshot is old enough."""
        self._journal.append(record)
        if time.monotonic() - self._last >= self.snapshot_every:
            write_sweep(self.out, result)
            self._last = time.monotonic()

    def end(self, result, complete: bool) -> None:
        """Write the HDF5 file; remove the journal if the sweep is complete."""
        write_sweep(self.out, result)
        if self._journal is not None:
            self._journal.close(remove=complete)
