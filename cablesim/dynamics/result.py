"""Result of a time history (forced or free vibration)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .status import Status


@dataclass(frozen=True)
class SlackRecord:
    """Slack episodes of a time history (exact analysis, ``slack: continue``).

    Attributes
    ----------
    t : ndarray
        Instants at which a segment changed mode, s (ascending).
    segment : ndarray of int
        1-based segment of each event.
    kind : ndarray of str
        ``"slack"`` (onset: the segment's length fell to its natural length) or ``"taut"``
        (re-tightening).
    peak_tension : ndarray, shape (n + 1,)
        Largest tension of each segment over the run, N (located on every step's interpolant
        where the integrator tracks slack segments, else between the saved instants from the
        tensions and their rates; :mod:`cablesim.dynamics.peaks`).
    peak_time : ndarray, shape (n + 1,)
        When it occurred, s.
    slack_time : ndarray, shape (n + 1,)
        Time each segment spent slack, s.
    episodes : ndarray of int, shape (n + 1,)
        Number of slack episodes of each segment.
    chatter_holds : int
        Transitions that came within the chatter window of the previous one of their segment.
    handling : str
        How slack segments and chattering were handled, in words.
    """

    t: np.ndarray
    segment: np.ndarray
    kind: np.ndarray
    peak_tension: np.ndarray
    peak_time: np.ndarray
    slack_time: np.ndarray
    episodes: np.ndarray
    chatter_holds: int = 0
    handling: str = ""

    @classmethod
    def from_events(cls, events, n_segments, t_end, initially_slack, peak, peak_time, chatter_holds=0, handling=""):
        """Summarise ``events`` (``(t, 0-based segment, kind)``) of a run that reached ``t_end``."""
        ev = [e for e in events if e[0] <= t_end]
        t = np.array([e[0] for e in ev], dtype=float)
        seg = np.array([e[1] + 1 for e in ev], dtype=np.int64)
        kind = np.array([e[2] for e in ev], dtype=str) if ev else np.array([], dtype="<U5")
        slack_time = np.zeros(n_segments)
        episodes = np.asarray(initially_slack, dtype=np.int64).copy()
        since = np.where(initially_slack, 0.0, np.nan)
        for ti, k, kd in ev:
            if kd == "slack":
                since[k] = ti
                episodes[k] += 1
            elif np.isfinite(since[k]):
                slack_time[k] += ti - since[k]
                since[k] = np.nan
        open_ = np.isfinite(since)
        slack_time[open_] += t_end - since[open_]
        return cls(t, seg, kind, np.asarray(peak, dtype=float), np.asarray(peak_time, dtype=float), slack_time,
                   episodes, int(chatter_holds), handling)

    def fraction_of(self, duration: float) -> np.ndarray:
        """Time spent slack over ``duration`` per segment."""
        return self.slack_time / duration if duration > 0 else np.zeros_like(self.slack_time)


@dataclass(frozen=True)
class HistoryResult:
    """Time history of the cable about its static equilibrium.

    Time runs along the first axis, degrees of freedom (DOF order ``[x1, x2, x3, x4, ...]``,
    vertical axis down) along the second.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Saved instants, s.
    z : ndarray, shape (m, 2n)
        Displacements from the static equilibrium, ``z = y - y(0)``, m.
    v : ndarray, shape (m, 2n)
        Velocities ``y'``, m/s.
    zc, ze : ndarray, shape (m, 2n), or None
        Configurational and elastic parts of ``z`` (eq. 22), m; None if not computed.
    T : ndarray, shape (m, n + 1)
        Segment tensions, N.
    residual : ndarray, shape (m,)
        Drift of the dynamic equilibrium (eq. 15), ``|M y'' + C y' + P - F| / |F0|``.
    y0 : ndarray, shape (2n,)
        The static equilibrium the displacements are measured from, m.
    T0 : ndarray, shape (n + 1,)
        Tensions at that equilibrium, N.
    omega : float or None
        Forcing frequency, rad/s (None for free vibration).
    analysis : str
        ``"exact"`` or ``"approximate"``.
    integrator : str
        Name of the time-integration scheme.
    status : Status
        :attr:`Status.COMPLETED`, or why the run stopped early (the arrays hold everything up
        to then).
    message : str
        The outcome in words: ``"completed"``, or when and why the run stopped and what to try.
    t_stop : float or None
        Time the run stopped early, s (None if it completed).
    modal_omega : ndarray
        Linear modal frequencies about the equilibrium, rad/s.
    settings : dict
        Everything else worth recording (step, tolerances, damping, initial conditions).
    dof : tuple of int, optional
        1-based DOF numbers of the columns of ``z``, ``v``, ``zc``, ``ze`` when only some
        channels were kept (None: all, in order).
    slack : SlackRecord, optional
        Slack events and per-segment peak tension, time slack and episodes (None when not
        recorded).
    warnings : tuple of str
        Warnings, one paragraph each: the integrator's notes on how its steps were set
        (:meth:`~cablesim.dynamics.integrators.base.Integrator.run_notes`) and plausibility
        warnings (strains beyond the model's range, a drift of eq. 15 beyond its bound); stored
        in the file (``/history`` attribute ``warnings``).
    """

    t: np.ndarray
    z: np.ndarray
    v: np.ndarray
    zc: np.ndarray | None
    ze: np.ndarray | None
    T: np.ndarray
    residual: np.ndarray
    y0: np.ndarray
    T0: np.ndarray
    omega: float | None
    analysis: str
    integrator: str
    status: Status
    message: str
    t_stop: float | None
    modal_omega: np.ndarray
    settings: dict = field(default_factory=dict)
    dof: tuple | None = None
    slack: SlackRecord | None = None
    warnings: tuple = ()

    @property
    def dof_numbers(self) -> tuple:
        """1-based DOF number of each stored column."""
        return self.dof if self.dof is not None else tuple(range(1, self.z.shape[1] + 1))

    def keep(self, dof_numbers) -> "HistoryResult":
        """The same history with only the given DOF (1-based numbers) kept."""
        cols = [self.dof_numbers.index(d) for d in dof_numbers]
        pick = lambda a: None if a is None else a[:, cols]  # noqa: E731
        return replace(self, z=self.z[:, cols], v=self.v[:, cols], zc=pick(self.zc), ze=pick(self.ze),
                       dof=tuple(int(d) for d in dof_numbers))

    @property
    def completed(self) -> bool:
        """Whether the run reached its requested duration."""
        return self.status is Status.COMPLETED

    @property
    def n_dof(self) -> int:
        """Number of degrees of freedom."""
        return self.z.shape[1]
