"""Case-file shorthand: cable.length/nodes/mass_per_length and loads.gravity/point expand to
exactly the explicit lists they stand for."""

from __future__ import annotations

import numpy as np
import pytest

from cablesim.case import parse_case
from cablesim.errors import CablesimError

SHORT = """\
name: heavy
cable: {L: 100.0, H: 2.0, length: 102.5, nodes: 4, EA: 2.0e8, mass_per_length: 10.0}
loads:
  gravity: 9.81
  F0: [100.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
  point: [{node: 2, F: [0.0, 5.0e3], FL: [0.0, 1.0e3], mass: 500.0}, {node: 4, F: [-1.0e3, 0.0]}]
"""


def explicit_text() -> str:
    seg = 102.5 / 5
    m = [10.0 * seg] * 4
    m[1] += 500.0
    F0 = [100.0, 9.81 * m[0], 0.0, 9.81 * m[1] + 5.0e3, 0.0, 9.81 * m[2], -1.0e3, 9.81 * m[3]]
    FL = [0.0, 0.0, 0.0, 1.0e3, 0.0, 0.0, 0.0, 0.0]
    return (
        f"name: heavy\ncable: {{L: 100.0, H: 2.0, S: {[seg] * 5}, EA: 2.0e8, masses: {m}}}\n"
        f"loads: {{F0: {F0}, FL: {FL}}}\n"
    )


def test_shorthand_expands_to_the_explicit_lists():
    short, full = parse_case(SHORT), parse_case(explicit_text())
    assert short.cable.S == pytest.approx(full.cable.S, rel=1e-15)
    np.testing.assert_allclose(short.cable.masses, full.cable.masses, rtol=1e-14)
    np.testing.assert_allclose(short.F0, full.F0, rtol=1e-14)
    np.testing.assert_allclose(short.FL, full.FL, rtol=1e-14)
    assert short.cable.n_nodes == 4
    assert short.to_cable().total_length == pytest.approx(102.5, rel=1e-14)


def test_mass_per_length_on_unequal_segments():
    case = parse_case("cable: {L: 300.0, H: 20.0, S: [130.0, 100.0, 110.0], EA: 1.0e9, mass_per_length: 2.0}\n"
                      "loads: {gravity: 10.0}\n")
    np.testing.assert_allclose(case.cable.masses, [230.0, 210.0])
    np.testing.assert_allclose(case.F0, [0.0, 2300.0, 0.0, 2100.0])
    assert case.loads.FL is None


def test_stored_text_is_expanded_and_reparses_to_the_same_case():
    case = parse_case(SHORT, overrides=["cable.length=110.0"])
    assert case.cable.S[0] == pytest.approx(22.0)
    text = case.text
    body = [line for line in text.splitlines() if not line.startswith("#")]
    assert not any(k in "\n".join(body) for k in ("length:", "nodes:", "mass_per_length", "gravity", "point"))
    assert "# | " in text and "nodes: 4" in text and "--set cable.length=110.0" in text  # the original, as comments
    again = parse_case(text)
    assert again == case
    assert again.text.count("# | ") == text.count("# | ")  # re-parsing an explicit text keeps it as it is


def test_explicit_lists_are_left_as_they_are():
    text = "cable: {L: 300.0, H: 20.0, S: [130.0, 100.0, 110.0], EA: 1.0e9, masses: [8.0e3, 1.4e4]}\n" \
           "loads: {F0: [1.0, 2.0, 3.0, 4.0]}\n"
    case = parse_case(text)
    assert case.text == text and case.loads.FL is None


def _error(text: str) -> str:
    with pytest.raises(CablesimError) as info:
        parse_case(text)
    return str(info.value)


CABLE = "cable: {L: 100.0, H: 0.0, EA: 2.0e8, %s}\n"


@pytest.mark.parametrize("cable, loads, needles", [
    ("length: 102.5, mass_per_length: 1.0", "gravity: 9.81", ["`cable.nodes` is required"]),
    ("nodes: 3, mass_per_length: 1.0", "gravity: 9.81", ["`cable.length` is required"]),
    ("length: 102.5, nodes: 0, mass_per_length: -1.0", "gravity: 9.81", ["`cable.nodes`", "`cable.mass_per_length`"]),
    ("length: -1.0, nodes: 3, mass_per_length: 1.0", "gravity: 9.81", ["`cable.length`"]),
    ("length: 102.5, nodes: 2.5, mass_per_length: 1.0", "gravity: 9.81", ["`cable.nodes`"]),
    ("length: 102.5, nodes: 3, S: [1.0, 2.0, 3.0, 4.0], mass_per_length: 1.0", "gravity: 9.81", ["`cable.S` and `cable.length`"]),
    ("length: 102.5, nodes: 3", "gravity: 9.81", ["`cable.masses` is required"]),
    ("length: 102.5, nodes: 3, masses: [1.0, 1.0, 1.0], mass_per_length: 1.0", "gravity: 9.81", ["both give the masses"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "gravity: -9.81", ["`loads.gravity`"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "{}", ["`loads.F0` is required"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "point: [{node: 4, F: [0.0, 1.0]}]", ["`loads.point[1].node` is 4", "n = 3"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "point: [{node: 0}]", ["`loads.point[1].node`"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "point: [{node: 1, F: [1.0, 2.0, 3.0, 4.0]}]", ["`loads.point[1].F`", "3 (x, v, w)"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "point: [{node: 1, mass: -5.0}]", ["`loads.point[1].mass`"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "point: [{node: 1, force: [1.0, 2.0]}]", ["`loads.point[1].force`", "not a known key"]),
    ("length: 102.5, nodes: 3, mass_per_length: 1.0", "gravity: 9.81, F0: [1.0, 2.0]", ["loads.F0 has 2 values", "2n = 6"]),
])
def test_shorthand_errors_name_the_field(cable, loads, needles):
    loads_text = loads if loads.startswith("{") else "{" + loads + "}"
    msg = _error(CABLE % cable + f"loads: {loads_text}\n")
    assert "\n" not in msg
    for needle in needles:
        assert needle in msg, msg
