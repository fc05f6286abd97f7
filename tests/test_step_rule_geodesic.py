"""The out-of-plane block's step rule along the geodesic ``P_a (P_a^-1 P_b)^t``
(:func:`cablesim.orbits.stability.geodesic_step_ratio`), against closed-form families.

References written out here: blocks ``P(s) = S exp(A (T0 + s)) S^-1`` (two lightly damped pairs
turning fast with ``s``, made non-normal by ``S``), which lie exactly on their geodesic;
``P(s) = exp(A + s B)`` with ``A`` and ``B`` that do not commute, which does not, with the
geodesic's true mid-step error ``log(P_a^-1 P(h / 2)) - log(P_a^-1 P(h)) / 2`` from scipy's
``logm``; and the period-doubling tongue of ``tests/test_step_rule_blocks.py`` in closed form
(imported from it).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import scipy.linalg as sl

from cablesim.orbits import Settings, continuation
from cablesim.orbits.stability import (StepLog, geodesic_model_ratio, geodesic_step_ratio, interpolated_step_ratio,
                                       path_step_ratio)
from test_step_rule_blocks import tongue, tongue_multipliers


def turning(rates=(1.1, 2.3), damping=(0.004, 0.006), seed=3):
    """``s -> S exp(A (T0 + s)) S^-1``: two damped pairs ``exp((-d +- i w) (T0 + s))``."""
    A = np.zeros((4, 4))
    for k, (w, d) in enumerate(zip(rates, damping)):
        A[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = [[-d, w], [-w, -d]]
    S = np.eye(4) + 0.3 * np.random.default_rng(seed).normal(size=(4, 4))
    Sinv = np.linalg.inv(S)
    return lambda s: S @ sl.expm(A * (7.0 + s)) @ Sinv


def test_a_block_on_its_geodesic_takes_the_steps_the_straight_line_refuses():
    P, h = turning(), 0.4  # the pairs turn by 0.44 and 0.92 rad over the step, 0.05 from the circle
    Pz, Pa, Pb = P(-h), P(0.0), P(h)
    # the geodesic is the block itself: at mid-step to rounding
    step = StepLog(Pa, Pb)
    assert step.usable()
    assert np.abs(Pa @ step.power(np.array([0.5]))[0] - P(0.5 * h)).max() < 1e-12
    # the straight line cuts across the chord: its determinant defect refuses the step
    assert interpolated_step_ratio(Pa, Pb) > 1.0
    # on the geodesic the moduli do not change and the model's error (the curvature of
    # log(P_a^-1 P(s)), zero here) is rounding: accepted, and by a wide margin
    assert geodesic_step_ratio(Pa, Pb, Pz, -h, h) < 0.25
    # without the point before the step there is no error estimate: the straight line judges
    assert geodesic_step_ratio(Pa, Pb) == interpolated_step_ratio(Pa, Pb)


def test_the_geodesic_error_estimate_converges_to_the_true_mid_step_error():
    rng = np.random.default_rng(7)
    A = 0.5 * rng.normal(size=(4, 4)) - 0.2 * np.eye(4)
    B = 0.5 * rng.normal(size=(4, 4))
    P = lambda s: sl.expm(A + s * B)  # noqa: E731
    rel = []
    for h in (0.08, 0.04, 0.02, 0.01):
        Pz, Pa, Pb = P(-0.7 * h), P(0.0), P(h)
        true = np.real(sl.logm(np.linalg.solve(Pa, P(0.5 * h)))) - 0.5 * np.real(sl.logm(np.linalg.solve(Pa, Pb)))
        Lb, Lz = StepLog(Pa, Pb).log(), StepLog(Pa, Pz).log()
        sz, sb = -0.7 * h, h
        est = -(sb * sb / 4.0) * (Lb / sb - Lz / sz) / (sb - sz)  # the estimate the rule uses
        assert np.linalg.norm(true) > 1e-3 * h * h  # the block is off its geodesic
        rel.append(np.linalg.norm(est - true) / np.linalg.norm(true))
    # first order in h: the relative error of the estimate halves with the step
    assert rel[-1] < 0.05
    assert all(r1 < 0.6 * r0 for r0, r1 in zip(rel, rel[1:]))


def doubling_sign_changes(ths) -> int:
    """Sign changes of the tongue's period-doubling test ``prod(1 + mu)`` (closed form) along ``ths``."""
    pd = np.sign(np.prod(1.0 + np.array([tongue_multipliers(t) for t in ths]), axis=1).real)
    return int(np.count_nonzero(pd[1:] != pd[:-1]))


def march(judge, a: float, b: float, back: float = 0.05) -> list:
    """The points of a march from ``a`` to ``b`` as the continuation's: a step refused by
    ``judge(before, start, end) > 1`` is halved, an accepted one grows by 1.5; the first step
    starts with ``b - a`` and has a point ``back`` before ``a``."""
    pts, h = [a - back, a], b - a
    while pts[-1] < b - 1e-12:
        nxt = min(pts[-1] + h, b)
        if judge(pts[-2], pts[-1], nxt) > 1.0:
            h *= 0.5
            continue
        pts.append(nxt)
        h *= 1.5
    return pts[1:]


