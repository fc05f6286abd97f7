"""cablesim.roots.brentq against scipy.optimize.brentq, whose algorithm it follows step by step:
the same root to the last bit, the same refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq as scipy_brentq

from cablesim.roots import brentq


def _functions():
    rng = np.random.default_rng(7)
    for _ in range(200):
        c, k, p = rng.uniform(-3, 3), rng.uniform(0.1, 10), rng.integers(1, 4)
        yield (lambda x, c=c, k=k, p=p: math.atan(k * (x - c)) + 0.1 * (x - c) ** (2 * p + 1)), -5.0, 5.0
    yield (lambda x: x ** 3 - 2 * x - 5), 2.0, 3.0
    yield (lambda x: math.exp(x) - 1e-6), -20.0, 1.0
    yield (lambda x: math.tanh(50 * (x - 0.3))), -1.0, 1.0


@pytest.mark.parametrize("xtol, rtol", [(2e-12, 8.881784197001252e-16), (1e-14, 1e-12), (1e-15, 1e-13)])
def test_the_same_root_as_scipy_to_the_last_bit(xtol, rtol):
    for f, a, b in _functions():
        assert brentq(f, a, b, xtol=xtol, rtol=rtol) == scipy_brentq(f, a, b, xtol=xtol, rtol=rtol)
        assert brentq(f, b, a, xtol=xtol, rtol=rtol) == scipy_brentq(f, b, a, xtol=xtol, rtol=rtol)


def test_a_bracket_without_a_sign_change_and_a_root_at_an_end():
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1.0, -1.0, 1.0)
    assert brentq(lambda x: x - 2.0, 2.0, 5.0) == 2.0
    with pytest.raises(RuntimeError, match="no root found"):
        brentq(lambda x: math.atan(x - 0.1234567), -1e300, 1e300, xtol=1e-300, rtol=4.5e-16, maxiter=5)
