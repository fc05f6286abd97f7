"""What one orbit of a continuation costs before any is computed: integration steps and memory.

The step count of a flow over one orbit period is the shooting's own rule
(:meth:`~cablesim.orbits.shooting.Shooting.segment_steps`, the same for the matrix-free
shooting), evaluated at both ends of the range: it grows with the forcing period
``2 pi p / omega`` and with the fastest rate of the cable, which grows with its number of nodes.
Memory: the stored branch (every orbit's unknowns, state, multipliers and amplitudes) and the
working state of the flows. A dense shooting carries the variational equations, an ``n x n``
matrix per Runge-Kutta stage, and forms the ``m n x m n`` Jacobian of the shooting residual with
its bordered factorisation (a few evaluations alive at once along the branch); a matrix-free
one keeps Krylov bases of ``m n`` vectors and, with the Radau scheme, the tapes of its last
evaluations (a banded matrix per step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import radau as rd
from .matrixfree import KEEP_TAPES, MatrixFreeShooting
from .mfproblem import uses_matrix_free
from .continuation import Settings
from .shooting import Shooting
from .starting import cable_scales
from .systems import cable_system

#: Evaluations (Jacobians and their factorisations) alive at once along a dense branch: the
#: current point, the predictor, and the bracket of a special point being located.
LIVE_EVALUATIONS = 4
#: Krylov directions a matrix-free Newton solve may hold (``solve_orbit_mf``'s GMRES limit).
KRYLOV_DIRECTIONS = 200


@dataclass(frozen=True)
class OrbitBudget:
    """The cost of the orbits of a branch, from the shooting that would compute them.

    Attributes
    ----------
    states : int
        ``n``: the state dimension (``2 n_dof``, or more in the approximate analysis).
    matrix_free : bool
        Whether the orbits are shot matrix-free.
    scheme : str
        The integration scheme of the flows.
    steps : tuple of int
        Runge-Kutta steps of one flow over the whole orbit (every segment) at the two ends of
        the range, ``(start, stop)``.
    mean_steps : float
        Their mean over the range (16 values evenly spread), for extrapolating a probe at its
        start.
    working : float
        Bytes of the flows' and Newton's working state.
    per_orbit : float
        Bytes each stored orbit takes.
    least_orbits : int
        The fewest orbits the range can take: the continuation's largest step ``ds_max`` in
        scaled arclength moves the parameter by at most ``ds_max`` times its scale.
    """

    states: int
    matrix_free: bool
    scheme: str
    steps: tuple
    mean_steps: float
    working: float
    per_orbit: float
    least_orbits: int


def _working_bytes(sh, n: int, m: int, steps: int) -> float:
    """Bytes of the working state of the shooting ``sh`` (module docstring)."""
    N = m * n
    if isinstance(sh, Shooting):
        stages = sh.tableau.stages
        return 8.0 * ((stages + 3) * n * (n + 1) + LIVE_EVALUATIONS * (m * n * n + N * N + n * n) + 2 * (N + 1) ** 2)
    work = 8.0 * (KRYLOV_DIRECTIONS + 4) * (N + 1) * LIVE_EVALUATIONS
    if sh.scheme == "radau":
        mech = sh.mech
        nodes = n // 2
        kl = rd.q_bandwidth((mech.stiffness_rows - 1) // 2)
        per_step = 3 * nodes * (3 * kl + 1) + 3 * nodes + 3 * int(np.prod(mech.geo_shape)) + 3 * n  # as _Tape
        work += 8.0 * KEEP_TAPES * per_step * steps
    return work


def orbit_budget(eom, parameter: str, start: float, stop: float, period: int = 1, segments: int = 1,
                 gamma: float = 1.0, support: float = 1.0, matrix_free: bool | None = None) -> OrbitBudget:
    """Steps and memory of the orbits :func:`~cablesim.orbits.branches.continue_branches` would
    compute with the same arguments (nothing is integrated).

    Parameters
    ----------
    eom : EquationsOfMotion
    parameter : str
        ``"omega"``, ``"gamma"`` or ``"support"``.
    start, stop : float
        The range of the parameter.
    period, segments : int
        Period (forcing periods) and shooting segments of the first branch.
    gamma, support : float
        The load factor and support multiplier when they are not the parameter.
    matrix_free : bool, optional
        As for :func:`~cablesim.orbits.branches.trace_branches`.

    Returns
    -------
    OrbitBudget
    """
    g0 = start if parameter == "gamma" else gamma
    system = cable_system(eom, gamma=g0, support=start if parameter == "support" else support)
    mf = uses_matrix_free(system, matrix_free)
    kind = MatrixFreeShooting if mf else Shooting
    sh = kind(system, period=period, segments=segments, parameter=parameter, scheme="rk8")
    omegas = (start, stop) if parameter == "omega" else (eom.omega, eom.omega)
    steps = tuple(int(sh.segment_steps(w)) * segments for w in omegas)
    mean = float(np.mean([sh.segment_steps(w) * segments for w in np.linspace(*omegas, 16)]))
    n, nd = system.dim, eom.n_dof
    # unknowns u (m n), state, multipliers (complex, and their planes), two amplitudes per DOF
    per_orbit = 8.0 * (segments * n + n + 2 * n + 2 * nd) + 16.0 * n
    lam_scale = cable_scales(eom, parameter, start, stop, gamma, support)[1]
    least = 1 + math.ceil(abs(stop - start) / (Settings().ds_max * lam_scale))
    return OrbitBudget(states=n, matrix_free=mf, scheme=sh.scheme, steps=steps, mean_steps=mean,
                       working=_working_bytes(sh, n, segments, max(steps)), per_orbit=per_orbit, least_orbits=least)
