"""Ctrl-C (SIGINT) and SIGTERM, handled alike: stop at the next safe point, keep what is done.

- :func:`install` (the command line calls it) makes SIGTERM raise ``KeyboardInterrupt`` like
  SIGINT does, after noting which signal came, so that a terminated run writes its snapshot and
  says so exactly as an interrupted one; :func:`exit_status` then gives 143 or 130.
- :class:`Deferred` holds both signals off while a compiled loop runs (the time loop checks
  :attr:`Deferred.hit` between chunks, which return to Python many times a second).
- :data:`MAX_CHUNK_STEPS` bounds the steps of every compiled call, so that an interruption acts
  within about a second whatever the step size.
- :data:`STOP` is the flag of the compiled loops that cannot return to Python in chunks (the
  flow of one orbit, with its variational equations, is one call): such a loop reads it once a
  step and returns :data:`~cablesim.dynamics.status.INTERRUPTED` when it is set, and
  :func:`acted_on` turns that status into ``KeyboardInterrupt``. Python runs its signal handlers
  only between bytecodes, never inside a compiled call, so the flag is set by a thread that the
  signal itself wakes: :func:`install` makes the interpreter's C-level handler write each
  signal's number to a socket (``signal.set_wakeup_fd``), which that thread reads; the loops
  release the interpreter lock (``nogil``) so that it can run.
- :func:`watching` does only the last part, for the duration of a call of the Python API: Ctrl-C
  reaches the compiled loops too, while every handler stays the caller's.
"""

from __future__ import annotations

import contextlib
import signal
import socket
import threading

import numpy as np
from numba import types
from numba.extending import intrinsic

from .status import INTERRUPTED

#: Most time steps one compiled call may take before returning to Python.
MAX_CHUNK_STEPS = 20_000
#: Fewest steps of a chunk (chunks adapt between these to about a quarter second of wall time).
MIN_CHUNK_STEPS = 200

_received: list[int] = []
_SIGNALS = (signal.SIGINT, signal.SIGTERM)

#: ``STOP[0]`` is nonzero once SIGINT or SIGTERM has come during a compiled loop that reads it
#: (cleared by :func:`clear` as such a loop starts).
STOP = np.zeros(1, dtype=np.int64)


@intrinsic
def stop_requested(typingctx, flag):
    """``flag[0] != 0`` in a compiled loop (``flag``: :data:`STOP`, int64), read from memory at
    every call. A plain ``flag[0]`` is loop-invariant to the compiler (nothing in the loop writes
    it), and was hoisted out of the step loop of some kernels: a loop of 3e7 steps ran to its end
    with the flag set 50 ms in. An atomic (monotonic) load is never hoisted; it costs no more
    than the plain one."""

    def codegen(context, builder, signature, args):
        array = context.make_array(signature.args[0])(context, builder, args[0])
        value = builder.load_atomic(array.data, "monotonic", 8)
        return builder.icmp_signed("!=", value, value.type(0))

    return types.boolean(flag), codegen


#: The socket the interpreter writes signal numbers to, while :func:`install` is in force.
_wakeup: dict = {}


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _raise(signum, frame):
    _received.append(signum)
    raise KeyboardInterrupt


def install() -> None:
    """SIGINT and SIGTERM both raise ``KeyboardInterrupt`` (main thread), noting the signal, and
    set :data:`STOP` at once, even inside a compiled loop."""
    _received.clear()
    if _main_thread():
        for sig in _SIGNALS:
            signal.signal(sig, _raise)
        _watch()


def restore() -> None:
    """Python's own handlers again (SIGINT raises KeyboardInterrupt, SIGTERM ends the process),
    so that a signal during interpreter shutdown does not print a traceback."""
    if _main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        _unwatch()


@contextlib.contextmanager
def watching():
    """While in force, SIGINT and SIGTERM set :data:`STOP` at once, inside compiled loops too;
    the signal handlers are left as they are (the caller's: a script's Ctrl-C raises
    ``KeyboardInterrupt`` as usual, only within about a second even in the flow of a long
    orbit). Nested uses, and uses under :func:`install`, share the one watcher; the outermost
    removes it. Also a decorator (``@watching()``, the functions of the
    Python API). Without this a compiled loop of the orbits runs to its end before Python's
    handler can act."""
    mine = not _wakeup and _main_thread()
    if mine:
        _watch()
    try:
        yield
    finally:
        if mine:
            _unwatch()


def _watch() -> None:
    """Have the interpreter write each signal's number to a socket that a thread reads, setting
    :data:`STOP` for SIGINT and SIGTERM; a wakeup descriptor set by someone else (an event loop)
    is left alone."""
    if _wakeup:
        return
    reader, writer = socket.socketpair()
    writer.setblocking(False)  # the interpreter's handler must never block on it
    try:
        previous = signal.set_wakeup_fd(writer.fileno(), warn_on_full_buffer=False)
    except (ValueError, OSError):
        previous = None
    if previous != -1:
        if previous is not None:
            signal.set_wakeup_fd(previous)
        reader.close()
        writer.close()
        return
    _wakeup["writer"] = writer
    threading.Thread(target=_read_signals, args=(reader,), name="cablesim-signals", daemon=True).start()


def _read_signals(reader: socket.socket) -> None:
    with reader:
        while True:
            try:
                data = reader.recv(64)
            except OSError:
                return
            if not data:  # the writer closed: :func:`restore`
                return
            if any(b in _SIGNALS for b in data):
                STOP[0] = 1


def _unwatch() -> None:
    writer = _wakeup.pop("writer", None)
    if writer is not None:
        previous = signal.set_wakeup_fd(-1)
        if previous not in (-1, writer.fileno()):  # someone else's since: put it back
            signal.set_wakeup_fd(previous)
        writer.close()


def clear() -> None:
    """Clear :data:`STOP` as a compiled loop that reads it starts (a signal before it was acted on
    by the handlers already)."""
    STOP[0] = 0


def acted_on(code):
    """``code``, the status of a compiled loop that reads :data:`STOP`, after raising
    ``KeyboardInterrupt`` if the loop stopped for SIGINT or SIGTERM."""
    if code == INTERRUPTED:
        raise KeyboardInterrupt
    return code


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
