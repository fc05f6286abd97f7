"""Case files: parse_case / load_case, defaults, validation and its messages."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from cablesim.analyses.static import run_static
from cablesim.case import Case, example_text, load_case, parse_case
from cablesim.errors import CablesimError

CONFIG_EXAMPLE = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"

# A complete case with every optional key left out.
MINIMAL = """\
cable:
  L: 300.0
  H: 20.0
  S: [130.0, 100.0, 110.0]
  EA: 1.0e9
  masses: [8000.0, 14000.0]
loads:
  F0: [300.0e3, 1100.0e3, 450.0e3, 2000.0e3]
"""


def minimal(**sections) -> dict:
    """MINIMAL as a dict, with top-level keys replaced or added."""
    d = yaml.safe_load(MINIMAL)
    d["cable"]["EA"] = 1.0e9  # plain YAML reads "1.0e9" as a string
    d["loads"]["F0"] = [300.0e3, 1100.0e3, 450.0e3, 2000.0e3]
    d.update(sections)
    return d


def text_of(d: dict) -> str:
    return yaml.safe_dump(d, sort_keys=False)


def flat(msg: str) -> str:
    return " ".join(msg.split())


def parse_error(text: str, source: str = "<case>") -> str:
    with pytest.raises(CablesimError) as info:
        parse_case(text, source=source)
    msg = str(info.value)
    assert "\n" not in msg, "a case-file message is one paragraph on one line"
    return msg


# ----------------------------------------------------------------------------------------------
# defaults
# ----------------------------------------------------------------------------------------------
def test_defaults_of_a_minimal_case():
    case = parse_case(MINIMAL)
    assert case.analysis == "exact"
    assert case.damping.ratio == 0.01
    assert case.damping.modes == (1, 2)
    assert case.damping.a0 is None and case.damping.a1 is None
    assert case.loads.FL is None
    np.testing.assert_array_equal(case.FL, np.zeros(4))
    np.testing.assert_array_equal(case.F0, [300e3, 1100e3, 450e3, 2000e3])
    assert case.name == "case"  # parse_case's default_name
    assert case.cable.n_nodes == 2
    assert case.cable.axial_rigidity == 1.0e9


def test_default_name_argument_and_explicit_name():
    assert parse_case(MINIMAL, default_name="abc").name == "abc"
    assert parse_case("name: given-name\n" + MINIMAL, default_name="abc").name == "given-name"


def test_load_case_name_from_file_stem(tmp_path):
    p = tmp_path / "my-cable.v2.yaml"
    p.write_text(MINIMAL)
    case, text = load_case(p)
    assert case.name == "my-cable.v2"
    assert text == MINIMAL + "# cablesim name (the case file's): my-cable.v2\n"
    assert parse_case(text).name == "my-cable.v2"  # the stored text re-reads under the file's name


def test_load_case_stem_is_sanitised(tmp_path):
    p = tmp_path / "my cable (draft).yaml"
    p.write_text(MINIMAL)
    case, _ = load_case(p)
    assert case.name == "my-cable--draft-"


def test_load_case_explicit_name_wins_over_stem(tmp_path):
    p = tmp_path / "file-stem.yaml"
    p.write_text("name: from-file\n" + MINIMAL)
    assert load_case(p)[0].name == "from-file"


def test_load_case_stem_starting_with_underscore(tmp_path):
    p = tmp_path / "_draft.yaml"
    p.write_text(MINIMAL)
    case, _ = load_case(p)
    assert case.name


def test_null_name_falls_back_to_default_or_is_an_error():
    try:
        case = parse_case("name:\n" + MINIMAL, default_name="stem")
    except CablesimError as err:
        assert "name" in str(err)
    else:
        assert case.name == "stem"


def test_load_case_none_is_the_embedded_paper_example():
    case, text = load_case(None)
    assert text == example_text() + "# cablesim name (the case file's): paper-example\n"  # re-read under its name
    assert case.name == "paper-example"
    assert case == load_case(CONFIG_EXAMPLE)[0]


def test_paper_example_values():
    case, _ = load_case(CONFIG_EXAMPLE)
    c = case.cable
    assert (c.L, c.H, c.S, c.masses) == (300.0, 20.0, (130.0, 100.0, 110.0), (8000.0, 14000.0))
    assert c.axial_rigidity == pytest.approx(1e9, rel=1e-12)
    assert case.loads.F0 == (300e3, 1100e3, 450e3, 2000e3)
    assert case.loads.FL == (-6e3, 22e3, -18e3, 120e3)
    assert case.analysis == "exact"
    assert (case.damping.ratio, case.damping.modes) == (0.01, (1, 2))


def test_example_text_is_commented_yaml():
    text = example_text()
    assert text.lstrip().startswith("#")
    assert sum(line.lstrip().startswith("#") for line in text.splitlines()) >= 3
    assert parse_case(text, default_name="paper-example", record_name=True) == load_case(CONFIG_EXAMPLE)[0]


# ----------------------------------------------------------------------------------------------
# EA, or E and A
# ----------------------------------------------------------------------------------------------
def test_E_times_A():
    d = minimal()
    del d["cable"]["EA"]
    d["cable"].update(E=2.0e11, A=0.005)
    case = parse_case(text_of(d))
    assert case.cable.EA is None
    assert case.cable.axial_rigidity == pytest.approx(1.0e9, rel=1e-12)
    assert case.to_cable().EA == pytest.approx(1.0e9, rel=1e-12)


def test_EA_and_E_A_give_the_same_statics():
    d = minimal()
    del d["cable"]["EA"]
    d["cable"].update(E=2.0e11, A=0.005)
    r1 = run_static(parse_case(MINIMAL))
    r2 = run_static(parse_case(text_of(d)))
    np.testing.assert_allclose(r2.exact.y, r1.exact.y, rtol=1e-12)
    np.testing.assert_allclose(r2.modes.omega, r1.modes.omega, rtol=1e-9)


@pytest.mark.parametrize(
    "rigidity, needles",
    [
        ({}, ["`cable`", "EA", "E (N/m^2) and A"]),
        ({"E": 2e11}, ["`cable`", "EA", "both E"]),
        ({"A": 0.005}, ["`cable`", "EA"]),
        ({"EA": 1e9, "E": 2e11}, ["`cable`", "either EA or E and A, not both"]),
        ({"EA": 1e9, "E": 2e11, "A": 0.005}, ["`cable`", "not both"]),
        ({"EA": 0.0}, ["`cable.EA`", "greater than 0"]),
        ({"E": -2e11, "A": 0.005}, ["`cable.E`", "greater than 0"]),
        ({"E": 2e11, "A": 0.0}, ["`cable.A`", "greater than 0"]),
    ],
    ids=["none", "E-only", "A-only", "EA-and-E", "EA-and-E-A", "EA-zero", "E-negative", "A-zero"],
)
def test_rigidity_errors(rigidity, needles):
    d = minimal()
    del d["cable"]["EA"]
    d["cable"].update(rigidity)
    msg = parse_error(text_of(d))
    for needle in needles:
        assert needle in msg


# ----------------------------------------------------------------------------------------------
# numbers written like 1.0e9 (YAML 1.1 reads them as strings)
# ----------------------------------------------------------------------------------------------
def test_plain_yaml_reads_1e9_as_a_string():
    """The reason for cablesim's loader; also: importing cablesim must not change PyYAML."""
    assert yaml.safe_load("x: 1.0e9")["x"] == "1.0e9"
    assert yaml.safe_load("x: 1e9")["x"] == "1e9"


