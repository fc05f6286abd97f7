"""Compiled kernels of the shooting method: one flow segment with its variational equations.

A *vector field* is a compiled function::

    field(theta, omega, x, model, prm, work, dx, J, dp, ipar) -> status

It fills ``dx = f(x, theta; omega)``, the Jacobian ``J = df/dx`` and, when ``ipar >= 0``,
``dp = df/dprm[ipar]`` (when ``ipar`` is :data:`IPAR_OMEGA`, ``dp = df/domega`` at fixed
``theta``: zero for a field in which ``omega`` appears only through ``theta``, leave ``dp``
alone then); it returns :data:`OK` (0) or a failure code. Time enters through the forcing phase
``theta = omega t`` (and, for a field whose terms are rates of a prescribed motion, through
``omega`` itself). ``model`` holds the system's constants (any value numba
can pass: a named tuple for the cable, :class:`cablesim.mechanics.model.CableModel`), ``prm``
its continuation parameters (a float array: a parameter other than ``omega`` is one of its
entries, set by the caller), ``work`` its scratch space and the warm starts of inner solves (an
array or a tuple of arrays). :func:`flow_segment` is compiled once per field and per type of
these arguments, with the field's calls inlined.

:func:`flow_segment` integrates ``x' = f(x, omega t)`` over a time interval with a fixed-step
explicit Runge-Kutta scheme, together with

- the variational equations ``Y' = J Y`` (``Y(0) = I``): the Jacobian of the discrete map;
- the derivative with respect to the parameter: ``eta' = J eta + g`` with ``g = dp`` for a
  parameter in ``prm``, or ``g = -f / omega + df/domega`` for ``omega`` itself (the segment
  spans a fixed fraction of the forcing period, so ``omega`` acts by scaling time:
  ``t = tau T(omega)``, ``dT/domega = -T/omega``; ``df/domega`` at fixed ``theta`` is the field's
  own, explicit dependence);
- the divergence integral ``q = int tr J dt`` (Liouville: ``det Y = exp q`` for the exact flow);
- the extremes of every component over the segment, from the Hermite interpolant between
  steps (the samples and their rates; for a displacement whose velocity is a component too, its
  curvature as well: quintic), located by :func:`cablesim.dynamics.extremes.hermite_extreme`.

Because the augmented system is integrated by the same scheme, ``Y`` and ``eta`` are the exact
derivatives of the discrete flow map. The Jacobian is propagated in *chunks*, restarted from the
identity whenever the divergence integral over the chunk exceeds :data:`CHUNK_DIVERGENCE` in
modulus, and the chunks are multiplied; the log-determinant is accumulated chunk by chunk, so it
stays accurate when the monodromy is nearly singular (strongly damped modes).

Ctrl-C and SIGTERM: one segment is one compiled call, which may run for many seconds (a long
forcing period, a many-node cable), so the loop reads the interruption flag
:data:`~cablesim.dynamics.interrupts.STOP` once a step and returns ``INTERRUPTED`` when it is set;
it runs without the interpreter lock, so that the thread setting the flag can run. Every
kernel of the orbits called through an :class:`EntryPoint` does the same (its last argument).

Cost: the variational product ``J Y`` at every stage is the largest part of a step; it is summed
eight columns at a time in scalar accumulators (the same sums, in the same order, as one column
at a time: the flow map is bitwise unchanged).
"""

from __future__ import annotations

import numba
import numpy as np

from ..dynamics import interrupts
from ..dynamics.extremes import hermite_extreme
from ..dynamics.interrupts import Deferred, stop_requested
from ..dynamics.status import INNER_SOLVE, INTERRUPTED, NONFINITE, OK, SLACK
from ..jit import njit

#: Parameter modes of :func:`flow_segment`.
PARAM_NONE = 0
PARAM_OMEGA = 1
PARAM_PRM = 2
#: ``ipar`` asking a field for ``df/domega`` at fixed ``theta``.
IPAR_OMEGA = -2

