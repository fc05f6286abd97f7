"""Periodically forced first-order systems for the shooting method.

An :class:`OdeSystem` bundles a compiled vector field (contract in :mod:`cablesim.orbits.kernels`)
with its constants and what the shooting method needs to know about it: which entries
of ``prm`` are continuation parameters, how fast its fastest mode is (for the stability floor of
the fixed step) and which components are displacements (for amplitudes). The shooting and
continuation code never looks inside: :func:`cable_system` is the only place that knows about
cables.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from dataclasses import field as dc_field
from typing import NamedTuple

import numpy as np

from ..mechanics.banded import band_rows
from ..mechanics.model import CONTINUE
from ..modal import fastest_rate
from . import cablefield
from . import mechanical as mech
from .rotation import cable_rotation
from .symmetry import cable_frame, cable_mirror, component_frequencies
from .kernels import copy_work


@dataclass(frozen=True)
class OdeSystem:
    """``x' = f(x, omega t; prm)``, ``2 pi / omega``-periodic in time.

    Attributes
    ----------
    field : numba function
        The vector field (contract in :mod:`cablesim.orbits.kernels`).
    dim : int
        State dimension.
    prm : ndarray
        The parameters (copied; never modified in place by this object).
    work : ndarray or tuple of ndarray
        Initial content of the field's scratch space (warm starts); copied before every
        integration so the flow map does not depend on the call history.
    mirror : Mirror or None
        The state's mirror symmetry (:mod:`cablesim.orbits.symmetry`), if the system has one:
        the monodromy of an orbit fixed by it splits into two blocks.
    frame : Mirror or None
        The plane of a spatial cable's equilibrium (the mirror itself when the system has one,
        else that plane with loads out of it): the frame of the whirling measures of its orbits
        that leave the plane.
    model : object
        The field's constants (for the cable, a :class:`~cablesim.mechanics.model.CableModel`;
        an empty tuple for a system whose constants are all in ``prm``).
    omega : float
        Forcing frequency, rad/s (the continuation parameter may override it).
    parameters : dict
        Name -> index into ``prm`` of every parameter the field can differentiate with respect
        to (``omega`` is always available: it acts through the time scale).
    fastest_rate : float
        Largest ``|lambda|`` of the linearised field, 1/s: the fixed step must keep
        ``h * fastest_rate`` within the scheme's stability limit.
    displacements : ndarray of int
        Components reported as displacements (their extremes give the amplitudes).
    divergence : float or None
        ``tr(df/dx)`` if it is constant (Liouville check against ``exp(divergence T)``).
    noise : ndarray (dim,) or float
        Absolute round-off level of a flow-map evaluation per component: Newton's method
        counts differences below it as converged (tiny orbits cannot be resolved relatively
        better than this).
    names : tuple of str
        Component names, for messages.
    mechanical : Mechanical or None
        The same system in mechanical form, for the matrix-free shooting
        (:mod:`cablesim.orbits.matrixfree`); None if it has none (any vector field can still be
        shot matrix-free, its Jacobian formed at every stage).
    rotation : Rotation or None
        The rotations about the chord of a cable that lies straight along it
        (:mod:`cablesim.orbits.rotation`), if the system is invariant under them: the monodromy
        of an orbit they move has a multiplier +1 that the bifurcation tests exclude.
    slack : tuple or None
        ``(gaps, modes)``: the compiled functions with which the dense shooting can follow the
        flow through slack segments (:mod:`cablesim.orbits.slackflow`; a
        :class:`~cablesim.orbits.shooting.Shooting` made with ``through_slack=True``), or None
        (a flow that meets a slack segment stops there).
    """

    field: object
    dim: int
    prm: np.ndarray
    work: object
    omega: float
    parameters: dict = dc_field(default_factory=dict)
    fastest_rate: float = 0.0
    displacements: np.ndarray = dc_field(default_factory=lambda: np.zeros(0, dtype=int))
    divergence: float | None = None
    noise: object = 0.0
    names: tuple = ()
    model: object = ()
    mechanical: object = None
    mirror: object = None
    frame: object = None
    slack: object = None
    rotation: object = None

    def __post_init__(self):
        object.__setattr__(self, "prm", np.ascontiguousarray(self.prm, dtype=float).copy())
        work = np.ascontiguousarray(self.work, dtype=float) if isinstance(self.work, (list, np.ndarray)) else self.work
        object.__setattr__(self, "work", copy_work(work))
        object.__setattr__(self, "displacements", np.asarray(self.displacements, dtype=int))

    def with_prm(self, index: int, value: float) -> "OdeSystem":
        """A copy with ``prm[index] = value``."""
        prm = self.prm.copy()
        prm[index] = value
        return replace(self, prm=prm)


class Mechanical(NamedTuple):
    """A second-order system ``M z'' + C z' + P(z) = F`` on ``x = (z, v)`` through the compiled
    functions of :mod:`cablesim.orbits.mechanical` (its contract), for the matrix-free kernels.

    Attributes
    ----------
    balance, stiffness_times, stiffness_band, load_derivative : numba functions
        The contract's four functions.
    model : object
        Their constants: ``mass`` (diagonal of M) and ``C`` (banded) are read by the kernels.
    geo_shape : tuple of int
        Shape of the stiffness state ``geo`` that ``balance`` fills.
    stiffness_rows : int
        Rows of ``K``'s band storage, ``2 h + 1``.
    eigenvalues : ndarray complex
        Eigenvalues of the system linearised at ``x = 0``, 1/s (step rules of the implicit
        scheme).
    """

    balance: object
    stiffness_times: object
    stiffness_band: object
    load_derivative: object
    model: object
    geo_shape: tuple
    stiffness_rows: int
    eigenvalues: np.ndarray


def rayleigh_eigenvalues(w: np.ndarray, a0: float, a1: float) -> np.ndarray:
    """Eigenvalues of ``q'' + (a0 + a1 w^2) q' + w^2 q = 0`` for every modal frequency ``w``
    (two per mode: a complex pair, or two real roots when overdamped), 1/s."""
    w = np.asarray(w, dtype=float)
    b = a0 + a1 * w**2
    disc = (0.25 * b**2 - w**2).astype(complex)
    root = np.sqrt(disc)
    return np.concatenate([-0.5 * b + root, -0.5 * b - root])


def cable_mechanical(eom, model) -> Mechanical:
    """The cable's :class:`Mechanical` form (exact analysis), with the constants of ``model``
    (its corrected ``F0``) and the banded damping."""
    if not eom.exact:
        raise ValueError("the mechanical form exists for the exact analysis only")
    c = eom.cable
    mmodel = model._replace(C=np.ascontiguousarray(eom.C_band, dtype=float),
                            Cr=np.zeros((eom.n_dof, 0)))
    return Mechanical(mech.cable_balance, mech.cable_stiffness_times, mech.cable_stiffness_band,
                      mech.cable_load_derivative, mmodel, mech.geometry_shape(c.n_nodes, c.dim), band_rows(c.dim),
                      rayleigh_eigenvalues(eom.frequencies, eom.a0, eom.a1))


def cable_system(eom, gamma: float = 1.0, support: float = 1.0) -> OdeSystem:
    """The cable's equations of motion on ``(z, v)`` (:mod:`cablesim.orbits.cablefield`).

    Parameters
    ----------
    eom : EquationsOfMotion
        Exact or approximate analysis; its ``omega`` is the default forcing frequency and its
        ``FL`` the harmonic load that ``gamma`` multiplies.
    gamma : float
        Multiplier of ``FL`` and of the supports' motion.
    support : float
        Multiplier ``s`` of the supports' motion alone (their amplitudes ``eom.uA``, ``eom.uB``).

    Returns
    -------
    OdeSystem
        State ``(z, v)`` of dimension ``2 n_dof``, with parameters ``"gamma"`` (multiplies FL
        and the supports' motion) and ``"support"`` (the supports' motion alone); a spatial
        cable symmetric about a plane carries its :class:`~cablesim.orbits.symmetry.Mirror`.
    """
    if eom.moving_supports and not eom.exact:
        raise ValueError("moving supports need the exact analysis")
    nd = eom.n_dof
    model = eom.model(dense_damping=True)
    prm = np.zeros(2)
    prm[cablefield.GAMMA], prm[cablefield.SUPPORT] = float(gamma), float(support)
    if eom.analysis == "exact":
        fld, work = cablefield.exact_field, cablefield.exact_work(eom)
    else:
        fld, work = cablefield.approximate_field, cablefield.approximate_work(eom)
    w = eom.frequencies
    rate = fastest_rate(w, eom.a0, eom.a1)
    # Non-Rayleigh damping: bound the rate by the largest |eigenvalue| of the linear system.
    nd2 = 2 * nd
    A = np.zeros((nd2, nd2))
    A[:nd, nd:] = np.eye(nd)
    A[nd:, :nd] = -eom.K0 / eom.mass[:, None]
    A[nd:, nd:] = -eom.C / eom.mass[:, None]
    rate = max(rate, float(np.abs(np.linalg.eigvals(A)).max()))
    names = tuple(f"z{i + 1}" for i in range(nd)) + tuple(f"v{i + 1}" for i in range(nd))
    # Round-off of the flow map: forces of order |F0| resolved to ~1e-16 accumulate to about
    # 1e-15 of the chord in displacement (measured 6e-14 m on the paper's cable, exact
    # analysis); the approximate analysis works on absolute coordinates (y0 + z) and inner
    # solves: 1e-13 of the chord.
    # (velocities: times each component's fundamental frequency, as the continuation's scales)
    mirror = cable_mirror(eom)
    level = (1e-15 if eom.analysis == "exact" else 1e-13) * float(eom.cable.chord_length)
    noise = np.concatenate([np.full(nd, level), level * component_frequencies(eom, mirror)])
    # The sustained load is taken as the resisting force at y0 itself, so that z = 0 is an exact
    # equilibrium of the field (the static solve leaves |P(y0) - F0| at its tolerance, which
    # would otherwise offset tiny orbits). The third-order time integration does the same: F0
    # enters it only through y''(0) = M^-1 (F(0) - P(y0) - C y'(0)).
    dx, J, dp = np.empty(nd2), np.zeros((nd2, nd2)), np.zeros(nd2)
    at_rest = model._replace(moving=False)  # the equilibrium with the supports where they rest
    code = fld(0.0, float(eom.omega), np.zeros(nd2), at_rest, prm, copy_work(work), dx, J, dp, -1)
    if code == 0:
        model = model._replace(F0=model.F0 - eom.mass * dx[nd:])
    # the mechanical form holds the supports still (their motion enters the field only)
    mechanical = cable_mechanical(eom, model) if eom.exact and not eom.moving_supports else None
    return OdeSystem(
        field=fld,
        dim=nd2,
        prm=prm,
        work=work,
        model=model,
        omega=float(eom.omega),
        parameters={"gamma": cablefield.GAMMA, "support": cablefield.SUPPORT},
        fastest_rate=rate,
        displacements=np.arange(nd),
        divergence=-float(np.trace(eom.C / eom.mass[:, None])),
        noise=noise,
        names=names,
        mechanical=mechanical,
        mirror=mirror,
        frame=cable_frame(eom),
        rotation=cable_rotation(eom),
        # orbits through slack: the exact analysis with the supports at rest, unless the case
        # says slack: stop
        slack=((cablefield.exact_gaps, cablefield.exact_modes)
               if eom.exact and not eom.moving_supports and model.slack == CONTINUE else None),
    )
