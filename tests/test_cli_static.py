"""The `cablesim static` and `cablesim example` commands, end to end.

Real subprocesses (about a second each) are used for the default run, one explicit run, `example`,
`--version` and a few error cases (exit status, no traceback); everything else goes through the
same Typer app in-process.
"""

from __future__ import annotations

import importlib.metadata
import math
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml

import cablesim
from helpers_cli import error_paragraph
from cablesim.analyses.static import run_static
from cablesim.case import example_text, load_case, parse_case

CONFIG_EXAMPLE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

# Datasets the issue requires, with their units.
REQUIRED_UNITS = {
    "static/inextensible/x": "m",
    "static/inextensible/T": "N",
    "static/approximate/x": "m",
    "static/approximate/u": "m",
    "static/approximate/y": "m",
    "static/approximate/T": "N",
    "static/approximate/B": "1",
    "static/approximate/D": "m/N",
    "static/approximate/f": "m/N",
    "static/approximate/N": "m/N",
    "static/approximate/K": "N/m",
    "static/exact/y": "m",
    "static/exact/T": "N",
    "static/exact/K": "N/m",
    "modal/omega": "rad/s",
}
SHAPES = {"x": (4,), "u": (4,), "y": (4,), "T": (3,), "B": (3, 4), "D": (4, 4), "f": (4, 4), "N": (4, 4), "K": (4, 4)}


# ----------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------
def flat(text: str) -> str:
    """A wrapped paragraph on one line (the message may break a field name's neighbourhood)."""
    return " ".join(text.split())


def output_files(root: Path) -> list[Path]:
    """Every result-like file under root: .h5, .png, and temporaries (.part)."""
    return sorted(
        p for p in root.rglob("*") if p.is_file() and (p.suffix in (".h5", ".png") or ".part" in p.name)
    )


def assert_user_error(res, root: Path, *needles: str) -> str:
    """Exit status 2, one paragraph on stderr naming what's wrong, no traceback, no files."""
    rc, out, err = res[0], res[1], res[2]
    assert rc == 2, f"exit status {rc}; stderr:\n{err}"
    if len(res) > 3:  # in-process: the runner must not have caught anything but a clean exit
        assert isinstance(res[3], SystemExit), repr(res[3])
    assert "Traceback" not in err and "Traceback" not in out
    msg = error_paragraph(err)
    assert msg.startswith("error: "), err
    assert "\n\n" not in msg and all(line.strip() for line in msg.splitlines()), "one paragraph"
    assert out.strip() == "", "nothing on stdout for a failed run"
    for needle in needles:
        assert needle in flat(msg), f"{needle!r} not in: {flat(msg)}"
    assert output_files(root) == []
    runs = root / "runs"
    assert not runs.exists() or not [p for p in runs.rglob("*") if p.is_file()]
    return flat(msg)


def h5_datasets(path: Path) -> dict[str, np.ndarray]:
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    return out


def h5_units(path: Path) -> dict[str, str]:
    out = {}
    with h5py.File(path, "r") as f:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                u = obj.attrs.get("units")
                out[name] = u.decode() if isinstance(u, bytes) else u

        f.visititems(visit)
    return out


def h5_attrs(path: Path, group: str = "/") -> dict:
    with h5py.File(path, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f[group].attrs.items()}


def expected_datasets(result) -> dict[str, np.ndarray]:
    """What write_static should store for a StaticResult (dataset path -> array)."""
    r = result
    exp = {"static/P": r.P}
    if r.inextensible is not None:
        for k in ("x", "T", "B", "D"):
            exp[f"static/inextensible/{k}"] = getattr(r.inextensible, k)
    if r.approximate is not None:
        for k in ("x", "u", "y", "T", "B", "D", "f", "N", "K"):
            exp[f"static/approximate/{k}"] = getattr(r.approximate, k)
    if r.exact is not None:
        exp.update({"static/exact/y": r.exact.y, "static/exact/T": r.exact.T, "static/exact/K": r.exact.K,
                    "static/exact/l": r.exact.length})
    exp.update({"modal/omega": r.modes.omega, "modal/shapes": r.modes.shapes,
                "modal/damping_ratio": r.damping_ratios, "modal/inextensible_omega": r.inextensible_omega})
    return exp


