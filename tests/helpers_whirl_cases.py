"""Located out-of-plane bifurcations of the independent reference (``helpers_whirl.py``), their
case files, and the damped Mathieu closed form of a taut stay excited at its anchorage.

- :data:`WHIRL_CASE`: one mass between two segments, forced vertically near its in-plane
  frequency; :func:`pitchfork_omega` and :func:`pitchfork_amplitude` locate the forcing
  frequency (at the case's amplitude) and the load scale gamma (at the case's frequency) where an
  out-of-plane multiplier of the planar periodic response passes +1 (the whirling pitchfork);
  :func:`whirling_orbit` computes the nonplanar orbit past it by full spatial shooting.
- :func:`stay_case` (``nodes`` a parameter): a taut stay without gravity, its anchorage moving
  along the chord; :func:`tongue_edges` and :func:`tongue_threshold` locate where its first
  out-of-plane mode loses stability (multiplier -1 near omega = 2 w1).
- :func:`stay_mathieu`, :func:`mathieu_threshold`, :func:`mathieu_edges`: the closed form,
  :func:`mathieu_multipliers` the numerical Floquet of the damped Mathieu equation.

Every function taking a case takes a ``cablesim.case.Case`` (``cablesim.api.load_case``), whose
numbers only are read (:func:`helpers_whirl.cable_from_case`); :func:`cable_from_yaml` reads a
case file's raw numbers with the format's lumping rules written again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import yaml
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

from cablesim.api import load_case
from helpers_whirl import (
    LumpedCable,
    Motion,
    Orbit,
    cable_from_case,
    flow,
    floquet_multipliers,
    out_of_plane_monodromy,
    periodic_orbit,
    static_equilibrium,
    to_spatial,
    with_damping,
)

WHIRL_CASE = """\
# One mass between two elastic segments, sagging a little under light gravity, forced
# vertically in its plane near its in-plane frequency: the out-of-plane (whirling) motion is in
# principal parametric resonance with the tension modulated at twice the forcing frequency.
name: whirl-one-node
spatial: true
cable:
  L: 2.0                   # m
  H: 0.0                   # level supports
  S: [0.99, 0.99]          # natural lengths, m: about 1 % stretched
  EA: 1000.0               # N
  masses: [1.0]            # kg
loads:
  gravity: 0.5             # m/s^2, light: the node sags about 2.5 cm
  point:
    - {node: 1, FL: [0.0, 0.05, 0.0]}   # vertical harmonic load, N
damping:
  ratio: 0.005
  modes: [1, 2]
history:
  omega: 4.6               # rad/s
  duration: 300.0
  channels: [node1.v, node1.w]
outputs:
  split: false
"""

STAY_CASE = """\
# A taut stay without gravity, its anchorage A moving 5 mm along the chord (0.8, -0.6): the
# tension is modulated at the forcing frequency, and near twice the first out-of-plane frequency
# the first out-of-plane mode is in principal parametric resonance (multiplier -1).
name: stay-parametric
spatial: true
cable:
  L: 80.0                  # m
  H: -60.0                 # B 60 m above A: a 100 m chord
  length: 99.85            # natural length, m (taut: strain 1.5e-3)
  nodes: {nodes}
  EA: 2.0e9                # N
  mass_per_length: 80.0    # kg/m
loads:
  gravity: 0.0
supports:
  A:
    amplitude: [0.004, -0.003, 0.0]   # m: 5 mm along the chord
damping:
  ratio: 0.002
  modes: [1, 2]
history:
  omega: {omega}             # rad/s
  duration: 300.0
outputs:
  split: false
