"""The compiled kernels' decorator and their on-disk cache, keyed on the compiled sources.

numba keeps a compiled function on disk and reuses it while the function's own source file is
unchanged; it does not notice when a function that it calls, in another module, changes, so a
kernel edited in one file could run beside a stale copy of itself compiled into another. Every
compiled function of cablesim is therefore decorated with :func:`njit` from this module, which
places numba's cache in a folder named after a hash of every compiled source (:func:`cache_dir`):
changing any of them starts a fresh cache, and nothing stale can be loaded.

The compiled sources are the modules of :data:`COMPILED_PACKAGES` and every other module that
imports this one (``tests/test_jit_cache.py`` checks that what they import is among them).

Light on purpose: numba is imported on the first decoration, not when this module is imported.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
import re
import tempfile
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

    Used exactly as ``numba.njit``: ``@njit``, ``@njit(inline="always")``, ``@njit(SIGNATURE)``.
    numba's cache folder setting is changed only while the function is decorated (numba reads it
    then), so compiled functions of other packages in the same process keep their own cache.
    Floating-point errors follow numpy's rules (``error_model="numpy"``): a division by zero
    gives an infinity or NaN, which the kernels' status codes report, instead of raising inside
    a compiled loop.
    """
    kwargs.setdefault("cache", True)
    kwargs.setdefault("error_model", "numpy")
    if len(args) == 1 and inspect.isfunction(args[0]):
        return _compile(args[0], (), kwargs)
    return functools.partial(_compile, signature=args, options=kwargs)


def _compile(func, signature, options):
    import numba
    from numba.core import config

    previous = config.CACHE_DIR
    config.CACHE_DIR = str(cache_dir())
    try:
        return numba.njit(*signature, **options)(func)
    finally:
        config.CACHE_DIR = previous
