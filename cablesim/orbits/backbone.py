"""Backbone curves: the family of periodic orbits of an unforced, undamped system from a linear mode.

The free, conservative motions near a linear mode ``K`` of frequency ``w_K`` form a
one-parameter family of periodic orbits (a nonlinear normal mode): its frequency against its
amplitude is the *backbone* that the peaks of every lightly damped forced response follow.
The period ``T = 2 pi / w`` is unknown and the orbit's time origin arbitrary, so
:class:`BackboneProblem` solves, for the unknowns ``U = (u, delta)`` and the frequency ``w`` as
the continuation parameter::

    Phi_T(u; delta) - u = 0        (periodicity, shooting over T = p 2 pi / w)
    x_j(0) = 0                     (phase condition: component j vanishes at t = 0)

where ``delta`` is an *artificial damping* (Munoz-Almaraz, Freire, Galan, Doedel, Vanderbauwhede,
Physica D 181, 2003): the system must unfold its conserved energy by a parameter ``delta`` that
makes it strictly decrease along every non-constant orbit (for a mechanical system
``v' = ... - delta v``). Periodic orbits then exist only at ``delta = 0``, which Newton's method
finds, and the family is a regular curve of the extended system (without the unfolding the
periodicity condition of a conservative system is degenerate: a whole family solves it at
fixed ``w``). ``delta`` is reported; it stays at round-off level.

The derivative with respect to ``delta`` comes from the flow kernel; the one with respect to
``w`` from the time scale of an autonomous field (``dPhi/dw = -(T_seg / w) f(Phi)`` per segment,
exact for the continuous flow and to the integration error for the discrete one). The start is
the linear mode at a small amplitude, corrected on the hyperplane normal to the mode; the
family is then followed by :func:`cablesim.orbits.continuation.continuation` to the requested
amplitude.

Internal resonances: about an orbit of the family the other modes oscillate with Floquet
multipliers ``exp(+-2 pi i rho_j)``; ``rho_j`` (the mode's frequency in units of the backbone's)
is followed by continuity from its linear value ``w_j / w_K``. Where ``rho_j`` passes an integer
``k`` (the multiplier pair through +1: mode j at k times the backbone's frequency) or a
half-integer (through -1), the family meets a ``k:1`` or ``(2k+1):2`` internal resonance: the
point is located and named, and the continuation goes on along the family's branch through it.
Only modes with ``rho_j <= max_ratio`` are watched (a fast axial mode passes high multiples
constantly, with no exchange of energy worth naming). Stability: an orbit is stable when no
multiplier leaves the unit circle (beyond 1e-6).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from . import kernels as ok
from .continuation import Settings, continuation
from .shooting import Evaluation, FlowStatus, Shooting
from .systems import OdeSystem

#: Largest ``|mu| - 1`` of a stable conservative orbit (round-off of the discrete flow map).
STABILITY_TOL = 1e-6
#: Largest change of a watched frequency ratio per step.
RATIO_STEP = 0.05
#: Largest distance of a frequency ratio from its rational value at a located internal resonance.
RESONANCE_TOL = 1e-7


@dataclass
class BackboneEvaluation:
    """Residual, Jacobian and orbit data at one ``(U, w)`` (the continuation's protocol)."""

    r: np.ndarray
    J_u: np.ndarray
    J_lam: np.ndarray
    orbit: Evaluation
    omega: float
    delta: float
    ratios: np.ndarray
    others: np.ndarray
    vectors: np.ndarray
    tracked: np.ndarray


@dataclass
class BackbonePoint:
    """One periodic orbit of the family.

    Attributes
    ----------
    index : int
    omega : float
        Its frequency ``2 pi p / T``, rad/s.
    delta : float
        The artificial damping (zero up to round-off on a periodic orbit).
    state : ndarray (n,)
        State at ``t = 0`` (phase condition: component ``phase_index`` is zero).
    u : ndarray (m n,)
    amplitude, halfrange : ndarray
        Largest ``|x_i|`` and half the range over the orbit, per displacement component.
    multipliers : ndarray complex
    ratios : ndarray
        ``rho_j``: frequency of each other linear mode about the orbit, in units of ``omega``.
    stable, trusted : bool
    special : str or None
        ``"<k>:<l> internal resonance with mode <j>"`` where the family meets one.
    located : bool
    """

    index: int
    omega: float
    delta: float
    state: np.ndarray
    u: np.ndarray
    amplitude: np.ndarray
    halfrange: np.ndarray
    multipliers: np.ndarray
    ratios: np.ndarray
    stable: bool
    trusted: bool
    special: str | None = None
    located: bool = True


@dataclass
class Backbone:
    """A backbone curve: the family's points in order, why it ended and its cost."""

    mode: int
    linear_omega: float
    modes: np.ndarray
    points: list = field(default_factory=list)
    end: str = ""
    evaluations: int = 0
    segments: int = 0
    seconds: float = 0.0

    def values(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])

    @property
    def resonances(self) -> list:
        """The internal resonances met."""
        return [p for p in self.points if p.special is not None]


