"""harness.lp: the incremental linear programmes against scipy's linprog, and a silent HiGHS."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import linprog

from harness.lp import DualIncrementalLP, IncrementalLP

SOLVERS = [IncrementalLP, DualIncrementalLP]


def scipy_value(c, lo, hi, M, rlo, rhi):
    """The optimum by scipy's HiGHS from scratch (None if infeasible)."""
    A_ub, b_ub = [], []
    for row, a, b in zip(M, rlo, rhi, strict=True):
        if np.isfinite(b):
            A_ub.append(row)
            b_ub.append(b)
        if np.isfinite(a):
            A_ub.append(-row)
            b_ub.append(-a)
    res = linprog(c, A_ub=np.array(A_ub), b_ub=np.array(b_ub),
                  bounds=list(zip(lo, hi, strict=True)), method="highs")
    return res.fun if res.status == 0 else None


@pytest.mark.parametrize("cls", SOLVERS)
@pytest.mark.parametrize("seed", range(6))
def test_grows_and_shrinks_like_a_fresh_solve(cls, seed):
    rng = np.random.default_rng(seed)
    n, k = 5 + seed % 3, 60
    M = rng.normal(size=(k, n))
    rlo = np.where(rng.random(k) < 0.5, -rng.random(k) - 0.2, -np.inf)
    rhi = rng.random(k) + 0.2
    c = rng.normal(size=n)
    lo, hi = np.full(n, -2.0), np.full(n, 2.0)
    lp = cls(lo, hi, c)
    lp.add(M[:20], rlo[:20], rhi[:20])
    assert lp.solve()
    assert c @ lp.x == pytest.approx(scipy_value(c, lo, hi, M[:20], rlo[:20], rhi[:20]),
                                     abs=1e-7)
    mark = lp.mark()
    lp.add(M[20:40], rlo[20:40], rhi[20:40])
    lp.add(M[40:], rlo[40:], rhi[40:])
    assert lp.rows == k
    assert lp.solve()
    assert c @ lp.x == pytest.approx(scipy_value(c, lo, hi, M, rlo, rhi), abs=1e-7)
    x = lp.x
    assert np.all(M @ x <= rhi + 1e-7) and np.all(M @ x >= rlo - 1e-7)
    assert np.all(x >= lo - 1e-9) and np.all(x <= hi + 1e-9)
    lp.restore(mark)  # back to the first 20 rows, warm
    assert lp.rows == 20
    assert lp.solve()
    assert c @ lp.x == pytest.approx(scipy_value(c, lo, hi, M[:20], rlo[:20], rhi[:20]),
                                     abs=1e-7)


@pytest.mark.parametrize("cls", SOLVERS)
def test_equality_rows_and_infeasibility(cls):
    lp = cls(np.zeros(2), np.full(2, 1.0), np.array([1.0, 1.0]))
    lp.add(np.array([[1.0, 1.0]]), 1.5, 1.5)  # x + y = 1.5
    assert lp.solve() and lp.x.sum() == pytest.approx(1.5) and lp.value == pytest.approx(1.5)
    mark = lp.mark()
    lp.add(np.array([[1.0, -1.0]]), 1.2, np.inf)  # x - y >= 1.2: with x <= 1, infeasible
    assert not lp.solve()
    lp.restore(mark)
    assert lp.solve() and lp.value == pytest.approx(1.5)


def test_dropping_from_inside_a_block_is_refused():
    lp = DualIncrementalLP(np.zeros(2), np.ones(2), np.ones(2))
    lp.add(np.eye(2), 0.0, 1.0)
    lp.add(np.eye(2), 0.0, 1.0)
    with pytest.raises(ValueError, match="not the start of a block"):
        lp.drop_from(1)
    assert lp.solve()  # nothing else broke


def test_highs_prints_nothing_to_standard_output():
    code = ("import numpy as np; from harness.lp import IncrementalLP;"
            "lp = IncrementalLP(np.zeros(1), np.ones(1), np.ones(1)); print(lp.solve())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "True"


@pytest.mark.parametrize("cls", SOLVERS)
@pytest.mark.parametrize("seed", range(4))
def test_pruning_keeps_the_optimum_and_the_row_indices(cls, seed):
    rng = np.random.default_rng(100 + seed)
    n, k = 6, 80
    M = rng.normal(size=(k, n))
    rhi = rng.random(k) + 0.2
    c = rng.normal(size=n)
    lo, hi = np.full(n, -2.0), np.full(n, 2.0)
    lp = cls(lo, hi, c)
    lp.add(M[:40], -np.inf, rhi[:40])
    lp.add(M[40:], -np.inf, rhi[40:])
    assert lp.solve()
    value = lp.value
    gone = lp.prune(since=10)
    # rows the optimum leaves slack, never one below ``since``, each at most once
    assert gone.size > 0 and gone.min() >= 10 and np.unique(gone).size == gone.size
    slack = M[gone] @ lp.x < rhi[gone] - 1e-9
    assert slack.all()
    assert lp.solve() and lp.value == pytest.approx(value, abs=1e-9)
    # indices are kept: the second block is still dropped from its own start
    lp.drop_from(40)
    assert lp.rows == 40 and lp.solve()
    # and the optimum is the fresh one of what is left: the first block without the pruned
    keep = np.setdiff1d(np.arange(40), gone)
    assert lp.value == pytest.approx(scipy_value(c, lo, hi, M[keep], np.full(keep.size, -np.inf),
                                                 rhi[keep]), abs=1e-7)
