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

import h5py

from ..errors import CablesimError
from .hdf5 import attr_text, is_complete_result
from .paths import OutputLock, beside
from .sweeps import write_sweep


def fingerprint(case_text: str, analysis, integrator) -> str:
    """What makes two sweeps the same: the case text and the analysis and integrator flags."""
    h = hashlib.sha256()
    for part in (case_text, str(analysis), str(integrator)):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


def damaged(path: Path, what: str, run: str = "sweep") -> CablesimError:
    """The refusal of a journal that cannot be trusted (``run``: what it journals)."""
    return CablesimError(
        f"The journal {path} is damaged ({what}), so --resume cannot trust it. Run the same command "
        f"without --resume to start the {run} afresh (the journal is replaced), or give another -o.",
        field=run,
    )


def read_journal(path: Path, fingerprint: str, run: str = "sweep") -> tuple[list[dict], list[str]]:
    """The records of a journal after checking that it belongs to this ``run`` (a sweep, a
    continuation), and warnings.

    A record that cannot be read or belongs to other settings is skipped with a warning (its
    point is computed again); a torn last record (a kill mid-write) is cut off the file. A
    journal whose first line does not name this run's settings is refused.
    """
    try:
        with open(path, "rb") as f:
            raw = f.read()
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise damaged(path, "it is not text", run) from None
    except OSError as exc:
        raise damaged(path, f"it cannot be read: {exc.strerror}", run) from None
    lines = text.split("\n")
    if not lines[0].strip():
        raise damaged(path, f"its first line, which names the {run}'s settings, is empty", run)
    try:
        head = json.loads(lines[0])
    except json.JSONDecodeError:
        raise damaged(path, "its first line is not a JSON record", run) from None
    if not isinstance(head, dict) or not isinstance(head.get("fingerprint"), str):
        raise damaged(path, f"its first line does not name the {run}'s settings", run)
    if head["fingerprint"] != fingerprint:
        raise CablesimError(
            f"The journal {path} belongs to a different case or different settings, so --resume "
            "cannot continue it. Run without --resume to start afresh (the journal is replaced), "
            "or give another output file with -o.",
            field=run,
        )
    records, warnings = [], []
    good = len(lines[0].encode()) + 1
    last = max((i for i, line in enumerate(lines) if line.strip()), default=0)
    for number, line in enumerate(lines[1:], start=2):
        if line.strip():
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                if number - 1 == last:
                    break  # a record torn by a kill: everything before it is intact
                warnings.append(f"journal line {number} is not a JSON record; its point is computed again")
                rec = None
            if rec is not None:
                if not isinstance(rec, dict) or rec.get("fingerprint") != fingerprint:
                    warnings.append(f"journal line {number} does not carry this {run}'s fingerprint (another "
                                    "run's or damaged); its point is computed again")
                else:
                    rec = dict(rec, line=number)
                    records.append(rec)
        good += len(line.encode()) + 1
    # Cut a torn tail off, so that new records start on a line of their own.
    with open(path, "r+b") as f:
        f.truncate(min(good, len(raw)))
    return records, warnings


#: Seconds between two syncs of a journal to the disk. Every record is flushed to the operating
#: system as it is written, which a killed process cannot lose; the sync (against a crash of
#: the machine itself) costs milliseconds, so it is made at most this often, and at the end.
SYNC_SECONDS = 1.0


class Journal:
    """An append-only file of JSON records, each flushed as it is written (:data:`SYNC_SECONDS`)."""

    def __init__(self, path: Path, fingerprint: str, fresh: bool):
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        if fresh:
            with open(path, "w") as f:
                f.write(json.dumps({"fingerprint": fingerprint}) + "\n")
                f.flush()
                os.fsync(f.fileno())
        self.f = open(path, "a")
        self._synced = time.monotonic()

    def append(self, rec: dict) -> None:
        self.f.write(json.dumps(rec) + "\n")
        self.f.flush()
        if time.monotonic() - self._synced >= SYNC_SECONDS:
            os.fsync(self.f.fileno())
            self._synced = time.monotonic()

    def close(self, remove: bool) -> None:
        if not remove and not self.f.closed:
            self.f.flush()
            os.fsync(self.f.fileno())
        self.f.close()
        if remove:
            self.path.unlink(missing_ok=True)


