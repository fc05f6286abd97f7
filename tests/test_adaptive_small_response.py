"""Error-controlled implicit steps on a response small beside the cable's chord: the taut stay of
``configs/stay-parametric.yaml`` (3.4 mm of axial motion on a 100 m chord, its anchorage moving,
started 1 mm out of its plane), 20 s, against scipy's DOP853 on the second-order form with moving
supports written in the tests (helpers_mechanics.SecondOrder).

Three things held such a run's steps whatever rtol asked: a fixed atol (1e-9 of the chord, 30
times rtol times the peak here; the default atol now follows rtol, tests/test_integrator_settings.py),
a rounding floor of the error estimate at 1e-15 of the chord (above the error a step was
allowed), and Newton iterations stopped at 1e-12 of the chord, whose leftover enters every step.
Measured with atol at 1e-6 of rtol times the chord: generalized-alpha at rtol 1e-5 was 1.5e-5
off the peak in z, now 4.6e-7; newmark 8.5e-7, now 5.7e-7.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers_mechanics import controlled_history_error, planned_history_reference

CASE = Path(__file__).resolve().parents[1] / "configs" / "stay-parametric.yaml"
DURATION = 20.0


@pytest.fixture(scope="module")
def stay():
    return planned_history_reference(CASE, DURATION)


@pytest.mark.parametrize("name", ["generalized-alpha",
                                  pytest.param("newmark", marks=pytest.mark.slow(reason="the same rule, a second scheme"))])
def test_error_control_holds_its_tolerance_on_a_small_response(stay, name):
    rtol = 1e-5
    err = controlled_history_error(*stay, name, rtol)
    assert err <= rtol, (name, err)
