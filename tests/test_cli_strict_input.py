"""Strict case files at the command line: every malformed or implausible input is refused with
exit status 2 and one paragraph naming the field (or the line) and the fix, and no file is left.

Each case here was once read silently as something else, or crashed with a traceback.
"""

from __future__ import annotations

import string

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cablesim.case import parse_case
from cablesim.errors import CablesimError
from helpers_cli import EXAMPLE, assert_refused, example_with


def _line(start: str) -> int:
    """The line number (from 1) of the example's first line starting with ``start``."""
    return next(i for i, line in enumerate(EXAMPLE.splitlines(), 1) if line.startswith(start))

A0A1 = ("  ratio: 0.01              # Rayleigh damping: this ratio in the two modes below\n"
        "  modes: [1, 2]            # which two modes get it (counted from 1)\n")

REFUSED = {
    # silently wrong numbers
    "duplicate-key": (example_with(("  H: 20.0", "  L: 200.0\n  H: 20.0")),
                      ["`L` appears twice in `cable`", f"lines {_line('  L: 300.0')} and {_line('  L: 300.0') + 1}",
                       "Keep one"]),
    "second-loads-section": (EXAMPLE + "\nloads:\n  F0: [1.0, 2.0, 3.0, 4.0]\n",
                             ["`loads` appears twice at the top level", f"lines {_line('loads:')} and"]),
    "booleans-as-masses": (example_with(("masses: [8000.0, 14000.0]", "masses: [true, yes]")),
                           ["`cable.masses[1]` must be a number, not true/false", "`cable.masses[2]`"]),
    "octal": (example_with(("H: 20.0", "H: 020")), ["`cable.H`", "octal number 16", "plain decimal"]),
    "base-60": (example_with(("L: 300.0", "L: 5:00")), ["`cable.L`", "base-60", "300"]),
    "hexadecimal": (example_with(("L: 300.0", "L: 0x12C")), ["`cable.L`", "hexadecimal"]),
    "quoted-number": (example_with(("L: 300.0", "L: '300'")), ["`cable.L` must be a number, not text"]),
    "EA-1e30": (example_with(("  E: 2.0e11", "  EA: 1.0e30\n  #E: 2.0e11"), ("  A: 0.005", "  #A: 0.005")),
                ["cable.EA = 1e+30 N is too stiff", "double precision", "at most", "refused rather than treated as inextensible"]),
    "EA-1e20": (example_with(("  E: 2.0e11", "  EA: 1.0e20\n  #E: 2.0e11"), ("  A: 0.005", "  #A: 0.005")),
                ["cable.EA", "too stiff"]),
    # tracebacks
    "loads-1e308": (example_with(("F0: [300.0e3", "F0: [1.0e308")), ["`loads.F0`", "item 1", "-1e+12 to 1e+12 N"]),
    "a0-a1-1e308": (example_with((A0A1, "  a0: 1.0e308\n  a1: 1.0e308\n")),
                    ["`damping.a0` must be from 0 to 10000 1/s", "`damping.a1`"]),
    "nested-brackets": ("cable: " + "[" * 10000 + "]" * 10000 + "\n", ["nests lists and mappings more than", "line 1"]),
    "alias-bomb": ("a: &a [x, x, x, x, x, x, x, x, x]\n"
                   + "".join(f"{c}: &{c} [{', '.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi")),
                   ["expands to more than", "aliases"]),
    "recursive-alias": ("cable: &c [*c]\n", ["contains itself"]),
    "segment-1e-300": (example_with(("S: [130.0, 100.0, 110.0]", "S: [1.0e-300, 100.0, 110.0]")),
                       ["`cable.S`", "from 0.001 to 1e+06 m", "item 1"]),
    "dt-1e-300": (EXAMPLE + "integrator:\n  name: rk4\n  dt: 1.0e-300\n", ["`integrator.dt` must be from 1e-09 to 1000 s"]),
    "20000-nodes": (example_with(("S: [130.0, 100.0, 110.0]", "S: [" + ", ".join(["0.02"] * 20001) + "]")),
                    ["`cable.S`", "at most 2000 interior nodes"]),
    "name-too-long": (example_with(("# name: my-case", "name: " + "a" * 300)), ["`name` is 300 characters long"]),
    # misleading
    "all-zero-loads": (example_with(("F0: [300.0e3, 1100.0e3, 450.0e3, 2000.0e3]", "F0: [0.0, 0.0, 0.0, 0.0]")),
                       ["loads.F0 is all zero", "no definite shape", "Give the sustained nodal loads"]),
}


@pytest.mark.parametrize("name", REFUSED)
def test_refused_case_files(name, invoke_cli, write_case, tmp_path):
    text, needles = REFUSED[name]
    case = write_case(text)
    res = invoke_cli("static", case, "--no-plot")
    msg = assert_refused(res, tmp_path, *needles, keep=())
    assert len(msg) < 1200


