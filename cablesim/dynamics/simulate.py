"""Time histories: integrate the equations of motion and observe the outputs.

:func:`simulate` drives any integrator chunk by chunk, each bounded in steps and in wall time:
between chunks it reports progress and honours Ctrl-C and SIGTERM within about a second, so an
interrupted run returns everything computed so far. A run that fails
(a segment goes slack, the state blows up, an inner solve fails) also returns everything up to
the last good instant, with a status that says what happened and what to try.
"""

from __future__ import annotations

import signal
import time
from typing import Callable

import numpy as np
from ..jit import njit

from ..errors import CablesimError, SlackSegmentError
from ..modal import fastest_rate
from ..statics import inextensible_equilibrium, resisting_force, segment_geometry
from .interrupts import MAX_CHUNK_STEPS, MIN_CHUNK_STEPS, Deferred, received
from ..mechanics.model import approximate_workspace
from .equations import EquationsOfMotion
from .extremes import signal_extremes
from .field import equilibrium_factors, observe
from .integrators import Integrator
from .integrators.events import CHATTER_TEXT
from .peaks import tension_rates
from .result import HistoryResult, SlackRecord
from .status import INNER_SOLVE, NONFINITE, OK, SLACK, STEP_UNDERFLOW, Status


@njit
def _observe_all(model, t, S, warm, zc, ze, T, residual, slack, awk, split):
    seg = np.empty(1, dtype=np.int64)
    k0 = equilibrium_factors(model, warm, awk)
    for i in range(t.size):
        residual[i] = observe(model, t[i], S[i], warm, zc[i], ze[i], T[i], seg, awk, split, k0)
        slack[i] = seg[0]


def step_size(integrator: Integrator, state) -> float:
    """The current step of a scheme, s (the fixed ``dt``, or the adaptive scheme's last step)."""
    if integrator.fixed_step:
        return float(integrator.dt)
    return float(state.extra.get("h", 0.0)) or 1e-3


def advance_in_chunks(integrator: Integrator, model, state, t_end: float, t_out: np.ndarray, out: np.ndarray,
                      max_steps: int = MAX_CHUNK_STEPS) -> tuple[int, int]:
    """``integrator.advance`` to ``t_end`` in calls of at most about ``max_steps`` steps each.

    The compiled loop then returns to Python often enough for Ctrl-C and SIGTERM to act within
    about a second, whatever the step size. The steps taken are the same as in one call (fixed
    steps stay on their grid; the adaptive scheme never shortens a step to meet a chunk's end).

    Returns
    -------
    n_written, status : int
        As :meth:`Integrator.advance`.
    """
    written = 0
    while True:
        t_stop = min(t_end, state.t + max_steps * step_size(integrator, state))
        n, code = integrator.advance(model, state, t_stop, t_out[written:], out[written:])
        written += n
        if code != OK or state.t >= t_end - 1e-12 * max(abs(t_end), 1.0) or t_stop >= t_end:
            return written, code


def failure_text(code: int, t: float, eom: EquationsOfMotion, integrator: Integrator, state_s) -> str:
    where = f"at t = {t:.6g} s"
    rate = fastest_rate(eom.frequencies, eom.a0, eom.a1)
    dt = getattr(integrator, "dt", None)
    limit = integrator.stability_limit
    if integrator.fixed_step and limit is not None and dt is not None and dt * rate > 0.7 * limit:
        # An explicit step beyond its stability limit grows without bound; a segment usually
        # compresses (reads as slack) before anything turns non-finite, so say so first.
        return (
            f"stopped {where}: {Status(code).text}, but the step dt = {dt:.3g} s exceeds {integrator.name}'s "
            f"stability limit (about {limit:g} / {rate:.4g} 1/s = {limit / rate:.3g} s, set by the fastest "
            "mode or, with stiffness-proportional damping, the fastest overdamped mode), which is "
            "the likely cause: use a smaller dt, dopri5, or the newmark or generalized-alpha integrator"
        )
    if code == INNER_SOLVE and not eom.exact:
        seg = _slack_in_approximate(eom, t, state_s)
        if seg is not None:
            return (
                f"stopped {where}: segment {seg} went slack. The approximate analysis needs every segment "
                "taut (with a slack segment the inextensible state x(P) is not determined); the exact "
                "analysis (analysis: exact) can continue through slack segments"
            )
    if code == SLACK:
        T = segment_geometry(eom.cable, eom.y0 + state_s[: eom.n_dof])[2]
        k = int(np.argmin(T)) + 1
        return (
            f"stopped {where}: segment {k} went slack (its tension fell to zero; with slack: stop the run "
            "ends there). Use slack: continue (the default) to continue through slack segments, reduce "
            "the harmonic loads FL, or raise the sustained loads F0."
        )
    if code in (NONFINITE, STEP_UNDERFLOW):
        return (
            f"stopped {where}: {Status(code).text}; try a smaller step or tolerance, or the "
            "generalized-alpha integrator."
        )
    if code == INNER_SOLVE:
        return f"stopped {where}: the inner equilibrium solve failed ({_inner_diagnosis(eom, t, state_s)}); reduce FL or the step size."
    return f"stopped {where}: {Status(code).text}."