"""


def _pad(values, n: int, dim: int) -> np.ndarray:
    v = np.array(values, dtype=float).reshape(n, -1)
    out = np.zeros((n, dim))
    out[:, : v.shape[1]] = v
    return out.ravel()


def cable_from_yaml(data: dict) -> LumpedCable:
    """A :class:`LumpedCable` from the raw numbers of a case file (a mapping, as YAML loads it),
    lumped by the rules of the case format written again here: ``length`` / ``nodes`` give n+1
    equal segments; ``mass_per_length`` gives node r half of each adjacent segment,
    ``mu (S_r + S_(r+1)) / 2``; ``gravity`` adds ``g M_r`` along +v (point masses included);
    ``per_length`` adds ``q (S_r + S_(r+1)) / 2``; ``point`` adds loads and masses at a node (1-based, or the node nearest
    a position ``x`` along the span or fraction ``s`` of the natural length);
    a planar list (x, v per node) is padded with w = 0 in a spatial case."""
    cab, ld = data["cable"], data["loads"]
    n = len(cab["S"]) - 1 if "S" in cab else int(cab["nodes"])
    S = np.array(cab["S"], dtype=float) if "S" in cab else np.full(n + 1, float(cab["length"]) / (n + 1))
    share = 0.5 * (S[:-1] + S[1:])
    masses = np.array(cab["masses"], dtype=float) if "masses" in cab else float(cab["mass_per_length"]) * share
    sp = data.get("supports") or {}
    three = [len(p.get(k, ())) == 3 for p in ld.get("point", ()) for k in ("F", "FL")]
    three += [len(ld.get(k) or ()) == 3 * n and n > 0 for k in ("F0", "FL")] + [len(ld.get("per_length", ())) == 3]
    three += [float(m["amplitude"][2]) != 0 for m in sp.values() if len(m["amplitude"]) == 3]
    dim = 3 if data.get("spatial") or float(cab.get("W", 0.0)) != 0 or any(three) else 2
    F0 = _pad(ld["F0"], n, dim) if "F0" in ld else np.zeros(dim * n)
    FL = _pad(ld["FL"], n, dim) if "FL" in ld else np.zeros(dim * n)
    # a point given by position goes on the nearest node, node r standing at the fraction
    # s_r = (S_1 + ... + S_r) / sum S of the natural length, x_r = L s_r along the span (a tie: the
    # node nearer A)
    frac = np.cumsum(S)[:-1] / S.sum()
    for p in ld.get("point", ()):
        if "node" in p:
            i = int(p["node"]) - 1
        else:
            at = float(p["s"]) if "s" in p else float(p["x"]) / float(cab["L"])
            i = int(np.argmin(np.abs(frac - at)))  # (argmin: the first, nearer A, of equals)
        masses[i] += float(p.get("mass", 0.0))
        for key, target in (("F", F0), ("FL", FL)):
            if key in p:
                target[dim * i : dim * i + len(p[key])] += np.array(p[key], dtype=float)
    F0[1::dim] += float(ld.get("gravity", 0.0)) * masses
    for k, q in enumerate(ld.get("per_length", ())):
        F0[k::dim] += float(q) * share
    EA = float(cab["EA"]) if "EA" in cab else float(cab["E"]) * float(cab["A"])
    motion = {}
    for end in ("A", "B"):
        m = sp.get(end)
        motion["u" + end] = np.zeros(dim) if m is None else _pad(m["amplitude"][:dim], 1, dim)
        motion["ph" + end] = 0.0 if m is None else float(m.get("phase", 0.0))
    B = [float(cab["L"]), float(cab["H"]), float(cab.get("W", 0.0))][:dim]
    c = LumpedCable(S=S, EA=EA, masses=masses, B=B, F0=F0, FL=FL, **motion)
    d = data.get("damping", {"ratio": 0.01})
    if "ratio" not in d:
        return replace(c, a0=float(d["a0"]), a1=float(d["a1"]))
    return with_damping(c, float(d["ratio"]), tuple(d.get("modes", (1, 2))))


def whirl_case():
    """The one-node whirling case (:data:`WHIRL_CASE`) as a ``Case``."""
    return load_case(yaml.safe_load(WHIRL_CASE))


def stay_case(nodes: int = 6, omega: float = 12.0):
    """The taut stay (:data:`STAY_CASE`) with ``nodes`` interior nodes, as a ``Case``."""
    return load_case(yaml.safe_load(STAY_CASE.format(nodes=nodes, omega=omega)))


# ----------------------------------------------------------------------------------------------
# Planar responses followed in a parameter, and the out-of-plane multipliers along them
# ----------------------------------------------------------------------------------------------
class PlanarBranch:
    """Planar periodic responses of the planar form of ``cable`` at (omega, gamma), each solved
    from the nearest one solved before (state and Jacobian), starting from the static state."""

    def __init__(self, cable: LumpedCable, tol: float = 1e-12, rtol: float = 1e-12):
        self.tol, self.rtol = tol, rtol  # of the shooting (see periodic_orbit) and the Hill integration
        self.cable = cable.planar()
        self.y0 = static_equilibrium(self.cable)
        self.solved: list[tuple[float, float, Orbit]] = []

    def motion(self, omega: float, gamma: float) -> Motion:
        return Motion(self.cable, omega, gamma, y0=self.y0)

    def orbit(self, omega: float, gamma: float) -> Orbit:
        motion = self.motion(omega, gamma)
        guess, jac = None, None
        if self.solved:
            near = min(self.solved, key=lambda s: abs(s[0] - omega) / omega + abs(s[1] - gamma) / gamma)
            guess, jac = near[2].x0, near[2].jacobian
        orbit = periodic_orbit(motion, guess, jac, monodromy=False, tol=self.tol)
        self.solved.append((omega, gamma, orbit))
        return orbit

    def out_of_plane(self, omega: float, gamma: float) -> np.ndarray:
        """Out-of-plane multipliers (Hill) of the planar orbit at (omega, gamma), largest first."""
        orbit = self.orbit(omega, gamma)
        return floquet_multipliers(out_of_plane_monodromy(self.motion(omega, gamma), orbit.x0, self.rtol))


@dataclass
class Located:
    """A located bifurcation: the parameter's value, the fixed one, and the multipliers there."""

    parameter: str  # "omega" (rad/s) or "gamma" (scale of the loads and support amplitudes)
    value: float
    omega: float
    gamma: float
    multipliers: np.ndarray  # out-of-plane (Hill) multipliers at the located value
    orbit: Orbit  # the planar orbit there (planar form's state)