#: Restart the propagated Jacobian when ``|int tr J dt|`` over a chunk exceeds this.
CHUNK_DIVERGENCE = 2.0

__all__ = ["EntryPoint", "INNER_SOLVE", "INTERRUPTED", "IPAR_OMEGA", "NONFINITE", "OK", "SLACK", "flow_segment",
           "copy_work"]


def copy_work(work):
    """A deep copy of a field's scratch space (an array, or a tuple or named tuple of them)."""
    if isinstance(work, np.ndarray):
        return work.copy()
    if isinstance(work, tuple):
        items = [copy_work(w) for w in work]
        return type(work)(*items) if hasattr(work, "_fields") else tuple(items)
    return work


class EntryPoint:
    """A compiled kernel called through the entry point compiled for its argument types
    (:func:`entry_point`, looked up on the first call): numba's type dispatch of a named-tuple
    argument costs about 20 us a call, a tenth of a one-period evaluation of the paper's cable.
    The function is the same either way.

    The kernel's last argument is the interruption flag
    :data:`~cablesim.dynamics.interrupts.STOP`, passed here (the caller gives the others), and
    its status ``INTERRUPTED`` becomes ``KeyboardInterrupt``
    (:func:`~cablesim.dynamics.interrupts.acted_on`)."""

    def __init__(self, kernel):
        self.kernel = kernel
        self._entry = None

    def __call__(self, *args):
        args = (*args, interrupts.STOP)
        if self._entry is None:
            self._entry = entry_point(self.kernel, args)
        interrupts.clear()
        return interrupts.acted_on(self._entry(*args))


#: Entry points by kernel and argument types, for :func:`entry_point`.
_ENTRIES: dict = {}


def entry_point(kernel, args):
    """The compiled entry point of ``kernel`` for the types of ``args`` (compiled, or loaded
    from the cache, on first use). Taken from what ``compile`` returns: a specialisation loaded
    from the cache is filed under the argument types it was compiled with, whose compiled
    functions (the vector field) are copies rebuilt from the cache (:mod:`cablesim.jit`)."""
    sig = tuple(numba.typeof(a) for a in args)
    key = (kernel, sig)
    if key not in _ENTRIES:
        # a signal inside numba's compiler left the kernel broken (RuntimeError "no compiled
        # object yet"): it is held off until the compilation (or the load) is done, then acted on
        with Deferred() as held:
            entry = kernel.compile(sig)
        if held.hit:
            raise KeyboardInterrupt
        _ENTRIES[key] = entry
    return _ENTRIES[key]


@njit
def _hermite_extremes(xa, xb, da, db, ca, cb, h, i, xmax, xmin):
    """Update ``xmax[i]``, ``xmin[i]`` with the interior extremes of the Hermite interpolant
    through ``(xa, da)`` and ``(xb, db)`` over a step ``h`` (quintic where the curvatures ``ca``,
    ``cb`` are known, else cubic: :func:`cablesim.dynamics.extremes.hermite_extreme`)."""
    s, p = hermite_extreme(xa, xb, da, db, ca, cb, h, 1.0)
    if s > 0.0 and p > xmax[i]:
        xmax[i] = p
    s, p = hermite_extreme(xa, xb, da, db, ca, cb, h, -1.0)
    if s > 0.0 and p < xmin[i]:
        xmin[i] = p


