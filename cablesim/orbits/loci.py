"""Curves of fold, period-doubling and Neimark-Sacker orbits in two parameters (loci).

A located bifurcation of a branch of periodic orbits (:mod:`cablesim.orbits.branches`) is a
codimension-one point: in a second parameter it lies on a curve. :class:`LocusProblem` writes
that curve as the solution set of the periodicity condition bordered by the minimally augmented
defining function of the bifurcation (:mod:`cablesim.orbits.bordered`)::

    r(u, p1, p2) = 0            (shooting residual, m n equations)
    g(u, p1, p2, [kappa]) = 0   (one equation; two, with kappa, for Neimark-Sacker)

with unknowns ``U = (u, p1[, kappa])`` and the second parameter ``p2`` as the continuation
parameter of :func:`cablesim.orbits.continuation.continuation`: the same pseudo-arclength
algorithm follows the curve round its turning points, locates special points on it and stops at
the bounds of ``p2``. Each Newton step costs one shooting evaluation with the derivatives of
both parameters and one more per vector the derivative of ``g`` needs (two for folds and period
doublings: the segment maps along the null vector, for ``p1`` and ``p2``; four more for
Neimark-Sacker); the tests in ``tests/test_orbits_loci.py`` measure it.

The first parameter ``p1`` is differentiated by the flow kernel itself, ``omega`` included
(through the time scale); ``p2`` must be a parameter of the system's ``prm`` (for the cable
``gamma`` or ``support``, the multiplier s of the supports' motion), differentiated by a second
pass of the kernel. Nothing here knows what the
system is.

Codimension-two points located on a curve (sign changes of test functions, secant method):

- fold curves: ``cusp`` (the quadratic coefficient ``w^T P''[v, v]`` of the fold vanishes: two
  fold curves meet in a cusp, where the hysteresis is born), ``fold-flip`` (another multiplier
  through -1), ``1:1 resonance`` (another multiplier through +1), ``fold-neimark-sacker``;
- period-doubling curves: ``fold-flip``, ``1:2 resonance`` (a second multiplier at -1),
  ``flip-neimark-sacker``;
- Neimark-Sacker curves: the strong resonances ``1:1`` (``kappa = 1``: the curve ends on a fold
  curve), ``1:2`` (``kappa = -1``: it ends on a period-doubling curve), ``1:3``, ``1:4``, and
  ``fold-neimark-sacker``, ``flip-neimark-sacker``;

and, on every curve, its turning points in ``p2`` (``turning point``: for instance the least
forcing at which a period-doubling tongue exists) and its crossings of given values of ``p2``
(``level``). A curve of folds of period-2p orbits that ends on the period-doubling curve of the
period-p orbits is marked there as a ``generalized period doubling``
(:mod:`cablesim.orbits.curves`; approximate: the defining system degenerates as the curves meet).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from . import bordered as bd
from . import kernels as ok
from . import stability
from .shooting import Evaluation, FlowStatus, Shooting
from .systems import OdeSystem

#: Codimension-two tests of each kind of curve (in the order of :meth:`LocusProblem.test_functions`).
CODIM2_TESTS = {
    "fold": ("cusp", "fold-flip", "1:1 resonance", "fold-neimark-sacker"),
    "period-doubling": ("fold-flip", "1:2 resonance", "flip-neimark-sacker"),
    # a planar orbit's symmetry-breaking pitchfork: another multiplier through -1, +1 or a pair
    "pitchfork": ("fold-flip", "1:1 resonance", "fold-neimark-sacker"),
    "neimark-sacker": ("1:1 resonance", "1:2 resonance", "1:3 resonance", "1:4 resonance",
                       "fold-neimark-sacker", "flip-neimark-sacker"),
}
#: Scaled size of the displacement along a null vector for the second derivatives.
DIRECTION_STEP = 1e-6


class TwoParameterFlows:
    """The shooting flow maps of one system with derivatives in two parameters.

    Two :class:`~cablesim.orbits.shooting.Shooting` objects share the system: one differentiates
    ``p1`` (``omega`` or a parameter of ``prm``), the other ``p2`` (a parameter of ``prm``);
    :meth:`set` puts the parameter values into both.
    """

    def __init__(self, system: OdeSystem, period: int, segments: int, parameters: tuple[str, str],
                 integration: dict | None = None):
        p1, p2 = parameters
        if p2 == "omega" or p2 not in system.parameters:
            raise ValueError(f"the second parameter must be one of {sorted(system.parameters)}, got {p2!r} "
                             "(omega, differentiated through the time scale, can only be the first)")
        if p1 == p2:
            raise ValueError("the two parameters must differ")
        integration = integration or {}
        self.base = system
        self.p1, self.p2 = p1, p2
        self.sh1 = Shooting(system, period, segments, parameter=p1, **integration)
        self.sh2 = Shooting(system, period, segments, parameter=p2, **integration)
        self.n, self.m = system.dim, segments

    def set(self, x1: float, x2: float) -> None:
        """Parameter values of the following evaluations."""
        sysm = self.base.with_prm(self.base.parameters[self.p2], x2)
        if self.p1 == "omega":
            self.sh1.system = sysm
            self.sh2.system = replace(sysm, omega=float(x1))
        else:
            sysm = sysm.with_prm(self.base.parameters[self.p1], x1)
            self.sh1.system = self.sh2.system = sysm

    def base_data(self, u: np.ndarray, x1: float, x2: float):
        """``(Evaluation, dparams (m, n, 2))`` at ``(u, x1, x2)``; ``dparams`` is None if a
        flow failed (the evaluation's ``status`` says why)."""
        self.set(x1, x2)
        ev = self.sh1.evaluate(u, x1)
        if ev.status != ok.OK:
            return ev, None
        S = np.asarray(u, dtype=float).reshape(self.m, self.n)
        d2 = []
        for k in range(self.m):
            seg = self.sh2.segment(k, S[k], x2, jac=True)
            if seg["status"] != ok.OK:
                return replace(ev, status=FlowStatus(seg["status"])), None
            d2.append(seg["dp"])
        return ev, np.stack([ev.J_lam.reshape(self.m, self.n), np.array(d2)], axis=-1)

    def directional(self, u: np.ndarray, x1: float, x2: float, directions: np.ndarray,
                    eps: float) -> bd.DirectionalData | None:
        """Segment Jacobians and parameter derivatives at ``u + eps directions`` (after
        :meth:`set` with the same values), or None if a flow failed."""
        S = np.asarray(u, dtype=float).reshape(self.m, self.n) + eps * directions
        G, dps = [], []
        for k in range(self.m):
            a = self.sh1.segment(k, S[k], x1, jac=True)
            b = self.sh2.segment(k, S[k], x2, jac=True)
            if a["status"] != ok.OK or b["status"] != ok.OK:
                return None
            G.append(a["G"])
            dps.append(np.stack([a["dp"], b["dp"]], axis=-1))
        return bd.DirectionalData(directions, eps, np.array(G), np.array(dps))

    @property
    def calls(self) -> int:
        """Segment integrations so far."""
        return self.sh1.calls + self.sh2.calls


@dataclass
class LocusEvaluation:
    """The residual of a locus and its derivatives at one ``(U, p2)``.

    Attributes
    ----------
    r, J_u, J_lam : ndarray
        Residual ``(r, g)``, its Jacobian with respect to ``U = (u, p1[, kappa])`` and to ``p2``
        (the continuation's protocol).
    orbit : Evaluation
        The shooting evaluation of the periodic orbit (multipliers, extremes, Liouville).
    p1, p2, kappa : float
    V, W : ndarray
        Right and left null vectors of the defining matrix (scaled, in the subspace).
    g : ndarray
        The defining functions (all bordered entries; ``r`` holds the ones used).
    critical : list of int
        Indices of the critical multipliers in ``orbit.multipliers``.
    cusp : float
        Normalised quadratic coefficient of a fold (NaN for the other kinds).
    """

    r: np.ndarray
    J_u: np.ndarray
    J_lam: np.ndarray
    orbit: Evaluation
    p1: float
    p2: float
    kappa: float
    V: np.ndarray
    W: np.ndarray
    g: np.ndarray
    critical: list
    cusp: float = np.nan
    #: On a curve of planar orbits: the other multipliers of the critical one's block.
    block_others: np.ndarray | None = None

    @property
    def multipliers(self) -> np.ndarray:
        return self.orbit.multipliers

    @property
    def others(self) -> np.ndarray:
        """The multipliers other than the critical ones (of its block, on a curve of planar
        orbits of a mirror-symmetric system)."""
        if self.block_others is not None:
            return self.block_others
        keep = np.ones(self.orbit.multipliers.size, dtype=bool)
        keep[self.critical] = False
        return self.orbit.multipliers[keep]


class LocusProblem:
    """A curve of bifurcations of ``kind`` as a continuation problem (module docstring).

    Parameters
    ----------
    flows : TwoParameterFlows
    kind : str
        ``"fold"``, ``"period-doubling"`` or ``"neimark-sacker"``.
    state_scale : ndarray (n,)
        Typical size of each state component.
    scales : (float, float)
        Typical sizes of ``p1`` and ``p2``.
    subspace : ndarray (n, q), optional
        Orthonormal basis (scaled coordinates) of an invariant subspace of the multipliers the
        bifurcation belongs to (default: the whole state space).
    levels : sequence of float
        Values of ``p2`` whose crossings are located.
    mirror : Mirror, optional
        For a curve of planar orbits of a mirror-symmetric system
        (:class:`~cablesim.orbits.symmetry.Mirror`), with ``plane`` the block (``in-plane`` or
        ``out-of-plane``) of the critical multiplier: the codimension-two tests look at that
        block's other multipliers only (a multiplier of the other block at -1 or +1 is where
        this curve crosses a curve of the other block, not a resonance of this one). Required
        for ``"pitchfork"``: the curve is one of planar orbits whose odd block has the
        multiplier +1; the singularity is sought in that block (the default subspace) and the
        odd rows of the periodicity condition, which vanish on a planar orbit and carry the
        pitchfork's null vector, are replaced by ``P_o u = 0`` (``P_o`` the projector on the odd
        coordinates), which keeps the orbit in the plane and the system regular.
    plane : str, optional
        See ``mirror``.
    """

    def __init__(self, flows: TwoParameterFlows, kind: str, state_scale: np.ndarray, scales: tuple[float, float],
                 subspace: np.ndarray | None = None, levels=(), mirror=None, plane: str | None = None):
        if kind not in bd.RANK_DEFECT:
            raise ValueError(f"unknown kind {kind!r}: one of {sorted(bd.RANK_DEFECT)}")
        self.flows, self.kind = flows, kind
        n, m = flows.n, flows.m
        self.n, self.m, self.N = n, m, n * m
        self.d, self.extra = bd.RANK_DEFECT[kind], bd.EXTRA_UNKNOWNS[kind]
        self.scale = np.asarray(state_scale, dtype=float)
        self.P_odd = None
        #: Orthonormal basis (state coordinates) of the block of the critical multiplier.
        self.block = None
        if mirror is not None and plane in mirror.labels:
            self.block = mirror.even if plane == mirror.labels[0] else mirror.odd
        if kind == "pitchfork":
            if mirror is None:
                raise ValueError("a pitchfork curve needs the mirror symmetry of the system (mirror)")
            odd = mirror.odd
            self.block = odd
            self.P_odd = odd @ odd.T
            if subspace is None:  # the odd coordinates in the scaled ones, orthonormal
                subspace = np.linalg.qr(odd / self.scale[:, None])[0]
        self.Q = np.eye(n) if subspace is None else np.asarray(subspace, dtype=float)
        self.levels = tuple(float(x) for x in levels)
        self.u_scale = np.concatenate([np.tile(self.scale, m), [float(scales[0])], np.ones(self.extra)])
        self.lam_scale = float(scales[1])
        self.r_scale = np.concatenate([np.tile(self.scale, m), np.ones(self.d)])
        self.test_names = CODIM2_TESTS[kind] + tuple(f"level {x:g}" for x in self.levels)
        #: The bordered entries used as equations (two of the four for Neimark-Sacker).
        self.entries = [(0, 0)] if self.d == 1 else [(0, 0), (1, 1)]
        self.B = self.C = None
        self.last_failure: FlowStatus | None = None
        self.evaluations = 0

    # ------------------------------------------------------------------------------------------
    def start(self, u: np.ndarray, x1: float, x2: float, kappa: float = 0.0) -> np.ndarray:
        """Borders from the orbit at ``(u, x1, x2)`` (a located bifurcation) and the unknowns
        ``U`` there.

        Raises
        ------
        FloatingPointError
            If the orbit's flow cannot be evaluated there.
        """
        ev, _ = self.flows.base_data(u, x1, x2)
        if ev.status != ok.OK:
            raise FloatingPointError(f"the flow of the start orbit failed ({ev.status.name})")
        self.B, self.C = bd.initial_borders(self._restricted(self._scaled(ev.monodromy), kappa), self.d)
        return np.concatenate([np.asarray(u, dtype=float), [x1], [kappa] if self.extra else []])

    def borders(self) -> tuple[np.ndarray, np.ndarray]:
        return self.B.copy(), self.C.copy()

    def set_borders(self, B: np.ndarray, C: np.ndarray) -> None:
        self.B, self.C = B.copy(), C.copy()

    def accept(self, ev: LocusEvaluation) -> None:
        """After an accepted point: borders from its null vectors."""
        self.B, self.C = bd.orthonormal(ev.W), bd.orthonormal(ev.V)

    def _scaled(self, M: np.ndarray) -> np.ndarray:
        return M * (self.scale[None, :] / self.scale[:, None])

    def _restricted(self, Ms: np.ndarray, kappa: float) -> np.ndarray:
        return self.Q.T @ bd.defining_matrix(self.kind, Ms, kappa) @ self.Q

    # ------------------------------------------------------------------------------------------
    def evaluate(self, U: np.ndarray, lam: float) -> LocusEvaluation | None:
        """The residual and Jacobian at ``(U, p2 = lam)``; None where a flow fails."""
        self.evaluations += 1
        N = self.N
        u, x1 = U[:N], float(U[N])
        kappa = float(U[N + 1]) if self.extra else 0.0
        x2 = float(lam)
        ev, dparams = self.flows.base_data(u, x1, x2)
        if dparams is None:
            self.last_failure = ev.status
            return None
        Ms = self._scaled(ev.monodromy)
        try:
            V, W, G = bd.bordered_solve(self._restricted(Ms, kappa), self.B, self.C)
        except np.linalg.LinAlgError:
            return None
        rows = self._gradients(u, x1, x2, kappa, ev, dparams, Ms, V, W)
        if rows is None:
            return None
        g = np.array([G[i, j] for i, j in self.entries])
        nU = N + 1 + self.extra
        J_u = np.zeros((N + self.d, nU))
        J_u[:N, :N] = ev.J_u
        J_u[:N, N] = dparams[:, :, 0].ravel()
        J_lam = np.concatenate([dparams[:, :, 1].ravel(), np.zeros(self.d)])
        for e, (gu, gp, gk) in enumerate(rows[0]):
            J_u[N + e, :N] = gu
            J_u[N + e, N] = gp[0]
            if self.extra:
                J_u[N + e, N + 1] = gk
            J_lam[N + e] = gp[1]
        r = ev.r
        if self.P_odd is not None:
            r = self._in_the_plane(u, r, J_u, J_lam)
        crit = bd.critical_indices(self.kind, ev.multipliers, kappa)
        block_others = None
        if self.block is not None:  # the other multipliers of the critical one's block
            mu_b = np.linalg.eigvals(self.block.T @ ev.monodromy @ self.block)
            block_others = np.delete(mu_b, bd.critical_indices(self.kind, mu_b, kappa))
        return LocusEvaluation(r=np.concatenate([r, g]), J_u=J_u, J_lam=J_lam, orbit=ev, p1=x1, p2=x2,
                               kappa=kappa, V=V, W=W, g=G.ravel(), critical=crit, cusp=rows[1],
                               block_others=block_others)

    def _in_the_plane(self, u, r, J_u, J_lam) -> np.ndarray:
        """The periodicity rows of a pitchfork curve (``odd`` in the class docstring): per
        segment ``P_e r + P_o u``, with ``J_u`` and ``J_lam`` changed to match in place."""
        n, m, N = self.n, self.m, self.N
        Po = self.P_odd
        Pe = np.eye(n) - Po
        rows = np.empty(N)
        for k in range(m):
            s = slice(k * n, (k + 1) * n)
            rows[s] = Pe @ r[s] + Po @ u[s]
            J_u[s, : N + 1] = Pe @ J_u[s, : N + 1]
            J_u[s, s] += Po
            J_lam[s] = Pe @ J_lam[s]
        return rows

    def _gradients(self, u, x1, x2, kappa, ev, dparams, Ms, V, W):
        """``([(dg/du, dg/dp, dg/dkappa) per equation], cusp coefficient)``, or None if a
        displaced flow failed (:func:`~cablesim.orbits.bordered.bilinear_gradient`)."""
        cache: dict = {}

        def along(b_scaled):
            b = b_scaled * self.scale
            key = b.tobytes()
            if key not in cache:
                dirs = bd.segment_directions(ev.G, b)
                eps = DIRECTION_STEP / max(float(np.abs(dirs / self.scale).max()), 1e-300)
                cache[key] = self.flows.directional(u, x1, x2, dirs, eps)
            return cache[key]

        QtMQ = self.Q.T @ Ms @ self.Q
        dk = bd.kappa_derivative(self.kind, QtMQ, W, V)
        rows = []
        for i, j in self.entries:
            w, v = self.Q @ W[:, i], self.Q @ V[:, j]
            gu, gp = np.zeros(self.N), np.zeros(2)
            for c, a, b in bd.derivative_terms(self.kind, Ms, kappa, w, v):
                data = along(b)
                if data is None:
                    return None
                du, dp = bd.bilinear_gradient(ev.G, dparams, a / self.scale, data)
                gu -= c * du
                gp -= c * dp
            rows.append((gu, gp, dk[i, j]))
        cusp = np.nan
        if self.kind == "fold":
            w, v = self.Q @ W[:, 0], self.Q @ V[:, 0]
            data = along(v)
            du, _ = bd.bilinear_gradient(ev.G, dparams, w / self.scale, data)
            cusp = float(du @ data.directions.ravel()) / (np.linalg.norm(w) * np.linalg.norm(v) ** 2)
        return rows, cusp

    # ------------------------------------------------------------------------------------------
    def test_functions(self, ev: LocusEvaluation) -> np.ndarray:
        """Values of :data:`CODIM2_TESTS` of the kind, then ``p2 - level`` for each level."""
        nc = np.asarray(ev.others, dtype=complex)
        minus = np.prod(nc - 1.0).real if nc.size else 1.0
        plus = np.prod(1.0 + nc).real if nc.size else 1.0
        pairs = stability.test_functions(nc)[1] if nc.size > 1 else 1.0
        if self.kind == "fold":
            values = [ev.cusp, plus, minus, pairs]
        elif self.kind == "pitchfork":
            values = [plus, minus, pairs]
        elif self.kind == "period-doubling":
            values = [minus, plus, pairs]
        else:
            k = ev.kappa
            values = [k - 1.0, k + 1.0, k + 0.5, k, minus, plus]
        return np.array(values + [ev.p2 - x for x in self.levels], dtype=float)

    def confirm(self, name: str, ev: LocusEvaluation) -> str | None:
        """A Neimark-Sacker test counts only where a complex pair crosses the unit circle (not
        at a neutral saddle)."""
        if name.endswith("neimark-sacker") and self.kind != "neimark-sacker":
            return name if stability.confirm("neimark-sacker", ev.others) else None
        return name

    def step_ratio(self, a: LocusEvaluation, b: LocusEvaluation, before=None) -> float:
        """How far the non-critical multipliers moved (:func:`~cablesim.orbits.stability.step_ratio`)."""
        oa, ob = a.others, b.others
        if oa.size == 0 or oa.size != ob.size:
            return 0.0
        return stability.step_ratio(oa, ob)