def locate(branch: PlanarBranch, parameter: str, bracket, fixed: float, xtol=1e-12) -> Located:
    """brentq on ``max|mu| - 1`` of the out-of-plane multipliers, in ``parameter`` ("omega" or
    "gamma") over ``bracket``, the other fixed; the crossing multiplier is then +1 or -1 (at a
    complex pair's collision, ``max|mu|`` is continuous). Located to ``xtol`` (absolute)."""

    def at(p):
        return (p, fixed) if parameter == "omega" else (fixed, p)

    def distance(p):
        return abs(branch.out_of_plane(*at(p))[0]) - 1.0

    value = brentq(distance, *bracket, xtol=xtol)
    omega, gamma = at(value)
    return Located(parameter, value, omega, gamma, branch.out_of_plane(omega, gamma), branch.orbit(omega, gamma))


#: Brackets of the whirling pitchfork of :data:`WHIRL_CASE` (planar branch stable across them).
PITCHFORK_OMEGA_BRACKET = (4.50, 4.60)  # rad/s, at gamma = 1
PITCHFORK_GAMMA_BRACKET = (0.5, 1.0)  # at the case's omega (4.6 rad/s)


def pitchfork_omega(case, bracket=PITCHFORK_OMEGA_BRACKET, gamma: float = 1.0) -> Located:
    """The forcing frequency (rad/s) in ``bracket`` where, at the case's load amplitude times
    ``gamma``, an out-of-plane multiplier of the planar periodic response passes +1 (to 1e-12)."""
    return locate(PlanarBranch(cable_from_case(case)), "omega", bracket, gamma)


def pitchfork_amplitude(case, bracket=PITCHFORK_GAMMA_BRACKET, omega: float | None = None) -> Located:
    """The scale gamma of the case's harmonic loads (its FL times gamma, N) in ``bracket`` where,
    at the case's ``history.omega`` (or ``omega``), an out-of-plane multiplier passes +1."""
    omega = case.history.omega if omega is None else omega
    return locate(PlanarBranch(cable_from_case(case)), "gamma", bracket, omega)


