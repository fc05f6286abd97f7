"""The package's structure, read from its source with ``ast``, so that the layering holds.

Layers from the bottom up (``cablesim/__init__.py`` documents them): a module imports only from
lower layers or from its own package; cablesim modules are imported at the top of files (the
command line and the package root, which load their machinery on demand, excepted); only
``plots/`` imports matplotlib and only ``io/`` imports h5py; no private name crosses a module
boundary; no import cycles; modules and functions stay short.
"""

from __future__ import annotations

import ast
import typing
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "cablesim"

#: Layer of each top-level module or subpackage of cablesim (lower imports nothing higher).
LAYERS = {
    "version": 0, "names": 0, "errors": 0, "jit": 0, "blas": 0, "roots": 0,
    "cable": 1, "channels": 1,
    "mechanics": 2,
    "statics": 3, "modal": 3,
    "dynamics": 4,
    "orbits": 5, "case": 5,
    "analyses": 6,
    "io": 7,
    "plots": 8,
    "stress": 9,
    "api": 10,
    "cli": 11,
    "cli_charts": 10.5, "cli_results": 10.5, "cli_figures": 10.5, "cli_views": 10.5, "warmup": 10.5,
    "cli_guard": 10.7,
}
#: Modules that import their machinery inside functions on purpose (start-up time).
LAZY_ENTRY_POINTS = {"cablesim", "cablesim.cli", "cablesim.cli_charts", "cablesim.cli_results", "cablesim.cli_figures",
                     "cablesim.cli_views", "cablesim.cli_guard"}
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 80


def _modules() -> dict[str, Path]:
    mods = {}
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = path
    return mods


MODULES = _modules()


def _resolve(module: str, node: ast.ImportFrom, is_package: bool) -> str:
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(module: str, path: Path):
    """(target module, line, at module level, imported names) of every cablesim import."""
    tree = ast.parse(path.read_text())
    is_package = path.name == "__init__.py"
    top_level = {id(n) for n in tree.body}
    # Imports under `if TYPE_CHECKING:` or `try:` at module level still count as module level.
    for n in tree.body:
        if isinstance(n, (ast.If, ast.Try)):
            top_level |= {id(m) for m in ast.walk(n)}
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            target = _resolve(module, node, is_package)
            if target == "cablesim" or target.startswith("cablesim."):
                names = [a.name for a in node.names]
                # `from . import api` imports a module, not a name
                subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in MODULES]
                for t in subs or [target]:
                    out.append((t, node.lineno, id(node) in top_level, [] if subs else names))
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name == "cablesim" or a.name.startswith("cablesim."):
                    out.append((a.name, node.lineno, id(node) in top_level, []))
    return out


def _third_party(path: Path) -> set[str]:
    roots = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            roots |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split(".")[0])
    return roots


def _unit(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_every_module_has_a_layer():
    units = {_unit(m) for m in MODULES if m != "cablesim"}
    assert units <= set(LAYERS), sorted(units - set(LAYERS))


def test_imports_point_down_only():
    bad = []
    for mod, path in MODULES.items():
        if mod == "cablesim":
            continue
        own = _unit(mod)
        for target, line, _, _ in _imports(mod, path):
            if target == "cablesim":
                bad.append(f"{mod}:{line} imports the package root")
                continue
            other = _unit(target)
            if other != own and LAYERS[other] >= LAYERS[own]:
                bad.append(f"{mod}:{line} imports {target} (layer {LAYERS[other]} >= {LAYERS[own]})")
    assert not bad, "\n".join(bad)


def test_cablesim_imports_at_top_of_files():
    bad = [f"{mod}:{line} imports {t} inside a function"
           for mod, path in MODULES.items() if mod not in LAZY_ENTRY_POINTS
           for t, line, top, _ in _imports(mod, path) if not top]
    assert not bad, "\n".join(bad)


def test_no_private_names_cross_modules():
    bad = []
    for mod, path in MODULES.items():
        for target, line, _, names in _imports(mod, path):
            bad += [f"{mod}:{line} imports {target}.{n}" for n in names if n.startswith("_") and not n.startswith("__")]
        # `module._name` through an imported cablesim module
        tree = ast.parse(path.read_text())
        aliases = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                for a in node.names:
                    target = _resolve(mod, node, path.name == "__init__.py")
                    if f"{target}.{a.name}" in MODULES:
                        aliases.add(a.asname or a.name)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases
                    and node.attr.startswith("_") and not node.attr.startswith("__")):
                bad.append(f"{mod}:{node.lineno} uses {node.value.id}.{node.attr}")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("library, home", [("matplotlib", "plots"), ("h5py", "io")])