def assert_matches_run_static(h5: Path, result):
    got = h5_datasets(h5)
    exp = expected_datasets(result)
    assert set(got) == set(exp)
    for name, val in exp.items():
        np.testing.assert_allclose(got[name], val, rtol=1e-10, atol=0, err_msg=name)
    modal = h5_attrs(h5, "modal")
    assert modal["analysis"] == result.analysis
    assert modal["a0"] == pytest.approx(result.a0, rel=1e-12)
    assert modal["a1"] == pytest.approx(result.a1, rel=1e-12)


def assert_png(path: Path):
    assert path.is_file()
    assert path.read_bytes()[:8] == PNG_MAGIC


# ----------------------------------------------------------------------------------------------
# happy path, real processes (module-scoped: each runs once)
# ----------------------------------------------------------------------------------------------
# The real-process runs of this module, started together (each costs about a second of start-up):
# name -> (args, case file text or None)
_SLACK = CONFIG_EXAMPLE.read_text().replace(
    "F0: [300.0e3, 1100.0e3, 450.0e3, 2000.0e3]", "F0: [1000.0e3, 0.0, -1000.0e3, 0.0]"
)
REAL_RUNS = {
    "default": (["static"], None),
    "explicit": (["static", "cable.yaml", "-o", "out/res.h5", "--analysis", "approximate"], CONFIG_EXAMPLE.read_text()),
    "malformed-yaml": (["static", "cable.yaml"], "cable: [1, 2\nloads: {\n"),
    "slack-segment": (["static", "cable.yaml"], _SLACK),
    "missing-file": (["static", "nope.yaml"], None),
}


@pytest.fixture(scope="module")
def real_runs(tmp_path_factory, cablesim_subprocesses):
    """name -> (cwd, (returncode, stdout, stderr)) for every entry of REAL_RUNS."""
    assert _SLACK != CONFIG_EXAMPLE.read_text()
    jobs, dirs = [], {}
    for name, (args, text) in REAL_RUNS.items():
        cwd = dirs[name] = tmp_path_factory.mktemp(f"real-{name}")
        if text is not None:
            (cwd / "cable.yaml").write_text(text)
        jobs.append((args, cwd))
    results = cablesim_subprocesses(jobs)
    return {name: (dirs[name], res) for name, res in zip(REAL_RUNS, results)}


@pytest.fixture(scope="module")
def default_run(real_runs):
    """`cablesim static` with no case file, in an empty working directory."""
    return real_runs["default"]


@pytest.fixture(scope="module")
def explicit_run(real_runs):
    """`cablesim static cable.yaml -o out/res.h5 --analysis approximate`."""
    return real_runs["explicit"]


def test_default_run_succeeds_and_writes_under_runs(default_run):
    cwd, (rc, out, err) = default_run
    assert rc == 0, err
    assert "Traceback" not in err
    h5 = cwd / "runs" / "paper-example" / "static.h5"
    assert h5.is_file()
    assert_png(h5.with_suffix(".png"))
    modes = h5.with_name("static-modes.png")  # the lowest mode shapes
    assert_png(modes)
    assert output_files(cwd) == [modes, h5, h5.with_suffix(".png")]  # nothing else, no .part left


def test_default_run_summary_is_readable(default_run):
    cwd, (rc, out, err) = default_run
    assert "static analysis of 'paper-example' (exact analysis)" in out
    assert "L = 300 m, H = 20 m" in out
    for heading in ("Node coordinates under F0", "Segment tensions", "Linear modes", "Rayleigh damping"):
        assert heading in out
    assert "Wrote runs/paper-example/static.h5 and runs/paper-example/static.png" in out
    # the frequencies printed are the ones stored
    omega = h5_datasets(cwd / "runs/paper-example/static.h5")["modal/omega"]
    for w in omega:
        assert f"{w:.7g}" in out
    assert max(len(line) for line in out.splitlines()) <= 140