@pytest.mark.parametrize("written", ["1.0e9", "1e9", "1E9", "1.0E+9", "+1.0e9", "1.e9", "10.0e+08", "1_000.0e6"])
def test_exponent_numbers_are_floats(written):
    case = parse_case(MINIMAL.replace("EA: 1.0e9", f"EA: {written}"))
    assert isinstance(case.cable.EA, float)
    assert case.cable.EA == 1.0e9


def test_exponent_numbers_everywhere():
    text = """\
cable:
  L: 3.0e2
  H: -2e1
  S: [1.3e2, 1e2, 1.1E2]
  EA: 1e9
  masses: [8.0e3, 1.4e4]
loads:
  F0: [3.0e5, 1.1e6, 4.5e5, 2e6]
  FL: [-6.0e3, 2.2e4, -1.8e4, 1.2e5]
damping:
  a0: 5e-2
  a1: 1.0e-3
"""
    case = parse_case(text)
    c = case.cable
    assert (c.L, c.H, c.S, c.EA, c.masses) == (300.0, -20.0, (130.0, 100.0, 110.0), 1e9, (8000.0, 14000.0))
    assert case.loads.F0 == (3e5, 1.1e6, 4.5e5, 2e6)
    assert case.loads.FL == (-6e3, 2.2e4, -1.8e4, 1.2e5)
    assert (case.damping.a0, case.damping.a1) == (0.05, 0.001)
    assert all(type(v) is float for v in (*c.S, *c.masses, *case.loads.F0, *case.loads.FL))