# ----------------------------------------------------------------------------------------------
# The whirling (nonplanar) orbits past the pitchfork, by full spatial shooting
# ----------------------------------------------------------------------------------------------
@dataclass
class Whirl:
    """A nonplanar periodic orbit: its spatial state at t = 0, the parameter's value there, and
    the largest |w| over the nodes and the period (m)."""

    x0: np.ndarray
    value: float
    max_w: float


def _spatial_state(planar_x: np.ndarray) -> np.ndarray:
    n2 = planar_x.size // 2
    return np.concatenate((to_spatial(planar_x[:n2]), to_spatial(planar_x[n2:])))


def _w_indices(n: int) -> np.ndarray:
    w = np.arange(2, 3 * n, 3)
    return np.concatenate((w, 3 * n + w))


def largest_w(motion: Motion, x0, samples: int = 2001) -> float:
    """max |w| over the nodes and one period of the spatial orbit from x0 (DOP853's dense output
    at ``samples`` instants)."""
    sol = solve_ivp(motion.rhs, (0.0, motion.period), x0, method="DOP853", rtol=1e-11, atol=motion.atol(),
                    t_eval=np.linspace(0.0, motion.period, samples))
    n = motion.cable.n
    return float(np.abs(sol.y[2 : 3 * n : 3]).max())


def whirling_orbit(case, located: Located, h: float, tol=1e-10, max_iter=20) -> Whirl:
    """The nonplanar orbit near a located pitchfork, by full spatial shooting of the reference.

    Newton on ``(x0, lambda)`` (lambda the located parameter, omega or gamma) for
    ``x(T) - x0 = 0`` and ``q . x0_w = h``: ``q`` the critical out-of-plane Floquet vector
    (multiplier +1 of the Hill monodromy, unit norm in the scales of the state), ``x0_w`` the
    out-of-plane part of the state; ``h`` (m) parametrises the branch, which leaves the planar
    orbit along ``q`` at the pitchfork. The Jacobian: the monodromy (variational equations) and
    ``d x(T) / d lambda`` by central differences."""
    cable = cable_from_case(case).spatial()
    branch = PlanarBranch(cable)
    pm = branch.motion(located.omega, located.gamma)
    Wm = out_of_plane_monodromy(pm, located.orbit.x0)
    mu, vec = np.linalg.eig(Wm)
    q = np.real(vec[:, np.argmin(abs(mu - 1.0))])
    q /= np.linalg.norm(q)
    widx = _w_indices(cable.n)
    x = _spatial_state(located.orbit.x0)
    x[widx] += h * q
    lam = located.value
    y0 = to_spatial(branch.y0)

    def motion(p):
        return Motion(cable, p, located.gamma, y0=y0) if located.parameter == "omega" else \
            Motion(cable, located.omega, p, y0=y0)

    for _ in range(max_iter):
        m = motion(lam)
        xT, Phi = flow(m, x, variational=True)
        r = np.append(xT - x, q @ x[widx] - h)
        scale = np.append(m.atol() / 1e-13, abs(h))
        if np.abs(r / scale).max() < tol:
            return Whirl(x, lam, largest_w(m, x))
        dl = 1e-6 * lam
        dphi = (flow(motion(lam + dl), x)[0] - flow(motion(lam - dl), x)[0]) / (2 * dl)
        J = np.zeros((x.size + 1, x.size + 1))
        J[:-1, :-1] = Phi - np.eye(x.size)
        J[:-1, -1] = dphi
        J[-1, widx] = q
        step = np.linalg.solve(J, r)
        x, lam = x - step[:-1], lam - step[-1]
    raise RuntimeError(f"whirling orbit: no convergence (residual {np.abs(r / scale).max():.3e})")
