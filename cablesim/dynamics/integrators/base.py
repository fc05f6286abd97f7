"""The integrator contract.

An integrator is an immutable object holding its settings (step size or tolerances). It
advances an :class:`IntegratorState` through the :class:`~cablesim.dynamics.equations.EquationsOfMotion`
up to a time, writing interpolated states at the requested output instants, and reports
failures as status codes (:mod:`cablesim.dynamics.kernels`), never by raising. The driver
(:func:`cablesim.dynamics.simulate.simulate`) calls it chunk by chunk, which keeps Ctrl-C and
progress reporting responsive while the compiled loop runs.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from ...jit import njit


@dataclass
class IntegratorState:
    """Mutable state carried between chunks.

    Attributes
    ----------
    t : float
        Current time, s.
    s : ndarray
        ``(z, y', y'')`` at ``t``.
    warm : ndarray, shape (2,)
        Warm start of the inner inextensible solves.
    extra : dict
        Scheme-specific data (current step size, step counter, stage rates, internal force).
    wk : tuple
        Scratch arrays of the compiled kernels (:func:`cablesim.dynamics.equations.workspace`).
    """

    t: float
    s: np.ndarray
    warm: np.ndarray
    extra: dict = field(default_factory=dict)
    wk: tuple = ()


class Integrator(ABC):
    """Base class of the time-integration schemes."""

    #: Name used in case files and on the command line.
    name: ClassVar[str]
    #: Whether the scheme uses a fixed step (else it adapts it to tolerances).
    fixed_step: ClassVar[bool]
    #: Global order of accuracy.
    order: ClassVar[int]
    #: One line for listings.
    description: ClassVar[str]
    #: Largest stable ``h * rate`` (rate: the fastest damped root) of an explicit scheme; None
    #: for an unconditionally stable one.
    stability_limit: ClassVar[float | None] = None

    @abstractmethod
    def start(self, eom, s0: np.ndarray, t0: float = 0.0) -> IntegratorState:
        """State at ``t0`` from the initial ``s0 = (z, y', y'')``."""

    @abstractmethod
    def advance(self, model, state: IntegratorState, t_end: float, t_out: np.ndarray, out: np.ndarray):
        """Advance ``state`` to at least ``t_end``.

        Parameters
        ----------
        model : tuple
            :meth:`EquationsOfMotion.params`.
        state : IntegratorState
            Updated in place.
        t_end : float
            Advance until ``state.t >= t_end`` (adaptive schemes may step past it).
        t_out : ndarray
            Output instants, ascending, all in ``(state.t, ...]``.
        out : ndarray, shape (len(t_out), 3 * n_dof)
            Receives interpolated states for every instant reached.

        Returns
        -------
        n_written : int
            How many rows of ``out`` were filled.
        status : int
            :data:`cablesim.dynamics.kernels.OK` or a failure code; on failure ``state`` holds
            the last good state.
        """

    def settings(self) -> dict:
        """The settings, for result files."""
        return {k: v for k, v in self.__dict__.items() if not k.startswith("_")}

    def run_notes(self, state) -> tuple[str, ...]:
        """What the user should know about how a finished run's steps were set, one paragraph
        each (the history's warnings): none unless a scheme says otherwise."""
        return ()

    def for_finite_differences(self) -> "Integrator":
        """A version whose flow map is smooth in the initial state (finite-difference monodromy):
        a fixed-step scheme as it is; an adaptive one tightened so that its step-size controller
        does not show in the differences."""
        return self

    def for_measuring(self, spacing: float) -> "Integrator":
        """A version whose saved states are accurate at samples ``spacing`` apart: an adaptive
        scheme (whose states between steps are interpolated) with its steps held to that
        spacing; a fixed-step scheme as it is."""
        return self

    def for_transient(self, rtol: float) -> "Integrator":
        """A version for a transient that need only come near a steady state: an adaptive scheme
        with its relative tolerance loosened to ``rtol`` (never tightened); a fixed-step one as
        it is."""
        return self


@njit(inline="always")
def hermite_weights(ta, tb, t):
    """Weights ``(h00, h10 h, h01, h11 h)`` of the cubic Hermite interpolant at ``t`` between
    ``ta`` and ``tb``: of the value at ``ta``, its derivative, the value at ``tb``, its derivative."""
    h = tb - ta
    th = (t - ta) / h
    th2 = th * th
    th3 = th2 * th
    return 2.0 * th3 - 3.0 * th2 + 1.0, (th3 - 2.0 * th2 + th) * h, -2.0 * th3 + 3.0 * th2, (th3 - th2) * h


@njit
def hermite(ta, tb, sa, sb, da, db, t, out):
    """Cubic Hermite interpolation of a state between two steps (4th-order accurate)."""
    h00, h10, h01, h11 = hermite_weights(ta, tb, t)
    for i in range(out.size):
        out[i] = h00 * sa[i] + h10 * da[i] + h01 * sb[i] + h11 * db[i]