def test_integers_stay_valid():
    case = parse_case(MINIMAL.replace("L: 300.0", "L: 300").replace("S: [130.0, 100.0, 110.0]", "S: [130, 100, 110]"))
    assert case.cable.L == 300.0
    assert case.cable.S == (130.0, 100.0, 110.0)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    x=st.floats(min_value=1e-30, max_value=1e30, allow_nan=False, allow_infinity=False),
    fmt=st.sampled_from(["{:e}", "{:E}", "{:.3e}", "{!r}", "{:.0e}", "{:g}"]),
)
def test_any_exponent_spelling_of_EA_parses_to_its_value(x, fmt):
    written = fmt.format(x)
    case = parse_case(MINIMAL.replace("EA: 1.0e9", f"EA: {written}"))
    assert case.cable.EA == float(written)


# ----------------------------------------------------------------------------------------------
# damping
# ----------------------------------------------------------------------------------------------
def test_damping_ratio_in_chosen_modes():
    case = parse_case(text_of(minimal(damping={"ratio": 0.02, "modes": [1, 3]})))
    assert case.damping.modes == (1, 3)
    r = run_static(case)
    np.testing.assert_allclose(r.damping_ratios[[0, 2]], 0.02, rtol=1e-10)
    w = r.modes.omega
    np.testing.assert_allclose(r.damping_ratios, r.a0 / (2 * w) + r.a1 * w / 2, rtol=1e-10)


def test_damping_a0_a1_alternative():
    case = parse_case(text_of(minimal(damping={"a0": 0.05, "a1": 1.0e-3})))
    d = case.damping
    assert (d.ratio, d.a0, d.a1) == (None, 0.05, 1.0e-3)
    r = run_static(case)
    assert (r.a0, r.a1) == (0.05, 1.0e-3)
    w = r.modes.omega
    np.testing.assert_allclose(r.damping_ratios, 0.05 / (2 * w) + 1e-3 * w / 2, rtol=1e-12)


def test_damping_zero_coefficients_are_allowed():
    case = parse_case(text_of(minimal(damping={"a0": 0.0, "a1": 0.0})))
    assert (case.damping.a0, case.damping.a1) == (0.0, 0.0)


@pytest.mark.parametrize(
    "damping, needles",
    [
        ({"a0": 0.1}, ["`damping`", "needs both a0 and a1"]),
        ({"a1": 0.1}, ["`damping`", "needs both a0 and a1"]),
        ({"ratio": 0.01, "a0": 0.1, "a1": 0.1}, ["`damping`", "not both"]),
        ({}, ["`damping`", "damping.ratio"]),
        ({"modes": [1, 2]}, ["damping.ratio"]),
        ({"ratio": -0.01}, ["`damping.ratio`"]),
        ({"ratio": 1.0}, ["`damping.ratio`"]),
        ({"ratio": float("nan")}, ["`damping.ratio`", "finite"]),
        ({"ratio": 0.01, "modes": [1, 1]}, ["damping.modes", "two different mode numbers"]),
        ({"ratio": 0.01, "modes": [0, 2]}, ["damping.modes"]),
        ({"ratio": 0.01, "modes": [1, 5]}, ["damping.modes", "2n = 4"]),
        ({"ratio": 0.01, "modes": [1, 2, 3]}, ["`damping.modes`"]),
        ({"a0": -1.0, "a1": 0.0}, ["`damping.a0`"]),
        ({"a0": 0.0, "a1": float("inf")}, ["`damping.a1`", "finite"]),
        ({"ratio": 0.01, "ratoi": 0.01}, ["`damping.ratoi`", "not a known key"]),
    ],
    ids=[
        "a0-only", "a1-only", "ratio-and-a0-a1", "empty", "modes-only", "ratio-negative",
        "ratio-one", "ratio-nan", "modes-equal", "modes-zero", "modes-beyond-2n", "three-modes",
        "a0-negative", "a1-inf", "typo",
    ],
)
def test_damping_errors(damping, needles):
    msg = parse_error(text_of(minimal(damping=damping)))
    for needle in needles:
        assert needle in msg, msg


