"""A linear programme that grows and shrinks by rows, solved warm by HiGHS (``highspy``).

The designs of the harness (:mod:`harness.tuning.reference`) solve a sequence
of linear programmes that differ by a block of rows: the band from one more
sample, a bound the last solution broke.  :class:`IncrementalLP` keeps one
HiGHS model and its basis between them (the dual simplex restarts from it:
adding rows keeps the basis dual feasible), and drops blocks of rows again.

HiGHS prints a banner to the process's standard output when its first
instance is made; the first instance here is made with file descriptor 1
pointed at ``os.devnull``, so that a command's output stays its own.
"""

from __future__ import annotations

import os
import sys
import threading

import numpy as np

__all__ = ["IncrementalLP"]

_LOCK = threading.Lock()
_QUIET = False


def _highs():  # -> highspy.Highs
    """Return a new silent HiGHS instance (the banner of the first one swallowed)."""
    global _QUIET
    import highspy  # deferred: the solver is loaded by the designs that need it

    with _LOCK:
        if not _QUIET:
            sys.stdout.flush()
            try:
                fd = os.dup(1)
            except OSError:  # no standard output to protect
                fd = -1
            if fd >= 0:
                nul = os.open(os.devnull, os.O_WRONLY)
                os.dup2(nul, 1)
                try:
                    h = highspy.Highs()
                finally:
                    os.dup2(fd, 1)
                    os.close(fd)
                    os.close(nul)
            else:
                h = highspy.Highs()
            _QUIET = True
        else:
            h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("log_to_console", False)
    # a sequence of small, warm-started programmes: no presolve (it would discard the basis),
    # the dual simplex (rows added keep the basis dual feasible), one thread
    h.setOptionValue("presolve", "off")
    h.setOptionValue("solver", "simplex")
    h.setOptionValue("simplex_strategy", 1)
    h.setOptionValue("threads", 1)
    return h