def test_default_run_layout_and_units(default_run):
    cwd, _ = default_run
    h5 = cwd / "runs" / "paper-example" / "static.h5"
    units = h5_units(h5)
    for name, unit in REQUIRED_UNITS.items():
        assert units.get(name) == unit, name
    assert "modal/shapes" in units
    # every dataset has a units attribute
    assert all(isinstance(u, str) and u for u in units.values()), units
    data = h5_datasets(h5)
    for name, shape in SHAPES.items():
        assert data[f"static/approximate/{name}"].shape == shape
    assert data["static/inextensible/x"].shape == (4,) and data["static/inextensible/T"].shape == (3,)
    assert data["static/exact/K"].shape == (4, 4)
    assert data["modal/omega"].shape == (4,) and data["modal/shapes"].shape == (4, 4)
    modal = h5_attrs(h5, "modal")
    assert modal["analysis"] == "exact"
    assert math.isfinite(modal["a0"]) and math.isfinite(modal["a1"])
    root = h5_attrs(h5)
    assert root["cablesim_version"] == cablesim.__version__


def test_default_run_stores_the_case_yaml(default_run):
    cwd, _ = default_run
    text = h5_attrs(cwd / "runs/paper-example/static.h5")["case_yaml"]
    assert text == example_text() + "# cablesim name (the case file's): paper-example\n"  # re-read under its name
    assert parse_case(text) == load_case(None)[0]


def test_default_run_values_agree_with_run_static(default_run):
    cwd, _ = default_run
    h5 = cwd / "runs/paper-example/static.h5"
    result = run_static(load_case(None)[0])
    assert_matches_run_static(h5, result)


def test_default_run_rayleigh_damping(default_run):
    """a0, a1 give ratio 0.01 in modes 1 and 2 (Rayleigh: a0 = 2 xi w1 w2/(w1+w2), a1 = 2 xi/(w1+w2))."""
    cwd, _ = default_run
    h5 = cwd / "runs/paper-example/static.h5"
    w = h5_datasets(h5)["modal/omega"]
    modal = h5_attrs(h5, "modal")
    assert modal["a0"] == pytest.approx(2 * 0.01 * w[0] * w[1] / (w[0] + w[1]), rel=1e-10)
    assert modal["a1"] == pytest.approx(2 * 0.01 / (w[0] + w[1]), rel=1e-10)
    np.testing.assert_allclose(h5_datasets(h5)["modal/damping_ratio"][:2], 0.01, rtol=1e-10)


def test_explicit_run_with_output_and_approximate(explicit_run):
    cwd, (rc, out, err) = explicit_run
    assert rc == 0, err
    assert "Traceback" not in err
    h5 = cwd / "out" / "res.h5"
    assert h5.is_file()
    assert_png(cwd / "out" / "res.png")
    assert not (cwd / "runs").exists(), "-o replaces the default runs/<name>/ location"
    assert "(approximate analysis)" in out
    assert "Wrote out/res.h5 and out/res.png" in out
    stored = h5_attrs(h5)["case_yaml"]  # the file, and the name it took from its file name
    assert stored.startswith(CONFIG_EXAMPLE.read_text()) and stored.count("\n") == CONFIG_EXAMPLE.read_text().count("\n") + 1


def test_explicit_run_approximate_changes_modal(explicit_run, default_run):
    cwd, _ = explicit_run
    approx = cwd / "out" / "res.h5"
    exact = default_run[0] / "runs/paper-example/static.h5"
    ma, me = h5_attrs(approx, "modal"), h5_attrs(exact, "modal")
    assert ma["analysis"] == "approximate" and me["analysis"] == "exact"
    wa, we = h5_datasets(approx)["modal/omega"], h5_datasets(exact)["modal/omega"]
    assert not np.allclose(wa, we, rtol=1e-6, atol=0)
    np.testing.assert_allclose(wa, we, rtol=0.05)  # but both describe the same cable
    assert ma["a0"] != me["a0"] and ma["a1"] != me["a1"]
    # the statics themselves do not depend on the choice
    for k in ("static/exact/y", "static/approximate/y", "static/inextensible/x"):
        np.testing.assert_allclose(h5_datasets(approx)[k], h5_datasets(exact)[k], rtol=1e-12)


def test_explicit_run_values_agree_with_run_static(explicit_run):
    cwd, _ = explicit_run
    result = run_static(load_case(CONFIG_EXAMPLE)[0], "approximate")
    assert_matches_run_static(cwd / "out" / "res.h5", result)
    assert all(h5_units(cwd / "out" / "res.h5").values())


def test_example_command_matches_shipped_config(run_cli):
    rc, out, err = run_cli("example")
    assert rc == 0, err
    assert out.lstrip().startswith("#"), "commented YAML"
    assert out == example_text()
    assert parse_case(out, default_name="paper-example", record_name=True) == load_case(CONFIG_EXAMPLE)[0]


