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
from .continuation import write_continuation
from .journal import JournalledFile, stored_state
from .paths import write_error


class ContinuationFile(JournalledFile):
    """A continuation's HDF5 file and journal (:class:`~cablesim.io.journal.JournalledFile`):
    the recorder :func:`cablesim.analyses.continuation.run_continuation` reports to."""

    run = "continuation"

    def nothing_to_resume(self) -> CablesimError:
        return nothing_to_resume_error(self.out, self.fingerprint)

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
    complete, fp = stored_state(out, "continuation", complete_if_unmarked=True)
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
