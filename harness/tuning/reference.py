"""A sampled reference designed by linear programming: every JL ramp shaped by its own filter.

JL is four ramps of constant jerk (each a filtered acceleration step of the AL
profile).  A shaper convolves all four with the same impulses; here each ramp
g gets its own finite impulse response A_g over the delays 0..D samples::

    j(k) = Σ_g Σ_d A_g[d] · j_g(k − d)

(the *dissociated* idea of the DJL profile, taken to every sample).  The
plant being linear, the load error at every sample and the free oscillation
after the motion are linear in the amplitudes (the final states of each ramp
delayed by d, by the plant's adjoint and one FFT correlation per ramp; the
error near the end by taking them back through the inputs that follow each
sample, as :class:`harness.tuning.shaping.ShapedObjective` does for one
base).  The design is a sequence of linear programmes (:class:`harness.lp.IncrementalLP`,
HiGHS, warm): the earliest sample m from which the error stays within the band
at every point of the set, m going down, with

* each ramp's filter summing to 1 (the acceleration levels of JL), the
  velocity and the position landing at the motion's end (equalities);
* the jerk within JL's largest, the acceleration within [−d_max, a_max], the
  velocity within [0, v_max] (mirrored for a negative move), on every sample,
  added where a solution breaks them;
* margins (the error within ``target`` of the band, the residual oscillation
  within ``residual`` of it) that keep the design between the set's points;
* optionally, graceful deadlines (each point of a wider set keeps the error in
  the band from its own instant on) and quiet unmodelled modes, as the LP
  shapers of :mod:`harness.tuning.shaping` have them.

The Z axis may still move after the motion (a short move while Z travels far):
the window then runs until Z rests, the plant free but time-varying in between;
and the design may settle after the motion (wide uncertainty, low damping): the
window runs ``after`` seconds past that.

The result is a jerk per sample (:class:`ReferenceDesign`), corrected to land
exactly; the generator FMU replays it (profile ``table``), and the harness
replays it exactly (:class:`harness.peers.trajectory.PiecewiseJerk`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..compiled import engine as _compiled_engine
from ..fmu import spec
from ..lp import DualIncrementalLP, IncrementalLP
from ..plant import hermite_mid, transitions
from ..scenario import Scenario
from ..simulation.session import Session
from ..uncertainty import Perturbation

__all__ = ["TABLE_PIECES", "RampObjective", "ReferenceDesign", "design_reference", "kinematics",
           "pieces", "quiet_bound", "sparse_support"]

_POLYGON = 16
"""Sides of the polygon inside which a residual's phasor is kept (an inner approximation)."""

LIMIT_MARGIN = 1e-7
"""The designs keep the acceleration and velocity limits this much (relative) inside."""

TABLE_PIECES = spec.MAX_TABLE
"""Most pieces of constant jerk a design may have: what the generator FMU's table holds."""


def pieces(jerk: np.ndarray) -> int:
    """Return the pieces of constant jerk of a per-sample jerk (runs of equal samples)."""
    j = np.asarray(jerk, dtype=float)
    return int(np.count_nonzero(np.diff(j) != 0.0)) + 1 if j.size else 0


