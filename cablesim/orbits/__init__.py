"""Periodic orbits, Floquet stability and pseudo-arclength continuation.

- :mod:`~cablesim.orbits.shooting`: flow maps with variational equations (compiled fixed-step
  Runge-Kutta), single and multiple shooting, Newton's method, Floquet multipliers;
- :mod:`~cablesim.orbits.continuation`: a generic pseudo-arclength continuation that locates
  special points of any problem's test functions (it knows neither cables nor output);
- :mod:`~cablesim.orbits.stability`: multiplier test functions for folds, period doublings and
  Neimark-Sacker bifurcations;
- :mod:`~cablesim.orbits.branches`: branches of periodic orbits with amplitudes, stability and
  branch switching at period doublings (:mod:`~cablesim.orbits.switching`); results in
  :mod:`~cablesim.orbits.diagram`; :func:`continue_branches` for the cable;
- :mod:`~cablesim.orbits.matrixfree`: shooting that uses the monodromy only through its action
  on vectors (directional variational equations, :mod:`~cablesim.orbits.directional`; the
  implicit Radau IIA flow for stiff cables, :mod:`~cablesim.orbits.radau`), Newton-GMRES
  (:mod:`~cablesim.orbits.krylov`) and the leading Floquet multipliers
  (:mod:`~cablesim.orbits.floquet`); :mod:`~cablesim.orbits.mfproblem` makes it a continuation
  problem (``matrix_free`` of :func:`continue_branches`, by default above 40 states), and
  :mod:`~cablesim.orbits.splitleading` on the planar orbits of a symmetric spatial cable (the
  leading multipliers of the in-plane and out-of-plane blocks apart);
- :mod:`~cablesim.orbits.budget`: the steps and memory of a branch's orbits before any is
  computed (the cost estimate of ``cablesim continue``);
- :mod:`~cablesim.orbits.systems`, :mod:`~cablesim.orbits.cablefield`: the vector fields;
  :mod:`~cablesim.orbits.starting`: starting states.

Typical use::

    diagram = continue_branches(eom, "omega", 0.5, 6.0)   # period 1, then the period-2 branches
    for br in diagram.branches:
        br.values, br.amplitude, br.stable, br.trusted    # per point
    diagram.bifurcations                                  # kind, parameter, branch, amplitude, ...

Accuracy and cost, measured on the paper's example cable (exact analysis, default ``rk8`` with
at least 48 steps per forcing period and ``h * 51.9 rad/s <= 1.25``):

- periodic orbit: 1.5e-10 relative to a 4000-steps-per-period solution; flow-map round-off
  about 6e-14 m (displacement-form forces); amplitudes (peak ``|z|`` from the quintic Hermite
  interpolant between steps, :mod:`cablesim.dynamics.extremes`) within 3e-11 of the largest
  amplitude of an independent integration of the same orbit (cubic before: up to 1e-7);
- Floquet multipliers: the slow modes' to 1e-9 or better (a central-difference monodromy through
  the package's DOPRI5 agrees to 3e-9), the fast modes' (27 and 52 rad/s, ``|mu|`` 0.06 .. 0.5)
  to 1e-5 .. 1e-7; Liouville's ``|log det(monodromy) + tr(M^-1 C) T|`` at most 8.5e-5 over the
  whole 0.5 .. 6 rad/s branch (2e-10 with ``step_rate=0.3``);
- derivative with respect to ``omega`` or ``gamma``: agrees with central differences of the
  flow map to 1e-9 .. 1.5e-8;
- bifurcations: located to about 1e-9 in the parameter (the period doublings' multiplier is
  -1 within 1e-9 in the independent finite-difference monodromy);
- cost: one shooting evaluation (flow, monodromy and parameter derivative) 0.75 ms at 6 rad/s
  (48 steps) to 6 ms at 0.5 rad/s (522 steps), about 13 us per step; the whole response over
  0.5 .. 6 rad/s (period-1 branch, period-doubling pair at 5.021 and 5.074 rad/s, the period-2
  branch between them with its fold at 4.987 rad/s) in 1.45 s of one core: 281 points, 877
  evaluations, 5.2 ms per point, 1.65 ms per Newton step. The approximate analysis costs about
  six times as much per evaluation (inner solves for the loads).
"""
from .branches import (
    Bifurcation,
    BranchEnd,
    OrbitBranch,
    OrbitPoint,
    OrbitProblem,
    ResponseDiagram,
    cable_scales,
    continue_branches,
    trace_branches,
)
from .continuation import Branch, Point, Settings, Status, continuation
from .shooting import Evaluation, FlowStatus, OrbitSolution, Shooting, SolveStatus, solve_orbit
from .starting import integrate_to_steady, linear_response, linear_response_state, state_from_history
from .systems import OdeSystem, cable_system

__all__ = [
    "Bifurcation", "Branch", "BranchEnd", "Evaluation", "FlowStatus", "OdeSystem", "OrbitBranch", "OrbitPoint",
    "OrbitProblem", "OrbitSolution", "Point", "ResponseDiagram", "Settings", "Shooting", "SolveStatus", "Status",
    "cable_scales", "cable_system", "continuation", "continue_branches", "integrate_to_steady", "linear_response",
    "linear_response_state", "solve_orbit", "state_from_history", "trace_branches",
]
