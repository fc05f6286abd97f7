"""Continuation with the matrix-free shooting against the dense one, on cables small enough for
both: the same branches, bifurcations and multipliers (the dense shooting is the reference: its
monodromy is formed and all its eigenvalues computed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cablesim.analyses.setup import build_equations
from cablesim.analyses.static import run_static
from cablesim.case import parse_case
from cablesim.orbits import Settings, continue_branches
from cablesim.orbits.mfproblem import MATRIX_FREE_DOF, use_matrix_free

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "paper-example.yaml"


@pytest.fixture(scope="module")
def paper():
    case = parse_case(CONFIG.read_text())
    return case, run_static(case)


def both(eom, **kw):
    dense = continue_branches(eom, matrix_free=False, **kw)
    free = continue_branches(eom, matrix_free=True, **kw)
    return dense, free


def assert_same_bifurcations(dense, free, state_tol):
    assert [b.kind for b in free.bifurcations] == [b.kind for b in dense.bifurcations]
    assert [len(b.points) for b in free.branches] == [len(b.points) for b in dense.branches]
    assert [b.end for b in free.branches] == [b.end for b in dense.branches]
    for a, b in zip(dense.bifurcations, free.bifurcations):
        assert b.located and b.trusted
        assert abs(a.parameter - b.parameter) < 1e-8
        assert np.abs(a.state - b.state).max() < state_tol * np.abs(a.state).max()
        assert abs(a.multiplier - b.multiplier) < 1e-8
        assert a.multipliers.size == b.multipliers.size  # 8 states: the whole spectrum either way
        assert max(np.abs(a.multipliers - m).min() for m in b.multipliers) < 1e-8


@pytest.mark.slow  # the period-doubling pair below runs in `make test`
def test_fold_pair(paper):
    """The softening fold pair at twice the load (4 DOF, 8 states)."""
    case, static = paper
    eom = build_equations(case, static, omega=2.0, load_scale=2.0)
    dense, free = both(eom, parameter="omega", start=2.0, stop=2.8, switch_branches=False,
                       settings=Settings(ds_max=0.01))
    assert [b.kind for b in dense.bifurcations] == ["fold", "fold"]
    # a fold's state is located along the tangent (pure state there) to the bracket width:
    # measured 5e-8 relative, its parameter to 3e-13
    assert_same_bifurcations(dense, free, state_tol=1e-6)
    br_d, br_f = dense.branches[0], free.branches[0]
    assert np.abs(br_f.values - br_d.values).max() < 1e-8
    regular = [p.special is None for p in br_d.points]  # at a fold a multiplier is 1 to round-off
    assert list(br_f.stable[regular]) == list(br_d.stable[regular])


def test_period_doubling_pair_and_the_doubled_branch(paper):
    """The period-doubling pair near 2 w1, the switch to the period-2 branch, its fold and its
    merge at the pair's other end."""
    case, static = paper
    eom = build_equations(case, static, omega=4.9)
    dense, free = both(eom, parameter="omega", start=4.9, stop=5.2)
    assert [b.kind for b in dense.bifurcations] == ["period-doubling", "period-doubling", "fold"]
    assert_same_bifurcations(dense, free, state_tol=1e-8)  # measured 1e-13
    assert free.stats["krylov_iterations"] > 0


def test_the_switch_by_size():
    assert not use_matrix_free(MATRIX_FREE_DOF, None) and use_matrix_free(MATRIX_FREE_DOF + 1, None)
    assert use_matrix_free(4, True) and not use_matrix_free(400, False)


def test_branch_multipliers_of_different_counts():
    """A matrix-free branch keeps as many multipliers as each point needs: the branch's table
    pads with NaN (it once failed on the ragged rows)."""
    from cablesim.orbits import OrbitBranch, OrbitPoint

    def point(i, mu):
        z = np.zeros(2)
        return OrbitPoint(branch=0, index=i, parameter=1.0 + i, omega=1.0 + i, period=1, state=z, u=z,
                          amplitude=z, halfrange=z, multipliers=np.asarray(mu, complex), stable=True,
                          trusted=True, residual=0.0, liouville=np.nan, special=None, located=True)

    br = OrbitBranch(index=0, period=1, parameter="omega")
    br.points = [point(0, [0.9, 0.5j, -0.5j]), point(1, [0.95])]
    table = br.multipliers
    assert table.shape == (2, 3)
    assert table[1, 0] == 0.95 and np.isnan(table[1, 1:]).all() and table[0, 1] == 0.5j
