"""Error-controlled steps of the implicit Newmark-family schemes.

Each step is the scheme's own (:func:`~cablesim.dynamics.integrators.newmark.galpha_step`); its
local error in the displacements is estimated from the same step, as Zienkiewicz and Xie (1991)
do for Newmark's method: the third-order Taylor expansion of ``y`` over the step, with the jerk
``y''' ~ (a_(n+1) - a_n) / h`` from the scheme's two accelerations, minus the scheme's update
``z_(n+1) = z_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_(n+1))``, gives

    e = (beta + (alpha_m - alpha_f) / 2 - 1/6) h^2 (a_(n+1) - a_n)

(Newmark's average acceleration: ``h^2 (a_(n+1) - a_n) / 12``, Zienkiewicz-Xie's estimate;
generalized-alpha carries an acceleration variable that approximates ``y''`` at
``t_n + (alpha_m - alpha_f) h``, whence the shift).

What the tolerance controls. On a response ``A sin(w t)`` the estimate is ``(w h)^3 A / 12``: per
radian of the motion, ``(w h)^2 / 12``, which is the scheme's relative frequency error (period
elongation). A response errs by its frequency error times its sensitivity to the natural
frequency: the steady part at most ``1 / xi`` (amplitude and phase) for a mode of damping ratio
``xi`` at resonance, the transient from rest at most ``1 / (e xi)``. So a step is accepted when

    max_i |e_i| <= max((atol + rtol z_peak) w_ref h / amplification, noise floor),

``z_peak`` the largest ``|z_i|`` of the run so far (the error is relative to the peak, as the
accuracy of a response is judged; the tensions are not controlled apart: a per-step bound on
each segment's elongation error, ``EA / S`` times that of z, was measured to cost a stiff heavy
cable steps near the rounding level of its coordinates), ``w_ref`` the frequency of interest and ``amplification``
``2 / xi(w_ref)`` (the Rayleigh damping ratio there,
:func:`~cablesim.dynamics.integrators.settings.amplification`). The error per unit step makes the
global error proportional to ``rtol`` (halving rtol halves it), and the amplification makes it
at most about ``rtol`` of the peak for a response that is damped and not far from linear (one
that grows, as in a parametric resonance, is not bounded so: the default rtol is set for them,
:data:`~cablesim.dynamics.integrators.settings.IMPLICIT_RTOL`). Each step's Newton iteration is
held to :data:`NEWTON_SHARE` of the error the step is allowed, since its leftover enters every
step whatever the truncation error. Steps follow
``h_new = h (0.9 / err)^(1/2)`` (the scaled estimate is of order h^2), grow at most
:data:`GROW_MAX` times a step and are never above ``h_max``, so that every period of interest
gets a few steps whatever the estimate says (an estimate from two accelerations cannot see a
step that aliases the forcing). A step that fails the test, or whose Newton iteration does not
converge, is retried shorter.

Slack onsets and re-tightenings are located on the accepted step's interpolant as in the
fixed-step loop, the step redone up to the event and the integration restarted there.
"""

from __future__ import annotations

import numpy as np

from ...jit import njit
from ..status import OK, SLACK, STEP_UNDERFLOW
from .events import locate_event
from .newmark import (carried_acceleration, galpha_step, scheme_acceleration, step_scratch, store_state,
                      write_step_outputs)

#: Safety factor of the step-size rule.
SAFETY = 0.9
#: Largest growth of the step from one step to the next ...
GROW_MAX = 2.0
#: ... and the largest reduction after a failed error test.
SHRINK_MIN = 0.2
#: The step after a failed Newton iteration, relative to the failed one.
SHRINK_NEWTON = 0.25
#: Newton's increments are held below this share of the local error a step is allowed (at most
#: the loose tolerance, 1e-12 of the chord; at least the noise floor below) ...
NEWTON_SHARE = 0.1
#: ... and where they stop decreasing within this many noise floors (1e-15 of the chord: some
#: five rounding units of the coordinates), that is taken as converged.
ROUNDING_STALL = 100.0
#: Estimates below this fraction of the loose Newton tolerance (1e-12 of the chord), 1e-17 of
#: the chord, are rounding noise (the accelerations carry that of the coordinates, about 2e-16
#: of the chord, divided by h^2; the estimate multiplies it by h^2 / 12): without the floor a
#: tight tolerance could fail however short the step, and the step would shrink to nothing. At
#: 1e-15 of the chord the floor was above the error allowed to a cable whose response is small
#: beside its chord (a taut stay: 3 mm on 100 m), whose steps then grew blind to rtol; at 1e-16
#: generalized-alpha at rtol 1e-6 on that stay was still 9e-6 off, at 1e-17 6.8e-7.
NOISE_FLOOR = 1e-5
#: A step counts as set by the floor, not by rtol, where the error it is allowed is below this
#: share of the floor (rtol then asks ten times what rounding resolves).
FLOOR_SET = 0.1


@njit
def error_constant(coef) -> float:
    """``beta + (alpha_m - alpha_f) / 2 - 1/6``: the local displacement error is this times
    ``h^2 (a_(n+1) - a_n)`` (``coef = (alpha_m, alpha_f, beta, gamma)``)."""
    return coef[2] + 0.5 * (coef[0] - coef[1]) - 1.0 / 6.0


@njit
def local_error(z1, a, a1, h, c_err, allowed, floor) -> float:
    """The largest local displacement error of a step over ``allowed`` (m), or over ``floor`` (m,
    what the step's Newton iteration resolves: below it the estimate is noise) where that is
    larger: at most 1 accepted. (Subtracting the floor from the estimate instead made the ratio
    steeper than ``h^2`` near the floor, and the step rule overshot: half the steps of a run
    whose allowed error was near the floor were rejected.)"""
    c = c_err * h * h
    big = 0.0
    for q in range(z1.size):
        big = max(big, abs(c * (a1[q] - a[q])))
    return big / max(allowed, floor)


