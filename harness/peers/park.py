"""Time-optimal jerk-limited rest-to-rest motion (Park, Lee, Oh & Moon 2017).

Park et al. (IJFIS 17(4), 2017, §3) plan a rest-to-rest move of length ``P``
under ``|v| <= V``, ``|a| <= A`` (``A = D``) and ``|j| <= J`` as seven
constant-jerk phases ``T_1 .. T_7`` with ``T_1 = T_3 = T_5 = T_7``,
``T_2 = T_6`` (point symmetry), jerks ``+J, 0, -J, 0, -J, 0, +J``, and three
cases:

* Case I   (v and a reach V and A): ``T_1 = A/J``, ``T_2 = V/A - A/J``,
  ``T_4 = P/V - (2 T_1 + T_2)``  (§3.1).
* Case II  (a reaches A, v does not): ``T_1 = A/J``, ``T_4 = 0``,
  ``T_2 = (-3 T_1 + sqrt(T_1² + 4 P / A)) / 2``  (§3.2, eq. 12).
* Case III (neither): ``T_2 = T_4 = 0``, ``T_1 = (P / (2 J))^(1/3)``  (§3.3).

Equations re-derived here because the text (as extracted) is wrong or garbled
-- see ``docs/peers.md``:

* §3: ``X_3 = T_5 + T_6 + T_6`` should read ``T_5 + T_6 + T_7``.
* Eq. (10): ``v_p = A (1/2 T_1 + T_2 + 1/2 T_3) = A (2 T_1 + T_2)``; the last
  member is wrong, ``v_p = A (T_1 + T_2)``.  Eq. (12) is the root of
  ``P = A (T_1 + T_2)(2 T_1 + T_2)``, i.e. it was derived from the correct
  ``v_p``; the printed numbers (and ruckig) agree with it.
* Case III: the paper writes ``P = 2 α² A T_1²`` and ends with a fourth root,
  ``T_1 = (P A / (2 J²))^(1/4)`` in the only dimensionally consistent reading
  of the extracted text.  With ``v_p = α A T_1`` (its own eq.) and
  ``X_1 = 2 T_1``, ``P = v_p X_1 = 2 α A T_1²`` (no square on α), and with
  ``α A = J T_1``, ``P = 2 J T_1³``: ``T_1 = (P / (2 J))^(1/3)``.  For the
  paper's Case III (P = 2000°) the printed form gives T_1 = 0.58857 s, a
  profile that travels 2038.9° instead of 2000°; the derived form gives
  T_1 = 0.58480 s, 2000° exactly, and ruckig's duration 4 T_1 = 2.33921 s.
  :func:`case3_T1_as_printed` keeps the printed form for that comparison.

Case selection is not spelled out in the paper; from the same closed forms:
Case III when ``P <= 2 A³ / J²`` (the triangle of acceleration does not reach
A) and ``J T_1² <= V``; Case I when ``V >= A²/J`` and ``P >= V (V/A + A/J)``;
Case II otherwise.  The paper dismisses the case where v reaches V but a does
not reach A ("does not make sure the time-optimality"); it does happen, and
is time-optimal, when ``V < A² / J`` (the velocity limit is hit while the
acceleration is still ramping).  It is implemented here as Case IV
(``T_1 = sqrt(V/J)``, ``T_2 = 0``, ``T_4 = P/V - 2 T_1``), outside the paper.

Works in any consistent unit (the paper's example is in degrees).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .trajectory import PiecewiseJerk

#: The limits of the paper's simulation (§4): J (°/s³), A = D (°/s²), V (°/s).
PAPER_LIMITS = {"J": 5000.0, "A": 3000.0, "V": 6000.0}
#: The paper's three moves (°): Case I, II, III.
PAPER_MOVES = {"I": 20000.0, "II": 6000.0, "III": 2000.0}

_JERK_SIGNS = (1.0, 0.0, -1.0, 0.0, -1.0, 0.0, 1.0)


@dataclass(frozen=True)
class ParkProfile:
    """A time-optimal rest-to-rest jerk-limited profile.

    Attributes
    ----------
    case : {"I", "II", "III", "IV"}
        Which limits are reached (IV: V but not A, outside the paper).
    P, V, A, J : float
        Signed distance and the limits.
    T : tuple of 7 float
        Phase durations T_1 .. T_7 (s).
    v_peak, a_peak : float
        Largest speed and acceleration reached (magnitudes).
    """

    case: str
    P: float
    V: float
    A: float
    J: float
    T: tuple[float, float, float, float, float, float, float]
    v_peak: float
    a_peak: float
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def total_time(self) -> float:
        """Motion time ``sum(T)`` (s)."""
        return float(sum(self.T))

    @property
    def switch_times(self) -> np.ndarray:
        """Cumulative phase ends t_1 .. t_7 (s)."""
        return np.cumsum(self.T)

    @property
    def jerks(self) -> tuple[float, ...]:
        """Jerk of each phase."""
        s = math.copysign(1.0, self.P)
        return tuple(s * c * self.J for c in _JERK_SIGNS)

    def motion(self, t0: float = 0.0, x0: float = 0.0, name: str = "time-optimal JL") \
            -> PiecewiseJerk:
        """Return the exact profile (jerk piecewise constant) from ``x0`` at ``t0``."""
        params = {"P": self.P, "V": self.V, "A": self.A, "J": self.J, "case": self.case}
        return PiecewiseJerk.from_jerk(self.T, self.jerks, t0=t0, x0=x0, name=name,
                                       params=params)

    def plot(self, title: str | None = None):
        """Position, velocity, acceleration and jerk; return the Figure."""
        return self.motion().plot(title=title or (
            f"Park et al. Case {self.case}: P = {self.P:g}, T = {self.total_time:.6g} s"))


def select_case(P: float, V: float, A: float, J: float) -> str:
    """Which limits a time-optimal rest-to-rest move of length ``|P|`` reaches.

    Returns
    -------
    {"I", "II", "III", "IV"}
        I: V and A; II: A only; III: neither; IV: V only (``V < A²/J``).
    """
    _check_limits(V, A, J)
    P = abs(P)
    T1 = (P / (2.0 * J)) ** (1.0 / 3.0)
    if J * T1 <= A and J * T1 * T1 <= V:
        return "III"
    if V >= A * A / J:
        return "I" if P >= V * (V / A + A / J) else "II"
    return "IV"


def _check_limits(V: float, A: float, J: float) -> None:
    for name, val in (("V", V), ("A", A), ("J", J)):
        if not (math.isfinite(val) and val > 0.0):
            raise ValueError(f"{name} must be positive and finite, got {val!r}")


def park_profile(P: float, V: float, A: float, J: float) -> ParkProfile:
    """Time-optimal rest-to-rest jerk-limited profile (Park et al. 2017, §3).

    Parameters
    ----------
    P : float
        Signed distance (m, rad, or the paper's degrees).
    V, A, J : float
        Speed, acceleration (= deceleration) and jerk limits (same unit per s, s², s³).

    Returns
    -------
    ParkProfile

    Examples
    --------
    >>> round(park_profile(20000, 6000, 3000, 5000).total_time, 6)
    5.933333
    """
    case = select_case(P, V, A, J)
    D = abs(P)
    if case == "I":
        T1 = A / J
        T2 = V / A - A / J
        X1 = 2.0 * T1 + T2
        T4 = (D - V * X1) / V
    elif case == "II":
        T1 = A / J
        T2 = (-3.0 * T1 + math.sqrt(T1 * T1 + 4.0 * D / A)) / 2.0
        T4 = 0.0
    elif case == "III":
        T1 = (D / (2.0 * J)) ** (1.0 / 3.0)
        T2 = T4 = 0.0
    else:  # IV: V reached while the acceleration still ramps (V < A²/J)
        T1 = math.sqrt(V / J)
        T2 = 0.0
        T4 = D / V - 2.0 * T1
    T2 = max(T2, 0.0)
    T4 = max(T4, 0.0)
    a_peak = J * T1
    v_peak = a_peak * (T1 + T2)
    T = (T1, T2, T1, T4, T1, T2, T1)
    return ParkProfile(case, float(P), V, A, J, T, v_peak, a_peak,
                       {"P": P, "V": V, "A": A, "J": J})


def case3_T1_as_printed(P: float, A: float, J: float) -> float:
    """Case III jerk time as printed in the paper (wrong, kept for the record).

    ``(P A / (2 J²))^(1/4)``, which follows from the misprinted
    ``P = 2 α² A T_1²``; see the module docstring.
    """
    return (abs(P) * A / (2.0 * J * J)) ** 0.25


def distance_of(T: tuple[float, ...] | list[float], J: float) -> float:
    """Distance travelled by the seven phases ``T`` with jerks ``+J, 0, -J, 0, -J, 0, +J``.

    Computed by integrating the phases (an independent check of a closed form).
    """
    m = PiecewiseJerk.from_jerk(list(T), [c * J for c in _JERK_SIGNS])
    return float(m.x[-1] - m.x[0])


def canonical_phases(durations: list[float] | np.ndarray, jerks: list[float] | np.ndarray,
                     tol: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
    """Drop empty phases and merge neighbours of equal jerk.

    Two descriptions of the same profile (Park's seven phases, ruckig's seven
    phases, which merge ``T_3`` and ``T_5`` when ``T_4 = 0``) become comparable.

    Returns
    -------
    durations, jerks : ndarray
    """
    d = np.asarray(durations, dtype=float)
    jr = np.asarray(jerks, dtype=float)
    scale = max(float(np.sum(d)), 1e-300)
    out_d: list[float] = []
    out_j: list[float] = []
    for h, jj in zip(d, jr, strict=True):
        if h <= tol * scale:
            continue
        if out_j and math.isclose(out_j[-1], jj, rel_tol=1e-12, abs_tol=1e-300):
            out_d[-1] += h
        else:
            out_d.append(float(h))
            out_j.append(float(jj))
    return np.array(out_d), np.array(out_j)
