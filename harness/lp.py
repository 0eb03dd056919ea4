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
