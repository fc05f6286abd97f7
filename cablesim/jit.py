"""The compiled kernels' decorator and their on-disk cache, keyed on the compiled sources.

numba keeps a compiled function on disk and reuses it while the function's own source file is
unchanged; it does not notice when a function that it calls, in another module, changes, so a
kernel edited in one file could run beside a stale copy of itself compiled into another. Every
compiled function of cablesim is therefore decorated with :func:`njit` from this module, which
places numba's cache in a folder named after a hash of every compiled source (:func:`cache_dir`):
changing any of them starts a fresh cache, and nothing stale can be loaded.

The compiled sources are the modules of :data:`COMPILED_PACKAGES` and every other module that
imports this one (``tests/test_jit_cache.py`` checks that what they import is among them).

Compiling, as opposed to loading from the cache, is watched (numba's ``numba:compile`` event
fires only on a cache miss): :func:`compile_seconds` and :func:`kernels_compiled` say how much
of this process went into it, and :func:`on_compile` lets the command line say so while it
happens, so that no first use compiles silently or counts as simulation.

Light on purpose: numba is imported on the first decoration, not when this module is imported.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
import re
import tempfile
import threading
import time
from pathlib import Path

#: The package's root folder.
PACKAGE = Path(__file__).resolve().parent
#: Subpackages whose every module counts as compiled source (kernels, and the constants and
#: helpers they freeze into compiled code).
COMPILED_PACKAGES = ("mechanics", "dynamics", "orbits")
_USES_JIT = re.compile(r"^\s*from\s+(\.+|cablesim\.)jit\s+import", re.MULTILINE)


def compiled_sources() -> list[Path]:
    """The source files whose compiled code the cache holds, in a fixed order."""
    found = set()
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE)
        if rel.parts[0] in COMPILED_PACKAGES or _USES_JIT.search(path.read_text(encoding="utf-8")):
            found.add(path)
    return sorted(found, key=lambda p: p.relative_to(PACKAGE).as_posix())


@functools.lru_cache(maxsize=1)
def source_hash() -> str:
    """SHA-256 (first 16 hex digits) of the compiled sources' relative paths and contents."""
    h = hashlib.sha256()
    for path in compiled_sources():
        h.update(path.relative_to(PACKAGE).as_posix().encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
        return True
    except OSError:
        return False


@functools.lru_cache(maxsize=1)
def cache_dir() -> Path:
    """The folder of numba's cache for this version of the compiled sources.

    ``cablesim/__pycache__/kernels-<hash>`` beside the sources when that is writable (a clone
    or an editable install; ``make clean`` removes it), else ``kernels-<hash>`` under
    ``$NUMBA_CACHE_DIR``, ``$XDG_CACHE_HOME/cablesim`` or ``~/.cache/cablesim``, else under the
    temporary folder.
    """
    name = f"kernels-{source_hash()}"
    env = os.environ.get("NUMBA_CACHE_DIR")
    xdg = os.environ.get("XDG_CACHE_HOME")
    candidates = [PACKAGE / "__pycache__" / name]
    if env:
        candidates.insert(0, Path(env) / "cablesim" / name)
    candidates += [Path(xdg) / "cablesim" / name] if xdg else []
    candidates += [Path.home() / ".cache" / "cablesim" / name, Path(tempfile.gettempdir()) / "cablesim" / name]
    for folder in candidates:
        if _writable(folder):
            return folder
    return candidates[-1]


def is_cached(pattern: str) -> bool:
    """Whether numba's cache already holds a compiled function whose index file matches
    ``pattern`` (for example ``"field.rate-*.nbi"``): a run needing it will not compile."""
    root = cache_dir()
    return root.is_dir() and any(root.glob(f"*/{pattern}"))


def njit(*args, **kwargs):
    """``numba.njit`` with ``cache=True``, cached in :func:`cache_dir`.

    Used exactly as ``numba.njit``: ``@njit``, ``@njit(inline="always")``, ``@njit(SIGNATURE)``;
    ``@njit(borrowed=True)`` for a function that allocates no array (a vector field called at
    every stage): its array arguments are then used without reference counting.
    numba's cache folder setting is changed only while the function is decorated (numba reads it
    then), so compiled functions of other packages in the same process keep their own cache.
    Floating-point errors follow numpy's rules (``error_model="numpy"``): a division by zero
    gives an infinity or NaN, which the kernels' status codes report, instead of raising inside
    a compiled loop.
    """
    kwargs.setdefault("cache", True)
    kwargs.setdefault("error_model", "numpy")
    if kwargs.pop("borrowed", False):
        # A function that allocates nothing can take its array arguments without numba's
        # reference counting, which costs a pair of atomic operations per array a call (about
        # 0.15 us for a vector field taking a CableModel: two thirds of a 2-node orbit field).
        kwargs["_nrt"] = False
    if len(args) == 1 and inspect.isfunction(args[0]):
        return _compile(args[0], (), kwargs)
    return functools.partial(_compile, signature=args, options=kwargs)


def _compile(func, signature, options):
    import numba
    from numba.core import config

    _install_watch()
    previous = config.CACHE_DIR
    config.CACHE_DIR = str(cache_dir())
    try:
        dispatcher = numba.njit(*signature, **options)(func)
        if options.get("cache"):
            dispatcher._cache = _stable_cache_class()(dispatcher.py_func)
        return dispatcher
    finally:
        config.CACHE_DIR = previous


def _function_key(func) -> str:
    """What identifies a compiled function passed as an argument, across processes: its
    qualified name, bytecode and source file's size and time."""
    try:
        st = os.stat(inspect.getsourcefile(func) or "")
        stamp = f"{st.st_size}:{st.st_mtime_ns}"
    except (OSError, TypeError):
        stamp = "?"
    code = hashlib.sha256(func.__code__.co_code).hexdigest()[:16]
    return f"{func.__module__}.{func.__qualname__}:{code}:{stamp}"


@functools.lru_cache(maxsize=None)
def _stable_cache_class():
    """numba's on-disk cache with a key that survives the process for kernels taking a compiled
    function as an argument (the orbits' flow takes the vector field).

    numba keys a cached specialisation on its argument types, and the type of a compiled
    function holds the function object itself, which is pickled with a random identity of its
    process: such a kernel missed the cache in every process (compiled again, its index growing
    by one entry a run), and an index entry whose function had been collected could not be
    written again (``ReferenceError: underlying object has vanished``). Here such a type enters
    the key as the function's name, bytecode and source stamp (:func:`_function_key`).

    A specialisation loaded from the cache is given the argument types it was looked up with:
    the stored ones hold copies of the functions rebuilt from the pickle, and a kernel compiled
    in this process that calls it (its caller missing from the cache: a first compilation
    interrupted, or two processes compiling at once) found no version for its own functions and
    failed to type.
    """
    from numba.core import types, typing
    from numba.core.caching import FunctionCache

    class StableFunctionCache(FunctionCache):
        def _index_key(self, sig, codegen):
            stable = tuple(f"compiled function {_function_key(t.dispatcher.py_func)}"
                           if isinstance(t, types.Dispatcher) else t for t in sig)
            return super()._index_key(stable, codegen)

        def load_overload(self, sig, target_context):
            cres = super().load_overload(sig, target_context)
            if cres is not None and any(isinstance(t, types.Dispatcher) for t in sig):
                # the stored signature holds copies of the functions, rebuilt from the pickle;
                # a kernel compiled now that calls this one looks it up by the live ones
                cres.fndesc.argtypes = tuple(sig)
                cres = cres._replace(signature=typing.signature(cres.signature.return_type, *sig))
            return cres

    return StableFunctionCache


# ----------------------------------------------------------------------------------------------
# Compilation, watched
# ----------------------------------------------------------------------------------------------
class _Watch:
    """What numba compiled in this process: top-level compiles (a kernel with the kernels it
    calls), their seconds, and the hooks told when one starts."""

    def __init__(self):
        self.depth = 0
        self.started = 0.0
        self.seconds = 0.0
        self.kernels = 0
        self.current = ""
        self.hooks: list = []
        self.installed = False
        self.lock = threading.Lock()


_WATCH = _Watch()


def _kernel_name(event) -> str:
    func = getattr(event.data.get("dispatcher"), "py_func", None) if isinstance(event.data, dict) else None
    if func is None:
        return "a kernel"
    return f"{func.__module__.rsplit('.', 1)[-1]}.{func.__name__}"


def _install_watch() -> None:
    """Listen to numba's compile events (once; numba is being imported anyway)."""
    if _WATCH.installed:
        return
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            with _WATCH.lock:
                _WATCH.kernels += 1
                _WATCH.current = _kernel_name(ev)
                top = _WATCH.depth == 0
                if top:
                    _WATCH.started = time.perf_counter()
                _WATCH.depth += 1
            for hook in list(_WATCH.hooks):
                hook(_WATCH.current)

        def on_end(self, ev):
            with _WATCH.lock:
                _WATCH.depth = max(0, _WATCH.depth - 1)
                if _WATCH.depth == 0:
                    _WATCH.seconds += time.perf_counter() - _WATCH.started

    event.register("numba:compile", Listener())
    _WATCH.installed = True


def compile_seconds() -> float:
    """Wall seconds this process has spent compiling kernels (not loading them from the
    cache), including a compilation under way."""
    with _WATCH.lock:
        running = time.perf_counter() - _WATCH.started if _WATCH.depth else 0.0
        return _WATCH.seconds + running


def kernels_compiled() -> int:
    """Kernels (and specialisations) this process has compiled rather than loaded from the cache."""
    return _WATCH.kernels


def compiling_now() -> str | None:
    """The kernel being compiled at this moment (None if none)."""
    return _WATCH.current if _WATCH.depth else None


class on_compile:
    """Context manager: ``hook(kernel_name)`` is called whenever a kernel starts compiling."""

    def __init__(self, hook):
        self.hook = hook

    def __enter__(self):
        _WATCH.hooks.append(self.hook)
        return self

    def __exit__(self, *exc):
        if self.hook in _WATCH.hooks:
            _WATCH.hooks.remove(self.hook)
        return False