class IncrementalLP:
    """``min c·x`` subject to rows ``lo ≤ M x ≤ hi`` added and removed in blocks.

    Parameters
    ----------
    lower, upper : array_like
        The variables' bounds (``±inf`` for none).
    cost : array_like
        The objective's coefficients.
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray, cost: np.ndarray) -> None:
        import highspy  # deferred: see _highs

        self._hs = highspy
        self.inf = float(highspy.kHighsInf)
        lo = np.where(np.isfinite(lower), lower, -self.inf).astype(float)
        up = np.where(np.isfinite(upper), upper, self.inf).astype(float)
        self.n = lo.size
        self.h = _highs()
        self.h.addVars(self.n, lo, up)
        self.h.changeColsCost(self.n, np.arange(self.n, dtype=np.int32),
                              np.asarray(cost, dtype=float))
        self.rows = 0
        self.x = np.zeros(self.n)
        self.value = np.inf
        self.iterations = 0
        self.solves = 0

    def add(self, M: np.ndarray, lower: np.ndarray | float, upper: np.ndarray | float
            ) -> tuple[int, int]:
        """Add dense rows ``lower ≤ M x ≤ upper``; return their index range ``(first, end)``."""
        M = np.atleast_2d(np.asarray(M, dtype=float))
        k = M.shape[0]
        if k == 0:
            return self.rows, self.rows
        lo = np.broadcast_to(np.asarray(lower, dtype=float), (k,))
        up = np.broadcast_to(np.asarray(upper, dtype=float), (k,))
        lo = np.where(np.isfinite(lo), lo, -self.inf)
        up = np.where(np.isfinite(up), up, self.inf)
        nz = M != 0.0
        counts = nz.sum(axis=1)
        starts = np.concatenate(([0], np.cumsum(counts)[:-1])).astype(np.int32)
        rr, cc = np.nonzero(nz)
        self.h.addRows(k, lo, up, int(rr.size), starts, cc.astype(np.int32), M[rr, cc])
        first = self.rows
        self.rows += k
        return first, self.rows

    def mark(self) -> tuple[int, object]:
        """Return the current rows and basis, to come back to (:meth:`restore`)."""
        return self.rows, self.h.getBasis()

    def restore(self, mark: tuple[int, object]) -> None:
        """Drop the rows added since :meth:`mark` and take its basis back (a warm restart)."""
        rows, basis = mark
        self.drop_from(rows)
        if getattr(basis, "valid", False):
            self.h.setBasis(basis)

    def drop_from(self, first: int) -> None:
        """Remove every row from index ``first`` on (the blocks added last)."""
        if first < self.rows:
            idx = np.arange(first, self.rows, dtype=np.int32)
            self.h.deleteRows(int(idx.size), idx)
            self.rows = first

    def solve(self) -> bool:
        """Solve from the current basis; return True if optimal (``x``, ``value`` set)."""
        st = self._hs.HighsModelStatus
        for fresh in (False, True):
            if fresh:  # numerical trouble from the warm basis: once more from scratch
                self.h.clearSolver()
            self.h.run()
            self.solves += 1
            info = self.h.getInfo()
            self.iterations += int(info.simplex_iteration_count)
            status = self.h.getModelStatus()
            if status in (st.kOptimal, st.kInfeasible, st.kUnboundedOrInfeasible,
                          st.kUnbounded):
                break
        if status != st.kOptimal:
            return False
        self.x = np.asarray(self.h.getSolution().col_value, dtype=float)
        self.value = float(info.objective_function_value)
        return True


class DualIncrementalLP:
    """:class:`IncrementalLP` solved through its dual: few variables, many rows, warm.

    The primal ``min c·z`` over rows ``lo ≤ a·z ≤ hi`` and bounds is written as
    ``min c·z  s.t.  G z ≥ g`` (each finite side of a row or bound one row of G),
    whose dual ``max g·y  s.t.  Gᵀ y = c, y ≥ 0`` has one column per row of G and
    as many rows as the primal has variables.  Adding primal rows adds dual
    columns: the last basis stays feasible and HiGHS's primal simplex goes on
    from it, its basis as small as the primal's variables are few.  The primal
    solution is the dual's row duals; an unbounded dual is an infeasible primal.

    Parameters
    ----------
    lower, upper, cost : array_like
        As for :class:`IncrementalLP`.
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray, cost: np.ndarray) -> None:
        import highspy  # deferred: see _highs

        self._hs = highspy
        self.inf = float(highspy.kHighsInf)
        self.n = int(np.size(cost))
        self.c = np.asarray(cost, dtype=float)
        self.h = _highs()
        self.h.setOptionValue("simplex_strategy", 4)  # primal: columns added keep it feasible
        self.h.changeObjectiveSense(highspy.ObjSense.kMaximize)
        self.h.addRows(self.n, self.c, self.c, 0, np.zeros(self.n, dtype=np.int32),
                       np.zeros(0, dtype=np.int32), np.zeros(0))
        self.rows = 0          # primal rows added (bounds excluded)
        self._blocks: list[tuple[int, int]] = []  # (first row, dual columns) of each add
        eye = np.eye(self.n)
        self._add(eye, np.asarray(lower, float), np.asarray(upper, float))
        self.bound_cols = self.h.getNumCol()
        self.x = np.zeros(self.n)
        self.value = np.inf
        self.iterations = 0
        self.solves = 0

    def _add(self, M: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> int:
        """Add the dual columns of rows ``lo ≤ M z ≤ hi``; return how many."""
        cols, costs = [], []
        for sgn, side in ((1.0, lo), (-1.0, hi)):
            fin = np.isfinite(side)
            if fin.any():
                cols.append(sgn * M[fin])
                costs.append(sgn * side[fin])
        if not cols:
            return 0
        Gt = np.vstack(cols)  # one dual column per row
        g = np.concatenate(costs)
        k = Gt.shape[0]
        nz = Gt != 0.0
        starts = np.concatenate(([0], np.cumsum(nz.sum(axis=1))[:-1])).astype(np.int32)
        rr, cc = np.nonzero(nz)
        self.h.addCols(k, g, np.zeros(k), np.full(k, self.inf), int(rr.size), starts,
                       cc.astype(np.int32), Gt[rr, cc])
        return k

    def add(self, M: np.ndarray, lower: np.ndarray | float, upper: np.ndarray | float
            ) -> tuple[int, int]:
        """Add dense rows ``lower ≤ M z ≤ upper``; return their index range."""
        M = np.atleast_2d(np.asarray(M, dtype=float))
        k = M.shape[0]
        lo = np.broadcast_to(np.asarray(lower, dtype=float), (k,)).copy()
        hi = np.broadcast_to(np.asarray(upper, dtype=float), (k,)).copy()
        lo[lo <= -self.inf] = -np.inf
        hi[hi >= self.inf] = np.inf
        first = self.rows
        self._blocks.append((first, self._add(M, lo, hi)))
        self.rows += k
        return first, self.rows

    def mark(self) -> tuple[int, object]:
        """Return the current rows and basis, to come back to (:meth:`restore`)."""
        return self.rows, self.h.getBasis()

    def restore(self, mark: tuple[int, object]) -> None:
        """Drop the rows added since :meth:`mark` and take its basis back (a warm restart)."""
        rows, basis = mark
        self.drop_from(rows)
        if getattr(basis, "valid", False):
            self.h.setBasis(basis)

    def drop_from(self, first: int) -> None:
        """Remove every primal row from index ``first`` on (a block boundary)."""
        if first >= self.rows:
            return
        starts = [b[0] for b in self._blocks]
        if first not in starts:
            raise ValueError(f"drop_from({first}): not the start of a block of rows "
                             f"(blocks start at {starts})")
        k = 0
        while self._blocks and self._blocks[-1][0] >= first:
            k += self._blocks.pop()[1]
        total = self.h.getNumCol()
        if k:
            idx = np.arange(total - k, total, dtype=np.int32)
            self.h.deleteCols(int(idx.size), idx)
        self.rows = first

    def solve(self) -> bool:
        """Solve from the current basis; return True if the primal is optimal."""
        st = self._hs.HighsModelStatus
        for fresh in (False, True):
            if fresh:
                self.h.clearSolver()
            self.h.run()
            self.solves += 1
            info = self.h.getInfo()
            self.iterations += int(info.simplex_iteration_count)
            status = self.h.getModelStatus()
            if status in (st.kOptimal, st.kInfeasible, st.kUnboundedOrInfeasible,
                          st.kUnbounded):
                break
        if status != st.kOptimal:
            return False
        self.x = np.asarray(self.h.getSolution().row_dual, dtype=float)
        self.value = float(info.objective_function_value)
        return True