def _slack_in_approximate(eom: EquationsOfMotion, t: float, s) -> int | None:
    """The segment (1-based) of the inextensible cable that is slack or nearly so under the
    internal forces of eq. 15 at the last good state, or None."""
    P = eom.internal_force(t, s)
    try:
        inext = inextensible_equilibrium(eom.cable, P)
    except SlackSegmentError as exc:
        return int(exc.segment)
    except CablesimError:
        return None
    k = int(np.argmin(inext.T))
    return k + 1 if inext.T[k] < 1e-3 * eom.T0[k] else None


def _inner_diagnosis(eom: EquationsOfMotion, t: float, s) -> str:
    """Why the inextensible state x(P) was not found at the last good state."""
    nd = eom.n_dof
    if eom.exact:
        P = resisting_force(eom.cable, eom.y0 + s[:nd])
    else:
        P = eom.internal_force(t, s)
    try:
        inext = inextensible_equilibrium(eom.cable, P)
    except SlackSegmentError as exc:
        return f"under the current internal forces segment {exc.segment} of the inextensible cable goes slack"
    except CablesimError:
        return "the inextensible equilibrium under the current internal forces does not converge"
    k = int(np.argmin(inext.T))
    return (
        f"segment {k + 1} of the inextensible cable is nearly slack: tension {inext.T[k]:.3g} N "
        f"against {eom.T0[k]:.3g} N at equilibrium"
    )


def _slack_record(eom: EquationsOfMotion, state, T: np.ndarray, t: np.ndarray, S: np.ndarray) -> SlackRecord:
    """Events and per-segment peak tension, time slack and episodes of a run up to ``t[-1]``:
    the peak located on the step interpolants where the integrator tracked it, else between the
    saved instants (``S``) from the tensions and their rates (:mod:`.extremes`)."""
    ex = state.extra
    n1 = eom.cable.n_segments
    nd = eom.n_dof
    rates = np.empty((t.size, n1))
    tension_rates(eom.model(), np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(S), rates)
    peak, when, _, _ = signal_extremes(t, T, rates)
    if "evw" in ex:
        tracked = (ex["evw"][3] > peak) & (ex["evw"][4] <= t[-1])
        peak = np.where(tracked, ex["evw"][3], peak)
        when = np.where(tracked, ex["evw"][4], when)
    if eom.continues_slack:
        handling = "tension-only segments; every slack onset and re-tightening located and the integration restarted there; " + CHATTER_TEXT
    else:
        handling = "slack: stop (the run ends where a segment first goes slack)"
    return SlackRecord.from_events(ex.get("events", []), n1, float(t[-1]), ex.get("initially_slack", np.zeros(n1, bool)),
                                   peak, when, ex.get("chatter_holds", 0), handling)


def _bad_instants(eom, S, T, residual, zc, ze, split: bool):
    """``(split, bad)``: whether the configurational/elastic split is kept, and the instants
    holding a non-finite value (nothing non-finite leaves silently: the record is cut at the
    first)."""
    bad = ~(np.isfinite(S).all(axis=1) & np.isfinite(T).all(axis=1) & np.isfinite(residual))
    if split and not (np.isfinite(zc[0]).all() and np.isfinite(ze[0]).all()):
        split = False  # no inextensible split even at the start (a displaced start far from it): none
    if split and not eom.continues_slack:
        # Through slack episodes z_c, z_e are NaN wherever the inextensible state x(P) under the
        # current internal forces does not exist (a segment of it slack): that ends nothing.
        bad |= ~(np.isfinite(zc).all(axis=1) & np.isfinite(ze).all(axis=1))
    return split, bad