@njit
def adaptive_advance(model, s, P_n, warm, wk, awk, evw, track, t, h, t_end, coef, rtol, atol, h_max, per_step,
                     t_out, out, ztol, maxit, counts, peaks, jerk):
    """Error-controlled steps from ``t`` until ``t >= t_end`` (the last step may pass it).

    ``per_step = w_ref / amplification`` (1/s) turns the tolerance into an error per unit step;
    ``counts`` (accepted, rejected by the error test, retried after Newton failed, and accepted
    with an allowed error below :data:`FLOOR_SET` of the rounding floor: set by the floor, not
    by rtol) is incremented, ``peaks[0]`` (the largest ``|z_i|`` so far, m) and ``jerk`` (the last step's
    ``dy''/dt``, for the scheme's acceleration at a new step size: see
    :func:`~cablesim.dynamics.integrators.newmark.scheme_acceleration`) updated.

    Returns ``(t, h, written, status, segment)``: the time reached, the next step proposed, the
    rows of ``out`` filled, a status code and the segment that changes mode at ``t`` (-1: none),
    as :func:`~cablesim.dynamics.integrators.rk._dopri_advance` does.
    """
    nd = model.mass.size
    z, v, a = s[:nd].copy(), s[nd : 2 * nd].copy(), s[2 * nd :].copy()
    z1, v1, a1, P1, a_used = np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd), np.empty(nd)
    delta, c_err = coef[0] - coef[1], error_constant(coef)
    scratch = step_scratch(model)
    sa, sb, da, db = np.empty(3 * nd), np.empty(3 * nd), np.empty(3 * nd), np.empty(3 * nd)
    ae, ae1 = np.empty(nd), np.empty(nd)
    warm_try, jerk_try = np.empty(warm.size), np.empty(nd)
    floor = NOISE_FLOOR * ztol
    zround = ROUNDING_STALL * floor
    h_min = 1e-12 * (1.0 + abs(t))
    j = 0
    while t < t_end:
        h = min(h, h_max)
        allowed = (atol + rtol * peaks[0]) * per_step * h
        # Newton's error enters every step whatever the truncation: held to a share of the error
        # allowed (down to the rounding floor), or a slowly growing response seeded by it is off
        # by its accumulation, which no tolerance reduces.
        ztight = min(ztol, max(floor, NEWTON_SHARE * allowed))
        warm_try[:] = warm
        scheme_acceleration(a, jerk, delta * h, a_used)
        st = galpha_step(model, z, v, a_used, P_n, warm_try, wk, awk, t + h, h, coef, ztight, zround, maxit, z1, v1,
                         a1, P1, scratch)
        if st == SLACK:  # slack: stop, and the converged state has a slack segment
            store_state(s, z, v, a)
            return t, h, j, st, -1
        if st != OK:  # Newton did not converge (or the state is not finite): a shorter step
            counts[2] += 1
            h *= SHRINK_NEWTON
            if h < h_min:
                store_state(s, z, v, a)
                return t, h, j, st, -1
            continue
        err = local_error(z1, a_used, a1, h, c_err, allowed, floor)
        if not err <= 1.0:
            counts[1] += 1
            h *= max(SHRINK_MIN, SAFETY * err ** -0.5) if np.isfinite(err) else SHRINK_MIN
            if h < h_min:
                store_state(s, z, v, a)
                return t, h, j, STEP_UNDERFLOW, -1
            continue
        jerk_try[:] = jerk
        carried_acceleration(a_used, a1, h, delta * h, jerk_try)
        tb = t + h
        k = -1
        if track:
            store_state(sa, z, v, a)
            store_state(sb, z1, v1, a1)
            te, k = locate_event(model, t, tb, sa, sb, wk.taut, evw)
            if k >= 0 and te <= t:  # across already at the start (end of a chatter hold)
                store_state(s, z, v, a)
                return t, h, j, OK, k
            if k >= 0:  # redo the step up to the event, in the modes valid there
                warm_try[:] = warm
                scheme_acceleration(a, jerk, delta * (te - t), a_used)
                st = galpha_step(model, z, v, a_used, P_n, warm_try, wk, awk, te, te - t, coef, ztight, zround, maxit,
                                 z1, v1, a1, P1, scratch)
                if st != OK:
                    store_state(s, z, v, a)
                    return t, h, j, st, -1
                jerk_try[:] = jerk
                carried_acceleration(a_used, a1, te - t, delta * (te - t), jerk_try)
                tb = te
        if j < t_out.size and t_out[j] <= tb:
            j = write_step_outputs(model, awk, t, tb, z, v, a, z1, v1, a1, P_n, P1, ae, ae1, scratch, sa, sb, da, db,
                                   t_out, out, j)
        counts[0] += 1
        counts[3] += 1 if allowed < FLOOR_SET * floor else 0
        for q in range(nd):
            peaks[0] = max(peaks[0], abs(z1[q]))
        z[:], v[:], a[:], P_n[:] = z1, v1, a1, P1
        warm[:] = warm_try
        jerk[:] = jerk_try
        t = tb
        if k >= 0:
            store_state(s, z, v, a)
            return t, h, j, OK, k
        h *= GROW_MAX if err == 0.0 else min(GROW_MAX, SAFETY * err ** -0.5)
    store_state(s, z, v, a)
    return t, h, j, OK, -1
