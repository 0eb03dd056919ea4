"""Independent checks of generated motions (shared by the generator tests).

Nothing here calls the planner: the checks work on the FMU's sampled outputs
and on the definitions of the paper (stage = jerk time, jerk = a/T_F, JL =
moving average of the AL profile).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.fmu.runner import Trajectory


def total_distance(p: dict) -> float:
    n = int(p["n_segments"])
    if n == 0:
        return float(p["distance"])
    return float(np.sum(np.asarray(p["seg_distance"])[:n]))


def end_velocity(p: dict) -> float:
    n = int(p["n_segments"])
    return float(p["v_e"]) if n == 0 else float(np.asarray(p["seg_v_end"])[n - 1])


def motion_start(tr: Trajectory) -> float:
    """First generator sample (FMU start time + k Te) at or after t_start."""
    p = tr.params
    t0, Te = tr.t[0], p["Te"]
    k = (p["t_start"] - t0) / Te
    k = round(k) if abs(k - round(k)) <= 1e-9 * (1 + abs(k)) else np.ceil(k)
    return t0 + k * Te


def check_end_and_limits(tr: Trajectory, *, rel_x: float = 1e-9) -> int:
    """The invariants of issue #2 that hold for every profile; returns the done index."""
    p = tr.params
    D = total_distance(p)
    ve = end_velocity(p)
    vmax, amax, dmax = p["v_max"], p["a_max"], p["d_max"]
    assert tr.done.any(), "motion never done"
    k = int(np.argmax(tr.done))
    assert tr.done[k:].all(), "done must stay true"
    assert not tr.done[:k].any()
    # done at t_start + motion_time: the first communication point at or after it
    step = tr.t[1] - tr.t[0]
    t_done = motion_start(tr) + tr.motion_time
    assert t_done - 1e-9 <= tr.t[k] < t_done + step - 1e-9, (tr.t[k], t_done)
    # end state
    scale = max(abs(D), p["v_max"] * p["Te"])
    x_done = tr.x[k] - ve * (tr.t[k] - t_done)  # the sample may come after the end
    assert abs(x_done - (p["x0"] + D)) <= rel_x * scale + 4e-16 * abs(p["x0"]), (
        x_done, p["x0"] + D)
    assert abs(tr.v[k] - ve) <= 1e-12 * max(vmax, 1.0), (tr.v[k], ve)
    assert abs(tr.a[k]) <= 1e-12 * max(amax, dmax, 1.0), tr.a[k]
    # after the end: constant velocity, no jerk
    assert np.all(tr.j[k:] == 0.0) and np.all(tr.a[k:] == 0.0)
    np.testing.assert_allclose(tr.x[k:], tr.x[k] + ve * (tr.t[k:] - tr.t[k]), rtol=0,
                               atol=1e-9 * max(abs(D), 1.0) + 1e-12 * abs(p["x0"]))
    # limits, sign-adjusted for the direction of the move
    tol = 1 + 1e-12
    assert np.all(np.abs(tr.v) <= vmax * tol), np.abs(tr.v).max() / vmax
    if p["n_segments"] == 0 or all(np.sign(d) >= 0 for d in p["seg_distance"][: p["n_segments"]]) \
            or all(np.sign(d) <= 0 for d in p["seg_distance"][: p["n_segments"]]):
        sg = -1.0 if D < 0 else 1.0
        aa = sg * tr.a
        assert aa.max() <= amax * tol, (aa.max(), amax)
        assert (-aa).max() <= dmax * tol, ((-aa).max(), dmax)
    else:
        assert np.abs(tr.a).max() <= max(amax, dmax) * tol
    for arr in (tr.x, tr.v, tr.a, tr.j, tr.x_AL, tr.v_AL, tr.a_AL):
        assert np.all(np.isfinite(arr))
    return k


@dataclass
class Run:
    """A maximal run of constant non-zero jerk."""

    start: int
    length: int
    jerk: float


def jerk_runs(j: np.ndarray, rtol: float = 1e-9) -> list[Run]:
    """Maximal runs of (numerically) equal non-zero jerk."""
    runs: list[Run] = []
    k, n = 0, len(j)
    scale = np.abs(j).max() if n else 0.0
    while k < n:
        if abs(j[k]) <= 1e-12 * scale:
            k += 1
            continue
        s = k
        while k + 1 < n and abs(j[k + 1] - j[s]) <= rtol * abs(j[s]):
            k += 1
        runs.append(Run(s, k - s + 1, float(j[s])))
        k += 1
    return runs