class JournalledFile:
    """An HDF5 result file kept with its journal and lock while a run writes it (the sweep's
    :class:`SweepFile`, the continuation's
    :class:`~cablesim.io.continuation_journal.ContinuationFile`): the journal is ``out`` +
    ``.journal``, the lock ``out`` + ``.lock``, the snapshots go to :func:`snapshot_path`.

    Parameters
    ----------
    out : Path
        The HDF5 file.
    fingerprint : str
        From :func:`fingerprint`; stored with every record and in the HDF5 file, and checked on
        resume.
    resume : bool
        Go on from the journal of an interrupted run.
    snapshot_every : float
        Seconds between atomic rewrites of the HDF5 file.
    command : str
        The command line, recorded in the lock so that a second writer is told who holds it.

    While the run goes on, it holds ``out.lock`` (a second run writing the same file is
    refused). If ``out`` already holds a complete result, the snapshots go beside it
    (:func:`cablesim.io.paths.beside`) and replace it only once the run is complete.
    """

    #: The kind of run whose journals this reads (:func:`read_journal`).
    run = "sweep"

    def __init__(self, out: Path, fingerprint: str, resume: bool = False, snapshot_every: float = 3.0,
                 command: str = ""):
        self.out = Path(out)
        self.journal_path = self.out.with_name(self.out.name + ".journal")
        self.fingerprint = fingerprint
        self.resume = resume
        self.snapshot_every = snapshot_every
        self.lock = OutputLock(self.out, command)
        self.snapshot = snapshot_path(self.out)
        self.warnings: list[str] = []
        self._journal = None
        self._last = time.monotonic()
        self.lock.refuse_if_taken()

    def nothing_to_resume(self) -> CablesimError:
        """Why ``--resume`` found no journal at :attr:`out`."""
        raise NotImplementedError

    def previous(self) -> list[dict]:
        """Records of the interrupted run (empty unless resuming)."""
        if not self.resume:
            return []
        if not self.journal_path.exists():
            raise self.nothing_to_resume()
        records, warnings = read_journal(self.journal_path, self.fingerprint, run=self.run)
        self.warnings += warnings
        return records

    def begin(self) -> None:
        """Take the lock and open the journal (a fresh one unless resuming)."""
        self.lock.acquire()
        self._journal = Journal(self.journal_path, self.fingerprint, fresh=not self.resume)
        self._last = time.monotonic()


class SweepFile(JournalledFile):
    """A sweep's HDF5 file and journal (:class:`JournalledFile`): the recorder
    :func:`cablesim.analyses.sweep.run_sweep` reports to."""

    def nothing_to_resume(self) -> CablesimError:
        if self.out.exists():
            return CablesimError(f"{self.out} is already complete (no journal to resume); nothing to do.")
        return CablesimError(
            f"There is no interrupted sweep to resume at {self.out} (no {self.journal_path.name}); "
            "run the command without --resume."
        )

    def point(self, point, result) -> None:
        """Journal one point (a :class:`~cablesim.analyses.sweep_points.SweepPoint`, in its JSON
        form); rewrite the HDF5 file if the last snapshot is old enough."""
        self._journal.append(dict(point.to_json(), fingerprint=self.fingerprint))
        if time.monotonic() - self._last >= self.snapshot_every:
            write_sweep(self.snapshot, result, self.fingerprint)
            self._last = time.monotonic()

    def end(self, result, complete: bool) -> None:
        """Write the HDF5 file (the final name once complete); remove the journal if complete."""
        try:
            if self._journal is None:
                return  # never began: nothing was computed, nothing is written
            if complete:
                write_sweep(self.out, result, self.fingerprint)
                if self.snapshot != self.out:
                    self.snapshot.unlink(missing_ok=True)
            else:
                write_sweep(self.snapshot, result, self.fingerprint)
            self._journal.close(remove=complete)
        finally:
            self.lock.release()


def snapshot_path(out: Path) -> Path:
    """Where an unfinished sweep writes: ``out``, or beside it if ``out`` holds a complete result."""
    return beside(out) if is_complete_result(out) else Path(out)


def nothing_to_resume(out: Path, fingerprint_now: str) -> bool:
    """Whether ``--resume`` finds ``out`` already complete with these settings (nothing to do)."""
    if out.with_name(out.name + ".journal").exists() or not out.is_file():
        return False
    complete, fp = stored_state(out, "sweep", complete_if_unmarked=False)
    if complete and fp not in (None, fingerprint_now):
        raise CablesimError(
            f"{out} holds a complete sweep of another case or other settings, so there is nothing to resume: "
            "run the command without --resume to replace it, or give another -o.", field="sweep")
    return complete


def stored_state(path, group: str, complete_if_unmarked: bool) -> tuple[bool, str | None]:
    """``(complete, fingerprint)`` of the result file ``path`` whose results are in ``/group``
    (``(False, None)`` if it is missing, unreadable or has no such group); a group without a
    ``complete`` attribute counts as ``complete_if_unmarked`` (files written before the mark)."""
    try:
        with h5py.File(path, "r") as f:
            g = f.get(group)
            if not isinstance(g, h5py.Group):
                return False, None
            fp = g.attrs.get("fingerprint")
            return bool(g.attrs.get("complete", complete_if_unmarked)), None if fp is None else attr_text(fp)
    except (OSError, KeyError, ValueError):
        return False, None