def test_heavy_libraries_stay_in_their_layer(library, home):
    bad = [m for m, p in MODULES.items() if library in _third_party(p) and _unit(m) != home]
    assert not bad, f"{library} imported outside cablesim/{home}/: {bad}"


def test_no_import_cycles():
    graph = {m: {t for t, _, _, _ in _imports(m, p) if t in MODULES and t != m} for m, p in MODULES.items()}
    graph["cablesim"] = set()  # the root's lazy API is not a dependency of anything
    state: dict[str, int] = {}
    cycles = []

    def visit(m, stack):
        state[m] = 1
        for t in graph.get(m, ()):
            if state.get(t) == 1:
                cycles.append(" -> ".join(stack[stack.index(t):] + [t]) if t in stack else f"{m} -> {t}")
            elif t not in state:
                visit(t, stack + [t])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [m])
    assert not cycles, "\n".join(cycles)


def test_modules_and_functions_are_short():
    bad = []
    for mod, path in MODULES.items():
        src = path.read_text()
        n = len(src.splitlines())
        if n > MAX_MODULE_LINES:
            bad.append(f"{mod}: {n} lines")
        for node in ast.walk(ast.parse(src)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                body = node.body
                if len(body) > 1 and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                    body = body[1:]  # the docstring does not count; nor does the signature
                length = node.end_lineno - body[0].lineno + 1
                if length > MAX_FUNCTION_LINES:
                    bad.append(f"{mod}.{node.name}: {length} lines")
    assert not bad, "\n".join(bad)


def test_names_agree_everywhere():
    """One tuple of names per choice builds the schema, the CLI choices and the registries."""
    from cablesim import case, cli, names
    from cablesim.dynamics.integrators import INTEGRATORS

    assert tuple(INTEGRATORS) == names.INTEGRATORS
    assert tuple(e.value for e in cli.IntegratorName) == names.INTEGRATORS
    assert tuple(e.value for e in cli.Analysis) == names.ANALYSES

    def literal(model, field):
        ann = model.model_fields[field].annotation
        args = typing.get_args(ann)
        lit = next((a for a in args if typing.get_origin(a) is typing.Literal), ann)
        return typing.get_args(lit)

    assert literal(case.Case, "analysis") == names.ANALYSES
    assert literal(case.IntegratorSpec, "name") == names.INTEGRATORS
    assert literal(case.SweepSpec, "direction") == names.DIRECTIONS


def test_kernel_status_codes_are_the_status_values():
    from cablesim.dynamics import status as kn
    from cablesim.dynamics.status import Status

    assert (kn.OK, kn.NONFINITE, kn.SLACK, kn.INNER_SOLVE, kn.STEP_UNDERFLOW) == (
        Status.COMPLETED, Status.NONFINITE, Status.SLACK, Status.INNER_SOLVE, Status.STEP_UNDERFLOW)
    assert all(s.text for s in Status)


def test_the_package_map_names_every_unit():
    doc = (ROOT / "__init__.py").read_text()
    missing = [u for u in LAYERS if f"``{u}" not in doc and f"{u}/" not in doc and f"``{u}``" not in doc]
    assert not missing, missing
