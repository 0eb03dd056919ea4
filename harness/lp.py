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
        self._ids = np.zeros(0, dtype=np.int64)  # each model row's index (rows pruned leave gaps)
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
        self._ids = np.r_[self._ids, np.arange(first, self.rows)]
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
            idx = np.flatnonzero(self._ids >= first).astype(np.int32)
            if idx.size:
                self.h.deleteRows(int(idx.size), idx)
            self._ids = self._ids[self._ids < first]
            self.rows = first

    def prune(self, since: int = 0) -> np.ndarray:
        """Remove the rows (index ``since`` on) the last solution leaves slack; return them.

        A row whose slack is basic holds no weight in the optimum: removing it
        keeps the optimum and the basis, and makes the next solves cheaper.
        Rows keep their indices (:meth:`drop_from` still works); a row removed
        may be added again.  Prune only after a solve, and not between a
        :meth:`mark` and its :meth:`restore`.
        """
        basis = self.h.getBasis()
        if not getattr(basis, "valid", False) or not self._ids.size:
            return np.zeros(0, dtype=np.int64)
        basic = self._hs.HighsBasisStatus.kBasic
        slack = np.fromiter((st == basic for st in basis.row_status), bool,
                            count=self._ids.size)
        gone = np.flatnonzero(slack & (self._ids >= since))
        if gone.size:
            self.h.deleteRows(int(gone.size), gone.astype(np.int32))
        ids = self._ids[gone]
        self._ids = np.delete(self._ids, gone)
        return ids

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
        self._starts: list[int] = []  # the first row of each block added
        self._owner = np.zeros(0, dtype=np.int64)  # each dual column's primal row
        eye = np.eye(self.n)
        self._add(eye, np.asarray(lower, float), np.asarray(upper, float))
        self.bound_cols = self.h.getNumCol()
        self.x = np.zeros(self.n)
        self.value = np.inf
        self.iterations = 0
        self.solves = 0

    def _add(self, M: np.ndarray, lo: np.ndarray, hi: np.ndarray, first: int = -1) -> int:
        """Add the dual columns of rows ``lo ≤ M z ≤ hi`` (rows ``first``…); return how many."""
        cols, costs, rows = [], [], []
        for sgn, side in ((1.0, lo), (-1.0, hi)):
            fin = np.isfinite(side)
            if fin.any():
                cols.append(sgn * M[fin])
                costs.append(sgn * side[fin])
                rows.append(first + np.flatnonzero(fin))
        if not cols:
            return 0
        if first >= 0:
            self._owner = np.r_[self._owner, np.concatenate(rows)]
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
        self._add(M, lo, hi, first)
        self._starts.append(first)
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
        if first not in self._starts:
            raise ValueError(f"drop_from({first}): not the start of a block of rows "
                             f"(blocks start at {self._starts})")
        self._starts = [b for b in self._starts if b < first]
        gone = np.flatnonzero(self._owner >= first)
        if gone.size:
            idx = (self.bound_cols + gone).astype(np.int32)
            self.h.deleteCols(int(idx.size), idx)
        self._owner = self._owner[self._owner < first]
        self.rows = first

    def prune(self, since: int = 0) -> np.ndarray:
        """Remove the rows (index ``since`` on) the last solution leaves slack; return them.

        A row none of whose dual columns is basic holds no weight in the optimum
        (its multipliers are zero): removing it keeps the optimum and the basis,
        and makes the next solves cheaper (the dual simplex prices every
        column).  Rows keep their indices (:meth:`drop_from` still works); a row
        removed may be added again.  Prune only after a solve, and not between
        a :meth:`mark` and its :meth:`restore`.
        """
        basis = self.h.getBasis()
        if not getattr(basis, "valid", False) or not self._owner.size:
            return np.zeros(0, dtype=np.int64)
        basic_st = self._hs.HighsBasisStatus.kBasic
        status = list(basis.col_status)[self.bound_cols:]
        basic = np.fromiter((st == basic_st for st in status), bool, count=self._owner.size)
        binding = np.unique(self._owner[basic])
        gone = np.flatnonzero((self._owner >= since) & ~np.isin(self._owner, binding))
        if gone.size:
            idx = (self.bound_cols + gone).astype(np.int32)
            self.h.deleteCols(int(idx.size), idx)
        rows = np.unique(self._owner[gone])
        self._owner = np.delete(self._owner, gone)
        return rows

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