# ----------------------------------------------------------------------------------------------
# frozen model
# ----------------------------------------------------------------------------------------------
def test_case_is_frozen():
    case = parse_case(MINIMAL)
    with pytest.raises(ValidationError):
        case.analysis = "approximate"
    with pytest.raises(ValidationError):
        case.name = "other"
    with pytest.raises(ValidationError):
        case.cable.L = 1.0
    with pytest.raises(ValidationError):
        case.loads.F0 = (0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValidationError):
        case.damping.ratio = 0.5
    with pytest.raises(TypeError):
        case.cable.S[0] = 1.0  # tuples
    assert case == parse_case(MINIMAL)


def test_derived_arrays_do_not_alias_the_case():
    case = parse_case(MINIMAL)
    case.F0[0] = -1.0
    case.FL[0] = -1.0
    assert case.loads.F0[0] == 300e3 and case.cable.S[0] == 130.0


# ----------------------------------------------------------------------------------------------
# validation messages
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "section, key, dotted",
    [
        ("cable", "mases", "cable.mases"),
        ("loads", "F1", "loads.F1"),
        ("damping", "mode", "damping.mode"),
        (None, "analyis", "analyis"),
        (None, "Cable", "Cable"),
    ],
)
def test_unknown_key_names_the_dotted_path(section, key, dotted):
    d = minimal(damping={"ratio": 0.01})
    if section is None:
        d[key] = "x"
    elif section == "cable" and key == "mases":
        d["cable"]["mases"] = d["cable"].pop("masses")
    else:
        d[section][key] = [1.0, 2.0]
    msg = parse_error(text_of(d), source="cases/x.yaml")
    assert f"`{dotted}` is not a known key" in msg
    assert "cases/x.yaml" in msg
    assert "cablesim example" in msg
    if key == "mases":
        assert "`cable.masses` is required" in msg


@pytest.mark.parametrize(
    "path, value, needle",
    [
        (("cable", "L"), 0.0, "`cable.L`"),
        (("cable", "L"), -300.0, "`cable.L`"),
        (("cable", "S"), [130.0, 0.0, 110.0], "`cable.S` every value must be a positive finite number; item 2"),
        (("cable", "S"), [130.0, -100.0, 110.0], "`cable.S` every value must be a positive finite number; item 2"),
        (("cable", "masses"), [8000.0, 0.0], "`cable.masses` every value must be a positive finite number; item 2"),
        (("cable", "masses"), [-8000.0, 14000.0], "item 1"),
        (("cable", "H"), float("nan"), "`cable.H` must be a finite number, not NaN or infinity"),
        (("cable", "L"), float("inf"), "`cable.L` must be a finite number"),
        (("cable", "EA"), float("inf"), "`cable.EA` must be a finite number"),
        (("cable", "S"), [130.0, float("inf"), 110.0], "`cable.S[2]` must be a finite number"),
        (("cable", "masses"), [8000.0, float("-inf")], "`cable.masses[2]` must be a finite number"),
        (("loads", "F0"), [300e3, float("nan"), 450e3, 2000e3], "`loads.F0[2]` must be a finite number"),
        (("loads", "FL"), [0.0, 0.0, 0.0, float("nan")], "`loads.FL[4]` must be a finite number"),
        (("cable", "masses"), [8000.0], "cable.masses has 1 values but cable.S has 3 segments"),
        (("cable", "S"), [130.0, 100.0, 110.0, 10.0], "cable.masses has 2 values but cable.S has 4 segments"),
        (("cable", "S"), [340.0], "`cable.S`"),
        (("loads", "F0"), [1.0, 2.0, 3.0], "loads.F0 has 3 values; this cable has n = 2 interior nodes, so it needs 2n = 4"),
        (("loads", "FL"), [1.0, 2.0, 3.0, 4.0, 5.0], "loads.FL has 5 values"),
        (("loads", "F0"), "lots", "`loads.F0`"),
        (("cable", "masses"), [8000.0, "heavy"], "`cable.masses[2]`"),
        (("analysis",), "exakt", "`analysis`"),
        (("name",), "bad name", "`name`"),
        (("cable",), 5, "`cable`"),
    ],
)
def test_field_errors_name_the_field(path, value, needle):
    d = minimal()
    target = d
    for p in path[:-1]:
        target = target[p]
    target[path[-1]] = value
    text = text_of(d)
    if isinstance(value, float) and math.isnan(value) or value in (float("inf"),):
        assert ".nan" in text or ".inf" in text  # really the YAML spelling
    assert needle in parse_error(text)