def test_version(run_cli):
    rc, out, err = run_cli("--version")
    assert rc == 0, err
    assert out.strip() == f"cablesim {cablesim.__version__}"
    assert cablesim.__version__ == importlib.metadata.version("cablesim")


# ----------------------------------------------------------------------------------------------
# happy path, in-process
# ----------------------------------------------------------------------------------------------
def test_name_from_stem_and_output_relative_to_cwd(invoke_cli, tmp_path, paper_case):
    """A case file without `name` in another folder: output goes to ./runs/<stem>/."""
    paper_case.pop("name", None)
    case_file = tmp_path / "cases" / "my-cable.yaml"
    case_file.parent.mkdir()
    case_file.write_text(yaml.safe_dump(paper_case))
    rc, out, err, exc = invoke_cli("static", "cases/my-cable.yaml")
    assert rc == 0, (err, exc)
    h5 = tmp_path / "runs" / "my-cable" / "static.h5"
    assert output_files(tmp_path) == [h5.with_name("static-modes.png"), h5, h5.with_suffix(".png")]
    assert_png(h5.with_suffix(".png"))
    assert not (case_file.parent / "runs").exists()
    assert "static analysis of 'my-cable'" in out


def test_analysis_from_file_and_override(invoke_cli, tmp_path, write_case, paper_case):
    paper_case["analysis"] = "approximate"
    write_case(paper_case, "c.yaml")
    rc, _, err, _ = invoke_cli("static", "c.yaml", "--no-plot", "-o", "a.h5")
    assert rc == 0, err
    rc, _, err, _ = invoke_cli("static", "c.yaml", "--no-plot", "-o", "e.h5", "--analysis", "exact")
    assert rc == 0, err
    assert h5_attrs(tmp_path / "a.h5", "modal")["analysis"] == "approximate"
    assert h5_attrs(tmp_path / "e.h5", "modal")["analysis"] == "exact"
    assert not (tmp_path / "a.png").exists(), "--no-plot"


def test_exponent_strings_and_EA_work_from_the_command_line(invoke_cli, tmp_path, write_case, default_run):
    """`EA: 1.0e9` and loads like `300.0e3` (strings in YAML 1.1) give the paper's results."""
    text = (
        "cable:\n  L: 3.0e2\n  H: 2.0e1\n  S: [1.3e2, 1.0e2, 1.1e2]\n  EA: 1.0e9\n  masses: [8.0e3, 1.4e4]\n"
        "loads:\n  F0: [300.0e3, 1100.0e3, 450.0e3, 2000.0e3]\n"
    )
    write_case(text, "sci.yaml")
    rc, out, err, exc = invoke_cli("static", "sci.yaml", "--no-plot")
    assert rc == 0, (err, exc)
    mine = h5_datasets(tmp_path / "runs/sci/static.h5")
    paper = h5_datasets(default_run[0] / "runs/paper-example/static.h5")  # E and A, not EA
    for k in ("static/exact/y", "static/exact/T", "modal/omega"):
        np.testing.assert_allclose(mine[k], paper[k], rtol=1e-9, err_msg=k)
    assert h5_attrs(tmp_path / "runs/sci/static.h5")["case_yaml"] == text + "# cablesim name (the case file's): sci\n"


def test_example_output_runs(invoke_cli, tmp_path):
    """The README workflow: `cablesim example > my-case.yaml; cablesim static my-case.yaml`. A
    case copied from the example gets its own folder (it wrote into runs/paper-example/)."""
    rc, out, _, _ = invoke_cli("example")
    assert rc == 0
    (tmp_path / "my-case.yaml").write_text(out)
    rc, _, err, _ = invoke_cli("static", "my-case.yaml", "--no-plot")
    assert rc == 0, err
    assert (tmp_path / "runs" / "my-case" / "static.h5").is_file()
    assert not (tmp_path / "runs" / "paper-example").exists()


