"""Ctrl-C (SIGINT) and SIGTERM, handled alike: stop at the next safe point, keep what is done.

- :func:`install` (the command line calls it) makes SIGTERM raise ``KeyboardInterrupt`` like
  SIGINT does, after noting which signal came, so that a terminated run writes its snapshot and
  says so exactly as an interrupted one; :func:`exit_status` then gives 143 or 130.
- :class:`Deferred` holds both signals off while a compiled loop runs (the time loop checks
  :attr:`Deferred.hit` between chunks, which return to Python many times a second).
- :data:`MAX_CHUNK_STEPS` bounds the steps of every compiled call, so that an interruption acts
  within about a second whatever the step size.
"""

from __future__ import annotations

import signal
import threading

#: Most time steps one compiled call may take before returning to Python.
MAX_CHUNK_STEPS = 20_000
#: Fewest steps of a chunk (chunks adapt between these to about a quarter second of wall time).
MIN_CHUNK_STEPS = 200

_received: list[int] = []
_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _raise(signum, frame):
    _received.append(signum)
    raise KeyboardInterrupt


def install() -> None:
    """SIGINT and SIGTERM both raise ``KeyboardInterrupt`` (main thread), noting the signal."""
    _received.clear()
    if _main_thread():
        for sig in _SIGNALS:
            signal.signal(sig, _raise)


def restore() -> None:
    """Python's own handlers again (SIGINT raises KeyboardInterrupt, SIGTERM ends the process),
    so that a signal during interpreter shutdown does not print a traceback."""
    if _main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def received() -> int | None:
    """The last signal that interrupted this run (None if none did)."""
    return _received[-1] if _received else None


def signal_name() -> str:
    """``"SIGTERM"`` or ``"Ctrl-C"`` for the last interruption."""
    return "SIGTERM" if received() == signal.SIGTERM else "Ctrl-C"


def exit_status() -> int:
    """143 after SIGTERM, 130 after Ctrl-C (128 + the signal number, as shells do)."""
    return 128 + int(signal.SIGTERM) if received() == signal.SIGTERM else 128 + int(signal.SIGINT)


class Deferred:
    """Hold SIGINT and SIGTERM off (main thread only) and note them in :attr:`hit`."""

    def __init__(self):
        self.hit = False
        self._old = {}

    def __enter__(self):
        if _main_thread():
            for sig in _SIGNALS:
                self._old[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum, frame):
        _received.append(signum)
        self.hit = True

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        return False
