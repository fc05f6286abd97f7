"""Steady-state response at one forcing frequency.

The state is sampled stroboscopically, once per forcing period ``T = 2 pi / w``, at the phase
where the forcing is ``F0`` (``sin w t = 0``). The response is declared steady with period
``p`` forcing periods (``p = 1`` harmonic, ``p = 2`` the 1/2 subharmonic, ...) when

1. **periodicity**: the stroboscopic samples ``q_k = (z, y'/w)`` repeat with period ``p``,
   ``max |q_k - q_{k-p}| <= tol * scale`` for each of the last ``hold`` samples (``scale`` is
   the largest ``|q|`` over those samples), for the smallest such ``p <= max_period``; and
2. **stability**: the periodic orbit so found is stable: every Floquet multiplier (eigenvalue
   of the monodromy matrix of the stroboscopic map over ``p`` periods, by finite differences on
   the reduced state) has modulus at most ``1 + 1e-3``.

The second test is what keeps an early stop from hiding a late jump: a small-amplitude response
that is itself an *unstable* periodic orbit repeats to many digits for hundreds of seconds
before it jumps (the paper's Figs. 3b and 8c). Such a point is integrated on, and reported as
not steady if the cap is reached first.

When steady, ``p`` more periods are sampled finely for the peak ``|z_i|`` from the equilibrium,
the half peak-to-peak range and the dominant response frequency (the extremes located between
the samples on the quintic Hermite interpolant of ``z``, ``y'``, ``y''``:
:mod:`cablesim.dynamics.extremes`; dopri5's steps held to the sample spacing over that orbit,
its dense output being a cubic interpolant). When the cap is reached first,
the same quantities come from the last ``window`` seconds and the point is flagged not steady.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from .equations import EquationsOfMotion
from .extremes import peak_and_half_range
from .integrators import Integrator
from .simulate import advance_in_chunks, failure_text
from .result import SlackRecord
from .status import OK, Status

#: Default forcing periods between two calls of a ``decide`` hook of :func:`steady_response`
#: (:mod:`cablesim.orbits.accelerate` uses it as its longest interval).
DECIDE_EVERY = 10
#: Floquet multipliers above this modulus mark an unstable periodic orbit.
UNSTABLE_MULTIPLIER = 1.0 + 1e-3


@dataclass(frozen=True)
class SteadyCriterion:
    """How a sweep point decides that the response is steady.

    Attributes
    ----------
    cap : float
        Most simulated seconds per point.
    window : float
        Seconds at the end used for the amplitude when no steady state is found.
    tol : float
        Relative periodicity tolerance.
    hold : int
        Consecutive stroboscopic samples the periodicity must hold for.
    max_period : int
        Largest response period looked for, in forcing periods.
    floquet : bool
        Check the stability of the periodic orbit found (recommended; see module docstring).
    samples_per_period : int
        Fine samples per forcing period for amplitudes and spectra.
    """

    cap: float = 3000.0
    window: float = 200.0
    tol: float = 1e-5
    hold: int = 12
    max_period: int = 6
    floquet: bool = True
    samples_per_period: int = 128


@dataclass
class PointResult:
    """Steady (or last-window) response at one forcing frequency.

    Attributes
    ----------
    omega : float
        Forcing frequency, rad/s.
    amplitude : ndarray (C,)
        Peak ``|z_i|`` from the equilibrium, m.
    halfrange : ndarray (C,)
        Half the peak-to-peak range, m.
    period : int
        Response period in forcing periods (0: no periodic response found).
    steady : bool
    response_frequency : ndarray (C,)
        Dominant frequency of each channel's response, rad/s.
    t_end : float
        Simulated time used, s.
    floquet : float
        Largest Floquet multiplier modulus of the last orbit checked (NaN if none).
    final_state : ndarray
        ``(z, y', y'')`` at the end, at forcing phase 0 (start of a continuation sweep).
    status : Status
        :attr:`Status.COMPLETED` when the integration ran to its end (steady or cap reached),
        else why it stopped.
    message : str
        ``"steady"``, ``"cap reached"`` or when and why the run stopped.
    decided : str
        How the point was decided: ``"integrated"`` (periodicity of the integrated response),
        ``"shooting"`` (the periodic orbit the response approaches, found by shooting), ``"cap"``
        (no steady state before the cap) or ``"failed"``.
    multipliers : ndarray (complex) or None
        Floquet multipliers of the orbit, by decreasing modulus, where computed.
    peak_tension, slack_fraction : ndarray or None
        Per segment, the largest tension (N) and the fraction of the time slack, when the exact
        analysis continues through slack segments (None otherwise): over the steady orbit (one
        orbit period from forcing phase 0: its snap loads, the same whether the point was
        decided by integration or by shooting) for a steady point; over the whole integration
        (transient included) for one that is not steady or failed.
    """

    omega: float
    amplitude: np.ndarray
    halfrange: np.ndarray
    period: int
    steady: bool
    response_frequency: np.ndarray
    t_end: float
    floquet: float
    final_state: np.ndarray
    status: Status
    message: str
    decided: str = "integrated"
    multipliers: np.ndarray | None = None
    peak_tension: np.ndarray | None = None
    slack_fraction: np.ndarray | None = None

    @property
    def failed(self) -> bool:
        """Whether the integration stopped early (a slack segment, a blow-up)."""
        return not self.status.success


def _amplitudes(rec: np.ndarray, t: np.ndarray, nd: int, channels: np.ndarray, period: float = 0.0):
    """Peak |z| and half range per channel, located between the samples on the Hermite
    interpolant of ``z`` with its rates ``y'`` and curvatures ``y''`` (:mod:`.extremes`);
    ``period`` > 0: the record spans exactly one orbit of that period."""
    z, v, a = (rec[:, o + channels] for o in (0, nd, 2 * nd))
    return peak_and_half_range(t, z, v, a, period)


def _joined(pieces, state) -> tuple[np.ndarray, np.ndarray]:
    """Times and states of consecutive ``(times, states)`` pieces (the current state if none)."""
    if not pieces:
        return np.array([state.t]), state.s[None, :]
    return np.concatenate([p[0] for p in pieces]), np.concatenate([p[1] for p in pieces])


def _dominant_frequency(z: np.ndarray, dt: float) -> np.ndarray:
    """Dominant nonzero frequency (rad/s) of each column of a uniformly sampled record."""
    zc = z - z.mean(axis=0)
    spec = np.abs(np.fft.rfft(zc, axis=0))
    spec[0] = 0.0
    k = np.argmax(spec, axis=0)
    return 2.0 * np.pi * k / (z.shape[0] * dt)


def monodromy_multipliers(
    eom: EquationsOfMotion, integrator: Integrator, s_star: np.ndarray, p: int, rel_step: float = 1e-6
) -> np.ndarray:
    """Floquet multipliers of the periodic orbit through ``s_star`` (forcing phase 0).

    The monodromy matrix of the map over ``p`` forcing periods is built by finite differences
    on the reduced state: ``(z, y')`` for the exact analysis (``y''`` follows from eq. 15), and
    ``(y', y'')`` for the approximate one (``z`` is a neutral direction there: the configuration
    follows from P).

    Returns
    -------
    ndarray
        Multipliers sorted by decreasing modulus.
    """
    nd = eom.n_dof
    T = 2.0 * np.pi / eom.omega
    model = eom.model()
    exact = eom.exact
    lo = 0 if exact else nd  # first component of the reduced state
    idx = np.arange(lo, lo + 2 * nd)
    scale = max(np.abs(s_star[idx]).max(), 1e-9 * eom.cable.chord_length)

    def flow(s0: np.ndarray) -> np.ndarray:
        st = integrator.start(eom, s0)
        out = np.empty((1, s0.size))
        n, code = advance_in_chunks(integrator, model, st, p * T, np.array([p * T]), out)
        if code != OK or n != 1:
            raise FloatingPointError("flow failed")
        return out[0]

    def consistent(s: np.ndarray) -> np.ndarray:
        if exact:  # y'' from eq. 15 at phase 0, where F = F0
            return eom.initial_state(z0=s[:nd], v0=s[nd : 2 * nd])
        return s

    base = flow(consistent(s_star.copy()))
    J = np.empty((2 * nd, 2 * nd))
    for j, comp in enumerate(idx):
        d = rel_step * scale
        s = s_star.copy()
        s[comp] += d
        J[:, j] = (flow(consistent(s))[idx] - base[idx]) / d
    mu = np.linalg.eigvals(J)
    return mu[np.argsort(-np.abs(mu))]


def _floquet_integrator(integrator: Integrator) -> Integrator:
    # An adaptive scheme chooses different steps for nearby starts; tighten it so that the
    # finite differences see the dynamics, not the step-size controller.
    return integrator.for_finite_differences()


def steady_response(
    eom: EquationsOfMotion,
    integrator: Integrator,
    channels: np.ndarray,
    criterion: SteadyCriterion,
    s0: np.ndarray | None = None,
    decide: Callable[[int, np.ndarray, np.ndarray], PointResult | None] | None = None,
    decide_every: int = DECIDE_EVERY,
) -> PointResult:
    """Integrate from ``s0`` until the response is steady (see module docstring) or the cap.

    Parameters
    ----------
    eom : EquationsOfMotion
        With ``omega > 0``.
    integrator : Integrator
    channels : ndarray of int
        0-based DOF indices to report.
    criterion : SteadyCriterion
    s0 : ndarray, optional
        Initial ``(z, y', y'')`` at forcing phase 0 (default: the equilibrium at rest).
    decide : callable, optional
        Called as ``decide(k, s, strobes)`` after every chunk of ``decide_every`` forcing
        periods (``k`` periods done, ``s`` the state at forcing phase 0, ``strobes`` the
        ``k + 1`` stroboscopic samples ``(z, y'/w)`` so far); a
        :class:`PointResult` it returns ends the point (how
        :mod:`cablesim.orbits.accelerate` decides by shooting).
    decide_every : int
        Forcing periods between two calls of ``decide``.

    Returns
    -------
    PointResult
    """
    track: dict = {}
    r = _steady(eom, integrator, channels, criterion, s0, decide, track, max(1, int(decide_every)))
    return _with_slack_stats(r, eom, track.get("state"), track.get("t0", 0.0))


def _with_slack_stats(r: PointResult, eom: EquationsOfMotion, state, t0: float, t_end: float | None = None
                      ) -> PointResult:
    """``r`` with the per-segment peak tension and slack fraction of the integration from ``t0``
    to ``t_end`` (the integrator's own time if None; an adaptive one may have stepped past the
    last instant measured), kept if ``r`` has them already: a steady point's are its orbit's."""
    ex = {} if state is None else state.extra
    if not ex.get("track") or r.peak_tension is not None:
        return r
    span = (state.t if t_end is None else t_end) - t0
    if span <= 0:
        return r
    rec = SlackRecord.from_events([(t - t0, k, kind) for t, k, kind in ex["events"]], eom.cable.n_segments, span,
                                  ex["initially_slack"], ex["evw"][3], ex["evw"][4])
    return replace(r, peak_tension=rec.peak_tension.copy(), slack_fraction=rec.fraction_of(span))


def _steady(eom, integrator, channels, criterion, s0, decide, track, decide_every) -> PointResult:
    nd = eom.n_dof
    w = eom.omega
    T = 2.0 * np.pi / w
    crit = criterion
    spp = crit.samples_per_period
    model = eom.model()
    s0 = eom.initial_state() if s0 is None else np.array(s0, dtype=float)
    state = integrator.start(eom, s0)
    track.update(state=state, t0=state.t)
    n_cap = max(int(np.floor(crit.cap / T + 1e-9)), 1)
    k_window = max(0, n_cap - int(np.ceil(crit.window / T)))
    strobes = np.empty((n_cap + 1, 2 * nd))
    strobes[0, :nd] = s0[:nd]
    strobes[0, nd:] = s0[nd : 2 * nd] / w
    fine: list[tuple[np.ndarray, np.ndarray]] = []  # (times, states) of the final window
    k = 0
    chunk = 20 if decide is None else decide_every
    floquet = np.nan
    recheck_after = 0
    hold = max(crit.hold, 3)
    ftol = crit.tol
    f_integ = _floquet_integrator(integrator) if crit.floquet else None
    floor = _noise_floor(eom, integrator, ftol)

    while k < n_cap:
        kk = min(k + chunk, n_cap)
        in_window = kk > k_window
        if in_window:
            k0 = max(k, k_window)
            if k0 > k:  # reach the window first with strobes only
                kk = k0
                in_window = False
        if in_window:
            t_out = T * (k + np.arange(1, (kk - k) * spp + 1) / spp)
        else:
            t_out = T * np.arange(k + 1, kk + 1)
        out = np.empty((t_out.size, 3 * nd))
        n, code = advance_in_chunks(integrator, model, state, t_out[-1], t_out, out)
        if code != OK:
            return _failed(eom, integrator, channels, (t_out[:n], out[:n]), state, code, fine)
        if in_window:
            fine.append((t_out, out))
            sel = out[spp - 1 :: spp]
        else:
            sel = out
        strobes[k + 1 : kk + 1, :nd] = sel[:, :nd]
        strobes[k + 1 : kk + 1, nd:] = sel[:, nd : 2 * nd] / w
        k = kk
        chunk = min(chunk * 2, 200) if decide is None else decide_every
        if decide is not None and k < n_cap:
            decided = decide(k, out[-1].copy(), strobes[: k + 1])  # out[-1]: at phase 0
            if decided is not None:
                return decided

        p = _periodic(strobes[: k + 1], hold, crit.max_period, ftol, floor)
        if p == 0 or k < recheck_after:
            continue
        if crit.floquet and 2 * nd <= 80:
            floquet = _largest_multiplier(eom, f_integ, state.s.copy(), p)
            if floquet > UNSTABLE_MULTIPLIER:
                # An unstable orbit: keep integrating; look again after it has had time to leave.
                recheck_after = k + max(50, 10 * p)
                continue
        # measured from the state at phase 0 (out[-1]; the integrator may have stepped past it),
        # as an orbit found by shooting is: the same orbit, the same measurement
        return _finish_steady(eom, integrator, model, out[-1].copy(), channels, p, k, T, spp, floquet)

    # the state at the last forcing phase 0 (the integrator's own state may have stepped past it)
    return _cap_reached(eom, channels, state, fine, spp, floquet, out[-1].copy(), float(t_out[-1]))


def _cap_reached(eom, channels, state, fine, spp, floquet, s_end, t_end) -> PointResult:
    """No steady state before the cap: amplitudes over the last window; ``s_end`` the state at
    ``t_end``, the last whole forcing period (the start state a chained sweep hands on, which
    must be at forcing phase 0: ``y''`` there is consistent with ``F = F0`` only)."""
    nd = eom.n_dof
    T = 2.0 * np.pi / eom.omega
    t, rec = _joined(fine, state)
    z = rec[:, :nd][:, channels]
    amp, half = _amplitudes(rec, t, nd, channels)
    freq = _dominant_frequency(z, T / spp) if z.shape[0] > 8 else np.full(channels.size, np.nan)
    return PointResult(
        omega=eom.omega,
        amplitude=amp,
        halfrange=half,
        period=0,
        steady=False,
        response_frequency=freq,
        t_end=t_end,
        floquet=floquet,
        final_state=s_end,
        status=Status.COMPLETED,
        message="cap reached",
        decided="cap",
    )


def _noise_floor(eom, integrator, tol: float) -> float:
    """Differences below what the integrator resolves are noise: for a tiny response the
    periodicity test is relative to the integrator's absolute tolerance, not to zero (the floor
    bounds the scale from below, so the absolute threshold is at least ``tol * floor``)."""
    return max(1e-9 * eom.cable.chord_length, 3.0 * getattr(integrator, "atol", 0.0) / tol)


def _largest_multiplier(eom, integrator, s_star, p) -> float:
    """Modulus of the largest Floquet multiplier (NaN if no perturbed flow can be integrated)."""
    for rel_step in (1e-6, 1e-8):
        try:
            return float(np.abs(monodromy_multipliers(eom, integrator, s_star, p, rel_step)[0]))
        except FloatingPointError:
            continue
    return np.nan


def _periodic(strobes: np.ndarray, hold: int, max_period: int, tol: float, floor: float) -> int:
    """Smallest p whose periodicity holds over the last ``hold`` strobes (0 if none).

    A period p > 1 also needs the differences over every shorter lag q < p to persist over a
    long baseline (five hold windows) rather than decay: a slowly decaying transient whose phase
    advance nearly closes after p periods (a mode near w/2, say) would otherwise pass for a 1/p
    subharmonic.
    """
    k = strobes.shape[0] - 1
    for p in range(1, max_period + 1):
        h = max(hold, 3 * p)
        if k < h + p:
            return 0
        scale = max(np.abs(strobes[k - h + 1 - p : k + 1]).max(), floor)
        if _lag_diff(strobes, k, h, p).max() > tol * scale:
            continue
        if p == 1:
            return 1
        if k < 5 * h + p:
            return 0  # too early to tell a subharmonic from a slow transient
        if all(_persists(strobes, k, h, q, tol * scale) for q in range(1, p)):
            return p
    return 0


def _lag_diff(strobes: np.ndarray, k: int, h: int, q: int) -> np.ndarray:
    """``max_i |q_j - q_{j-q}|`` for the ``h`` strobes j ending at k."""
    return np.abs(strobes[k - h + 1 : k + 1] - strobes[k - h + 1 - q : k + 1 - q]).max(axis=1)


def _persists(strobes: np.ndarray, k: int, h: int, q: int, tol_abs: float) -> bool:
    """Whether the lag-q difference is a lasting feature: well above tolerance, and as large
    now as four hold windows ago."""
    now = _lag_diff(strobes, k, h, q).mean()
    before = _lag_diff(strobes, k - 4 * h, h, q).mean()
    return now > 10.0 * tol_abs and now >= 0.9 * before


def periodic_response(
    eom: EquationsOfMotion,
    integrator: Integrator,
    s0: np.ndarray,
    t0: float,
    channels: np.ndarray,
    period: int,
    criterion: SteadyCriterion,
    floquet: float = np.nan,
    decided: str = "integrated",
    multipliers: np.ndarray | None = None,
) -> PointResult:
    """The response over one orbit from a state on a periodic orbit, measured as a steady sweep
    point is: ``period`` forcing periods sampled ``criterion.samples_per_period`` times each.

    Parameters
    ----------
    s0 : ndarray
        ``(z, y', y'')`` at ``t0``, a whole number of forcing periods (forcing phase 0).
    """
    T = 2.0 * np.pi / eom.omega
    k = int(round(t0 / T))
    r = _finish_steady(eom, integrator, eom.model(), np.asarray(s0, dtype=float), channels, period, k, T,
                       criterion.samples_per_period, floquet)
    r.decided = decided if not r.failed else "failed"
    r.multipliers = multipliers
    return r


def _finish_steady(eom, integrator, model, s_k, channels, p, k, T, spp, floquet) -> PointResult:
    """The steady point measured over one orbit from ``s_k``, the state at ``t = k T``; with
    slack tracking, the peak tensions and slack fractions are the orbit's (the steady snap loads),
    not the transient's."""
    nd = eom.n_dof
    state = integrator.start(eom, s_k, k * T)
    t_out = T * (k + np.arange(1, p * spp + 1) / spp)
    out = np.empty((t_out.size, 3 * nd))
    # the orbit whose amplitudes are measured: an adaptive scheme's saved states come from the
    # cubic Hermite interpolant between its steps, whose error h^4 |z^(4)| / 384 at its natural
    # steps reaches 2e-7 of the amplitude (paper example, 4-5 rad/s), so its steps are held to
    # the sample spacing over this one orbit (1.5e-8 for a sinusoid)
    n, code = advance_in_chunks(integrator.for_measuring(T / spp), model, state, t_out[-1], t_out, out)
    if code != OK:
        return _failed(eom, integrator, channels, (t_out[:n], out[:n]), state, code, [])
    z = out[:, :nd][:, channels]
    # the record spans one orbit: its last sample is the image of the one before the first
    amp, half = _amplitudes(out, t_out, nd, channels, period=p * T)
    return _with_slack_stats(PointResult(
        omega=eom.omega,
        amplitude=amp,
        halfrange=half,
        period=p,
        steady=True,
        response_frequency=_dominant_frequency(z, T / spp),
        t_end=float(t_out[-1]),
        floquet=floquet,
        final_state=out[-1].copy(),
        status=Status.COMPLETED,
        message="steady",
    ), eom, state, k * T, float(t_out[-1]))


def _failed(eom, integrator, channels, out, state, code, fine) -> PointResult:
    nd = eom.n_dof
    t, rec = _joined([*fine, out] if out[1].shape[0] else fine, state)
    amp, half = _amplitudes(rec, t, nd, channels)
    return PointResult(
        omega=eom.omega,
        amplitude=amp,
        halfrange=half,
        period=0,
        steady=False,
        response_frequency=np.full(channels.size, np.nan),
        t_end=state.t,
        floquet=np.nan,
        final_state=state.s.copy(),
        status=Status(code),
        message=failure_text(code, state.t, eom, integrator, state.s).rstrip("."),
        decided="failed",
    )
