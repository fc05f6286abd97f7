"""Static models against independent references, convergence and robustness.

- exact vs approximate elastic analysis as EA grows (second-order agreement);
- the elastic catenary (Irvine), written here in closed form, as the limit of many equal nodes;
- the taut beaded string (closed-form frequencies);
- robustness over wide ranges of EA, load scale, sag and node count;
- slack segments, checked against a geometric criterion written here.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from scipy.optimize import root

from cablesim.cable import Cable
from cablesim.errors import CablesimError, ConvergenceError, SlackSegmentError
from cablesim.modal import modal_analysis, sole_inextensible_frequency
from cablesim.statics import (
    approximate_equilibrium,
    exact_equilibrium,
    inextensible_equilibrium,
    resisting_force,
)

PAPER_P = np.array([300e3, 1100e3, 450e3, 2000e3])
PAPER_S = np.array([130.0, 100.0, 110.0])
PAPER_M = np.array([8000.0, 14000.0])


def paper_cable(EA: float = 1e9, S=PAPER_S) -> Cable:
    return Cable(300.0, 20.0, S, EA, PAPER_M)


def my_resisting_force(cable: Cable, y) -> np.ndarray:
    """Nodal forces T_r e_r - T_{r+1} e_{r+1} with T_r = EA (l_r - S_r) / S_r, written here."""
    pts = np.vstack([[0.0, 0.0], np.reshape(y, (-1, 2)), [cable.L, cable.H]])
    d = np.diff(pts, axis=0)
    ell = np.hypot(d[:, 0], d[:, 1])
    F = (cable.EA * (ell - cable.S) / cable.S / ell)[:, None] * d
    return (F[:-1] - F[1:]).reshape(-1)


def assert_exact_solution(cable: Cable, P, ex):
    """P(y) = P up to 1e-9 |P| plus what a 1e-12 relative position error allows (|K| ~ EA/S)."""
    scale = max(cable.chord_length, cable.total_length)
    assert ex.segments.closure_error < 1e-11 * scale
    assert np.all(np.isfinite(ex.y)) and np.all(ex.T > 0)
    tol = 1e-9 * np.linalg.norm(P) + 1e-12 * scale * cable.EA / cable.S.min()
    assert np.linalg.norm(my_resisting_force(cable, ex.y) - P) < tol
    assert np.linalg.norm(resisting_force(cable, ex.y) - P) < tol


def assert_inextensible_solution(cable: Cable, P, inx):
    """Segments keep their natural lengths, tensions are positive and balance the loads."""
    scale = max(cable.chord_length, cable.total_length)
    assert inx.segments.closure_error < 1e-11 * scale
    pts = np.vstack([[0.0, 0.0], inx.x.reshape(-1, 2), cable.chord])
    d = np.diff(pts, axis=0)
    ell = np.hypot(d[:, 0], d[:, 1])
    assert np.all(np.abs(ell - cable.S) <= inx.segments.closure_error + 1e-12 * scale)
    assert np.all(inx.T > 0)
    F = inx.T[:, None] * d / ell[:, None]
    assert np.linalg.norm((F[:-1] - F[1:]).ravel() - P) < 1e-9 * np.linalg.norm(P)


# ----------------------------------------------------------------------------------------------
# Exact vs approximate elastic analysis as EA grows
# ----------------------------------------------------------------------------------------------
def test_exact_minus_approximate_is_second_order_in_compliance():
    """|y_exact - (x + u)| = O(1/EA^2) on the paper example, while |y_exact - x| = O(1/EA):
    the approximate analysis captures exactly the first-order elastic displacement."""
    EAs = np.array([1e8, 1e9, 1e10, 1e11])
    err2, err1 = [], []
    for EA in EAs:
        c = paper_cable(EA)
        app = approximate_equilibrium(c, PAPER_P)
        ex = exact_equilibrium(c, PAPER_P)
        err2.append(np.linalg.norm(ex.y - (app.x + app.u)))
        err1.append(np.linalg.norm(ex.y - app.x))
    err2, err1 = np.array(err2), np.array(err1)
    slope2 = np.polyfit(np.log(EAs), np.log(err2), 1)[0]
    slope1 = np.polyfit(np.log(EAs), np.log(err1), 1)[0]
    assert -2.1 < slope2 < -1.9, (slope2, err2)
    assert -1.05 < slope1 < -0.95, (slope1, err1)
    ratios = err2[:-1] / err2[1:]
    assert np.all(ratios > 70), ratios  # 1e8 is still far from the asymptote
    assert np.all(np.abs(ratios[1:] / 100 - 1) < 0.05), ratios
    # The second-order coefficient EA^2 |y_exact - (x + u)| settles.
    coef = err2 * EAs**2
    assert abs(coef[-1] / coef[-2] - 1) < 0.01


def test_exact_lowest_frequency_tends_to_sole_inextensible_frequency():
    """Paper example: the lowest exact-analysis frequency tends to the closed-form sole
    inextensible frequency (eq. 21) with an error ~ 1/EA; the other three grow like sqrt(EA)."""
    EAs = np.array([1e9, 1e10, 1e11, 1e12])
    c0 = paper_cable(np.inf)
    inx = inextensible_equilibrium(c0, PAPER_P)
    w_inx = sole_inextensible_frequency(inx.x, PAPER_P, inx.T[1], c0.S, c0.masses, c0.L, c0.H)
    errs, high = [], []
    for EA in EAs:
        c = paper_cable(EA)
        w = modal_analysis(exact_equilibrium(c, PAPER_P).K, c.mass_diagonal).omega
        errs.append(abs(w[0] - w_inx))
        high.append(w[1:])
    errs = np.array(errs)
    slope = np.polyfit(np.log(EAs), np.log(errs), 1)[0]
    assert -1.1 < slope < -0.9, (slope, errs)
    assert errs[-1] < 1e-4 * w_inx
    high = np.array(high)
    growth = high[-1] / high[-2]
    assert np.allclose(growth, np.sqrt(10.0), rtol=0.02), growth


# ----------------------------------------------------------------------------------------------
# Elastic catenary (Irvine), supports at different levels
# ----------------------------------------------------------------------------------------------
def elastic_catenary(L, H, L0, w, EA):
    """Closed-form elastic catenary through (0, 0) and (L, H), vertical axis DOWN.

    Lagrangian coordinate s along the unstretched cable, weight w per unstretched length.
    The cable force at s is (Hc, V0 - w s) (V0: downward component at A); the stretched
    tangent is (1 + T/EA) F / T, so

        x(s) = Hc s / EA + (Hc / w) [asinh(V0/Hc) - asinh((V0 - w s)/Hc)]
        y(s) = (V0 s - w s^2 / 2) / EA + [sqrt(Hc^2 + V0^2) - sqrt(Hc^2 + (V0 - w s)^2)] / w

    and Hc, V0 solve the closure x(L0) = L, y(L0) = H. ``EA = inf`` gives the inextensible one.
    Returns the function s -> (x, y) and (Hc, V0).
    """
    c = 0.0 if np.isinf(EA) else 1.0 / EA

    def xy(s, Hc, V0):
        x = Hc * s * c + Hc / w * (np.arcsinh(V0 / Hc) - np.arcsinh((V0 - w * s) / Hc))
        y = (V0 * s - 0.5 * w * s**2) * c + (np.hypot(Hc, V0) - np.hypot(Hc, V0 - w * s)) / w
        return x, y

    W = w * L0

    def residual(z):
        x, y = xy(L0, W * np.exp(z[0]), W * z[1])
        return [x / L - 1.0, (y - H) / L]

    sol = root(residual, [0.0, 0.5], method="hybr", tol=1e-13)
    assert np.max(np.abs(residual(sol.x))) < 1e-13
    Hc, V0 = W * np.exp(sol.x[0]), W * sol.x[1]
    return (lambda s: xy(s, Hc, V0)), (Hc, V0)


CATENARY_CASES = {
    # name: (L, H, L0, w, EA); w * L0 = 6500 N, tensions ~ 4 kN
    "nearly-inextensible-B-lower": (100.0, 30.0, 130.0, 50.0, 1e9),  # strain ~ 5e-6
    "extensible-B-lower": (100.0, 30.0, 130.0, 50.0, 5e4),  # strain ~ 9 %
    "extensible-B-higher": (100.0, -40.0, 125.0, 50.0, 5e4),
    "inextensible-model-B-lower": (100.0, 30.0, 130.0, 50.0, np.inf),
}


@pytest.mark.parametrize("name", list(CATENARY_CASES))
def test_equal_node_chain_converges_to_elastic_catenary(name):
    """n equal segments S = L0/(n+1), node loads w L0/(n+1): node positions converge to the
    closed-form elastic catenary at s_k = k L0/(n+1), with max error ~ 1/n^2."""
    L, H, L0, w, EA = CATENARY_CASES[name]
    curve, (Hc, V0) = elastic_catenary(L, H, L0, w, EA)
    ns = np.array([4, 8, 16, 32, 64])
    errs, h_errs = [], []
    for n in ns:
        c = Cable(L, H, np.full(n + 1, L0 / (n + 1)), EA, np.ones(n))
        P = np.zeros(2 * n)
        P[1::2] = w * L0 / (n + 1)
        if np.isinf(EA):
            sol = inextensible_equilibrium(c, P)
            y = sol.x
        else:
            sol = exact_equilibrium(c, P)
            y = sol.y
        xr, yr = curve(np.arange(1, n + 1) * L0 / (n + 1))
        errs.append(np.abs(y - np.column_stack([xr, yr]).ravel()).max())
        h_errs.append(abs(sol.segments.F[0, 0] - Hc) / Hc)
    errs = np.array(errs)
    assert np.all(np.diff(errs) < 0), errs
    order = -np.polyfit(np.log(ns + 1.0), np.log(errs), 1)[0]
    assert 1.7 < order < 2.3, (order, errs)
    assert errs[-1] < 1e-4 * L0
    # The horizontal tension converges too.
    assert np.all(np.diff(h_errs) < 0) and h_errs[-1] < 1e-3, h_errs
    if name.startswith("extensible"):
        # The elastic terms matter far more than the discretisation error: the inextensible
        # catenary with the same L0 is far from the nodes, so the test sees the stretching.
        curve0, _ = elastic_catenary(L, H, L0, w, np.inf)
        s = np.arange(1, ns[-1] + 1) * L0 / (ns[-1] + 1)
        gap = np.abs(np.concatenate(curve(s)) - np.concatenate(curve0(s))).max()
        assert gap > 100 * errs[-1]


# ----------------------------------------------------------------------------------------------
# Taut beaded string
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [1, 5, 50])
def test_taut_beaded_string_frequencies(n):
    """H = 0, equal segments with sum S < chord, no loads: a straight string with pretension
    T0 = EA (L - sum S)/sum S. Its 2n frequencies are the transverse family
    2 sqrt(T0/(m a)) sin(k pi / (2(n+1))) and the longitudinal family
    2 sqrt(EA/(m S_seg)) sin(k pi / (2(n+1))), k = 1..n."""
    L, EA, m = 120.0, 2e8, 500.0
    a = L / (n + 1)
    S_seg = a * (1.0 - 1e-3)
    c = Cable(L, 0.0, np.full(n + 1, S_seg), EA, np.full(n, m))
    P = np.zeros(2 * n)
    ex = exact_equilibrium(c, P)
    T0 = EA * (L - c.S.sum()) / c.S.sum()
    k = np.arange(1, n + 1)
    assert np.allclose(ex.y[0::2], k * a, rtol=0, atol=1e-11 * L)
    assert np.allclose(ex.y[1::2], 0.0, rtol=0, atol=1e-11 * L)
    assert np.allclose(ex.T, T0, rtol=1e-10, atol=0)
    assert np.linalg.norm(my_resisting_force(c, ex.y)) < 1e-12 * EA
    sn = np.sin(k * np.pi / (2 * (n + 1)))
    transverse = 2 * np.sqrt(T0 / (m * a)) * sn
    longitudinal = 2 * np.sqrt(EA / (m * S_seg)) * sn
    ref = np.sort(np.concatenate([transverse, longitudinal]))
    omega = modal_analysis(ex.K, c.mass_diagonal).omega
    assert omega.shape == (2 * n,)
    np.testing.assert_allclose(omega, ref, rtol=1e-9, atol=0)


def test_pretensioned_cable_carries_loads():
    """Exact model with sum S < chord under the paper's loads: a genuine equilibrium whose
    segments are all longer than their natural lengths; the inextensible and approximate
    analyses refuse the same cable."""
    c = paper_cable(1e9, S=np.array([100.0, 100.0, 100.0]))  # chord 300.67 m
    ex = exact_equilibrium(c, PAPER_P)
    assert_exact_solution(c, PAPER_P, ex)
    assert np.all(ex.length > c.S)
    with pytest.raises(ConvergenceError):
        inextensible_equilibrium(c, PAPER_P)
    with pytest.raises(ConvergenceError):
        approximate_equilibrium(c, PAPER_P)


# ----------------------------------------------------------------------------------------------
# Robustness
# ----------------------------------------------------------------------------------------------
def _paper_lengths(factor):
    """Paper segment proportions scaled so sum S = factor * chord (None: the paper's S)."""
    if factor is None:
        return PAPER_S
    return PAPER_S * factor * np.hypot(300.0, 20.0) / PAPER_S.sum()


@pytest.mark.parametrize("length_factor", [1.0001, None, 3.0], ids=["taut", "paper", "very-slack"])
@pytest.mark.parametrize("load_scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("EA", [1e6, 1e8, 1e10, 1e13])
def test_robust_over_EA_loads_and_sag(EA, load_scale, length_factor):
    """All three analyses solve the paper cable for EA from 1e6 to 1e13, loads from 1e-3 to
    1e3 times F0, sum S from 1.0001 to 3 times the chord; solutions satisfy equilibrium."""
    c = paper_cable(EA, _paper_lengths(length_factor))
    P = load_scale * PAPER_P
    ex = exact_equilibrium(c, P)
    assert_exact_solution(c, P, ex)
    inx = inextensible_equilibrium(c, P)
    assert_inextensible_solution(c, P, inx)
    app = approximate_equilibrium(c, P)
    assert np.all(np.isfinite(app.K)) and np.all(np.isfinite(app.u))
    # N P = u (D P = 0 only up to roundoff |D| |P| eps, which matters when u is tiny).
    tol = 1e-8 * np.linalg.norm(app.u) + 1e-13 * np.linalg.norm(app.N) * np.linalg.norm(P)
    assert np.linalg.norm(app.N @ P - app.u) < tol


@pytest.mark.parametrize("length_factor", [1.0001, 1.1, 3.0])
@pytest.mark.parametrize("n", [50, 200])
def test_robust_many_nodes(n, length_factor):
    """n up to 200, equal segments, equal masses, equal vertical loads: all analyses solve."""
    L, H = 300.0, 20.0
    chord = np.hypot(L, H)
    c = Cable(L, H, np.full(n + 1, length_factor * chord / (n + 1)), 1e9, np.full(n, 1000.0))
    P = np.zeros(2 * n)
    P[1::2] = 2e6 / n
    ex = exact_equilibrium(c, P)
    assert_exact_solution(c, P, ex)
    inx = inextensible_equilibrium(c, P)
    assert_inextensible_solution(c, P, inx)
    app = approximate_equilibrium(c, P)
    assert np.all(np.isfinite(app.u))
    assert np.linalg.norm(app.N @ P - app.u) < 1e-8 * np.linalg.norm(app.u)


# ----------------------------------------------------------------------------------------------
# Slack segments
# ----------------------------------------------------------------------------------------------
def slack_gap(cable: Cable, P, k: int, elastic: bool) -> float:
    """Distance between the ends of segment k (0-based) when it carries nothing.

    With F_k = 0 the force in segment 1 is Q_k (sum of the loads on nodes before k): the
    segments before k hang from A along their forces, those after k hang from B. Segment k is
    slack exactly when that gap is shorter than its natural length (convex complementary
    energy: the kink F_1 = Q_k is then its minimiser).
    """
    n = cable.n_nodes
    Q = np.zeros((n + 1, 2))
    Q[1:] = np.cumsum(np.reshape(P, (-1, 2)), axis=0)
    F = Q[k] - Q
    T = np.hypot(F[:, 0], F[:, 1])
    others = np.delete(T, k)
    if others.size and others.min() <= 1e-9 * max(float(np.abs(Q).max()), 1.0):
        # another segment carries nothing either: its direction, and so the gap, is undefined
        # (loads along the chord that leave two segments unloaded at once)
        return float("nan")
    ell = cable.S * (1.0 + T / cable.EA) if elastic else cable.S
    left = sum((ell[i] * F[i] / T[i] for i in range(k)), np.zeros(2))
    right = cable.chord - sum((ell[i] * F[i] / T[i] for i in range(k + 1, n + 1)), np.zeros(2))
    return float(np.linalg.norm(right - left))


def test_slack_nodes_pulled_together():
    """Paper cable, node 1 pulled towards B and node 2 towards A: the middle segment slackens
    (its ends, hanging from A and B along the loads, are 63 m apart < S2 = 100 m)."""
    c = paper_cable()
    P = np.array([1e6, 0.0, -1e6, 0.0])
    assert slack_gap(c, P, 1, elastic=False) < c.S[1]
    for solve in (inextensible_equilibrium, approximate_equilibrium, exact_equilibrium):
        with pytest.raises(SlackSegmentError) as err:
            solve(c, P)
        assert err.value.segment == 2
        assert isinstance(err.value, CablesimError)


def test_slack_large_upward_load():
    """A long first segment and a large upward load on node 2 (near B): node 2 is lifted
    above B and the first segment can no longer be taut -> SlackSegmentError on segment 1.
    The same downward load is carried with positive tensions."""
    c = Cable(300.0, 20.0, [320.0, 40.0, 60.0], 1e9, [1000.0, 1000.0])
    P_up = np.array([0.0, 1e5, 0.0, -2e6])
    assert slack_gap(c, P_up, 0, elastic=False) < c.S[0]
    for solve in (inextensible_equilibrium, exact_equilibrium):
        with pytest.raises(SlackSegmentError) as err:
            solve(c, P_up)
        assert err.value.segment == 1
    P_down = np.array([0.0, 1e5, 0.0, 2e6])
    assert_inextensible_solution(c, P_down, inextensible_equilibrium(c, P_down))
    assert_exact_solution(c, P_down, exact_equilibrium(c, P_down))


def test_paper_cable_upward_loads_stay_taut():
    """On the paper cable even large upward loads leave every segment taut (the slack
    configurations are geometrically impossible), so they must solve, not raise."""
    c = paper_cable()
    for P in ([0.0, -5e6, 0.0, 1e5], [300e3, 1100e3, 450e3, -8e6], [0.0, 1100e3, 0.0, -5e6]):
        P = np.array(P)
        assert all(slack_gap(c, P, k, elastic=False) > c.S[k] for k in range(3))
        assert_inextensible_solution(c, P, inextensible_equilibrium(c, P))
        assert_exact_solution(c, P, exact_equilibrium(c, P))


@st.composite
def any_direction_cases(draw):
    """Random cable (n = 1..5, sum S 1.05..2 x chord, chord inclined up to 0.6 rad) with loads
    of magnitude 1e4..1e5 N in any direction."""
    fl = lambda lo, hi: st.floats(lo, hi, allow_nan=False, allow_infinity=False)  # noqa: E731
    n = draw(st.integers(1, 5))
    S = draw(st.lists(fl(0.2, 1.0), min_size=n + 1, max_size=n + 1))
    ang, ratio = draw(fl(-0.6, 0.6)), draw(fl(1.05, 2.0))
    mags = draw(st.lists(fl(0.1, 1.0), min_size=n, max_size=n))
    dirs = draw(st.lists(fl(-np.pi, np.pi), min_size=n, max_size=n))
    return S, ang, ratio, mags, dirs


def build_any_direction_case(S, ang, ratio, mags, dirs):
    S = 100.0 * np.asarray(S)
    chord = S.sum() / ratio
    n = S.size - 1
    mags, dirs = np.asarray(mags), np.asarray(dirs)
    P = 1e5 * np.column_stack([mags * np.cos(dirs), mags * np.sin(dirs)]).ravel()
    return Cable(chord * np.cos(ang), chord * np.sin(ang), S, 1e8, np.ones(n)), P


SOLVERS = ((inextensible_equilibrium, False), (exact_equilibrium, True))


def slack_margins(c: Cable, P, elastic: bool) -> np.ndarray:
    return np.array([slack_gap(c, P, k, elastic) / c.S[k] - 1.0 for k in range(c.n_segments)])


# Loads along the chord but for a 0.012 N cross component: two taut segments carry 0.009 N
# against 1e5 N in the others. Newton stalled at a closure error of 4e-8 m (round-off of the
# difference F - Q_k amplified by |Q_k| / T_k) until the small force became the unknown.
TINY_FORCE_EXAMPLE = ([1, 1, 1, 1, 1], 0.0, 2.0, [1, 1, 1, 1], [0.0, 0.0, 1.192092896e-07, np.pi])


@settings(max_examples=60, deadline=None)
@example(case=TINY_FORCE_EXAMPLE)
@given(case=any_direction_cases())
def test_slack_detection_matches_geometric_criterion(case):
    """Random cables and loads in any direction: SlackSegmentError is raised exactly when the
    geometric criterion finds a segment whose ends, with it unloaded, are closer than its
    natural length, and names such a segment.

    Otherwise the solver returns the tensioned equilibrium."""
    c, P = build_any_direction_case(*case)
    for solve, elastic in SOLVERS:
        margins = slack_margins(c, P, elastic)
        assume(np.all(np.abs(margins) > 1e-3))  # stay clear of the borderline (and of undefined gaps)
        slack = np.flatnonzero(margins < 0)
        if slack.size:
            with pytest.raises(SlackSegmentError) as err:
                solve(c, P)
            assert err.value.segment - 1 in slack
        else:
            sol = solve(c, P)
            if elastic:
                assert_exact_solution(c, P, sol)
            else:
                assert_inextensible_solution(c, P, sol)


# A case that once stalled damped Newton at the kink F = Q_2 (segment 2's force -> 0) although
# segment 2 is taut: n=1, S=[60, 60], L=100, H=0, P=1e5*(cos 0.6545, sin 0.6545).

# The failing case from the reason above, in the strategy's parametrisation.
STALL_EXAMPLE = ([0.6, 0.6], 0.0, 1.2, [1.0], [0.6545])


@settings(max_examples=60, deadline=None)
@example(case=STALL_EXAMPLE)
@given(case=any_direction_cases())
def test_tensioned_cases_with_loads_in_any_direction_converge(case):
    """Random cables and loads in any direction: whenever no segment is slack (with a margin),
    every solver returns the tensioned equilibrium (natural/elastic lengths, P(y) = P)."""
    c, P = build_any_direction_case(*case)
    for solve, elastic in SOLVERS:
        margins = slack_margins(c, P, elastic)
        assume(np.all(margins > 1e-3))
        sol = solve(c, P)
        if elastic:
            assert_exact_solution(c, P, sol)
        else:
            assert_inextensible_solution(c, P, sol)


_CH = 150.0 / 1.05  # chord of the "singular" case, as built by any_direction_cases
SINGLE_NODE_STALLS = {
    # S = [60, 60], chord 100 m level; load 1e5 N 37.5 deg below the horizontal towards B:
    # T = (102666, 7463.5) N; Newton used to stall at a kink here, in all three models.
    "stall": (60.0, 100.0, 0.0, 0.6545),
    # S = [75, 75], chord 142.86 m at 0.4089 rad (B lower), horizontal load 1e5 N towards B:
    # T = (113373, 17030) N; the start makes both segments parallel (singular Hessian).
    "singular": (75.0, _CH * np.cos(0.40891374875212166), _CH * np.sin(0.40891374875212166), 0.0),
}


@pytest.mark.parametrize(
    "which, solve",
    [
        ("stall", inextensible_equilibrium),
        ("stall", approximate_equilibrium),
        ("stall", exact_equilibrium),
        ("singular", inextensible_equilibrium),
        ("singular", approximate_equilibrium),
    ],
    ids=lambda v: v if isinstance(v, str) else v.__name__.split("_")[0],
)
def test_single_node_with_one_small_tension_converges(which, solve):
    """n = 1, both segments clearly taut. Reference (inextensible): the node sits at the
    intersection of the circles |x| = S, |x - B| = S where T solving T1 e1 - T2 e2 = P is
    positive (so not slack). Reference (exact): P(y) = P solved here with scipy from there."""
    S1, L, H, th = SINGLE_NODE_STALLS[which]
    c = Cable(L, H, [S1, S1], 1e8, [1.0])
    P = 1e5 * np.array([np.cos(th), np.sin(th)])
    mid, d = c.chord / 2.0, c.chord_length
    candidates = []
    for side in (1.0, -1.0):  # the two intersections of the circles
        x = mid + side * np.sqrt(S1**2 - (d / 2.0) ** 2) * np.array([-c.H, c.L]) / d
        e1, e2 = x / S1, (c.chord - x) / S1
        T = np.linalg.solve(np.column_stack([e1, -e2]), P)
        if np.all(T > 0):
            candidates.append((x, T))
    assert len(candidates) == 1  # exactly one of them is in tension
    x, T = candidates[0]
    assert np.all(T > 0.07 * np.linalg.norm(P))
    assert np.all(slack_margins(c, P, elastic=False) > 0.05)
    sol = solve(c, P)
    if solve is exact_equilibrium:
        assert_exact_solution(c, P, sol)
        ref = root(lambda y: (my_resisting_force(c, y) - P) / 1e5, x, tol=1e-14)
        assert np.allclose(my_resisting_force(c, ref.x), P, rtol=0, atol=1e-6)
        np.testing.assert_allclose(sol.y, ref.x, rtol=0, atol=1e-9 * c.chord_length)
    else:
        np.testing.assert_allclose(sol.x, x, rtol=1e-10)
        np.testing.assert_allclose(sol.T, T, rtol=1e-10)


def test_inextensible_cable_shorter_than_chord_is_refused():
    """sum S <= chord: no inextensible (or approximate) equilibrium -> CablesimError."""
    chord = np.hypot(300.0, 20.0)
    for total in (0.9 * chord, chord):
        c = paper_cable(1e9, S=PAPER_S * total / PAPER_S.sum())
        with pytest.raises(CablesimError):
            inextensible_equilibrium(c, PAPER_P)
        with pytest.raises(CablesimError):
            approximate_equilibrium(c, PAPER_P)


def test_unloaded_slack_cable_is_refused():
    """No loads and sum S > chord: no segment can carry tension -> SlackSegmentError."""
    c = paper_cable()
    for solve in (inextensible_equilibrium, exact_equilibrium):
        with pytest.raises(SlackSegmentError):
            solve(c, np.zeros(4))