@pytest.mark.parametrize(
    "drop, needle",
    [(("cable",), "`cable` is required; add it"), (("loads",), "`loads` is required"),
     (("cable", "L"), "`cable.L` is required"), (("cable", "S"), "`cable.S` is required"),
     (("cable", "masses"), "`cable.masses` is required"), (("loads", "F0"), "`loads.F0` is required")],
)
def test_missing_keys(drop, needle):
    d = minimal()
    target = d
    for p in drop[:-1]:
        target = target[p]
    del target[drop[-1]]
    assert needle in parse_error(text_of(d))


def test_several_problems_in_one_message():
    d = minimal()
    del d["cable"]["L"]
    d["cable"]["masses"] = [8000.0, -1.0]
    msg = parse_error(text_of(d))
    assert "`cable.L` is required" in msg and "`cable.masses`" in msg and "; " in msg


@pytest.mark.parametrize(
    "text, needles",
    [
        ("cable: [1, 2\nloads: {", ["not valid YAML", "line 2"]),
        ("cable:\n\tL: 3\n", ["not valid YAML", "line 2"]),
        ("", ["must be a YAML mapping", "`cable` and `loads`"]),
        ("- 1\n- 2\n", ["must be a YAML mapping"]),
        ("just a string", ["must be a YAML mapping"]),
    ],
    ids=["unclosed", "tab", "empty", "list", "scalar"],
)
def test_yaml_level_errors(text, needles):
    msg = parse_error(text, source="bad.yaml")
    assert "bad.yaml" in msg
    for needle in needles:
        assert needle in msg


def test_load_case_missing_file(tmp_path):
    with pytest.raises(CablesimError, match="does not exist"):
        load_case(tmp_path / "nope.yaml")


def test_load_case_directory(tmp_path):
    with pytest.raises(CablesimError, match="cannot be read"):
        load_case(tmp_path)


# ----------------------------------------------------------------------------------------------
# robustness: any value in any field gives a Case or a CablesimError, never another exception
# ----------------------------------------------------------------------------------------------
_FIELDS = [
    ("name",), ("analysis",), ("cable",), ("loads",), ("damping",),
    ("cable", "L"), ("cable", "H"), ("cable", "S"), ("cable", "EA"), ("cable", "masses"),
    ("loads", "F0"), ("loads", "FL"),
    ("damping", "ratio"), ("damping", "modes"), ("damping", "a0"),
]
_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-10**6, 10**6),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=8),
)
_values = st.one_of(_scalars, st.lists(_scalars, max_size=6), st.dictionaries(st.text(max_size=4), _scalars, max_size=2))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(_FIELDS), value=_values)
def test_any_value_gives_a_case_or_a_cablesim_error(path, value):
    d = minimal(damping={"ratio": 0.01})
    target = d
    for p in path[:-1]:
        target = target[p]
    target[path[-1]] = value
    try:
        case = parse_case(text_of(d))
    except CablesimError as err:
        assert "\n" not in str(err)
    else:
        assert isinstance(case, Case)
