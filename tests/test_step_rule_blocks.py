"""The step rule of the out-of-plane block, judged on the monodromy block's matrix
(:func:`cablesim.orbits.stability.interpolated_step_ratio`), against closed-form families.

References written out here: a 2 x 2 family whose multipliers are known in closed form,
``P(th) = -rho [[cos th, sin th + d], [-(sin th - d), cos th]]`` with multipliers
``-rho (cos th +- sqrt(d^2 - sin^2 th))``: complex for ``|sin th| > d``, split on the real axis
around ``th = 0`` where one of them reaches ``-rho (1 + d)`` (a period-doubling tongue when that
is beyond -1), and a damped rotation ``r R(th)`` whose multipliers ``r e^{+-i th}`` never leave the
circle of radius ``r``.
"""

from __future__ import annotations

import numpy as np

from cablesim.orbits.stability import interpolated_step_ratio, step_ratio


def tongue(th: float, rho: float = 0.9, d: float = 0.3) -> np.ndarray:
    return -rho * np.array([[np.cos(th), np.sin(th) + d], [-(np.sin(th) - d), np.cos(th)]])


def tongue_multipliers(th: float, rho: float = 0.9, d: float = 0.3) -> np.ndarray:
    root = np.sqrt(complex(d * d - np.sin(th) ** 2))
    return -rho * np.array([np.cos(th) + root, np.cos(th) - root])


def test_a_multiplier_through_minus_one_and_back_within_the_step_is_not_stepped_over():
    a, b = -0.5, 0.5
    ths = np.linspace(a, b, 2001)
    largest = np.array([np.abs(tongue_multipliers(t)).max() for t in ths])
    # the closed form: inside the circle at both ends, beyond -1 in the middle of the step
    assert largest[0] < 1.0 and largest[-1] < 1.0 and largest.max() > 1.1
    assert np.allclose(np.sort_complex(np.linalg.eigvals(tongue(0.2))), np.sort_complex(tongue_multipliers(0.2)))
    mu_a, mu_b = np.linalg.eigvals(tongue(a)), np.linalg.eigvals(tongue(b))
    # the same multipliers at both ends (a conjugate pair, far enough from -1): judged on them the
    # step is accepted and the two crossings of -1 inside it are missed
    assert step_ratio(mu_a, mu_b) < 1.0
    assert interpolated_step_ratio(tongue(a), tongue(b)) > 1.0
    # a march that halves a refused step and grows an accepted one by 1.5 (as the continuation
    # does) puts points between the two crossings: the test function prod(1 + mu) changes sign
    # twice along them, at the closed form's crossings
    pts, h = [a], b - a
    while pts[-1] < b - 1e-12:
        nxt = min(pts[-1] + h, b)
        if interpolated_step_ratio(tongue(pts[-1]), tongue(nxt)) > 1.0:
            h *= 0.5
            continue
        pts.append(nxt)
        h *= 1.5
    pd = np.sign([np.prod(1.0 + tongue_multipliers(t)).real for t in pts])
    true = np.sign(np.prod(1.0 + np.array([tongue_multipliers(t) for t in ths]), axis=1).real)
    assert np.count_nonzero(true[1:] != true[:-1]) == 2
    assert np.count_nonzero(pd[1:] != pd[:-1]) == 2


def test_a_turning_pair_that_stays_off_the_circle_takes_a_longer_step():
    r = 0.8
    rot = lambda th: r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])  # noqa: E731
    a, b = np.pi - 0.2, np.pi - 0.45
    # the multipliers' motion near -1 holds the step judged on them
    assert step_ratio(np.linalg.eigvals(rot(a)), np.linalg.eigvals(rot(b))) > 1.0
    # the matrix's: the pair turns on the circle of radius r, never within 1 - r of it
    assert interpolated_step_ratio(rot(a), rot(b)) < 1.0
    # and the linear interpolant's own multipliers stay inside, off the circle by at least
    # half the distance of the true ones
    for t in np.linspace(0.0, 1.0, 33):
        mu = np.linalg.eigvals((1 - t) * rot(a) + t * rot(b))
        assert np.abs(mu).max() < 1.0 - 0.5 * (1.0 - r)


def test_the_model_error_bounds_the_turn_of_a_pair_on_the_circle():
    # a pair turning by dth on |mu| = r: the interpolant's multipliers at mid-step are short of
    # the true ones by r (1 - cos(dth / 2)); the rule's determinant defect is 1 - cos^2(dth / 2)
    r = 0.95
    rot = lambda th: r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])  # noqa: E731
    for dth in (0.05, 0.2, 0.6):
        mid = np.linalg.eigvals(0.5 * (rot(1.0) + rot(1.0 + dth)))
        short = r - np.abs(mid).max()
        assert np.isclose(short, r * (1 - np.cos(dth / 2)), rtol=1e-9)
        defect = 1.0 - np.cos(dth / 2) ** 2
        assert defect >= short  # the defect is at least the shortfall it stands for
    # a large turn against a small distance from the circle is refused
    assert interpolated_step_ratio(rot(1.0), rot(1.6)) > 1.0