def test_pretensioned_short_cable_with_exact_analysis(invoke_cli, tmp_path, write_case, paper_case):
    """sum S below the chord is a legal pretensioned cable for the exact analysis."""
    paper_case["cable"]["S"] = [100.0, 100.0, 100.0]  # 300 m < chord 300.67 m
    write_case(paper_case, "taut.yaml")
    rc, out, err, exc = invoke_cli("static", "taut.yaml", "-o", "taut.h5")
    assert rc == 0, (err, exc)
    h5 = tmp_path / "taut.h5"
    assert_png(tmp_path / "taut.png")
    with h5py.File(h5, "r") as f:
        assert set(f["static"]) == {"P", "exact"}
        assert f["modal"].attrs["analysis"] == "exact"
        T = f["static/exact/T"][()]
    assert np.all(T > 0)
    assert all(h5_units(h5).values())
    assert_matches_run_static(h5, run_static(load_case(tmp_path / "taut.yaml")[0]))


def test_upward_loads_do_not_slacken_the_cable(invoke_cli, tmp_path, write_case, paper_case):
    """A large upward (negative) load alone cannot slacken a segment: with no horizontal loads the
    horizontal force component is the same, and positive, in every segment (the cable just takes an
    inverted shape). This guards against a false 'slack' report."""
    paper_case["loads"]["F0"] = [0.0, -5000e3, 0.0, 100e3]
    write_case(paper_case, "up.yaml")
    rc, _, err, exc = invoke_cli("static", "up.yaml", "--no-plot", "-o", "up.h5")
    assert rc == 0, (err, exc)
    data = h5_datasets(tmp_path / "up.h5")
    assert np.all(data["static/exact/T"] > 1e6)
    assert data["static/exact/y"][1] < 0  # node 1 is above support A (vertical axis down)


def test_one_node_cable_has_no_finite_inextensible_frequency(invoke_cli, tmp_path, write_case):
    write_case({"cable": {"L": 100.0, "H": 0.0, "S": [60.0, 60.0], "EA": 1e8, "masses": [1000.0]},
                "loads": {"F0": [0.0, 1e4]}}, "one.yaml")
    rc, _, err, _ = invoke_cli("static", "one.yaml", "--no-plot")
    assert rc == 0, err
    data = h5_datasets(tmp_path / "runs/one/static.h5")
    assert data["modal/omega"].shape == (2,)
    assert data["modal/inextensible_omega"].size == 0


# ----------------------------------------------------------------------------------------------
# bad input: real processes (exit status, no traceback, nothing written)
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "name, needles",
    [
        ("malformed-yaml", ["not valid YAML", "line 2"]),
        ("slack-segment", ["Segment 2", "slack"]),
        ("missing-file", ["does not exist", "nope.yaml"]),
    ],
)
def test_bad_input_in_a_real_process(real_runs, name, needles):
    cwd, res = real_runs[name]
    assert_user_error(res, cwd, *needles)


# ----------------------------------------------------------------------------------------------
# bad input: in-process, every kind
# ----------------------------------------------------------------------------------------------
def _mutate(fn):
    def build(d, text):
        fn(d)
        return d

    return build


def _replace(old, new, *more):
    """Edit the shipped config text: replace old by new (and further old, new pairs)."""
    pairs = [(old, new), *zip(more[::2], more[1::2])]

    def build(d, text):
        for o, n in pairs:
            assert o in text
            text = text.replace(o, n, 1)
        return text

    return build


def _set(section, key, value):
    return _mutate(lambda d: d[section].__setitem__(key, value))


def _drop(section, key=None):
    return _mutate(lambda d: d.pop(section) if key is None else d[section].pop(key))


def _ea(value):
    def fn(d):
        d["cable"].pop("E")
        d["cable"].pop("A")
        d["cable"]["EA"] = value

    return _mutate(fn)


def _short(d):
    d["cable"]["S"] = [100.0, 100.0, 100.0]


def _short_approx(d):
    _short(d)
    d["analysis"] = "approximate"


