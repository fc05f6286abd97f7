"""BLAS on one thread while orbits are traced (``cablesim.blas``): the limit holds inside the
computation and the caller's setting comes back after it."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from cablesim.blas import one_blas_thread
from cablesim.orbits import continue_branches

from test_orbits_matrixfree import heavy


def _blas_threads() -> list[int]:
    return [int(lib["num_threads"]) for lib in threadpool_info() if lib["user_api"] == "blas"]


def test_one_blas_thread_limits_and_gives_back():
    np.linalg.eigvals(np.eye(3))  # numpy's BLAS loaded
    before = _blas_threads()
    assert before, "no BLAS library found loaded"
    with one_blas_thread():
        assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before


def test_orbits_are_traced_on_one_blas_thread():
    """Every converged orbit of a matrix-free continuation is computed with BLAS on one
    thread, and the setting is back after it, also when the continuation ends by an error."""
    before = _blas_threads()
    seen = []
    eom = heavy(12, 1.5, load=50.0)
    d = continue_branches(eom, "omega", 1.5, 1.52, switch_branches=False, matrix_free=True, scheme="auto",
                          callback=lambda p: seen.append(_blas_threads()))
    assert len(d.branches[0].points) >= 2 and len(seen) == len(d.branches[0].points)
    assert all(threads == [1] * len(threads) for threads in seen)
    assert _blas_threads() == before

    def fail(point):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        continue_branches(eom, "omega", 1.5, 1.52, switch_branches=False, matrix_free=True, scheme="auto",
                          callback=fail)
    assert _blas_threads() == before