def kinematics(jerk: np.ndarray, Te: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return x − x0, v, a at the samples 0..n of a per-sample jerk from rest (exact cubics)."""
    j = np.asarray(jerk, dtype=float)
    a = np.concatenate(([0.0], np.cumsum(j * Te)))
    v = np.concatenate(([0.0], np.cumsum(Te * a[:-1] + 0.5 * Te**2 * j)))
    x = np.concatenate(([0.0], np.cumsum(Te * v[:-1] + 0.5 * Te**2 * a[:-1] + Te**3 / 6.0 * j)))
    return x, v, a


@dataclass
class _Span:
    """What the programmes need for one span D (every ramp delayed by 0..D samples)."""

    D: int
    delays: np.ndarray  # the delays computed (0..D): the arrays' last axis
    k_end: int      # the motion's end (absolute sample)
    k_hi: int       # the window's last sample (the plant free from there on)
    k_w: int        # the window's first sample
    T: float        # the motion time (s)
    C: np.ndarray   # (R, 2, G, nd): each row's state at k_hi, each delay of ``delays``
    C_end: np.ndarray  # (R, 2, G, nd): each row's state at the motion's end (k_end)
    sig: np.ndarray  # (R,) decay rate at rest
    wd: np.ndarray  # (R,) damped angular frequency at rest
    sig_end: np.ndarray  # (R,) the same at the motion's end (Z may still move)
    wd_end: np.ndarray
    E: np.ndarray   # (P, G, nd, W+1): the load error at samples k_w..k_hi
    v: np.ndarray   # (k_end+1, G, nd): velocity, acceleration, jerk, position of each
    a: np.ndarray   #   ramp delayed by d, at the samples 0..k_end
    j: np.ndarray
    x: np.ndarray


class RampObjective:
    """The error of every JL ramp delayed by every d ≤ D, at every point of a set.

    Parameters
    ----------
    sc : Scenario
        A single-move scenario.
    session : Session
        Plans on its fast engine.
    T_F : sequence of float
        JL's jerk times.
    points : sequence of Perturbation
        The uncertainty set.
    band : float
        The settling band (m).
    piece : float
        Each run of constant jerk is cut into pieces of at most this many jerk
        times, each with its own filter (1: JL's four ramps; less: more freedom).
    window : bool
        Compute the load error near the end and after the motion (False: only
        the states when the motion ends, ``C_end``, e.g. for modes kept quiet).
    """

    def __init__(self, sc: Scenario, session: Session, T_F: tuple[float, ...],
                 points: tuple[Perturbation, ...], band: float, piece: float = 1.0,
                 window: bool = True) -> None:
        if not band > 0:
            raise ValueError(f"band must be > 0 m, got {band!r}")
        self.sc, self.s, self.points, self.band = sc, session.fast(), tuple(points), band
        self.Te = self.h = sc.simulation.Te
        if abs(sc.simulation.step - self.Te) > 1e-12 * self.Te:
            raise ValueError("the reference design needs the communication step equal to Te")
        self.window = bool(window)
        self.T_F = tuple(float(t) for t in T_F)
        params = self.s.move_params(sc, "JL", self.T_F)
        self.T_base = self.s.axis.plan(params)
        self.k0 = int(round(self.s.axis.motion_start() / self.Te))
        n = int(round(self.T_base / self.Te))
        S = self.s.axis.samples(0, 1, self.k0 + n + 1)
        j = np.asarray(S[3, self.k0:self.k0 + n], dtype=float).copy()
        self.n_base = n
        self.j_max = float(np.max(np.abs(j)))
        nz = np.abs(j) > 1e-12 * self.j_max
        edges = np.flatnonzero(np.diff(np.r_[0, nz.astype(np.int8), 0]))
        # each run of constant jerk cut into pieces of at most ``piece`` jerk times
        n_F = max(1, int(round(self.T_F[0] / self.Te * piece)))
        self.ramps: list[np.ndarray] = []
        for lo, hi in zip(edges[::2], edges[1::2], strict=True):
            k = int(math.ceil((hi - lo) / n_F - 1e-9))
            cuts = np.linspace(lo, hi, k + 1).round().astype(int)
            for a, b in zip(cuts[:-1], cuts[1:], strict=True):
                jg = np.zeros(n)
                jg[a:b] = j[a:b]
                self.ramps.append(jg)
        self.G = len(self.ramps)
        self.modes = sc.modemap.scheduled()
        self.pivot = sc.z.z0 + 0.5 * sc.z.distance
        tm = sc.modemap.tuned
        f_end = float(tm.f(sc.z.z0 + sc.z.distance))
        self.period = 1.0 / (f_end * math.sqrt(1.0 - tm.zeta ** 2))
        self._spans: dict[tuple[int, int], _Span] = {}

    @property
    def nm(self) -> int:
        """Modes per point."""
        return len(self.modes)

    def span(self, D: int, after: float = 0.0, stride: int = 1) -> _Span:
        """Return the span D's states, window and kinematics (cached).

        Parameters
        ----------
        D : int
            The longest delay (samples): the motion is D samples longer than JL.
        after : float
            Seconds the window runs past the instant the plant is free (the
            motion ended, Z at rest) and its tail.
        stride : int
            Only the delays 0, stride, 2·stride, … and D are computed
            (:attr:`_Span.delays`); the arrays' last axis runs over them.
        """
        key = (int(D), int(round(after / self.h)), int(stride))
        got = self._spans.get(key)
        if got is not None:
            return got
        sc, s, h, D = self.sc, self.s, self.h, int(D)
        dly = np.unique(np.r_[np.arange(0, D + 1, max(1, int(stride))), D]).astype(int)
        nd = dly.size
        T = (self.n_base + D) * self.Te  # the table's length, as the replay computes it
        v_z, _ = s.z_velocity(sc, T)
        T_z = s.z_axis.plan(s.z_move_params(sc, v_z))
        k_end = self.k0 + self.n_base + D
        k_z = int(math.ceil((s.z_axis.motion_start() + T_z) / h - 1e-9)) if sc.z.moves else 0
        k_free = max(k_end, k_z)
        # half a damped period of the slowest row, and the decay of a sample's phase (as the
        # bound's horizon): within it, some sample is near every crest
        P, nm = len(self.points), self.nm
        Z = s.z_axis.samples(0, 1, k_free + 2)
        z, vz = Z[0, :k_free + 1], Z[1, :k_free + 1]
        z_rest = np.array([z[k_free]])
        f_rest, zeta, gain = [], [], []
        for p in self.points:
            for m in self.modes:
                f_rest.append(float(p.frequencies(m.f_array, z_rest, self.pivot)[0]))
                zeta.append(p.zeta(m.zeta))
                gain.append(m.gain)
        za = np.array(zeta)
        w = 2.0 * np.pi * np.array(f_rest)
        sig, wd = za * w, w * np.sqrt(1.0 - za * za)
        z_e = np.array([z[k_end]])
        w_e = 2.0 * np.pi * np.array([float(p.frequencies(m.f_array, z_e, self.pivot)[0])
                                      for p in self.points for m in self.modes])
        sig_end, wd_end = za * w_e, w_e * np.sqrt(1.0 - za * za)
        with np.errstate(divide="ignore"):
            tau = np.where(sig > 0, -np.log(np.cos(0.5 * wd * h)) / np.where(sig > 0, sig, 1.0),
                           0.0)
        tail = int(math.ceil(float(np.max(math.pi / wd + tau)) / h)) + 2
        k_hi = k_free + tail + int(round(after / h))
        zm = hermite_mid(z[:-1], vz[:-1], z[1:], vz[1:], h)
        zm = np.concatenate((zm, np.full(k_hi - k_free, z[k_free])))
        F = np.vstack([p.frequencies(m.f_array, zm, self.pivot) for p in self.points
                       for m in self.modes])  # (R, k_hi)
        R = F.shape[0]
        psi = np.empty((R, k_end, 2, 2))
        _compiled_engine().adjoint_modes(h, np.ascontiguousarray(F[:, :k_end]), za,
                                         np.array(gain), k_end, psi)
        G, n = self.G, self.n_base
        # each ramp's input (a, j), position and velocity on the absolute grid, undelayed
        U = np.zeros((G, 2, k_end))
        A = np.zeros((G, k_end + 1))
        X = np.zeros((G, k_end + 1))
        V = np.zeros((G, k_end + 1))
        J = np.zeros((G, k_end + 1))
        for g, jg in enumerate(self.ramps):
            full = np.zeros(k_end - self.k0)
            full[:n] = jg
            x, v, a = kinematics(full, self.Te)
            U[g, 0, self.k0:] = a[:-1]
            U[g, 1, self.k0:] = full
            A[g, self.k0:] = a
            X[g, self.k0:] = x
            V[g, self.k0:] = v
            J[g, self.k0:k_end] = full
        # the states at k_end: C[r, s, g, d] = Σ_k ψ[r, k, s, :] · U[g, :, k − d] (FFT)
        L = 1 << int(math.ceil(math.log2(k_end + D + 1)))
        Pa = np.fft.rfft(psi[:, :, :, 0].transpose(0, 2, 1), L)
        Pj = np.fft.rfft(psi[:, :, :, 1].transpose(0, 2, 1), L)
        C_end = np.empty((R, 2, G, nd))
        for g in range(G):
            corr = np.fft.irfft(Pa * np.conj(np.fft.rfft(U[g, 0], L))
                                + Pj * np.conj(np.fft.rfft(U[g, 1], L)), L)
            C_end[:, :, g, :] = corr[:, :, dly]
        kidx = np.arange(k_end + 1)[:, None] - dly[None, :] + D

        def delayed(M: np.ndarray) -> np.ndarray:
            return np.stack([np.concatenate([np.zeros(D), M[g]])[kidx] for g in range(G)],
                            axis=1)

        if not self.window:  # the states when the motion ends, nothing else
            sp = _Span(D, dly, k_end, k_end, k_end, T, C_end, C_end, sig, wd, sig_end, wd_end,
                       np.zeros((P, G, nd, 0)), delayed(V), delayed(A), delayed(J),
                       delayed(X))
            self._spans[key] = sp
            return sp
        # the window before the end: the final states taken back through the inputs after k
        lead = max(1, int(math.ceil(self.period / h)))
        k_w = max(self.k0, k_end - D - lead)
        W = k_end - k_w
        phi = transitions(2.0 * np.pi * F[:, k_w:k_end], za[:, None], h)  # (R, W, 2, 2)
        det = phi[..., 0, 0] * phi[..., 1, 1] - phi[..., 0, 1] * phi[..., 1, 0]
        inv = np.empty_like(phi)
        inv[..., 0, 0], inv[..., 1, 1] = phi[..., 1, 1] / det, phi[..., 0, 0] / det
        inv[..., 0, 1], inv[..., 1, 0] = -phi[..., 0, 1] / det, -phi[..., 1, 0] / det
        back = np.empty((W + 1, R, 2, 2))
        back[W] = np.eye(2)
        for i in range(W - 1, -1, -1):
            back[i] = np.matmul(inv[:, i], back[i + 1])
        idx = np.arange(k_w, k_end + 1)[None, :] - dly[:, None] + D  # (nd, W+1)
        ps = psi[:, k_w:k_end].transpose(1, 0, 2, 3).reshape(W, 2 * R, 2)
        n_after = k_hi - k_end
        E = np.empty((P, G, nd, W + 1 + n_after))
        off = self.sc.move.x0 - self.sc.move.target
        # after the end: free, time-varying while Z moves (the reference at rest at target)
        phi_a = transitions(2.0 * np.pi * F[:, k_end:k_hi], za[:, None], h)  # (R, n_after,...)
        C = np.empty_like(C_end)
        for g in range(G):
            ug = np.concatenate([np.zeros((2, D)), U[g]], axis=1)
            Ud = np.stack([ug[0][idx[:, :-1]], ug[1][idx[:, :-1]]], axis=1)  # (nd, 2, W)
            contrib = np.matmul(ps, Ud.transpose(2, 1, 0)).reshape(W, R, 2, nd)
            part = np.zeros((W + 1, R, 2, nd))
            part[:W] = np.cumsum(contrib[::-1], axis=0)[::-1]
            eps = np.matmul(back, C_end[None, :, :, g, :] - part)[:, :, 0, :]  # (W+1, R, nd)
            xg = np.concatenate([np.zeros(D), X[g]])[idx]  # (nd, W+1)
            if g == 0:
                xg = xg + off
            E[:, g, :, :W + 1] = (eps.reshape(W + 1, P, nm, nd).sum(axis=2).transpose(1, 2, 0)
                                  + xg[None])
            st = C_end[:, :, g, :]  # (R, 2, nd)
            for i in range(n_after):
                st = np.matmul(phi_a[:, i], st)
                E[:, g, :, W + 1 + i] = st[:, 0, :].reshape(P, nm, nd).sum(axis=1)
            C[:, :, g, :] = st
        sp = _Span(D, dly, k_end, k_hi, k_w, T, C, C_end, sig, wd, sig_end, wd_end, E,
                   delayed(V), delayed(A), delayed(J), delayed(X))
        if len(self._spans) >= 6:
            self._spans.pop(next(iter(self._spans)))
        self._spans[key] = sp
        return sp


@dataclass
class ReferenceDesign:
    """A reference designed by :func:`design_reference`.

    Attributes
    ----------
    jerk : ndarray
        The jerk on each sample from the motion's start (m/s³), landing exactly.
    amplitudes : ndarray
        Shape (G, D + 1): each ramp's filter.
    D : int
        The span (samples).
    settle_sample : int
        The LP's settling sample (absolute).
    t_lp : float
        The LP's largest error over the band from there on (≤ ``target``).
    motion_time : float
        ``len(jerk) · Te`` (s).
    lp_solves, lp_iterations : int
        The programmes solved, and their simplex iterations.
    seconds : float
        Time of the design.
    notes : list of str
        What it ran into.
    """

    jerk: np.ndarray
    amplitudes: np.ndarray
    D: int
    settle_sample: int
    t_lp: float
    motion_time: float
    lp_solves: int
    lp_iterations: int
    seconds: float
    notes: list[str] = field(default_factory=list)


def _land(jerk: np.ndarray, Te: float, distance: float, j_max: float) -> np.ndarray:
    """Return the jerk corrected to land exactly, its pieces of constant jerk kept.

    The programme meets the end conditions to its tolerance; the three residuals
    (a_N, v_N, x_N − distance) are removed by the least change of the pieces'
    jerks (each piece one value, the pieces at the jerk limit left alone), so
    that the table keeps its pieces.
    """
    N = jerk.size
    k = np.arange(N)
    M = np.vstack((np.full(N, Te), Te**2 * (N - k - 0.5),
                   Te**3 * ((N - k - 1) ** 2 / 2.0 + (N - k - 1) / 2.0 + 1.0 / 6.0)))
    x, v, a = kinematics(jerk, Te)
    r = np.array([a[-1], v[-1], x[-1] - distance])
    starts = np.flatnonzero(np.r_[True, np.diff(jerk) != 0.0])
    run_of = np.cumsum(np.r_[True, np.diff(jerk) != 0.0]) - 1  # each sample's piece
    Mr = np.zeros((3, starts.size))
    np.add.at(Mr.T, run_of, M.T)  # the effect of a piece's jerk
    free = (np.abs(jerk[starts]) < j_max * (1.0 - 1e-6)) & (jerk[starts] != 0.0)
    if free.sum() < 3:
        free = np.abs(jerk[starts]) < j_max * (1.0 - 1e-6)
    if free.sum() < 3:
        return jerk
    Mf = Mr[:, free]
    delta = np.zeros(starts.size)
    delta[free] = -Mf.T @ np.linalg.solve(Mf @ Mf.T, r)
    return jerk + delta[run_of]

def design_reference(obj: RampObjective, D: int, *, target: float = 0.95,
                     residual: float = 0.95, minimax: np.ndarray | None = None,
                     deadlines: np.ndarray | None = None,
                     quiet: tuple[RampObjective, np.ndarray] | None = None,
                     after: float = 0.0, step: int = 4, stride: int = 1,
                     support: np.ndarray | list[np.ndarray] | None = None,
                     dual: bool = True, per_round: int = 48,
                     max_solves: int | None = None) -> ReferenceDesign | None:
    """Design the reference of span D that settles first at the ``minimax`` points.

    Parameters
    ----------
    obj : RampObjective
        The ramps, the set.
    D : int
        The span (samples).
    target : float
        The error is kept within this fraction of the band (a margin between points).
    residual : float
        The free oscillation at the window's end within this fraction of the band.
    minimax : ndarray of bool, optional
        The points whose settling is minimised (default every point).
    deadlines : ndarray, optional
        Per point, the instant (s from the motion's start) from which its error
        must stay in the band (``inf``: none).
    quiet : (RampObjective, ndarray), optional
        Modes to keep quiet: an objective of the same move whose points and
        modes are them, and the most each (point, mode) row's residual may be
        when the motion ends (m; :func:`quiet_bound`).
    after : float
        Seconds the window runs past the plant's becoming free (a design may
        settle that late).
    step : int
        Samples m goes down by at first.
    stride : int
        The delays computed: 0, stride, 2·stride, … and D (:meth:`RampObjective.span`).
    support : ndarray of int, or list of them, optional
        The delays (among those) each piece's filter may use (one array for
        every piece, or one per piece); default every one computed.
    per_round : int
        Most rows of one kind added per round (the rows a solution breaks).
    max_solves : int, optional
        Programmes the search for the earliest sample may solve: past them, the
        earliest feasible sample found so far is kept (and a note says so).  A count,
        not a time: the design is the same on any machine.
    dual : bool
        Solve the programmes through their duals (:class:`harness.lp.DualIncrementalLP`:
        few variables, many rows); False: as they are.

    Returns
    -------
    ReferenceDesign or None
        None if no design of this span settles within the window at every point.
    """
    t0 = time.perf_counter()
    sp = obj.span(D, after, stride)
    G, P, nm = obj.G, len(obj.points), obj.nm
    pos = {int(d): i for i, d in enumerate(sp.delays)}
    if support is None:
        sups = [sp.delays] * G
    elif not isinstance(support, list):
        sups = [np.unique(np.r_[0, np.asarray(support, int)])] * G
    else:
        if len(support) != G:
            raise ValueError(f"support must be one array of delays, or one per piece ({G}), "
                             f"got {len(support)}")
        sups = [np.unique(np.r_[0, np.asarray(x, int)]) for x in support]
    for x in sups:
        if any(int(d) not in pos for d in x):
            raise ValueError(f"support must hold delays among {sp.delays.tolist()} (0..{D} "
                             f"every {stride}), got {support!r}")
    idx = [np.array([pos[int(d)] for d in x]) for x in sups]  # their places in the span
    # the variables are each filter's tail sums S_i = Σ_{d ≥ s_i} A[d] at the support's
    # delays s_1 < … < s_K (S_0 = 1: each filter sums to 1, JL's acceleration levels): a
    # quantity Q of the design is Q(s_0) + Σ_i S_i (Q(s_i) − Q(s_{i−1})).  The columns are
    # then the effect of delaying a ramp a little more (bounded), not of a whole ramp (whose
    # position grows without bound: the programme would be ill-conditioned)
    ns = [x.size - 1 for x in sups]
    n = int(sum(ns))
    col0 = np.r_[0, np.cumsum(ns)].astype(int)  # each piece's first column

    def on(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(..., G, D+1) -> the constant (...,) and the columns (..., n)."""
        c = sum(M[..., g, 0] for g in range(G))
        cols = [np.diff(M[..., g, idx[g]], axis=-1) for g in range(G)]
        return c, np.concatenate(cols, axis=-1)

    mm = np.ones(P, bool) if minimax is None else np.asarray(minimax, bool)
    dl = np.full(P, math.inf) if deadlines is None else np.asarray(deadlines, float)
    band = obj.band
    mv = obj.sc.move
    # S_1 in [0, 2] and |S_i − S_{i+1}| <= 1 (each amplitude within [−1, 1]), S_K within [−1, 1]
    lo_s = np.full(n, -float(D + 1))
    hi_s = np.full(n, float(D + 1))
    lp = (DualIncrementalLP if dual else IncrementalLP)(np.r_[lo_s, 0.0], np.r_[hi_s, np.inf],
                                                        np.r_[np.zeros(n), 1.0])
    if n:
        amp_rows = np.zeros((n + G, n))
        amp_lo = np.zeros(n + G)
        r = 0
        for g in range(G):
            for i in range(ns[g] + 1):  # A_i = S_i − S_{i+1} (S_0 = 1, S_{ns+1} = 0)
                if i >= 1:
                    amp_rows[r, col0[g] + i - 1] = 1.0
                if i < ns[g]:
                    amp_rows[r, col0[g] + i] = -1.0
                amp_lo[r] = 1.0 if i == 0 else 0.0
                r += 1
        lp.add(np.hstack([amp_rows, np.zeros((amp_rows.shape[0], 1))]), -1.0 - amp_lo,
               1.0 - amp_lo)
    k_end, W0 = sp.k_end, sp.k_w
    sgn = 1.0 if mv.distance >= 0 else -1.0
    c_v, M_v = on(sp.v[k_end])  # at rest at the target at the motion's end
    lp.add(np.r_[M_v / mv.v_max, 0.0], -c_v / mv.v_max, -c_v / mv.v_max)
    c_x, M_x = on(sp.x[k_end])
    lp.add(np.r_[M_x / abs(mv.distance), 0.0], (mv.distance - c_x) / abs(mv.distance),
           (mv.distance - c_x) / abs(mv.distance))
    # every other constraint is a family of rows ``lo ≤ M x − tau t ≤ hi``, added lazily:
    # only the rows the current solution breaks (the active set is small)
    cos_p = math.cos(math.pi / _POLYGON)
    c_C, M_C = on(sp.C)  # (R, 2), (R, 2, n)
    fams: list[tuple[np.ndarray, float, np.ndarray, np.ndarray]] = []

    def family(c: np.ndarray, M: np.ndarray, tau: float, lo: np.ndarray | float,
               hi: np.ndarray | float) -> None:
        """Add the rows ``lo ≤ c + M x − tau t ≤ hi`` (c, M: one entry, one row per row)."""
        M = M.reshape(-1, n)
        k = M.shape[0]
        c = np.broadcast_to(np.asarray(c, float).ravel(), (k,)) if np.ndim(c) else np.full(k, c)
        fams.append((M, tau, np.broadcast_to(np.asarray(lo, float), (k,)) - c,
                     np.broadcast_to(np.asarray(hi, float), (k,)) - c))

    def polygon(c: np.ndarray, M: np.ndarray, sig: np.ndarray, wd: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
        """Return the residual phasor's projections: constants (R, poly), columns (R, poly, n)."""
        th = 2.0 * np.pi * np.arange(_POLYGON) / _POLYGON
        c0, c1 = c[:, 0], (c[:, 1] + sig * c[:, 0]) / wd
        M0, M1 = M[:, 0], (M[:, 1] + sig[:, None] * M[:, 0]) / wd[:, None]
        pc = np.cos(th)[None] * c0[:, None] + np.sin(th)[None] * c1[:, None]
        pm = np.cos(th)[None, :, None] * M0[:, None] + np.sin(th)[None, :, None] * M1[:, None]
        return pc, pm

    pc, pm = polygon(c_C, M_C, sp.sig, sp.wd)
    pc, pm = pc.reshape(P, nm, _POLYGON), pm.reshape(P, nm, _POLYGON, n)
    k_res = nm * target / (residual * band * cos_p)
    family(pc[mm] * k_res, pm[mm] * k_res, 1.0, -np.inf, 0.0)
    c_d = c_C[:, 0].reshape(P, nm).sum(axis=1)[mm] / band  # the deflection at k_hi
    M_d = M_C[:, 0].reshape(P, nm, n).sum(axis=1)[mm] / band
    family(np.r_[c_d, -c_d], np.vstack([M_d, -M_d]), 1.0, -np.inf, 0.0)
    if quiet is not None:
        qobj, bound = quiet
        qs = qobj.span(D, after, stride)  # their residual when the motion ends
        qc, qm = polygon(*on(qs.C_end), qs.sig_end, qs.wd_end)
        k_q = 1.0 / (bound[:, None] * cos_p)
        family(qc * k_q, qm * k_q[:, :, None], 0.0, -np.inf, 1.0)
    sig_p = sp.sig.reshape(P, nm).min(axis=1)
    t_hi = sp.k_hi * obj.h - mv.t_start
    c_E, M_E = on(sp.E.transpose(0, 3, 1, 2))  # (P, W), (P, W, n)
    for p in np.flatnonzero(np.isfinite(dl)):
        grow = math.exp(float(sig_p[p]) * max(0.0, float(dl[p]) - t_hi))
        k_g = nm / (residual * band * cos_p * grow)
        family(pc[p] * k_g, pm[p] * k_g, 0.0, -np.inf, 1.0)
        k_p = int(math.ceil((float(dl[p]) + mv.t_start) / obj.h - 1e-9))
        if k_p <= sp.k_hi:
            i0 = max(k_p, W0) - W0
            family(c_E[p, i0:] / (band * target), M_E[p, i0:] / (band * target), 0.0, -1.0, 1.0)
    # the limits, a little inside (the solver meets its rows to its tolerances; the
    # generator replays a table within its limits to 1e-10); the velocity is kept at the
    # samples, and between two it can exceed both by j_max Te^2 / 8 (a turning inside)
    k_in = 1.0 - LIMIT_MARGIN
    lo_a, hi_a = (-mv.d_max * k_in, mv.a_max * k_in) if sgn > 0 else (-mv.a_max * k_in,
                                                                        mv.d_max * k_in)
    v_in = mv.v_max * k_in - obj.j_max * obj.Te ** 2 / 8.0
    lo_v, hi_v = (0.0, v_in) if sgn > 0 else (-v_in, 0.0)
    for Q, low, high in ((sp.j, -obj.j_max, obj.j_max), (sp.a, lo_a, hi_a), (sp.v, lo_v, hi_v)):
        scale = max(abs(low), abs(high))
        c_q, M_q = on(Q)
        family(c_q / scale, M_q / scale, 0.0, low / scale, high / scale)
    n_fixed = len(fams)
    # the band from sample m on, at the minimax points: |E x| / band <= t
    c_W, M_W = c_E[mm] / band, M_E[mm] / band  # (P_mm, W), (P_mm, W, n)
    n_mm = int(mm.sum())
    kept: set[tuple[int, int]] = set()
    row_key: dict[int, tuple[int, int]] = {}  # each lazy row's key, by its index in the LP
    lazy0 = lp.rows  # the rows from here on are lazy (pruned when slack, added again if broken)

    def prune() -> None:
        """Drop the lazy rows the last solution leaves slack (cheaper solves; exact)."""
        for r in lp.prune(lazy0).tolist():
            kept.discard(row_key.pop(r))

    def solve(m: int) -> bool:
        """Solve with the band from sample m on, adding the rows the solution breaks."""
        fams[n_fixed:] = []
        cw, win = c_W[:, m - W0:].ravel(), M_W[:, m - W0:].reshape(-1, n)
        family(np.r_[cw, -cw], np.vstack([win, -win]), 1.0, -np.inf, 0.0)
        n_win = win.shape[0]
        while True:
            if not lp.solve():
                return False
            x, t = lp.x[:n], lp.x[n]
            if t > target:  # rows only add: t is already a lower bound past the target
                return True
            # every broken row of every family, then the worst of them (relative to their
            # scale) -- the most per family, and the most overall -- added at once
            found: list[tuple[float, int, int, tuple[int, int]]] = []
            for f, (M, tau, lo, hi) in enumerate(fams):
                val = M @ x - tau * t
                over = np.maximum(val - hi, lo - val)
                scale = np.maximum(1.0, np.maximum(np.abs(np.where(np.isfinite(lo), lo, 0.0)),
                                                   np.abs(np.where(np.isfinite(hi), hi, 0.0))))
                rel = over / scale
                bad = np.flatnonzero(rel > 1e-9)
                if not bad.size:
                    continue
                bad = bad[np.argsort(-rel[bad])]
                picked = 0
                for i in bad.tolist():
                    if f < n_fixed:
                        key = (f, i)
                    else:  # a window row: its sign, point and absolute sample
                        w_len = n_win // n_mm
                        key = (n_fixed + (i >= n_win), (i % n_win // w_len) * 1_000_000
                               + m + i % n_win % w_len)
                    if key in kept:
                        continue
                    found.append((float(rel[i]), f, i, key))
                    picked += 1
                    if picked >= per_round:
                        break
            found.sort(key=lambda r: -r[0])
            found = found[:4 * per_round]
            added = bool(found)
            for f in sorted({r[1] for r in found}):
                M, tau, lo, hi = fams[f]
                idx = np.array([r[2] for r in found if r[1] == f])
                keys = [r[3] for r in found if r[1] == f]
                kept.update(keys)
                r0, _ = lp.add(np.hstack([M[idx], np.full((idx.size, 1), -tau)]), lo[idx],
                               hi[idx])
                row_key.update(zip(range(r0, r0 + len(keys)), keys, strict=True))
            if not added:
                return True

    if not solve(sp.k_hi + 1) or lp.x[n] > target:
        return None
    prune()
    notes: list[str] = []
    best = (sp.k_hi + 1, lp.x[:n].copy(), float(lp.x[n]))
    # the earliest feasible m: its error ratio t(m) grows as m goes down; the next m is where
    # the secant of ln t through the two nearest probes crosses ln target (a bisection when
    # it stalls), starting from JL's own end; the rows of an infeasible m are dropped (its
    # basis too), those of a feasible one kept
    ts: dict[int, float] = {sp.k_hi + 1: max(float(lp.x[n]), 1e-12)}
    good, below = sp.k_hi + 1, sp.k_w
    guess = min(max(obj.k0 + obj.n_base, sp.k_w + 1), good - 1)
    lt = math.log(target)
    while good - below > 1:
        if max_solves is not None and lp.solves >= max_solves:
            notes.append(f"stopped after {lp.solves} programmes: the settling sample is "
                         f"within [{below + 1}, {good}]")
            break
        m = guess if guess is not None else (good + below) // 2
        guess = None
        first, snap = lp.mark(), set(kept)
        if solve(m) and lp.x[n] <= target:
            good, best = m, (m, lp.x[:n].copy(), float(lp.x[n]))  # type: ignore[assignment]
            ts[m] = max(float(lp.x[n]), 1e-12)
            prune()
        else:
            ts[m] = float(lp.x[n]) if lp.solves and lp.x[n] > target else math.inf
            lp.restore(first)
            kept.clear()
            kept.update(snap)
            for r in [r for r in row_key if r >= first[0]]:
                del row_key[r]
            below = m
        # the secant of ln t through the probes nearest the crossing
        near = sorted((k for k in ts if math.isfinite(ts[k])), key=lambda k: abs(
            math.log(ts[k]) - lt))[:2]
        if len(near) == 2 and near[0] != near[1]:
            (m1, m2) = near
            l1, l2 = math.log(ts[m1]), math.log(ts[m2])
            if l1 != l2:
                est = m1 + (lt - l1) * (m2 - m1) / (l2 - l1)
                if below < est < good:
                    cand = int(math.floor(est)) if below < math.floor(est) else below + 1
                    guess = min(max(cand, below + 1), good - 1)
                    if guess in ts:
                        guess = None
    if best is None:
        return None
    m, S, t = best
    amps = np.zeros((G, D + 1))
    for g in range(G):
        tails = np.r_[1.0, S[col0[g]:col0[g + 1]], 0.0]
        amps[g, sups[g]] = tails[:-1] - tails[1:]
    jerk = np.zeros(obj.n_base + D)
    for g in range(G):
        for d in np.flatnonzero(np.abs(amps[g]) > 1e-12):
            jerk[d:d + obj.n_base] += amps[g, d] * obj.ramps[g]
    jerk = sgn * _land(sgn * jerk, obj.Te, abs(mv.distance), obj.j_max)
    return ReferenceDesign(jerk, amps, D, m, t, jerk.size * obj.Te, lp.solves, lp.iterations,
                           time.perf_counter() - t0, notes)


def quiet_bound(qobj: RampObjective, floor: float) -> np.ndarray:
    """Return each row's bound for modes kept quiet: JL's own residual, or ``floor`` bands.

    ``qobj`` is a :class:`RampObjective` whose modes are the ones to keep quiet
    (:meth:`harness.tuning.graceful.UnmodelledModes.scenario`); JL is every
    ramp undelayed (span 0).
    """
    sp = qobj.span(0)
    C = sp.C_end[:, :, :, 0].sum(axis=2)  # (R, 2): JL's state when it ends
    amp = np.hypot(C[:, 0], (C[:, 1] + sp.sig_end * C[:, 0]) / sp.wd_end)
    return np.maximum(amp, floor * qobj.band)


def sparse_support(design: ReferenceDesign, budget: int) -> list[np.ndarray]:
    """Return each piece's largest amplitudes' delays, ``budget`` of them in all.

    A design whose table has too many pieces (each amplitude starts and ends
    one) is designed again on these delays alone.
    """
    A = np.abs(design.amplitudes)
    G = A.shape[0]
    order = np.argsort(-A, axis=None)
    keep: list[set[int]] = [{0} for _ in range(G)]
    for f in order[:max(budget, G)]:
        g, d = divmod(int(f), A.shape[1])
        if A[g, d] > 1e-12:
            keep[g].add(d)
    return [np.array(sorted(k)) for k in keep]