def linear_modes(system: OdeSystem, unfolding: str):
    """The undamped linear modes of the system about ``x = 0``: frequencies (ascending, rad/s)
    and complex eigenvectors (columns) of the field's Jacobian there, ``delta = 0``."""
    n = system.dim
    prm = system.prm.copy()
    prm[system.parameters[unfolding]] = 0.0
    dx, J, dp = np.empty(n), np.zeros((n, n)), np.zeros(n)
    code = system.field(0.0, float(system.omega), np.zeros(n), system.model, prm, ok.copy_work(system.work), dx, J, dp, -1)
    if code != ok.OK:
        raise FloatingPointError(f"the field cannot be evaluated at its equilibrium (status {code})")
    lam, vec = np.linalg.eig(J)
    keep = np.flatnonzero(lam.imag > 1e-12 * max(1.0, np.abs(lam).max()))
    order = keep[np.argsort(lam.imag[keep])]
    return lam.imag[order], vec[:, order]


def mode_start(system: OdeSystem, unfolding: str, mode: int, amplitude: float):
    """``(x0, omega, phase_index, frequencies, vectors)``: linear mode ``mode`` (1-based) at
    phase 0 with its largest displacement ``amplitude``, the component that vanishes there, and
    every mode's frequency and eigenvector (:func:`linear_modes`)."""
    freqs, vecs = linear_modes(system, unfolding)
    if not 1 <= mode <= freqs.size:
        raise ValueError(f"mode {mode} does not exist: the system has {freqs.size} oscillatory modes")
    e = vecs[:, mode - 1]
    d = system.displacements
    j = d[int(np.argmax(np.abs(e[d])))]
    e = e * (np.abs(e[j]) / e[j])  # its largest displacement real: x(0) = Re e at a turning point
    phase_index = int(np.argmax(np.abs(e.imag)))
    x0 = e.real * (amplitude / np.abs(e.real[d]).max())
    x0[phase_index] = 0.0
    return x0, float(freqs[mode - 1]), phase_index, freqs, vecs