@njit
def _logdet(Y, n, LU):
    """``(log|det|, sign)`` of the leading n x n block of Y (partial pivoting)."""
    for i in range(n):
        for j in range(n):
            LU[i, j] = Y[i, j]
    logdet = 0.0
    sign = 1.0
    for k in range(n):
        p = k
        big = abs(LU[k, k])
        for i in range(k + 1, n):
            if abs(LU[i, k]) > big:
                big = abs(LU[i, k])
                p = i
        if big == 0.0:
            return -np.inf, 0.0
        if p != k:
            sign = -sign
            for j in range(n):
                tmp = LU[k, j]
                LU[k, j] = LU[p, j]
                LU[p, j] = tmp
        piv = LU[k, k]
        if piv < 0.0:
            sign = -sign
        logdet += np.log(abs(piv))
        for i in range(k + 1, n):
            f = LU[i, k] / piv
            if f != 0.0:
                for j in range(k + 1, n):
                    LU[i, j] -= f * LU[k, j]
    return logdet, sign


@njit
def _close_chunk(Y, n, ncol, Mtot, ptot, tmpM, tmpp, LU, info, first):
    """Fold the chunk's Jacobian ``Y`` into the totals and restart it from the identity."""
    ld, sg = _logdet(Y, n, LU)
    info[1] += ld
    info[2] *= sg
    info[3] += 1.0
    if first:
        for i in range(n):
            for j in range(n):
                Mtot[i, j] = Y[i, j]
            ptot[i] = Y[i, n] if ncol > n else 0.0
    else:
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for k in range(n):
                    acc += Y[i, k] * Mtot[k, j]
                tmpM[i, j] = acc
            acc = Y[i, n] if ncol > n else 0.0
            for k in range(n):
                acc += Y[i, k] * ptot[k]
            tmpp[i] = acc
        for i in range(n):
            ptot[i] = tmpp[i]
            for j in range(n):
                Mtot[i, j] = tmpM[i, j]
    for i in range(n):
        for j in range(ncol):
            Y[i, j] = 0.0
        Y[i, i] = 1.0


@njit
def _start_segment(x, Y, xmax, xmin, info):
    """Jacobian chunk from the identity, extremes at the start state, ``info`` cleared."""
    for i in range(x.size):
        Y[i, i] = 1.0
        xmax[i] = x[i]
        xmin[i] = x[i]
    info[0] = 0.0
    info[1] = 0.0
    info[2] = 1.0
    info[3] = 0.0


@njit
def _stage_state(x, K, Yf, KYf, xs, Ysf, A, st, h, with_jac):
    """Stage state ``xs = x + h sum_r A[st, r] K[r]`` (and the same for the flat ``Y``)."""
    n = x.size
    nY = Yf.size
    for i in range(n):
        xs[i] = x[i]
    if with_jac:
        for i in range(nY):
            Ysf[i] = Yf[i]
    for r in range(st):
        a = h * A[st, r]
        if a != 0.0:
            for i in range(n):
                xs[i] += a * K[r, i]
            if with_jac:
                for i in range(nY):
                    Ysf[i] += a * KYf[r, i]


@njit
def _variational_rate_whole(J, Ys, dx, dp, KYst, omega, pmode):
    """Stage rate of the variational equations, ``KYst = J Ys`` plus the parameter forcing in
    the extra column; returns ``tr J`` (for the divergence integral)."""
    n, ncol = Ys.shape
    tr = 0.0
    for i in range(n):
        tr += J[i, i]
        j = 0
        # eight columns at a time in scalar accumulators (registers), each summed over r in
        # order: the same sums as a column at a time, about twice as fast
        while j + 8 <= ncol:
            a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
            for r in range(n):
                jr = J[i, r]
                if jr != 0.0:
                    a0 += jr * Ys[r, j]
                    a1 += jr * Ys[r, j + 1]
                    a2 += jr * Ys[r, j + 2]
                    a3 += jr * Ys[r, j + 3]
                    a4 += jr * Ys[r, j + 4]
                    a5 += jr * Ys[r, j + 5]
                    a6 += jr * Ys[r, j + 6]
                    a7 += jr * Ys[r, j + 7]
            KYst[i, j] = a0
            KYst[i, j + 1] = a1
            KYst[i, j + 2] = a2
            KYst[i, j + 3] = a3
            KYst[i, j + 4] = a4
            KYst[i, j + 5] = a5
            KYst[i, j + 6] = a6
            KYst[i, j + 7] = a7
            j += 8
        while j < ncol:
            a0 = 0.0
            for r in range(n):
                jr = J[i, r]
                if jr != 0.0:
                    a0 += jr * Ys[r, j]
            KYst[i, j] = a0
            j += 1
    if ncol > n:
        for i in range(n):
            if pmode == PARAM_OMEGA:
                KYst[i, n] -= dx[i] / omega
            KYst[i, n] += dp[i]
    return tr


