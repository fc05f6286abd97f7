"""The matrix-free branch's step rule on a truncated spectrum: the monodromy on the kept
subspace along its geodesic (:func:`cablesim.orbits.floquet.leading_step_ratio`).

References written out here: monodromies ``M(s) = R(s) (V0 P(s) V0^T + W0 D W0^T) R(s)^T`` of
120 states, whose kept subspace ``R(s) V0`` turns with ``s`` (``R = exp(K s)``, ``K`` skew) and
carries a closed-form block ``P(s)``: two damped pairs turning past -1 and +1 at a fixed modulus,
or the period-doubling tongue of ``tests/test_step_rule_blocks.py`` (its multipliers in closed
form); the rest of the spectrum ``D`` is below the bound. The leading multipliers are computed
from the action ``X -> M X`` alone, as on a heavy cable. (On heavy cables themselves the
geodesic's multipliers at mid-step are checked against the orbit re-solved there by
``benchmarks/bench_heavy_orbits.py --check-steps``.)
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl

from cablesim.orbits.floquet import (aligned_block, kept_block, leading_multipliers, leading_step_ratio,
                                     truncated_step_ratio)
from test_step_rule_blocks import tongue
from test_step_rule_geodesic import doubling_sign_changes, march

N = 120


def passing(s: float) -> np.ndarray:
    """Two damped pairs ``r exp(+-i theta(s))``: ``theta = pi - 0.1 + s`` at ``r = 0.95`` (past -1)
    and ``0.05 + 0.8 s`` at ``r = 0.94`` (past +1), made non-normal by a fixed similarity."""
    A = np.zeros((4, 4))
    for k, (th, w, r) in enumerate(((np.pi - 0.1, 1.0, 0.95), (0.05, 0.8, 0.94))):
        t = th + w * s
        A[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = r * np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    S = np.eye(4) + 0.3 * np.random.default_rng(3).normal(size=(4, 4))
    return S @ A @ np.linalg.inv(S)


def family(block, k: int, turn: float, seed: int = 5):
    """``s -> M(s)`` (module docstring): ``block`` (k x k) on a subspace turning at the rate ``turn``."""
    rng = np.random.default_rng(seed)
    Q0 = np.linalg.qr(rng.standard_normal((N, N)))[0]
    V0, W0 = Q0[:, :k], Q0[:, k:]
    K = rng.standard_normal((N, N))
    K = turn * (K - K.T) / np.sqrt(N)
    D = np.diag(np.linspace(0.01, 0.2, N - k))
    return lambda s: sl.expm(K * s) @ (V0 @ block(s) @ V0.T + W0 @ D @ W0.T) @ sl.expm(K * s).T


def leading(M, s: float):
    A = M(s)
    lead = leading_multipliers(lambda X: A @ X, N)
    assert not lead.complete  # a truncated spectrum, as on a heavy cable
    return lead


def test_pairs_turning_past_minus_one_and_plus_one_take_the_steps_their_moduli_allow():
    """The pairs keep their moduli (0.05 and 0.06 from the circle) while they turn by 0.3 and
    0.24 rad past -1 and +1: judged as multipliers that move, the step is refused many times
    over; on the geodesic of the kept subspace's monodromy it is accepted, for a subspace at rest
    and for one that turns with the parameter (aligned by Procrustes)."""
    h = 0.3
    for turn in (0.0, 0.2):
        M = family(passing, 4, turn)
        Lz, La, Lb = (leading(M, s) for s in (-h, 0.0, h))
        assert La.multipliers.size == 4
        assert truncated_step_ratio(La.multipliers, Lb.multipliers) > 5.0
        assert leading_step_ratio(La, Lb, Lz, -h, h) < 0.8
        # the aligned blocks are similar to the kept ones: the same multipliers
        Va, Sa = kept_block(La)
        Vb, Sb = kept_block(Lb)
        mu = np.sort_complex(np.linalg.eigvals(aligned_block(Vb, Sb, Va)))
        assert np.abs(mu - np.sort_complex(Lb.multipliers)).max() < 1e-8
        # without the point before the step (a branch's first step) the multipliers alone judge
        assert leading_step_ratio(La, Lb) == truncated_step_ratio(La.multipliers, Lb.multipliers)


def test_a_tongue_inside_the_step_is_not_stepped_over():
    """The tongue's multipliers are the same at both ends of [-0.5, 0.5] and pass -1 twice
    inside. Judged on the multipliers alone the step across it is accepted (their motion is
    nil); on the geodesic, with the point before the step, it is refused. A march as the
    continuation's (halve a refused step, grow an accepted one by 1.5) puts points between the
    two crossings: the test function ``prod(1 + mu)`` changes sign twice along them, as along
    the closed form."""
    M = family(lambda s: np.pad(tongue(s), ((0, 2), (0, 2))) + np.diag([0, 0, 0.7, 0.6]), 4, 0.2)
    a, b = -0.5, 0.5
    assert doubling_sign_changes(np.linspace(a, b, 2001)) == 2
    leads = {s: leading(M, s) for s in (a - 0.05, a, b)}
    assert truncated_step_ratio(leads[a].multipliers, leads[b].multipliers) < 0.25
    assert leading_step_ratio(leads[a], leads[b], leads[a - 0.05], -0.05, b - a) > 1.0

    def judge(z, s, nxt):
        leads.setdefault(nxt, leading(M, nxt))
        return leading_step_ratio(leads[s], leads[nxt], leads[z], z - s, nxt - s)

    assert doubling_sign_changes(march(judge, a, b)) == 2