class BackboneProblem:
    """The periodic orbits of the unforced system as a continuation problem (module docstring).

    Parameters
    ----------
    system : OdeSystem
        Autonomous (its field must not depend on the forcing phase) and conservative at
        ``delta = 0``.
    unfolding : str
        The parameter ``delta`` of ``system.parameters``.
    phase_index : int
        Component that vanishes at ``t = 0``.
    state_scale : ndarray (n,)
    omega_scale : float
    mode : int
        The mode followed (1-based; its own multipliers are the trivial pair at +1).
    frequencies : ndarray
        Linear frequencies of all modes, rad/s (the start of the frequency ratios).
    vectors : ndarray (n, modes) complex
        Their eigenvectors (of the Jacobian at the equilibrium, eigenvalue ``i w``).
    """

    def __init__(self, system: OdeSystem, unfolding: str, phase_index: int, state_scale: np.ndarray,
                 omega_scale: float, mode: int, frequencies: np.ndarray, vectors: np.ndarray, period: int = 1,
                 segments: int = 1,
                 integration: dict | None = None, max_ratio: float = 5.0):
        self.base = system
        self.sh = Shooting(system, period, segments, parameter=unfolding, **(integration or {}))
        self.n, self.m = system.dim, segments
        self.N = self.n * self.m
        self.phase_index = int(phase_index)
        self.scale = np.asarray(state_scale, dtype=float)
        w = float(frequencies[mode - 1])
        self.others_modes = np.array([k for k in range(frequencies.size) if k != mode - 1], dtype=int)
        self.reference = np.asarray(frequencies, dtype=float)[self.others_modes] / w
        self.max_ratio = float(max_ratio)
        vecs = np.asarray(vectors, dtype=complex)[:, self.others_modes] / self.scale[:, None]
        vecs[self.phase_index] = 0.0  # on the phase section, as the Poincare map's (see _ratios)
        self.vectors = vecs / np.linalg.norm(vecs, axis=0)
        delta_scale = w * 1e-3
        self.u_scale = np.concatenate([np.tile(self.scale, self.m), [delta_scale]])
        self.lam_scale = float(omega_scale)
        self.r_scale = np.concatenate([np.tile(self.scale, self.m), [self.scale[self.phase_index]]])
        self.test_names = tuple(f"mode {k + 1}" for k in self.others_modes)
        self.last_failure: FlowStatus | None = None
        self.evaluations = 0

    def _end_rates(self, ev: Evaluation) -> np.ndarray:
        """``f`` at the end of every segment (for the derivative with respect to ``omega``)."""
        sysm = self.sh.system
        prm = sysm.prm.copy()
        prm[sysm.parameters[self.sh.parameter]] = ev.lam
        out = np.empty((self.m, self.n))
        dx, J, dp = np.empty(self.n), np.zeros((self.n, self.n)), np.zeros(self.n)
        for k in range(self.m):
            code = sysm.field(0.0, float(sysm.omega), np.ascontiguousarray(ev.ends[k]), sysm.model, prm,
                              ok.copy_work(sysm.work), dx, J, dp, -1)
            if code != ok.OK:
                return None
            out[k] = dx
        return out

    def evaluate(self, U: np.ndarray, lam: float) -> BackboneEvaluation | None:
        self.evaluations += 1
        N = self.N
        omega = float(lam)
        if not omega > 0.0:
            return None
        self.sh.system = replace(self.base, omega=omega)
        ev = self.sh.evaluate(U[:N], float(U[N]))
        if ev.status != ok.OK:
            self.last_failure = ev.status
            return None
        rates = self._end_rates(ev)
        if rates is None:
            return None
        seg = ev.T / self.m
        J_u = np.zeros((N + 1, N + 1))
        J_u[:N, :N] = ev.J_u
        J_u[:N, N] = ev.J_lam
        J_u[N, self.phase_index] = 1.0
        J_lam = np.concatenate([(-seg / omega) * rates.ravel(), [0.0]])
        r = np.concatenate([ev.r, [U[self.phase_index]]])
        ratios, others, vectors, tracked = self._ratios(ev.monodromy, rates[-1])
        return BackboneEvaluation(r=r, J_u=J_u, J_lam=J_lam, orbit=ev, omega=omega, delta=float(U[N]),
                                  ratios=ratios, others=others, vectors=vectors, tracked=tracked)

    def _section(self, f: np.ndarray) -> np.ndarray:
        """``I - f e_j^T / f_j`` (scaled coordinates): along the flow onto the phase section."""
        fs = f / self.scale
        P = np.eye(self.n)
        if fs[self.phase_index] != 0.0:
            P[:, self.phase_index] -= fs / fs[self.phase_index]
        return P

    def _ratios(self, M: np.ndarray, f: np.ndarray):
        """The frequency ratios followed from the last accepted point (module docstring), their
        eigenvectors, and the multipliers without the trivial pair.

        The trivial pair is removed exactly: on the phase section ``x_j = 0`` the linearised
        Poincare map ``D = (I - f e_j^T / f_j) M`` keeps every multiplier but the flow's own
        (its eigenvectors are those of ``M`` carried along the flow onto the section), and its
        eigenvalue 1 along the family is semisimple, so it is told from a mode's pair passing +1
        to round-off. A multiplier ``exp(2 pi i theta)`` gives ``rho`` only up to an integer and
        a sign (its conjugate partner has ``-theta``): each mode keeps the eigenvector that
        overlaps most with its eigenvector at the last point, and the integer that puts ``rho``
        nearest its last value; where a pair passes +1 or -1 the eigenvector goes on smoothly
        while its multiplier crosses to the other half-plane, so a ratio passing an integer is
        told from one turning back."""
        j = self.phase_index
        Ms = M * (self.scale[None, :] / self.scale[:, None])
        D = (self._section(f) @ Ms)
        keep = np.arange(self.n) != j
        mu, Y = np.linalg.eig(D[np.ix_(keep, keep)])
        X = np.zeros((self.n, mu.size), dtype=complex)
        X[keep] = Y
        X /= np.linalg.norm(X, axis=0)
        rest_i = np.ones(mu.size, dtype=bool)
        rest_i[int(np.argmin(np.abs(mu - 1.0)))] = False  # the family's own direction
        rest, Xr = mu[rest_i], X[:, rest_i]
        out, vectors = self.reference.copy(), self.vectors.copy()
        tracked = np.exp(2j * np.pi * out)
        if rest.size == 0:
            return out, rest, vectors, tracked
        for k, rho in enumerate(self.reference):
            overlap = self.vectors[:, k].conj() @ Xr
            c = int(np.argmax(np.abs(overlap)))
            theta = np.angle(rest[c]) / (2.0 * np.pi)
            out[k] = theta + np.round(rho - theta)
            tracked[k] = rest[c]
            vectors[:, k] = Xr[:, c] * (np.abs(overlap[c]) / overlap[c] if overlap[c] != 0 else 1.0)
        return out, rest, vectors, tracked

    def accept(self, ev: BackboneEvaluation) -> None:
        """After an accepted point: its ratios and eigenvectors are the reference of the next."""
        self.reference = ev.ratios.copy()
        self.vectors = ev.vectors.copy()

    def test_functions(self, ev: BackboneEvaluation) -> np.ndarray:
        """``sin(2 pi rho_j)`` for the watched modes: zero where a mode's pair reaches +1 (an
        integer ratio) or -1 (a half-integer). Where the pair splits along the real axis there
        (the orbit is unstable over a short stretch of the family) the ratio stays at the
        rational value, and the located point lies on that stretch. Modes beyond ``max_ratio``
        give 1 (the test's value at ``rho = k + 1/4``, so that it stays continuous)."""
        rho = ev.ratios
        return np.where(rho <= self.max_ratio + 0.25, np.sin(2.0 * np.pi * rho), 1.0)

    def confirm(self, name: str, ev: BackboneEvaluation) -> str | None:
        """``"<k>:<l> internal resonance with mode <j>"`` from the ratio at the point."""
        j = self.test_names.index(name)
        k2 = int(round(2.0 * float(ev.ratios[j])))
        ratio = f"{k2 // 2}:1" if k2 % 2 == 0 else f"{k2}:2"
        return f"{ratio} internal resonance with mode {self.others_modes[j] + 1}"

    def step_ratio(self, a: BackboneEvaluation, b: BackboneEvaluation, before=None) -> float:
        watched = (a.ratios <= self.max_ratio + 1.0) | (b.ratios <= self.max_ratio + 1.0)
        if not watched.any():
            return 0.0
        return float(np.abs(b.ratios - a.ratios)[watched].max()) / RATIO_STEP