@njit
def _variational_rate(J, Yc, dx, dp, KYc, omega, pmode, rows, bounds, ncol, Jb):
    """Stage rate of the variational equations on the compact blocks of ``Y``
    (:func:`flow_segment`): ``KY_b = J_bb Y_b`` for each diagonal block ``b``, the same sums as
    :func:`_variational_rate_whole` without the blocks' zero couplings, plus the parameter
    forcing in the extra column (of the first block); returns ``tr J`` (for the divergence
    integral). ``Jb``: scratch for a block of ``J``."""
    n = J.shape[0]
    tr = 0.0
    for i in range(n):
        tr += J[i, i]
    off = 0
    for blk in range(bounds.size - 1):
        lo = bounds[blk]
        kb = bounds[blk + 1] - lo
        nc = kb + 1 if (blk == 0 and ncol > n) else kb
        for p in range(kb):
            for q in range(kb):
                Jb[p, q] = J[rows[lo + p], rows[lo + q]]
        for p in range(kb):
            base = off + p * nc
            j = 0
            while j + 8 <= nc:  # eight columns at a time, as in _variational_rate_whole
                a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
                for r in range(kb):
                    jr = Jb[p, r]
                    if jr != 0.0:
                        rr = off + r * nc + j
                        a0 += jr * Yc[rr]
                        a1 += jr * Yc[rr + 1]
                        a2 += jr * Yc[rr + 2]
                        a3 += jr * Yc[rr + 3]
                        a4 += jr * Yc[rr + 4]
                        a5 += jr * Yc[rr + 5]
                        a6 += jr * Yc[rr + 6]
                        a7 += jr * Yc[rr + 7]
                KYc[base + j] = a0
                KYc[base + j + 1] = a1
                KYc[base + j + 2] = a2
                KYc[base + j + 3] = a3
                KYc[base + j + 4] = a4
                KYc[base + j + 5] = a5
                KYc[base + j + 6] = a6
                KYc[base + j + 7] = a7
                j += 8
            while j < nc:
                a0 = 0.0
                for r in range(kb):
                    jr = Jb[p, r]
                    if jr != 0.0:
                        a0 += jr * Yc[off + r * nc + j]
                KYc[base + j] = a0
                j += 1
            if nc > kb:
                i = rows[lo + p]
                if pmode == PARAM_OMEGA:
                    KYc[base + kb] -= dx[i] / omega
                KYc[base + kb] += dp[i]
        off += kb * nc
    return tr


@njit
def _compact_size(n, ncol, bounds):
    """Length of the compact blocks of ``Y`` (:func:`flow_segment`)."""
    size = 0
    for blk in range(bounds.size - 1):
        kb = bounds[blk + 1] - bounds[blk]
        size += kb * (kb + 1 if (blk == 0 and ncol > n) else kb)
    return size


@njit
def _blocks_to_full(Yc, Y, rows, bounds, to_full):
    """Copy the compact blocks into the full ``Y`` (``to_full``) or the identity's blocks into
    the compact ones (after a chunk's restart), column ``n`` being the parameter's."""
    n, ncol = Y.shape
    off = 0
    for blk in range(bounds.size - 1):
        lo = bounds[blk]
        kb = bounds[blk + 1] - lo
        nc = kb + 1 if (blk == 0 and ncol > n) else kb
        for p in range(kb):
            for q in range(nc):
                col = rows[lo + q] if q < kb else n
                if to_full:
                    Y[rows[lo + p], col] = Yc[off + p * nc + q]
                else:
                    Yc[off + p * nc + q] = 1.0 if q == p else 0.0
        off += kb * nc