# ----------------------------------------------------------------------------------------------
# The damped Mathieu equation q'' + 2 zeta w1 q' + w1^2 (1 + eps sin(omega t)) q = 0
# ----------------------------------------------------------------------------------------------
def mathieu_multipliers(w1: float, zeta: float, eps: float, omega: float) -> np.ndarray:
    """Floquet multipliers over one period 2 pi / omega, by DOP853 (rtol 1e-12), largest first."""

    def rhs(t, z):
        q = z.reshape(2, 2)
        k = w1 * w1 * (1 + eps * math.sin(omega * t))
        return np.array([q[1], -2 * zeta * w1 * q[1] - k * q[0]]).ravel()

    sol = solve_ivp(rhs, (0, 2 * math.pi / omega), np.eye(2).ravel(), method="DOP853", rtol=1e-12, atol=1e-14)
    return floquet_multipliers(sol.y[:, -1].reshape(2, 2))


def mathieu_threshold(zeta: float) -> float:
    """The least ``eps`` of the principal tongue (omega near 2 w1), to first harmonic balance:
    ``eps_c = 4 zeta sqrt(1 - zeta^2)``, error O(zeta^3)."""
    return 4 * zeta * math.sqrt(1 - zeta * zeta)


def mathieu_edges(w1: float, zeta: float, eps: float) -> tuple[float, float]:
    """Edges (rad/s) of the principal tongue at ``eps``, to first harmonic balance.

    With ``q = a cos(omega t / 2) + b sin(omega t / 2)`` and ``nu = omega / 2``, the terms in
    ``cos(nu t)``, ``sin(nu t)`` give ``(w1^2 - nu^2)^2 + 4 zeta^2 w1^2 nu^2 = eps^2 w1^4 / 4``
    (the third harmonic dropped). Solved for ``nu^2``:
    ``nu^2 = w1^2 [1 - 2 zeta^2 -+ sqrt(eps^2/4 - 4 zeta^2 + 4 zeta^4)]``, edges ``2 nu``; error
    O(eps^2) w1: the dropped harmonic shifts both edges up by about ``eps^2 w1 / 32`` (measured
    against numerical Floquet, tests/test_whirl_reference.py)."""
    disc = eps * eps / 4 - 4 * zeta * zeta + 4 * zeta**4
    if disc < 0:
        raise ValueError(f"eps = {eps:g} is below the threshold {mathieu_threshold(zeta):g}: no tongue")
    r = math.sqrt(disc)
    return 2 * w1 * math.sqrt(1 - 2 * zeta * zeta - r), 2 * w1 * math.sqrt(1 - 2 * zeta * zeta + r)


def lumped_string_frequency(T: float, m: float, h: float, n: int, k: int = 1) -> float:
    """k-th frequency (rad/s) of n equal masses m on a string of tension T, segments h:
    ``2 sqrt(T / (m h)) sin(k pi / (2 (n + 1)))``."""
    return 2 * math.sqrt(T / (m * h)) * math.sin(k * math.pi / (2 * (n + 1)))


def continuous_string_frequency(T: float, mu: float, length: float, k: int = 1) -> float:
    """k-th frequency (rad/s) of a string: ``k pi sqrt(T / mu) / length``; the lumped one differs
    by O(1/n^2) (``sin x = x (1 - x^2/6 + ...)``, ``x = k pi / (2 (n+1))``)."""
    return k * math.pi * math.sqrt(T / mu) / length