BAD = [
    # id, builder, extra args, needles
    ("malformed-yaml", lambda d, t: "cable:\n  L: [300.0\nloads: x\n", [], ["not valid YAML", "line"]),
    ("tab-indent", lambda d, t: t.replace("  L: 300.0", "\tL: 300.0"), [], ["not valid YAML", "line"]),
    ("empty-file", lambda d, t: "", [], ["must be a YAML mapping", "`cable` and `loads`"]),
    ("top-level-list", lambda d, t: "- cable\n- loads\n", [], ["must be a YAML mapping"]),
    ("missing-cable", _drop("cable"), [], ["`cable` is required"]),
    ("missing-loads", _drop("loads"), [], ["`loads` is required"]),
    ("missing-L", _drop("cable", "L"), [], ["`cable.L` is required"]),
    ("missing-S", _drop("cable", "S"), [], ["`cable.S` is required"]),
    ("missing-masses", _drop("cable", "masses"), [], ["`cable.masses` is required"]),
    ("missing-F0", _drop("loads", "F0"), [], ["`loads.F0` is required"]),
    ("missing-rigidity", _mutate(lambda d: (d["cable"].pop("E"), d["cable"].pop("A"))), [], ["`cable`", "EA"]),
    ("E-without-A", _drop("cable", "A"), [], ["`cable`", "EA", "A (m^2)"]),
    ("EA-and-E-A", _set("cable", "EA", 1e9), [], ["`cable`", "not both"]),
    ("masses-too-few", _set("cable", "masses", [8000.0]), [], ["cable.masses", "cable.S", "n = 2 masses"]),
    ("masses-too-many", _set("cable", "masses", [1.0, 2.0, 3.0]), [], ["cable.masses has 3 values", "cable.S"]),
    ("S-too-many", _set("cable", "S", [130.0, 100.0, 110.0, 10.0]), [], ["cable.masses", "cable.S has 4"]),
    ("S-single", _set("cable", "S", [340.0]), [], ["`cable.S`"]),
    ("F0-too-short", _set("loads", "F0", [1.0, 2.0, 3.0]), [], ["loads.F0 has 3 values", "2n = 4"]),
    ("F0-too-long", _set("loads", "F0", [1.0] * 7), [], ["loads.F0 has 7 values", "2n = 4", "3n = 6"]),
    ("F0-n-not-2n", _set("loads", "F0", [300e3, 1100e3]), [], ["loads.F0 has 2 values"]),
    ("FL-too-long", _set("loads", "FL", [1.0] * 5), [], ["loads.FL has 5 values", "2n = 4"]),
    ("FL-empty", _set("loads", "FL", []), [], ["loads.FL has 0 values"]),
    ("L-zero", _set("cable", "L", 0.0), [], ["`cable.L`", "greater than 0"]),
    ("L-negative", _set("cable", "L", -300.0), [], ["`cable.L`", "greater than 0"]),
    ("S-zero", _set("cable", "S", [130.0, 0.0, 110.0]), [], ["`cable.S`", "item 2", "positive"]),
    ("S-negative", _set("cable", "S", [-130.0, 100.0, 110.0]), [], ["`cable.S`", "item 1", "positive"]),
    ("EA-zero", _ea(0.0), [], ["`cable.EA`", "greater than 0"]),
    ("EA-negative", _ea(-1e9), [], ["`cable.EA`", "greater than 0"]),
    ("E-negative", _set("cable", "E", -2e11), [], ["`cable.E`", "greater than 0"]),
    ("A-zero", _set("cable", "A", 0.0), [], ["`cable.A`", "greater than 0"]),
    ("mass-zero", _set("cable", "masses", [8000.0, 0.0]), [], ["`cable.masses`", "item 2", "positive"]),
    ("mass-negative", _set("cable", "masses", [-8000.0, 14000.0]), [], ["`cable.masses`", "item 1"]),
    ("H-nan", _replace("H: 20.0", "H: .nan"), [], ["`cable.H`", "finite", "NaN"]),
    ("L-inf", _replace("L: 300.0", "L: .inf"), [], ["`cable.L`", "finite"]),
    ("S-inf", _replace("S: [130.0, 100.0", "S: [130.0, .inf"), [], ["`cable.S[2]`", "finite"]),
    ("E-inf", _replace("E: 2.0e11", "E: .inf"), [], ["`cable.E`", "finite"]),
    ("EA-nan", _replace("  E: 2.0e11", "  # E", "  A: 0.005", "  EA: .nan"), [], ["`cable.EA`", "finite"]),
    ("mass-minus-inf", _replace("masses: [8000.0, 14000.0]", "masses: [8000.0, -.inf]"), [],
     ["`cable.masses[2]`", "finite"]),
    ("F0-nan", _replace("F0: [300.0e3, 1100.0e3", "F0: [300.0e3, .nan"), [], ["`loads.F0[2]`", "finite"]),
    ("FL-inf", _replace("FL: [-6.0e3", "FL: [-.Inf"), [], ["`loads.FL[1]`", "finite"]),
    ("ratio-nan", _replace("ratio: 0.01", "ratio: .nan"), [], ["`damping.ratio`", "finite"]),
    ("typo-mases", _replace("  masses: [", "  mases: ["), [], ["`cable.mases` is not a known key", "spelling"]),
    ("typo-top-level", _replace("analysis: exact", "analyis: exact"), [], ["`analyis` is not a known key"]),
    ("typo-damping", _replace("modes: [1, 2]", "mode: [1, 2]"), [], ["`damping.mode` is not a known key"]),
    ("typo-loads", _replace("  FL: [", "  Fl: ["), [], ["`loads.Fl` is not a known key"]),
    ("bad-analysis", _replace("analysis: exact", "analysis: exakt"), [], ["`analysis`", "'exact' or 'approximate'"]),
    ("bad-name", _replace("# name: my-case", "name: paper example"), [], ["`name`", "letters, digits"]),
    ("damping-modes-beyond-2n", _replace("modes: [1, 2]", "modes: [1, 5]"), [], ["damping.modes", "2n = 4"]),
    ("damping-ratio-and-a0", _replace("modes: [1, 2]", "a0: 0.1"), [], ["`damping`", "not both"]),
    ("too-short-approximate", _mutate(_short_approx), [], ["cable.S", "chord", "analysis: exact"]),
    ("too-short-flag-approximate", _mutate(_short), ["--analysis", "approximate"], ["cable.S", "chord", "Lengthen"]),
    ("slack-inward-loads", _set("loads", "F0", [1000e3, 0.0, -1000e3, 0.0]), [], ["Segment 2", "slack", "loads"]),
    ("slack-inward-loads-approximate", _set("loads", "F0", [1000e3, 0.0, -1000e3, 0.0]),
     ["--analysis", "approximate"], ["Segment 2", "slack"]),
    ("slack-no-load", _set("loads", "F0", [0.0, 0.0, 0.0, 0.0]), [], ["Segment", "slack"]),
]


