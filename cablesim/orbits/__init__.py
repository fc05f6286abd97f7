"""Periodic orbits, Floquet stability and pseudo-arclength continuation.

- :mod:`~cablesim.orbits.shooting`: flow maps with variational equations (compiled fixed-step
  Runge-Kutta), single and multiple shooting, Newton's method, Floquet multipliers;
- :mod:`~cablesim.orbits.continuation`: a generic pseudo-arclength continuation that locates
  special points of any problem's test functions;
- :mod:`~cablesim.orbits.stability`: multiplier test functions for folds, period doublings and
  Neimark-Sacker bifurcations;
- :mod:`~cablesim.orbits.branches`: branches of periodic orbits with amplitudes, stability and
  branch switching at period doublings; :func:`continue_branches` for the cable;
- :mod:`~cablesim.orbits.systems`, :mod:`~cablesim.orbits.cablefield`: the vector fields.
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