def simulate(
    eom: EquationsOfMotion,
    integrator: Integrator,
    duration: float,
    output_step: float,
    s0: np.ndarray | None = None,
    progress: Callable[[float], None] | None = None,
    split: bool = True,
    chunk_seconds: float = 0.25,
) -> HistoryResult:
    """Integrate the equations of motion from ``s0`` (default: equilibrium at rest).

    Parameters
    ----------
    eom : EquationsOfMotion
    integrator : Integrator
    duration : float
        Simulated time, s.
    output_step : float
        Interval between saved instants, s.
    s0 : ndarray, optional
        Initial ``(z, y', y'')`` (see :meth:`EquationsOfMotion.initial_state`).
    progress : callable, optional
        Called with the simulated time reached after each chunk.
    split : bool
        Compute the configurational/elastic split ``z_c``, ``z_e`` (one inner solve per saved
        instant).
    chunk_seconds : float
        Wall-clock length of a chunk between progress reports and checks for Ctrl-C and SIGTERM
        (a chunk is also bounded in steps, :data:`~cablesim.dynamics.interrupts.MAX_CHUNK_STEPS`).

    Returns
    -------
    HistoryResult
    """
    if s0 is None:
        s0 = eom.initial_state()
    model = eom.model()
    nd = eom.n_dof
    n_out = int(np.floor(duration / output_step + 1e-9))
    t_out = np.arange(1, n_out + 1) * output_step
    out = np.empty((n_out + 1, 3 * nd))
    out[0] = s0
    state = integrator.start(eom, s0)
    written = 0
    code = state.extra.get("code", OK)
    steps = float(MIN_CHUNK_STEPS)  # steps per chunk, adapted to about `chunk_seconds` of wall time
    status, message, t_stop = Status.COMPLETED, Status.COMPLETED.text, None
    with Deferred() as stop:
        while code == OK and state.t < duration - 1e-12 * max(duration, 1.0):
            if stop.hit:
                status, t_stop = Status.INTERRUPTED, state.t
                by = " (SIGTERM)" if received() == signal.SIGTERM else ""
                message = f"interrupted at t = {state.t:.6g} s{by}"
                break
            h = step_size(integrator, state)
            t_end = min(state.t + min(steps * h, 50.0 * output_step + h, 10.0 + h), duration)
            wall = time.perf_counter()
            n, code = integrator.advance(model, state, t_end, t_out[written:], out[1 + written :])
            written += n
            if progress is not None:
                progress(min(state.t, duration))
            spent = time.perf_counter() - wall
            steps = float(np.clip(steps * np.clip(chunk_seconds / max(spent, 1e-4), 0.5, 4.0), 1.0, MAX_CHUNK_STEPS))
        # a signal while the instants are evaluated is held off too: what was integrated is kept
        if code != OK:
            status, t_stop = Status(code), state.t
            message = failure_text(code, state.t, eom, integrator, state.s).rstrip(".")
        m = written + 1
        t = np.concatenate([[0.0], t_out[:written]])
        S = out[:m]
        zc = np.empty((m, nd))
        ze = np.empty((m, nd))
        T = np.empty((m, eom.cable.n_segments))
        residual = np.empty(m)
        slack = np.empty(m, dtype=np.int64)
        _observe_all(model, t, S, np.array(eom.F1, dtype=float), zc, ze, T, residual, slack, approximate_workspace(eom.cable.n_nodes, eom.cable.dim), split)
        split, bad = _bad_instants(eom, S, T, residual, zc, ze, split)
        if bad.any():
            first = int(np.argmax(bad))
            m = max(first, 1)
            if status is Status.COMPLETED or first < written:
                status, t_stop = Status.OUTPUT_NONFINITE, float(t[first])
                message = f"stopped at t = {t[first]:.6g} s: {Status.OUTPUT_NONFINITE.text}"
        record = _slack_record(eom, state, T[:m], t[:m], S[:m]) if eom.exact else None
        return HistoryResult(
            slack=record,
            t=t[:m],
            z=S[:m, :nd].copy(),
            v=S[:m, nd : 2 * nd].copy(),
            zc=zc[:m] if split else None,
            ze=ze[:m] if split else None,
            T=T[:m],
            residual=residual[:m],
            y0=eom.y0,
            T0=eom.T0,
            omega=eom.omega if np.any(eom.FL != 0) or eom.moving_supports else None,  # forced
            analysis=eom.analysis,
            integrator=integrator.name,
            status=status,
            message=message,
            t_stop=t_stop,
            warnings=integrator.run_notes(state),
            modal_omega=eom.frequencies,
            settings={
                **{f"integrator_{k}": v for k, v in integrator.settings().items()},
                "duration": float(duration),
                "output_step": float(output_step),
                "a0": eom.a0,
                "a1": eom.a1,
                "slack": eom.slack if eom.exact else "stop",
            },
        )