def test_a_multiplier_through_minus_one_and_back_within_the_step_is_seen_on_the_geodesic():
    # the tongue's multipliers are the same at both ends of [-0.5, 0.5] and pass -1 twice inside
    a, b = -0.5, 0.5
    assert doubling_sign_changes(np.linspace(a, b, 2001)) == 2

    # judged on the geodesic alone, with the point before each step, a march puts points
    # between the crossings; every step is judged by the geodesic, none left to the straight line
    def judge(z, s, nxt):
        ratio = geodesic_model_ratio(tongue(s), tongue(nxt), tongue(z), z - s, nxt - s)
        assert ratio is not None
        return ratio

    assert doubling_sign_changes(march(judge, a, b)) == 2
    # the rule the continuation uses takes the smaller of the two models' ratios; the first
    # step across the whole tongue is refused by both
    assert geodesic_step_ratio(tongue(a), tongue(b), tongue(a - 0.05), -0.05, b - a) > 1.0


def test_a_pair_through_the_circle_and_back_off_the_geodesic_is_refused_by_its_error_estimate():
    # a turning pair whose modulus bulges past the circle between two points where it is the
    # same, far from +1 and -1: P(s) = exp(-0.03 + k s (h - s)) R(pi / 2 + s), largest modulus
    # exp(0.02) at s = h / 2
    h = 0.2
    k = 0.2 / h**2
    rot = lambda s: np.array([[np.cos(s), -np.sin(s)], [np.sin(s), np.cos(s)]])  # noqa: E731
    P = lambda s: np.exp(-0.03 + k * s * (h - s)) * rot(0.5 * np.pi + s)  # noqa: E731
    assert np.abs(np.linalg.eigvals(P(0.5 * h))).max() > 1.0 > np.abs(np.linalg.eigvals(P(h))).max()
    # the geodesic between the two points keeps the modulus exp(-0.03): its path alone sees
    # nothing
    step = StepLog(P(0.0), P(h))
    path = P(0.0) @ step.power(np.linspace(0.0, 1.0, 9))
    assert np.allclose(np.abs(np.linalg.eigvals(path)), np.exp(-0.03), rtol=1e-12)
    assert path_step_ratio(np.array([np.linalg.eigvals(Pt) for Pt in path])) < 0.25
    # the curvature of log(P_a^-1 P(s)) from the point before the step does
    assert geodesic_model_ratio(P(0.0), P(h), P(-h), -h, h) > 1.0


def test_a_fast_multiplier_deep_in_the_disc_does_not_hold_the_step_of_one_near_the_circle():
    # two pairs in one block, mixed by a non-orthogonal S: one at modulus 0.95 turning steadily
    # (on its geodesic), one at 0.55 whose modulus curves with s, P(s) = S blocks(s) S^-1
    rot = lambda r, a: r * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])  # noqa: E731
    S = np.eye(4) + 0.2 * np.random.default_rng(5).normal(size=(4, 4))
    Sinv = np.linalg.inv(S)

    def P(s):
        return S @ sl.block_diag(rot(0.95, 1.0 + 0.1 * s), rot(0.55 * np.exp(0.6 * s * s), 2.0 + 0.3 * s)) @ Sinv

    h = 0.5
    Pz, Pa, Pb = P(-h), P(0.0), P(h)
    ratio = geodesic_model_ratio(Pa, Pb, Pz, -h, h)
    # the same error matrix against the least distance from the circle (0.05, the steady pair's)
    step, back = StepLog(Pa, Pb), StepLog(Pa, Pz)
    E = -(h * h / 4.0) * (step.log() / h - back.log() / -h) / (2.0 * h)
    middle = Pa @ step.power(np.array([0.5]))[0]
    assert np.linalg.norm(middle @ E, 2) / (0.5 * 0.05) > 1.0
    assert ratio < 0.5
    # the certificate holds: every true multiplier at mid-step within a quarter of its distance
    # from the circle of the geodesic's (the rule allows half)
    true = np.linalg.eigvals(P(0.5 * h))
    model = np.linalg.eigvals(middle)
    for mu in true:
        assert np.abs(model - mu).min() <= 0.25 * (1.0 - abs(mu))


class Recorded:
    """``r(u, lam) = u - lam`` (a straight branch), whose step rule records what it is given."""

    u_scale = np.array([1.0])
    lam_scale = 1.0
    test_names = ()

    def __init__(self):
        self.calls = []

    def evaluate(self, u, lam):
        return SimpleNamespace(u=np.array(u, float), lam=float(lam), r=np.array(u, float) - lam,
                               J_u=np.eye(1), J_lam=-np.ones(1))

    def test_functions(self, ev):
        return np.zeros(0)

    def step_ratio(self, ev_a, ev_b, ev_before):
        self.calls.append((ev_a, ev_b, ev_before))
        return 0.1


def test_the_continuation_gives_the_step_rule_the_point_before_the_step():
    problem = Recorded()
    br = continuation(problem, np.array([0.0]), 0.0, Settings(lam_min=-1.0, lam_max=1.0, ds=0.05, ds_max=0.2))
    assert len(problem.calls) > 5
    assert problem.calls[0][2] is None  # the first step has no point before it
    lams = [p.lam for p in br.points]
    for ev_a, ev_b, ev_before in problem.calls[1:]:
        k = lams.index(ev_a.lam)
        assert ev_before is br.points[k - 1].evaluation and ev_before.lam < ev_a.lam < ev_b.lam
