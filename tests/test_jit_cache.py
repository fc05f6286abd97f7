"""numba's on-disk cache cannot go stale: it is keyed on a hash of every compiled source.

numba reuses a cached function while its own file is unchanged, even when a function it calls in
another module has changed. cablesim's kernels are all decorated through ``cablesim.jit``, whose
cache folder is named after a hash of the compiled sources, so that any edit starts a fresh cache.
These checks make sure nothing bypasses it.
"""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
from pathlib import Path

from cablesim import jit

ROOT = Path(jit.__file__).resolve().parent


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _resolve(path: Path, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    base = _module_name(path).split(".")
    if path.name != "__init__.py":
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _is_compiled(fn: ast.FunctionDef) -> bool:
    for d in fn.decorator_list:
        target = d.func if isinstance(d, ast.Call) else d
        if isinstance(target, ast.Name) and target.id == "njit":
            return True
    return False


def test_no_kernel_bypasses_the_keyed_cache():
    """numba's own decorators appear nowhere but in cablesim/jit.py."""
    bad = []
    for path in ROOT.rglob("*.py"):
        if path.name == "jit.py":
            continue
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "numba":
                bad += [f"{path.name}:{node.lineno} imports numba.{a.name}" for a in node.names
                        if a.name in ("njit", "jit", "generated_jit", "vectorize", "guvectorize", "cfunc")]
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "numba" \
                    and node.attr in ("njit", "jit", "cfunc", "vectorize"):
                bad.append(f"{path.name}:{node.lineno} uses numba.{node.attr}")
    assert not bad, "\n".join(bad)


def test_every_compiled_function_is_in_the_hashed_sources():
    sources = set(jit.compiled_sources())
    missing = []
    for path in ROOT.rglob("*.py"):
        tree = ast.parse(path.read_text())
        if any(isinstance(n, ast.FunctionDef) and _is_compiled(n) for n in ast.walk(tree)) and path not in sources:
            missing.append(str(path.relative_to(ROOT)))
    assert not missing, missing


def test_compiled_code_reads_no_name_from_an_unhashed_module():
    """A constant frozen into compiled code must come from a hashed source, else editing it
    would leave the cached kernels stale."""
    sources = set(jit.compiled_sources())
    hashed = {_module_name(p) for p in sources}
    bad = []
    for path in sources:
        tree = ast.parse(path.read_text())
        foreign = {}
        for node in tree.body:
            if isinstance(node, ast.ImportFrom):
                target = _resolve(path, node)
                if target.startswith("cablesim") and target not in hashed:
                    for a in node.names:
                        if f"{target}.{a.name}" not in hashed:
                            foreign[a.asname or a.name] = target
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.startswith("cablesim") and a.name not in hashed:
                        foreign[(a.asname or a.name).split(".")[0]] = a.name
        for fn in ast.walk(tree):
            if isinstance(fn, ast.FunctionDef) and _is_compiled(fn):
                used = {n.id for stmt in fn.body for n in ast.walk(stmt) if isinstance(n, ast.Name)}
                bad += [f"{path.relative_to(ROOT)}:{fn.name} reads {name} from {foreign[name]}"
                        for name in sorted(used & set(foreign))]
    assert not bad, "\n".join(bad)


def _hash_of(tree: Path) -> str:
    code = "import sys; sys.path.insert(0, sys.argv[1]); from cablesim import jit; print(jit.source_hash())"
    out = subprocess.run([sys.executable, "-c", code, str(tree)], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_the_cache_folder_follows_the_compiled_sources_only(tmp_path):
    copy = tmp_path / "tree"
    shutil.copytree(ROOT, copy / "cablesim", ignore=shutil.ignore_patterns("__pycache__"))
    before = _hash_of(copy)
    assert before == jit.source_hash()
    # an edit outside the compiled code keeps the cache
    cli = copy / "cablesim" / "cli.py"
    cli.write_text(cli.read_text() + "\n# a comment\n")
    assert _hash_of(copy) == before
    # an edit to any compiled source starts a fresh one
    kernel = sorted((copy / "cablesim").rglob("*.py"), key=lambda p: p.as_posix())
    kernel = [p for p in kernel if (copy / "cablesim" / "mechanics") in p.parents][0]
    kernel.write_text(kernel.read_text() + "\n# a comment\n")
    assert _hash_of(copy) != before


def test_compiled_functions_are_cached_in_the_keyed_folder(tmp_path):
    """A kernel compiled in a fresh process leaves its index in the keyed folder, not in a
    __pycache__ beside its source."""
    code = (
        "import numpy as np\n"
        "from cablesim.mechanics import banded\n"
        "banded.is_band(np.zeros((7, 4)))\n"
        "from cablesim import jit\n"
        "print(jit.cache_dir())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    folder = Path(out.stdout.strip())
    assert folder.name == f"kernels-{jit.source_hash()}"
    assert any(folder.rglob("banded.is_band-*.nbi"))
    assert not any((ROOT / "mechanics").rglob("banded.is_band-*.nbi"))


_FLOW_PROBE = """
from cablesim import api
from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.orbits.kernels import flow_segment
from cablesim.orbits.shooting import Shooting
from cablesim.orbits.systems import cable_system
import numpy as np
case = api.load_case(None)
eom = build_equations(case, run_static(case, all_models=False), omega=2.4)
Shooting(cable_system(eom), period=1).segment(0, np.zeros(2 * eom.n_dof), 2.4)
print("MISSES", sum(flow_segment.stats.cache_misses.values()), "HITS", sum(flow_segment.stats.cache_hits.values()))
"""


def test_a_kernel_taking_the_vector_field_is_loaded_from_the_cache_by_a_later_process():
    """The orbits' flow takes the vector field (a compiled function) as an argument: keyed on the
    function object's identity in its process, it missed the cache and compiled again in every
    process (about a second and a half of every `cablesim continue`)."""
    runs = [subprocess.run([sys.executable, "-c", _FLOW_PROBE], capture_output=True, text=True, timeout=900)
            for _ in range(2)]
    assert all(r.returncode == 0 for r in runs), runs[-1].stderr[-2000:]
    assert "MISSES 0 HITS 1" in runs[1].stdout, runs[1].stdout


def test_the_cache_key_of_a_compiled_function_argument_outlives_the_function():
    """An index entry whose vector field had been collected could not be written again:
    `ReferenceError: underlying object has vanished` in the middle of a sweep."""
    import gc
    import pickle

    import numba
    from numba.core import types
    from numba.core.registry import cpu_target

    def make():
        @numba.njit
        def field(x):
            return 2.0 * x
        return field

    field = make()
    sig = (types.Dispatcher(field), types.float64)
    cache = jit._stable_cache_class()(make)  # (a cache for any function with a source file)
    key = cache._index_key(sig, cpu_target.target_context.codegen())
    del field, sig
    gc.collect()
    assert "compiled function" in str(key[0][0]) and "make.<locals>.field" in str(key[0][0])
    pickle.dumps(key)  # raised ReferenceError while the key held the function's type


_CALLEE_MODULE = '''
from cablesim.jit import njit


@njit
def square(x):
    return x * x


@njit
def apply_twice(f, x):
    return f(f(x))


@njit
def caller(f, x):
    return apply_twice(f, x) + 1.0
'''


def test_a_kernel_compiled_after_the_kernels_it_calls_were_cached(tmp_path):
    """A cache holding a kernel that takes a compiled function (``apply_twice``, as the slack
    flows' ``_start_modes`` takes the gap functions) but not the kernel calling it (a first
    compilation interrupted between the two, or two processes compiling at once): the caller,
    compiled in a later process, found the callee's cached version typed with copies of the
    functions rebuilt from the pickle and failed (numba TypingError: ``Invalid use of type(
    CPUDispatcher(...))``). It now compiles and runs."""
    import os

    (tmp_path / "callee_probe.py").write_text(_CALLEE_MODULE)
    code = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); import callee_probe as m; print(m.caller(m.square, 3.0))"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))

    def run():
        return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)

    first = run()
    assert first.returncode == 0 and first.stdout.strip() == "82.0", first.stderr[-2000:]
    callers = list((tmp_path / "cache").rglob("callee_probe.caller-*"))
    assert len(callers) == 2 and list((tmp_path / "cache").rglob("callee_probe.apply_twice-*.nbi"))
    for path in callers:
        path.unlink()
    for _ in range(2):  # the caller compiled again, then loaded from the cache
        again = run()
        assert again.returncode == 0 and again.stdout.strip() == "82.0", again.stderr[-2000:]