@njit
def _sample_step(k, x, K, xprev, dprev, h, xmax, xmin, rec):
    """Extremes over the interval ending at sample ``k`` (the rate at ``x_k`` is ``K[0]``) and,
    if ``rec`` has rows, the sample and its rate."""
    n = x.size
    half = n // 2
    if k > 0:
        for i in range(n):
            # A component whose rate is another component (a displacement beside its velocity,
            # as in the cable's (z, v)) has that component's rate for its curvature.
            ca = cb = np.nan
            if i < half and dprev[i] == xprev[half + i] and K[0, i] == x[half + i]:
                ca, cb = dprev[half + i], K[0, half + i]
            _hermite_extremes(xprev[i], x[i], dprev[i], K[0, i], ca, cb, h, i, xmax, xmin)
    for i in range(n):
        if x[i] > xmax[i]:
            xmax[i] = x[i]
        if x[i] < xmin[i]:
            xmin[i] = x[i]
    if rec.shape[0] > 0:
        for i in range(n):
            rec[k, i] = x[i]
            rec[k, n + i] = K[0, i]


@njit
def _advance_state(x, K, b, h, xprev, dprev):
    """``x += h sum_st b[st] K[st]``, keeping the sample and its rate for the interpolant;
    False when the new state is not finite."""
    for i in range(x.size):
        xprev[i] = x[i]
        dprev[i] = K[0, i]
        acc = 0.0
        for st in range(b.size):
            acc += b[st] * K[st, i]
        x[i] += h * acc
        if not np.isfinite(x[i]):
            return False
    return True


#: The step's sampling and state update, shared with the kernels that carry a few directions
#: instead of the whole Jacobian (:mod:`cablesim.orbits.directional`, :mod:`cablesim.orbits.radau`).
sample_step = _sample_step
advance_state = _advance_state


@njit
def _advance_jacobian(Yf, KYf, b, h):
    """``Y += h sum_st b[st] KY[st]`` on the flat views."""
    for st in range(b.size):
        hb = h * b[st]
        if hb != 0.0:
            for i in range(Yf.size):
                Yf[i] += hb * KYf[st, i]


#: The step's pieces, shared with the kernel that tracks slack segments
#: (:mod:`cablesim.orbits.slackflow`), whose steps are these same sums.
stage_state = _stage_state
variational_rate_whole = _variational_rate_whole
variational_rate = _variational_rate
compact_size = _compact_size
blocks_to_full = _blocks_to_full
close_chunk = _close_chunk
start_segment = _start_segment
advance_jacobian = _advance_jacobian