def _point(problem: BackboneProblem, system: OdeSystem, cp, index: int, liouville_tol: float) -> BackbonePoint:
    ev: BackboneEvaluation = cp.evaluation
    orb = ev.orbit
    d = system.displacements
    xmax, xmin = orb.xmax[d], orb.xmin[d]
    stable = bool(ev.others.size == 0 or np.abs(ev.others).max() <= 1.0 + STABILITY_TOL)
    trusted = bool(cp.residual <= 1e-8 and orb.liouville <= liouville_tol and np.all(np.isfinite(orb.multipliers)))
    located = cp.located
    if cp.special is not None and not located:
        # where the pair splits along the real axis the ratio is flat at its rational value and
        # the secant cannot shrink its bracket: the point is on the resonance if its ratio is
        located = bool(np.abs(np.sin(2.0 * np.pi * ev.ratios)).min() <= 2.0 * np.pi * RESONANCE_TOL)
    return BackbonePoint(index=index, omega=ev.omega, delta=ev.delta, state=cp.u[: problem.n].copy(),
                         u=cp.u[: problem.N].copy(), amplitude=np.maximum(np.abs(xmax), np.abs(xmin)),
                         halfrange=0.5 * (xmax - xmin), multipliers=orb.multipliers.copy(), ratios=ev.ratios.copy(),
                         stable=stable, trusted=trusted, special=cp.special, located=located)


