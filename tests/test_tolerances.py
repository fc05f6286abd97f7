"""Tolerances that act: a tightened ``rtol`` tightens the run, and the records say what ran.

dopri5's absolute tolerance, when the case gives none, follows rtol
(``atol = 1e-10 chord x rtol / 1e-8``). With a fixed atol (3e-8 m on the paper example, whose
displacements are metres) the error test is dominated by atol: halving rtol three times left the
error at 2.2e-8, 2.0e-8, 2.0e-8, 1.6e-8 (a user would conclude the run had converged).

The reference is scipy's DOP853 at rtol 1e-13 on the second-order equations of motion written in
the tests (``helpers_dynamics``).
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from cablesim import api
from cablesim.analyses.setup import build_equations, make_integrator
from cablesim.dynamics.simulate import simulate
from cablesim.io.report import sweep_summary
from helpers_dynamics import reference_history, rel_error

OMEGA = 2.4  # the paper example's history frequency (history.omega), near its fundamental
DURATION = 200.0
STEP = 0.05


@pytest.fixture(scope="module")
def tight_reference(paper, exact_static):
    eom = build_equations(paper, exact_static, omega=OMEGA)
    t = np.arange(0, round(DURATION / STEP) + 1) * STEP
    z, _ = reference_history(eom, t, rtol=1e-13)
    return eom, z


def test_halving_rtol_halves_the_error(tight_reference):
    """rtol 1e-8 (the default), 5e-9, 2.5e-9, 1.25e-9, atol left to its default: each halving
    divides the error against the reference by 1 to 4 (a halving within a factor 2 either way),
    and the three together by 2 to 32 (measured: 2.2e-8, 1.5e-8, 9.4e-9, 4.6e-9)."""
    eom, z_ref = tight_reference
    errors = []
    for k in range(4):
        case = api.load_case(None, [f"integrator.rtol={1e-8 / 2**k!r}"])
        integ = make_integrator(case.integrator, eom, OMEGA)
        assert integ.name == "dopri5" and integ.atol == pytest.approx(1e-10 * eom.cable.chord_length / 2**k)
        hist = simulate(eom, integ, DURATION, STEP, split=False)
        assert hist.completed
        errors.append(rel_error(hist.z, z_ref))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    print("errors", ", ".join(f"{e:.2e}" for e in errors), "ratios", ", ".join(f"{r:.2f}" for r in ratios))
    assert np.all((ratios > 1.0) & (ratios < 4.0)), ratios
    assert 2.0 < errors[0] / errors[-1] < 32.0


def test_an_explicit_atol_is_kept(tight_reference):
    eom, _ = tight_reference
    case = api.load_case(None, ["integrator.rtol=1e-10", "integrator.atol=1e-9"])
    integ = make_integrator(case.integrator, eom, OMEGA)
    assert (integ.rtol, integ.atol) == (1e-10, 1e-9)


def test_history_and_sweep_files_state_the_effective_tolerances(tmp_path):
    chord = float(np.hypot(300.0, 20.0))
    case = api.load_case(None, ["integrator.rtol=2.5e-9", "sweep.omega=[2.0]", "sweep.duration=30",
                                "sweep.window=10"])
    run = api.history(case, omega=OMEGA, duration=2.0)
    run.to_hdf5(tmp_path / "h.h5")
    with h5py.File(tmp_path / "h.h5") as f:
        a = f["history"].attrs
        assert a["integrator_rtol"] == 2.5e-9
        assert a["integrator_atol"] == pytest.approx(2.5e-11 * chord, rel=1e-12)
    sw = api.sweep(case, jobs=1, output=tmp_path / "s.h5")
    with h5py.File(tmp_path / "s.h5") as f:
        a = f["sweep"].attrs
        assert a["integrator"] == "dopri5" and a["integrator_rtol"] == 2.5e-9
        assert a["integrator_atol"] == pytest.approx(2.5e-11 * chord, rel=1e-12)
    text = sweep_summary(case, sw.result, 1.0)
    assert "integrator dopri5 (rtol = 2.5e-09, atol = 7.52e-09 m at every point)" in text