@njit(nogil=True)
def flow_segment(field, model, prm, work, x0, theta0, omega, duration, nsteps, A, b, c, ipar, pmode, jac,
                 rows, bounds, xend, Mout, pout, xmax, xmin, rec, info, stop):
    """Integrate one segment (see the module docstring). Returns a status code (``INTERRUPTED``
    as soon as ``stop[0]`` is set: :data:`~cablesim.dynamics.interrupts.STOP`).

    Outputs: ``xend`` the final state; with ``jac``: ``Mout`` the Jacobian of the discrete map,
    ``pout`` its derivative with respect to the parameter (zero when ``pmode`` is
    :data:`PARAM_NONE`), ``info = (int tr J dt, log|det Mout|, sign det Mout, chunks)``;
    always: ``xmax``, ``xmin`` (extremes of each component), and, if ``rec`` has rows, the
    state and its rate at every step (``rec[k, :n]``, ``rec[k, n:]``).

    ``rows[bounds[k]:bounds[k + 1]]`` (ascending) are the state components of block ``k`` of
    the variational equations, carried on its diagonal blocks only, each stored compactly (the
    parameter's column with the first block), the full ``Y`` assembled at the end of each chunk.
    Exact when the Jacobian has no entries coupling the blocks, as on an orbit in a plane of
    mirror symmetry whose normal is a coordinate axis
    (:meth:`cablesim.orbits.symmetry.Mirror.coordinate_blocks`): each block's sums are the whole
    Jacobian's without their zero terms, so the map is bitwise the same at the blocks' cost.
    One block, ``rows = 0..n-1``: the whole Jacobian, as one array.
    """
    n = x0.size
    s = b.size
    h = duration / nsteps
    ncol = n + 1 if (jac and pmode != PARAM_NONE) else n
    ipar_f = ipar if pmode == PARAM_PRM else (IPAR_OMEGA if pmode == PARAM_OMEGA else -1)
    x = x0.copy()
    xs = np.empty(n)
    K = np.empty((s, n))
    dx = np.empty(n)
    dp = np.zeros(n)
    J = np.zeros((n, n))
    Y = np.zeros((n, ncol))
    nY = _compact_size(n, ncol, bounds)
    Yf = np.empty(nY)  # the blocks of Y, compact and flat for the stage combinations
    Ysf = np.empty(nY)
    KYf = np.empty((s, nY))
    Jb = np.empty((n, n))
    Ys2 = Ysf.reshape((n, ncol)) if bounds.size == 2 else Y
    KY2 = KYf.reshape((s, n, ncol)) if bounds.size == 2 else KYf.reshape((s, 1, nY))
    tmpM = np.empty((n, n))
    tmpp = np.empty(n)
    LU = np.empty((n, n))
    xprev = np.empty(n)
    dprev = np.empty(n)
    _start_segment(x, Y, xmax, xmin, info)
    if jac:
        _blocks_to_full(Yf, Y, rows, bounds, False)
    q_chunk = 0.0
    first_chunk = True
    for k in range(nsteps + 1):
        if stop_requested(stop):
            return INTERRUPTED
        last = k == nsteps
        # the last sample needs only its rate (first stage), not a step
        stage_jac = jac and not last
        for st in range(s if not last else 1):
            _stage_state(x, K, Yf, KYf, xs, Ysf, A, st, h, stage_jac)
            theta = theta0 + omega * h * (k + c[st])
            code = field(theta, omega, xs, model, prm, work, dx, J, dp, ipar_f)
            if code != OK:
                return code
            for i in range(n):
                if not np.isfinite(dx[i]):
                    return NONFINITE
                K[st, i] = dx[i]
            if stage_jac:
                if bounds.size == 2:  # the whole Jacobian: compact is the full layout
                    tr = _variational_rate_whole(J, Ys2, dx, dp, KY2[st], omega, pmode)
                else:
                    tr = _variational_rate(J, Ysf, dx, dp, KYf[st], omega, pmode, rows, bounds, ncol, Jb)
                info[0] += h * b[st] * tr
        _sample_step(k, x, K, xprev, dprev, h, xmax, xmin, rec)
        if last:
            break
        if not _advance_state(x, K, b, h, xprev, dprev):
            return NONFINITE
        if jac:
            _advance_jacobian(Yf, KYf, b, h)
            if abs(info[0] - q_chunk) > CHUNK_DIVERGENCE and k < nsteps - 1:
                _blocks_to_full(Yf, Y, rows, bounds, True)
                _close_chunk(Y, n, ncol, Mout, pout, tmpM, tmpp, LU, info, first_chunk)
                _blocks_to_full(Yf, Y, rows, bounds, False)
                first_chunk = False
                q_chunk = info[0]
    for i in range(n):
        xend[i] = x[i]
    if jac:
        _blocks_to_full(Yf, Y, rows, bounds, True)
        _close_chunk(Y, n, ncol, Mout, pout, tmpM, tmpp, LU, info, first_chunk)
    return OK