def trace_backbone(
    system: OdeSystem,
    mode: int,
    amplitude: float,
    unfolding: str = "delta",
    channels: np.ndarray | None = None,
    start_fraction: float = 0.01,
    state_scale: np.ndarray | None = None,
    settings: Settings | None = None,
    integration: dict | None = None,
    max_ratio: float = 5.0,
    liouville_tol: float = 1e-3,
    callback: Callable[[BackbonePoint], bool | None] | None = None,
) -> Backbone:
    """The backbone of linear mode ``mode`` up to ``amplitude`` (module docstring).

    Parameters
    ----------
    system : OdeSystem
        Autonomous, conservative at ``delta = 0``, with the unfolding parameter.
    mode : int
        Linear mode (1-based, by increasing frequency).
    amplitude : float
        The family is followed until the largest ``|x_i|`` over the orbit, among the
        displacement components ``channels``, reaches this.
    unfolding : str
        Name of the artificial damping in ``system.parameters``.
    channels : ndarray of int, optional
        Positions in ``system.displacements`` whose amplitude counts (default: all).
    start_fraction : float
        The first orbit's amplitude as a fraction of ``amplitude``.
    state_scale : ndarray (n,), optional
        Default: ``amplitude`` for displacements, ``amplitude * w_K`` for the rest.
    settings : Settings, optional
        Continuation settings (frequency bounds default to ``w_K / 4 .. 4 w_K``).
    integration : dict, optional
        ``scheme``, ``steps_per_period``, ``step_rate``.
    max_ratio : float
        Largest frequency ratio of the internal resonances watched.
    liouville_tol : float
    callback : callable, optional
        Receives every point; True ends the backbone.

    Returns
    -------
    Backbone
    """
    t0 = time.perf_counter()
    x0, w_k, phase_index, freqs, vecs = mode_start(system, unfolding, mode, start_fraction * amplitude)
    d = system.displacements
    sel = d if channels is None else d[np.asarray(channels, dtype=int)]
    if state_scale is None:
        state_scale = np.full(system.dim, amplitude * w_k)
        state_scale[d] = amplitude
    problem = BackboneProblem(system, unfolding, phase_index, state_scale, w_k, mode, freqs, vecs,
                              integration=integration, max_ratio=max_ratio)
    st = settings if settings is not None else Settings()
    if not np.isfinite(st.lam_min) and not np.isfinite(st.lam_max):
        st = replace(st, lam_min=0.25 * w_k, lam_max=4.0 * w_k)
    bb = Backbone(mode=mode, linear_omega=w_k, modes=freqs)
    pos = np.searchsorted(d, sel)

    def on_point(cp) -> bool:
        problem.accept(cp.evaluation)
        p = _point(problem, system, cp, len(bb.points), liouville_tol)
        bb.points.append(p)
        if p.amplitude[pos].max() >= amplitude:
            bb.end = f"reached the amplitude {amplitude:g}"
            return True
        if callback is not None and callback(p):
            bb.end = "stopped by callback"
            return True
        return False

    U0 = np.concatenate([x0, [0.0]])
    tangent = np.concatenate([x0, [0.0, 0.0]])
    res = continuation(problem, U0, w_k, st, callback=on_point, tangent=tangent)
    if not bb.end:
        texts = {0: "reached a bound of the frequency", 1: "most points reached", 2: "step too small",
                 4: "start failed"}
        bb.end = texts.get(int(res.status), str(res.status))
        if int(res.status) in (2, 4) and problem.last_failure is not None:
            bb.end += f" (the flow failed: {problem.last_failure.name.lower()})"
    bb.evaluations = problem.evaluations
    bb.segments = problem.sh.calls
    bb.seconds = time.perf_counter() - t0
    return bb
