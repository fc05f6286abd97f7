"""A sweep on a grid refines itself where neighbouring points disagree, so that a default
figure no longer hides a peak or a band narrower than the grid step: its peak agrees with the
continuation (an independent formulation: shooting and pseudo-arclength continuation), the
1/2-subharmonic band near twice the fundamental appears, a resumed refined sweep adds exactly
the points the uninterrupted one adds, and the figure and the summary say how the grid was
refined (or that it was not)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cablesim import api
from cablesim.analyses.refine import NEAR_UNIT, finest_step, refinements
from cablesim.analyses.sweep_points import CurveTable
from cablesim.io.report import sweep_summary
from helpers_sweep import Stop, stop_after

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "paper-example.yaml"
PEAK_GRID = ["sweep.omega={start: 2.3, stop: 2.7, num: 5}", "sweep.duration=1500", "sweep.window=100"]


def _table(amplitudes, period=None, steady=None, multipliers=None) -> CurveTable:
    a = np.asarray(amplitudes, dtype=float).reshape(-1, 1)
    t = CurveTable.empty(a.shape[0], 1, 4)
    t.amplitude[:] = a
    t.done[:] = True
    t.steady[:] = True if steady is None else steady
    t.period[:] = 1 if period is None else period
    for i, mu in (multipliers or {}).items():
        t.multipliers[i, : len(mu)] = mu
    return t


def test_the_rules_halve_where_neighbours_disagree_and_nowhere_else():
    w = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    fine = finest_step(w, 3)
    assert fine == pytest.approx(0.125)
    smooth = _table([1.0, 1.01, 1.02, 1.03, 1.04, 1.05])  # resolved, monotonic: nothing to add
    assert refinements(w, [smooth], fine, 100).size == 0
    peak = _table([1.0, 1.0, 5.0, 1.0, 1.0, 1.0])  # a peak and its flanks
    assert refinements(w, [peak], fine, 100).tolist() == [2.5, 3.5]
    band = _table([1.0] * 6, period=[1, 1, 2, 1, 1, 1])  # a change of response period
    assert refinements(w, [band], fine, 100).tolist() == [2.5, 3.5]
    # a multiplier next to -1 at 4.0: a period doubling may lie on either side of it
    near = _table([1.0] * 6, multipliers={3: [-1.0 + 0.5 * NEAR_UNIT, 0.3]})
    assert refinements(w, [near], fine, 100).tolist() == [3.5, 4.5]
    # ... but only over the first halvings: at eight times the finest step and below, no more
    close = np.array([3.0, 3.5, 4.0, 4.5])
    assert refinements(close, [_table([1.0] * 4, multipliers={2: [-1.0]})], 0.125, 100).size == 0
    # nothing finer than the finest step, and never more than the budget (widest first)
    assert refinements(np.array([1.0, 1.125]), [_table([1.0, 9.0])], 0.125, 100).size == 0
    uneven = np.array([1.0, 2.0, 2.5, 3.5])
    assert refinements(uneven, [_table([1.0, 9.0, 1.0, 9.0])], 0.125, 1).tolist() == [1.5]


@pytest.fixture(scope="module")
def peak_sweep(tmp_path_factory):
    """The example's softening resonance on a 0.1 rad/s grid, refined (the default for a grid)."""
    out = tmp_path_factory.mktemp("refine") / "peak.h5"
    case = api.load_case(EXAMPLE, PEAK_GRID)
    return case, out, api.sweep(case, jobs=2, output=out).result


def test_the_refined_peak_agrees_with_the_continuation_and_the_grid_alone_does_not(peak_sweep):
    """`make run` printed 8.35 m at 2.5 rad/s: the response peaks at 8.98 m near 2.48 rad/s."""
    case, _, res = peak_sweep
    assert res.settings["refine"] == 4 and res.n_refined > 0 and res.complete
    cont = api.continuation(api.load_case(EXAMPLE, ["continuation={omega: {start: 2.3, stop: 2.7}, channels: [z2]}"]))
    peak_cont = max(float(b.amplitude[b.stable, 0].max()) for b in cont.result.branches if b.stable.any())
    t = res.table(0)
    peak = float(np.nanmax(np.where(t.valid, t.amplitude[:, 0], np.nan)))
    assert abs(peak - peak_cont) <= 0.005 * peak_cont, (peak, peak_cont)
    grid = np.isin(res.omega, np.linspace(2.3, 2.7, 5))
    assert np.nanmax(t.amplitude[grid, 0]) < 0.95 * peak_cont  # the grid alone misses it by over 5 %
    assert np.diff(res.omega).min() == pytest.approx(0.1 / 16)  # four halvings of the grid step
    summary = sweep_summary(case, res, 1.0)
    assert "grid of 5 frequencies refined to 0.00625 rad/s where neighbouring points disagree" in summary


def test_a_resumed_refined_sweep_adds_the_same_points(peak_sweep, tmp_path):
    case, _, ref = peak_sweep
    out = tmp_path / "resumed.h5"
    with pytest.raises(Stop):  # stopped among the refined points
        api.sweep(case, jobs=1, output=out, progress=stop_after(9))
    calls = []
    res = api.sweep(case, jobs=1, output=out, resume=True, progress=lambda d, n: calls.append(d)).result
    assert res.complete and res.omega.tolist() == ref.omega.tolist()
    assert min(calls) >= 9 and len(set(calls)) == ref.omega.size - 9 + 1  # journalled points were kept
    np.testing.assert_array_equal(res.table(0).amplitude, ref.table(0).amplitude)


def test_an_unrefined_sweep_says_so(tmp_path):
    case = api.load_case(EXAMPLE, [*PEAK_GRID[1:], "sweep.omega=[2.3, 2.5, 2.7]", "sweep.duration=300"])
    res = api.sweep(case, jobs=1).result
    assert res.settings["refine"] == 0 and res.n_refined == 0  # a list is computed as given
    assert "grid step up to 0.2 rad/s, not refined (sweep.refine)" in sweep_summary(case, res, 1.0)


@pytest.mark.slow
def test_the_default_job_shows_the_subharmonic_band_and_the_true_peak(tmp_path):
    """`make run` (the shipped case as it stands): its printed peak within 0.5 % of the
    continuation's and 1/2-subharmonic points between the period doublings at 5.02 and 5.07."""
    from cablesim.io.sweeps import sweep_summary_rows

    out = tmp_path / "sweep.h5"
    res = api.sweep(api.load_case(EXAMPLE), jobs=-1, output=out).result
    cont = api.continuation(api.load_case(EXAMPLE)).result
    harmonic = [b for b in cont.branches if b.period == 1]
    peak_cont = max(float(b.amplitude[b.stable, 0].max()) for b in harmonic if b.stable.any())
    row = sweep_summary_rows(out)[0]
    assert abs(row["value"] - peak_cont) <= 0.005 * peak_cont, (row, peak_cont)
    t = res.table(0)
    band = res.omega[t.valid & t.steady & (t.period == 2)]
    assert band.size >= 3 and 5.02 < band.min() and band.max() < 5.075, band