def check_four_stages(tr: Trajectory, N: tuple[int, int, int, int]) -> None:
    """Rest-to-rest single move, stretch rule: the four constant-jerk stages.

    Stage 1 raises the acceleration from 0 to its level A in exactly N1
    samples with jerk A/T_F1; stage 2 brings it back to 0 in N2 samples with
    jerk -A/T_F2; stage 3 takes it to -D in N3 samples (jerk -D/T_F3); stage 4
    back to 0 in N4 samples (jerk D/T_F4).  (Signs for a positive move.)
    """
    p = tr.params
    Te = p["Te"]
    sg = -1.0 if total_distance(p) < 0 else 1.0
    a, j = sg * tr.a, sg * tr.j
    k0 = int(np.searchsorted(tr.t, motion_start(tr) - 1e-9))
    kend = int(np.argmax(tr.done))
    A, D = a.max(), -a.min()
    N1, N2, N3, N4 = N
    tol = 1e-9
    # stage 1
    assert np.allclose(j[k0:k0 + N1], A / (N1 * Te), rtol=tol, atol=0), "stage 1 jerk"
    assert abs(a[k0 + N1] - A) <= tol * A, "stage 1 reaches A after N1 samples"
    assert abs(j[k0 + N1] - A / (N1 * Te)) > tol * A / (N1 * Te), "stage 1 lasts N1 samples"
    # stage 4 ends the motion
    assert np.allclose(j[kend - N4:kend], D / (N4 * Te), rtol=tol, atol=0), "stage 4 jerk"
    assert abs(a[kend - N4] + D) <= tol * D, "stage 4 starts at -D"
    assert abs(j[kend - N4 - 1] - D / (N4 * Te)) > tol * D / (N4 * Te), "stage 4 lasts N4"
    # stage 2: the first return of a to 0 after the plateau at A
    after = np.nonzero(np.abs(a[k0 + N1:]) <= 1e-12 * A)[0]
    k2e = k0 + N1 + int(after[0])
    assert np.allclose(j[k2e - N2:k2e], -A / (N2 * Te), rtol=tol, atol=0), "stage 2 jerk"
    assert abs(a[k2e - N2] - A) <= tol * A, "stage 2 starts at A"
    # stage 3: the last sample at a = 0 before the negative plateau
    neg = np.nonzero(a[:kend - N4 + 1] < -tol * D)[0]
    k3s = int(neg[0]) - 1
    assert np.allclose(j[k3s:k3s + N3], -D / (N3 * Te), rtol=tol, atol=0), "stage 3 jerk"
    assert abs(a[k3s + N3] + D) <= tol * D, "stage 3 reaches -D after N3 samples"
    assert k3s >= k2e, "stages 2 and 3 do not overlap"


def moving_average_check(tr: Trajectory, N: int) -> tuple[float, float, float]:
    """Max errors of (a, v, x) of ``tr`` against the N-sample moving average of its AL input.

    Exact identities for a piecewise-constant AL acceleration filtered by a
    continuous moving average of N samples: acceleration = mean of the last N
    interval values (eq. 8, one sample later); velocity and position = means of
    the AL velocity / position over the last N intervals (trapezoid and
    Simpson rules are exact on those polynomial pieces).  Requires dt = Te and
    the AL profile resting before the start (v0 history).
    """
    p = tr.params
    Te, v0, x0 = p["Te"], p["v0"], p["x0"]
    k0 = int(np.searchsorted(tr.t, motion_start(tr) - 1e-9))
    a_al, v_al, x_al = tr.a_AL[k0:], tr.v_AL[k0:], tr.x_AL[k0:]
    pad = N
    A = np.concatenate([np.zeros(pad), a_al])
    V = np.concatenate([np.full(pad, v0), v_al])
    X = np.concatenate([x0 + v0 * Te * np.arange(-pad, 0), x_al])
    Ia = A[:-1]
    Iv = (V[:-1] + V[1:]) / 2
    Ix = (X[:-1] + X[1:]) / 2 - A[:-1] * Te**2 / 12
    ca, cv, cx = (np.concatenate([[0.0], np.cumsum(z)]) for z in (Ia, Iv, Ix))
    idx = np.arange(pad, pad + len(a_al))
    a_ma = (ca[idx] - ca[idx - N]) / N
    v_ma = (cv[idx] - cv[idx - N]) / N
    x_ma = (cx[idx] - cx[idx - N]) / N + v0 * N * Te / 2
    return (float(np.abs(a_ma - tr.a[k0:]).max()), float(np.abs(v_ma - tr.v[k0:]).max()),
            float(np.abs(x_ma - tr.x[k0:]).max()))
