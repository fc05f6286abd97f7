"""The continuation journal: every finished orbit on disk at once, and the HDF5 file kept current.

As a sweep's (:mod:`cablesim.io.journal`, whose journal file, fingerprint, lock and torn-record
handling this reuses): every record of the tracing (:mod:`cablesim.orbits.resume`: each orbit,
each checkpoint of the march with its tangent and step, each branch's start and end) is appended
to ``OUT.h5.journal`` and flushed to disk, and the HDF5 file is rewritten atomically from the
orbits done so far every few seconds (marked incomplete) and at the end. A killed continuation
therefore loses no finished orbit and never leaves a corrupt file; ``--resume`` restores the
finished branches and goes on from the last checkpoint. The journal is removed when the
continuation completes.
"""

from __future__ import annotations

import time
from pathlib import Path

from ..errors import CablesimError
from .continuation import stored_continuation_state, write_continuation
from .journal import Journal, read_journal, snapshot_path
from .paths import OutputLock, write_error


class ContinuationFile:
    """A continuation's HDF5 file and journal: the recorder
    :func:`cablesim.analyses.continuation.run_continuation` reports to.

    Parameters
    ----------
    out : Path
        The HDF5 file; the journal is ``out`` + ``.journal``, the lock ``out`` + ``.lock``.
    fingerprint : str
        From :func:`cablesim.io.journal.fingerprint`; stored with every record and in the HDF5
        file, and checked on resume.
    resume : bool
        Go on from the journal of an interrupted run.
    snapshot_every : float
        Seconds between atomic rewrites of the HDF5 file.
    command : str
        The command line, recorded in the lock.

    While it runs, the continuation holds ``out.lock``. If ``out`` already holds a complete
    result, the snapshots go beside it (:func:`cablesim.io.paths.beside`) and replace it only
    once the continuation is complete.
    """

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

    def previous(self) -> list[dict]:
        """Records of the interrupted run (empty unless resuming)."""
        if not self.resume:
            return []
        if not self.journal_path.exists():
            raise nothing_to_resume_error(self.out, self.fingerprint)
        records, warnings = read_journal(self.journal_path, self.fingerprint, run="continuation")
        self.warnings += warnings
        return records

    def begin(self) -> None:
        """Take the lock and open the journal (a fresh one unless resuming)."""
        self.lock.acquire()
        self._journal = Journal(self.journal_path, self.fingerprint, fresh=not self.resume)
        self._last = time.monotonic()

    def record(self, record: dict, result) -> None:
        """Journal one record; rewrite the HDF5 file from ``result()`` if the last snapshot is
        old enough and an orbit has been computed."""
        try:
            self._journal.append(dict(record, fingerprint=self.fingerprint))
        except OSError as exc:
            raise self.kept(write_error(self.journal_path, exc)) from None
        if time.monotonic() - self._last >= self.snapshot_every:
            res = result()
            if res.branches:
                try:
                    write_continuation(self.snapshot, res, self.fingerprint)
                except CablesimError as exc:
                    raise self.kept(exc) from None
            self._last = time.monotonic()

    def kept(self, exc: CablesimError) -> CablesimError:
        """A write that failed, with what the journal keeps and how to finish from it."""
        return CablesimError(f"{str(exc).rstrip('.')}. The orbits journaled until then are kept in "
                             f"{self.journal_path}: once there is room, the same command with --resume finishes the "
                             "continuation from them.", field="output")

    def end(self, result, complete: bool) -> None:
        """Write the HDF5 file (the final name once complete; none for a result without an
        orbit) and remove the journal if complete."""
        try:
            if self._journal is None:
                return  # never began: nothing was computed, nothing is written
            if result is not None and result.branches:
                try:
                    write_continuation(self.out if complete else self.snapshot, result, self.fingerprint)
                except CablesimError as exc:
                    self._close(remove=False)
                    raise self.kept(exc) from None
                if complete and self.snapshot != self.out:
                    self.snapshot.unlink(missing_ok=True)
            # a journal without an orbit holds nothing to go on from
            self._close(remove=complete or (result is not None and not result.branches))
        finally:
            self.lock.release()

    def _close(self, remove: bool) -> None:
        try:
            self._journal.close(remove)
        except OSError:  # a full disk refused the last flush: the records before it are on disk
            pass


def nothing_to_resume_error(out: Path, fingerprint_now: str) -> CablesimError:
    """Why ``--resume`` has nothing to go on from at ``out`` (no journal beside it)."""
    complete, fp = stored_continuation_state(out)
    if complete and fp in (None, fingerprint_now):
        return CablesimError(f"Nothing to resume: {out} already holds this continuation, complete (there is no "
                             f"{out.name}.journal). Run the command without --resume to compute it again.",
                             field="continuation")
    if complete:
        return CablesimError(f"Nothing to resume: {out} holds a complete continuation of another case or other "
                             "settings and there is no journal beside it. Run the command without --resume to "
                             "replace it, or give another -o.", field="continuation")
    return CablesimError(f"There is no interrupted continuation to resume at {out} (no {out.name}.journal); run "
                         "the command without --resume.", field="continuation")
