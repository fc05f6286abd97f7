"""Every integrator at its defaults on the shipped paper example's history (2.4 rad/s, 600 s,
from rest; ``cablesim history configs/paper-example.yaml --integrator NAME``): within 1e-5 of
the peak in z and in the segment tensions, against scipy's DOP853 (rtol 1e-11) on the
second-order form with the geometry and tensions written in the tests (helpers_dynamics.py).

Measured (largest error over the saved instants and DOF or segments, over the peak): rk4 at
its former 100 steps per period 1.2e-5 in z and 5.1e-5 in the tensions (at 200, 7.2e-7 and
3.4e-6; its step now also follows the modal estimate of its error: 1.4e-7 and 6.4e-7); dopri5
2.1e-8 and 7.5e-8; newmark 7.0e-7 and 5.0e-8 and generalized-alpha 7.7e-7 and 6.0e-8 at their
default rtol 1e-6 (6.8e-6 and 7.5e-6 in z at the former 1e-5).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers_dynamics import reference_history
from helpers_mechanics import moving_support_reference
from test_adaptive_implicit import own_tensions

from cablesim.analyses.setup import build_equations, frequency_of_interest, make_integrator, output_interval
from cablesim.dynamics.simulate import simulate

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


@pytest.fixture(scope="module")
def default_history(paper, exact_static):
    """The paper example's history section as ``cablesim history`` runs it (its frequency of
    interest and output step) and the reference's z and tensions at its saved instants."""
    h = paper.history
    eom = build_equations(paper, exact_static, omega=h.omega)
    w_int = frequency_of_interest(eom, h.omega)
    out = output_interval(h.output_step, w_int, h.duration)
    t = np.arange(0, int(round(h.duration / out)) + 1) * out
    zref = reference_history(eom, t)[0]
    return eom, (paper, h, w_int), out, zref, own_tensions(eom, zref)


def _errors(eom, integ, duration, out, zref, Tref):
    hist = simulate(eom, integ, duration, out, split=False)
    assert hist.completed and hist.z.shape == zref.shape
    return (np.abs(hist.z - zref).max() / np.abs(zref).max(),
            np.abs(own_tensions(eom, hist.z) - Tref).max() / Tref.max())


@pytest.mark.parametrize("name", [
    None, "rk4", "dopri5",
    pytest.param("newmark", marks=pytest.mark.slow(reason="about 18 s of error-controlled implicit steps")),
    pytest.param("generalized-alpha", marks=pytest.mark.slow(reason="about 18 s of error-controlled implicit steps"))])
def test_default_run_is_within_1e_5_of_the_peaks(default_history, name):
    eom, (case, h, w_int), out, zref, Tref = default_history
    integ = make_integrator(case.integrator, eom, w_int, name)
    ez, eT = _errors(eom, integ, h.duration, out, zref, Tref)
    assert ez < 1e-5 and eT < 1e-5, (integ.name, ez, eT)



def test_rk4_default_resolves_the_fast_modes_the_start_excites():
    """The taut stay of ``configs/stay-parametric.yaml``, its anchorage moving along the chord from
    t = 0: the start rings its axial modes (548-683 rad/s, damping ratios 0.06-0.08), which 200
    steps per forcing period (0.0026 s, ``w h`` up to 1.78) left 9.4e-4 off in z and 2.4e-4 in the
    tensions within the first 0.1 s (from rest, before the case gave its history a 1 mm
    out-of-plane disturbance; with it the same). The default step now follows the linear modal estimate of
    rk4's error (``cablesim.dynamics.integrators.modal_error``). Against scipy's DOP853 on the
    second-order form with moving supports written in the tests (helpers_mechanics.SecondOrder)."""
    from cablesim.analyses.dynamic import plan_history
    from cablesim.case import load_case

    duration = 2.0
    plan = plan_history(load_case(CONFIGS / "stay-parametric.yaml")[0], duration=duration, integrator="rk4")
    eom = plan.eom
    hist = simulate(eom, plan.integrator, duration, plan.output_step, s0=plan.s0, split=False)
    assert hist.completed
    z0 = None if plan.s0 is None else plan.s0[: eom.n_dof]  # the case's out-of-plane disturbance, at rest
    zref, Tref = moving_support_reference(eom, hist.t, z0)
    ez = np.abs(hist.z - zref).max() / np.abs(zref).max()
    eT = np.abs(hist.T - Tref).max() / Tref.max()
    assert ez < 1e-5 and eT < 1e-5, (plan.integrator.settings()["dt"], ez, eT)