@pytest.mark.parametrize("build, extra, needles", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input(invoke_cli, tmp_path, paper_case, build, extra, needles):
    content = build(paper_case, CONFIG_EXAMPLE.read_text())
    path = tmp_path / "case.yaml"
    path.write_text(content if isinstance(content, str) else yaml.safe_dump(content, sort_keys=False))
    res = invoke_cli("static", "case.yaml", *extra)
    msg = assert_user_error(res, tmp_path, *needles)
    assert len(msg) < 600, "one short paragraph"


def test_bad_input_with_output_option_leaves_nothing(invoke_cli, tmp_path, write_case, paper_case):
    paper_case["loads"]["F0"] = [1000e3, 0.0, -1000e3, 0.0]
    write_case(paper_case, "slack.yaml")
    res = invoke_cli("static", "slack.yaml", "-o", "out/res.h5")
    assert_user_error(res, tmp_path, "Segment 2")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("target", ["nope.yaml", "missing-dir/nope.yaml", "."], ids=["file", "dir-path", "a-directory"])
def test_unreadable_case_file(invoke_cli, tmp_path, target):
    res = invoke_cli("static", target)
    assert_user_error(res, tmp_path, "Case file")


@pytest.mark.parametrize("E, A", [(1e200, 1e200), (1e-200, 1e-200)], ids=["EA-overflows", "EA-underflows"])
def test_E_times_A_out_of_range(invoke_cli, tmp_path, write_case, paper_case, E, A):
    paper_case["cable"].update(E=E, A=A)
    write_case(paper_case, "ea.yaml")
    res = invoke_cli("static", "ea.yaml", "--no-plot")
    msg = assert_user_error(res, tmp_path)
    assert re.search(r"cable\.E|cable\.A|EA", msg)


def test_null_name(invoke_cli, tmp_path, write_case):
    write_case(CONFIG_EXAMPLE.read_text().replace("# name: my-case", "name:"), "nullname.yaml")
    rc, out, err, exc = invoke_cli("static", "nullname.yaml", "--no-plot")
    if rc == 0:
        assert (tmp_path / "runs" / "nullname" / "static.h5").is_file()
    else:
        assert_user_error((rc, out, err, exc), tmp_path, "name")
