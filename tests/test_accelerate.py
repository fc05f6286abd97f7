"""Steady states by shooting from the transient (``sweep.accelerate``): the same answers as
integration alone, sooner.

The reference is the package's plain steady-state detection (integration until the
stroboscopic samples repeat and the orbit is stable), an independent decision procedure: the
accelerated one must give the same period, the same steady/not-steady/failed flag and the same
amplitudes (1e-3 relative) at every point, and must never accept an unstable orbit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cablesim
from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.analyses.static import run_static
from cablesim.dynamics.steady import SteadyCriterion, steady_response
from cablesim.orbits.accelerate import accelerated_steady_response

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"
CHANNELS = np.array([1, 3])


@pytest.fixture(scope="module")
def paper():
    case = cablesim.load_case(CONFIG)
    return case, run_static(case)


def _both(paper, w, criterion=SteadyCriterion(), scale=1.0, slack=None):
    case, static = paper
    eom = build_equations(case, static, omega=w, load_scale=scale, slack=slack)
    integ = make_integrator(case.integrator, eom, max(w, float(eom.frequencies[0])))
    return (steady_response(eom, integ, CHANNELS, criterion),
            accelerated_steady_response(eom, integ, CHANNELS, criterion))


@pytest.mark.parametrize("w", [0.6, 1.26, 2.3, 2.48, 3.5, 5.0, 5.1, 5.5])
def test_same_answer_as_integration_alone(paper, w):
    plain, fast = _both(paper, w)
    assert fast.period == plain.period and fast.steady == plain.steady and fast.failed == plain.failed
    np.testing.assert_allclose(fast.amplitude, plain.amplitude, rtol=1e-3)
    np.testing.assert_allclose(fast.halfrange, plain.halfrange, rtol=1e-3)
    assert fast.t_end <= plain.t_end


def test_most_points_are_decided_by_shooting_sooner(paper):
    decided, saved = [], []
    for w in (1.0, 2.0, 3.0, 4.0, 5.5):
        plain, fast = _both(paper, w)
        decided.append(fast.decided)
        saved.append(plain.t_end / fast.t_end)
    assert decided.count("shooting") >= 4, decided
    assert np.median(saved) > 3.0, saved


def test_late_jump_is_not_hidden(paper):
    """5.05 rad/s: the response lingers for ~1000 s near the small harmonic orbit, which is
    unstable (inside the period-doubling band); shooting finds it and rejects it, and the point
    ends on the large period-2 orbit after the jump, as integration alone finds."""
    plain, fast = _both(paper, 5.05, SteadyCriterion(cap=4000.0))
    assert plain.period == fast.period == 2 and fast.steady
    assert fast.t_end > 1500.0
    np.testing.assert_allclose(fast.amplitude, plain.amplitude, rtol=1e-3)
    assert fast.multipliers is None or np.all(np.abs(fast.multipliers) < 1.0)


def test_slack_failure_stays_a_failure(paper):
    """A harmonic load that drives a segment slack: both stop, for the same reason, at the same
    instant to the transient's integration tolerance (rtol 1e-6 against the default 1e-8), with
    slack: stop."""
    plain, fast = _both(paper, 2.45, SteadyCriterion(cap=600.0), scale=10.0, slack="stop")
    assert plain.failed and fast.failed and fast.status == plain.status
    assert fast.t_end == pytest.approx(plain.t_end, rel=1e-6)


def test_sweep_records_how_points_were_decided(tmp_path):
    case = cablesim.load_case(CONFIG, overrides=["sweep.omega=[2.0, 3.0]", "sweep.channels=[z2]"])
    out = tmp_path / "s.h5"
    run = cablesim.sweep(case, jobs=1, output=out)
    d = run.result.data[0]
    assert list(d["decided"]) == ["shooting", "shooting"]
    assert np.all(np.abs(d["multipliers"]) < 1.0)
    import h5py

    with h5py.File(out) as f:
        assert [x.decode() for x in f["sweep/decided"][()]] == ["shooting", "shooting"]
        assert bool(f["sweep"].attrs["accelerate"]) is True
