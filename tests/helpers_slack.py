"""An independent event-driven shooting through slack for the tests: scipy's DOP853 (rtol 1e-12)
on the second-order equations with own geometry and tension-only segments by modes, the gaps
as terminal events, restarted in the new modes at each event; Newton's method on its period
map with a central finite-difference monodromy across the events."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp


def _geometry(y, L, H):
    pts = np.vstack([[0.0, 0.0], y.reshape(-1, 2), [L, H]])
    d = np.diff(pts, axis=0)
    return d, np.hypot(d[:, 0], d[:, 1])


class Reference:
    """The period map of ``M y'' + C y' + P(y) = F0 + FL sin(w t)``, ``P`` of the segments in
    their modes (taut: ``EA (l - S) / S`` along the segment; slack: nothing)."""

    def __init__(self, eom):
        c = eom.cable
        self.S, self.EA, self.L, self.H = np.asarray(c.S, float), float(c.EA), float(c.L), float(c.H)
        self.nd = eom.n_dof
        self.M, self.C, self.FL, self.w, self.y0 = eom.mass, eom.C, eom.FL, eom.omega, eom.y0
        # the sustained load that holds y0 (the static solve's tolerance aside), as cablesim's
        self.F0 = self.force(self.y0, np.ones(self.S.size))
        self.T = 2.0 * np.pi / self.w

    def force(self, y, taut):
        d, l = _geometry(y, self.L, self.H)
        f = (taut * self.EA * (l - self.S) / self.S / l)[:, None] * d
        return (f[:-1] - f[1:]).ravel()

    def gaps(self, x):
        return _geometry(self.y0 + x[: self.nd], self.L, self.H)[1] - self.S

    def gap_rates(self, x):
        nd = self.nd
        d, l = _geometry(self.y0 + x[:nd], self.L, self.H)
        dv = np.diff(np.vstack([[0.0, 0.0], x[nd:].reshape(-1, 2), [0.0, 0.0]]), axis=0)
        return np.einsum("ij,ij->i", d, dv) / l

    def flow(self, x0, rtol=1e-12, peaks=None, least=None, minima=None):
        """``(x(T), events)`` from ``x0`` at phase 0; events ``(t, segment 0-based, new mode)``.
        ``peaks`` (an array, one per segment): raised to the largest tension found at the gap
        rates' zeros (non-terminal events) and the period's ends, N; ``least``: lowered to the
        least elastic tension ``EA (l - S) / S`` there (negative inside a slack episode), N;
        ``minima`` (a list of lists, one per segment): extended by the elastic tension at every
        local minimum of the gap (the gap rate's upward zeros), N."""
        nd = self.nd
        x, t = np.asarray(x0, float), 0.0
        taut = (self.gaps(x) > 0).astype(float)
        events = []
        turns = [lambda t, s, k=k: self.gap_rates(s)[k] for k in range(self.S.size)]
        dips = []
        for k in range(self.S.size):
            dips.append(lambda t, s, k=k: self.gap_rates(s)[k])
            dips[-1].direction = 1.0
        if minima is None:
            dips = []

        def rhs(t, s):
            acc = self.F0 + self.FL * np.sin(self.w * t) - self.C @ s[nd:] - self.force(self.y0 + s[:nd], taut)
            return np.concatenate([s[nd:], acc / self.M])

        def gap(k):
            ev = lambda t, s: self.gaps(s)[k]  # noqa: E731
            ev.terminal = True
            ev.direction = -1.0 if taut[k] else 1.0
            return ev

        while True:
            nk = self.S.size
            sol = solve_ivp(rhs, (t, self.T), x, method="DOP853", rtol=rtol, atol=1e-14 * self.L,
                            events=[gap(k) for k in range(nk)] + (turns if peaks is not None or least is not None else [])
                            + dips)
            assert sol.status >= 0, sol.message
            if minima is not None:
                first = nk + (nk if peaks is not None or least is not None else 0)
                for k in range(nk):
                    minima[k] += [self.gaps(s)[k] * self.EA / self.S[k] for s in sol.y_events[first + k]]
            if least is not None:
                for k in range(nk):
                    for s in [*sol.y_events[nk + k], sol.y[:, 0], sol.y[:, -1]]:
                        least[k] = min(least[k], self.gaps(s)[k] * self.EA / self.S[k])
            if peaks is not None:
                for k in range(nk):
                    for s in [*sol.y_events[nk + k], sol.y[:, 0], sol.y[:, -1]]:
                        peaks[k] = max(peaks[k], taut[k] * max(self.gaps(s)[k], 0.0) * self.EA / self.S[k])
            if sol.status == 0:
                return sol.y[:, -1], events
            k = min((k for k in range(nk) if sol.t_events[k].size), key=lambda k: sol.t_events[k][0])
            t, x = sol.t_events[k][0], sol.y_events[k][0]
            taut[k] = 1.0 - taut[k]
            events.append((t, k, taut[k]))

    def monodromy(self, x, rel=1e-6):
        """Central differences of the period map, across its events."""
        n = x.size
        scale = np.concatenate([np.full(self.nd, np.abs(x[: self.nd]).max()), np.full(self.nd, np.abs(x[self.nd:]).max())])
        Mo = np.empty((n, n))
        for i in range(n):
            e = np.zeros(n)
            e[i] = rel * scale[i]
            Mo[:, i] = (self.flow(x + e)[0] - self.flow(x - e)[0]) / (2.0 * e[i])
        return Mo

    def orbit(self, x, iterations=8):
        """Newton's method on ``flow(x) - x`` with the finite-difference monodromy."""
        for _ in range(iterations):
            r = self.flow(x)[0] - x
            Mo = self.monodromy(x)
            dx = np.linalg.solve(Mo - np.eye(x.size), -r)
            x = x + dx
            if np.abs(dx).max() < 1e-12 * np.abs(x).max():
                break
        return x, Mo