# ----------------------------------------------------------------------------------------------
# The taut stay: its Mathieu closed form and its located tongue
# ----------------------------------------------------------------------------------------------
@dataclass
class StayMathieu:
    """The first out-of-plane mode of a taut lumped stay as a damped Mathieu equation
    ``q'' + 2 zeta w1 q' + w1^2 (1 + eps sin(omega t)) q = 0``.

    ``eps = gamma * a / (L_chord - S)``: ``a`` the anchorage amplitude along the chord. A chord
    change ``da`` changes every segment's ``l`` by ``da / (n+1)``, so the tension changes by
    ``EA da / S``, relative ``da / (L_chord - S)``: quasi-static, the tension is uniform. Neglected:
    the change of ``1/l`` in the stiffness ``T/l`` (relative O(strain) of eps:
    ``d(T/l)/(T/l) = (S / L_chord) da / (L_chord - S)``), the axial inertia (relative
    O(omega^2 / w_axial^2)), and the terms of second order in ``da``.
    """

    n: int
    tension: float  # N, at rest
    segment: float  # m, stretched segment length h
    node_mass: float  # kg
    w1: float  # rad/s, lumped: 2 sqrt(T/(m h)) sin(pi / (2 (n+1)))
    w1_continuous: float  # rad/s: pi sqrt(T/mu) / L_chord, mu = m / h
    zeta: float  # a0 / (2 w1) + a1 w1 / 2
    eps_per_gamma: float  # a / (L_chord - S)

    def threshold_gamma(self) -> float:
        """The least gamma of the tongue: ``mathieu_threshold(zeta) / eps_per_gamma``."""
        return mathieu_threshold(self.zeta) / self.eps_per_gamma

    def edges(self, gamma: float = 1.0, continuous: bool = False) -> tuple[float, float]:
        """The tongue's edges (rad/s) at ``gamma``; with the continuous string's w1 if asked."""
        return mathieu_edges(self.w1_continuous if continuous else self.w1, self.zeta, gamma * self.eps_per_gamma)


def stay_mathieu(case) -> StayMathieu:
    """The closed form of :class:`StayMathieu` for a taut stay case (equal segments and masses,
    no gravity, support A moving, B fixed)."""
    c = cable_from_case(case)
    chord = float(np.linalg.norm(c.B))
    S = float(c.S.sum())
    assert chord > S and np.ptp(c.S) < 1e-12 * S and not np.any(c.F0)
    T = c.EA * (chord - S) / S
    h = chord / (c.n + 1)
    m = float(c.masses[0])
    w1 = 2 * math.sqrt(T / (m * h)) * math.sin(math.pi / (2 * (c.n + 1)))
    along = abs(float(c.uA @ c.B) / chord)
    return StayMathieu(c.n, T, h, m, w1, math.pi * math.sqrt(T * h / m) / chord,
                       c.a0 / (2 * w1) + c.a1 * w1 / 2, along / (chord - S))


@dataclass
class Tongue:
    """The located principal tongue of the first out-of-plane mode: its edges (rad/s) at one
    gamma, or its tip (threshold gamma and the omega there)."""

    lower: Located | None = None
    upper: Located | None = None
    gamma_c: float | None = None
    omega_c: float | None = None


def tongue_edges(case, gamma: float = 1.0, xtol=1e-12) -> Tongue:
    """The edges in omega (rad/s) at ``gamma`` of the band where the first out-of-plane mode of
    the planar response of a taut stay (anchorage moving along the chord) is unstable, its
    multiplier through -1; brackets from the closed form (:func:`stay_mathieu`)."""
    lo, hi = stay_mathieu(case).edges(gamma)
    mid, width = 0.5 * (lo + hi), hi - lo
    branch = PlanarBranch(cable_from_case(case))
    return Tongue(lower=locate(branch, "omega", (lo - 0.5 * width, mid), gamma, xtol),
                  upper=locate(branch, "omega", (mid, hi + 0.5 * width), gamma, xtol))


def tongue_threshold(case, xtol=1e-10) -> Tongue:
    """The tongue's tip: the least gamma (times the case's anchorage amplitude, m) at which the
    first out-of-plane mode loses stability, and the omega (rad/s) there: gamma at the edge
    (brentq, at each omega) minimised over omega (Brent's bounded method, to 1e-7 rad/s, which
    gives gamma to about 1e-12: the edge is flat at the tip)."""
    cf = stay_mathieu(case)
    gc = cf.threshold_gamma()
    lo, hi = cf.edges(1.5 * gc)
    branch = PlanarBranch(cable_from_case(case))

    def edge_gamma(omega):
        return brentq(lambda g: abs(branch.out_of_plane(omega, g)[0]) - 1.0, 0.5 * gc, 4.0 * gc, xtol=xtol)

    res = minimize_scalar(edge_gamma, bounds=(lo, hi), method="bounded", options={"xatol": 1e-7})
    return Tongue(gamma_c=float(res.fun), omega_c=float(res.x))