def test_a_character_device_as_the_case_is_refused(invoke_cli, tmp_path):
    assert_refused(invoke_cli("static", "/dev/zero", "--no-plot"), tmp_path, "/dev/zero", "not a regular file")


def test_a_huge_case_file_is_refused_before_reading(invoke_cli, tmp_path):
    big = tmp_path / "big.yaml"
    with open(big, "w") as f:
        f.write("# padding\n" * 200_000)
    assert_refused(invoke_cli("static", big, "--no-plot"), tmp_path, "more than the 1000000")


def test_binary_case_file(invoke_cli, tmp_path):
    p = tmp_path / "bin.yaml"
    p.write_bytes(b"\xff\xfe\x00\x01" * 10)
    assert_refused(invoke_cli("static", p, "--no-plot"), tmp_path, "not UTF-8 text")


def test_ambiguous_numbers_in_set_are_refused(invoke_cli, tmp_path):
    assert_refused(invoke_cli("static", "--set", "cable.H=020", "--no-plot"), tmp_path, "`cable.H`", "octal")


def test_booleans_still_read_where_a_boolean_belongs():
    case = parse_case(EXAMPLE.replace("\nsweep:", "\nsweep:\n  floquet: yes", 1))
    assert case.sweep.floquet is True


def test_plain_numbers_still_read():
    case = parse_case(example_with(("L: 300.0", "L: 3_00"), ("H: 20.0", "H: 0"), ("S: [130.0, 100.0, 110.0]",
                                                                                    "S: [130, 1.0e2, .11e3]")))
    assert (case.cable.L, case.cable.H, case.cable.S) == (300.0, 0.0, (130.0, 100.0, 110.0))


def test_large_strain_is_a_warning_not_an_error(invoke_cli, write_case, tmp_path):
    case = write_case(example_with(("S: [130.0, 100.0, 110.0]", "S: [10.0, 14.0, 10.0]")))
    res = invoke_cli("static", case, "--no-plot", "-o", "short.h5")
    assert res.returncode == 0, res.stderr
    assert "warning: the static strain T/EA of segment 1 is 784 %" in " ".join(res.stderr.split())
    assert (tmp_path / "short.h5").is_file()


# ----------------------------------------------------------------------------------------------
# fuzzing: random mutations of the example give a Case or a one-line CablesimError, nothing else
# ----------------------------------------------------------------------------------------------
_LINES = EXAMPLE.splitlines(keepends=True)
_JUNK = st.text(alphabet=string.printable + "\u00e9\u2028", min_size=0, max_size=6)
_mutation = st.one_of(
    st.tuples(st.just("delete"), st.integers(0, len(EXAMPLE) - 1), st.integers(1, 5)),
    st.tuples(st.just("insert"), st.integers(0, len(EXAMPLE)), _JUNK),
    st.tuples(st.just("duplicate-line"), st.integers(0, len(_LINES) - 1), st.integers(0, len(_LINES))),
    st.tuples(st.just("swap-lines"), st.integers(0, len(_LINES) - 1), st.integers(0, len(_LINES) - 1)),
    st.tuples(st.just("number"), st.integers(0, 200), st.sampled_from(
        ["0", "-1", "1e308", "-1e308", ".nan", ".inf", "020", "5:00", "true", "no", "0x10", "1e-300", "'3'",
         "[]", "{}", "~", "*a", "&a 1", "1_0", "[[[[1]]]]"])),
)


def _mutate(text: str, muts) -> str:
    for kind, a, b in muts:
        lines = text.splitlines(keepends=True)
        if kind == "delete":
            text = text[:a] + text[a + b:]
        elif kind == "insert":
            text = text[:a] + b + text[a:]
        elif kind == "duplicate-line" and lines:
            lines.insert(min(b, len(lines)), lines[a % len(lines)])
            text = "".join(lines)
        elif kind == "swap-lines" and lines:
            i, j = a % len(lines), b % len(lines)
            lines[i], lines[j] = lines[j], lines[i]
            text = "".join(lines)
        elif kind == "number":
            import re

            nums = list(re.finditer(r"(?<![\w.])[-+]?\d[\d.e+-]*", text))
            if nums:
                m = nums[a % len(nums)]
                text = text[: m.start()] + b + text[m.end():]
    return text


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(muts=st.lists(_mutation, min_size=1, max_size=4))
def test_fuzzed_case_files_give_a_case_or_a_one_line_error(muts):
    text = _mutate(EXAMPLE, muts)
    try:
        case = parse_case(text, source="fuzz.yaml")
    except CablesimError as err:
        msg = str(err)
        assert "\n" not in msg and msg.strip() == msg and len(msg) < 4000
        assert "Traceback" not in msg
    else:
        c = case.cable
        assert 0 < c.L <= 1e5 and all(1e-3 <= s <= 1e6 for s in c.S)
        assert all(isinstance(m, float) for m in c.masses)
