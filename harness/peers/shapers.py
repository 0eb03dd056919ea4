"""Input shapers (ZV, ZVD, MZV, EI) convolved with an acceleration-limited profile.

The shapers themselves (amplitudes, times, residual ratio ``V(ω, ζ)``; the
formulas and their sources) are :mod:`harness.shaper_designs`, re-exported
here.  The shaped reference is ``q*(t) = sum_i A_i q(t - t_i)``
(Béarée 2014 §4.1, eq. 20-21).

The AL profile comes from the generator FMU (``profile = 1``); its
acceleration steps sit on whole samples.  Shaping is exact (continuous
delays, :meth:`~harness.peers.trajectory.PiecewiseJerk.weighted_sum`), or
with each delay rounded to the nearest sample (``quantize=True``), as a
controller running at ``Te`` would do it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..fmu import spec as fmu_spec
from ..fmu.runner import generate
from ..shaper_designs import SHAPERS, Shaper, ei, make_shaper, mzv, zv, zvd
from .context import PeerContext, PeerSpec
from .trajectory import PiecewiseJerk, SampledTrajectory, from_fmu

__all__ = ["SHAPERS", "Shaper", "al_profile", "base_motion", "build_shaped", "ei", "make_shaper",
           "mzv", "shape", "shaped_al", "zv", "zvd"]

def shape(motion: PiecewiseJerk, shaper: Shaper, *, Te: float | None = None,
          name: str | None = None) -> PiecewiseJerk:
    """Convolve a piecewise-jerk motion with a shaper (exactly).

    Parameters
    ----------
    motion : PiecewiseJerk
        Reference to shape (typically the AL profile).
    shaper : Shaper
    Te : float, optional
        When given, the impulse times are first rounded to multiples of ``Te``.
    name : str, optional
        Label; default ``"AL*<shaper>"``.
    """
    sh = shaper.quantized(Te) if Te else shaper
    out = PiecewiseJerk.weighted_sum([motion] * sh.A.size, sh.A, sh.t,
                                     name=name or f"AL*{shaper.name}")
    out.params = dict(motion.params)
    out.params.update({"shaper": shaper.name, "shaper_f": shaper.f, "shaper_zeta": shaper.zeta,
                       "shaper_A": sh.A.tolist(), "shaper_t": sh.t.tolist(),
                       "shaper_quantized_Te": Te})
    return out


def al_profile(params: Mapping[str, Any], *, fmu: Any = None, fmi_version: int = 2
               ) -> SampledTrajectory:
    """Generate the acceleration-limited profile with the FMU (``profile = 1``).

    Parameters
    ----------
    params : mapping
        FMU parameters (``distance``, ``v_max``, ``a_max``, ``d_max``, ``Te``, ...);
        ``profile`` is forced to 1.
    fmu, fmi_version
        Passed to :func:`harness.fmu.runner.generate`.
    """
    p = dict(params)
    p["profile"] = 1
    return from_fmu(generate(p, fmu=fmu, fmi_version=fmi_version), name="AL")


def shaped_al(params: Mapping[str, Any], shaper: Shaper, *, quantize: bool = False,
              fmu: Any = None, fmi_version: int = 2) -> SampledTrajectory:
    """AL profile from the FMU convolved with ``shaper``, sampled at the FMU's ``Te``.

    Parameters
    ----------
    params : mapping
        FMU parameters of the move.
    shaper : Shaper
    quantize : bool
        Round the impulse times to the sampling period (a controller's
        implementation) instead of shaping exactly.
    fmu, fmi_version
        Passed to :func:`harness.fmu.runner.generate`.

    Returns
    -------
    SampledTrajectory
        Named ``"AL*ZV"`` etc.; its ``exact`` motion is the exact convolution.
    """
    al = al_profile(params, fmu=fmu, fmi_version=fmi_version)
    Te = al.Te
    m = shape(al.to_motion(), shaper, Te=Te if quantize else None)
    return m.sample(Te, t0=float(al.t[0]))


def build_shaped(ctx: PeerContext, name: str) -> tuple[PiecewiseJerk, PeerSpec]:
    """Peers "AL*S" and "JL*S": the generator's AL or JL profile convolved with shaper S.

    S (ZV, ZVD, MZV, EI) is designed for the tuned mode at the end of the motion.
    """
    sh = make_shaper(name[3:], ctx.f_end, ctx.zeta)
    mot = shape(ctx.base(name[:2]), sh, name=name)
    jl_txt = f"JL T_F {ctx.T_F_JL * 1e3:.0f} ms; " if name[:2] == "JL" else ""
    return mot, PeerSpec(name, f"{jl_txt}{ctx.mode_text}; adds {sh.duration * 1e3:.0f} ms",
                         {"f": ctx.f_end, "zeta": ctx.zeta, "A": sh.A.tolist(),
                          "t": sh.t.tolist()})


def base_motion(sc: Any, profile: str, T_F: float | None = None, distance: float | None = None,
                *, session: Any = None, fmu: Any = None, fmi_version: int = 2) -> PiecewiseJerk:
    """Return the generator's AL or JL profile of the scenario's move, as an exact motion.

    Parameters
    ----------
    sc : harness.scenario.Scenario
    profile : {"AL", "JL"}
    T_F : float, optional
        JL jerk time (s), all four stages.
    distance : float, optional
        Signed distance (m); default the scenario's.
    session : harness.simulation.session.Session, optional
        Plan with its excited axis (FMU or fast engine); otherwise through
        :func:`harness.fmu.runner.generate` with ``fmu`` / ``fmi_version``.
    fmu, fmi_version
        Generator FMU when no session is given (default: the scenario's).

    Returns
    -------
    PiecewiseJerk
        Rebuilt exactly from the samples, then :meth:`~PiecewiseJerk.simplified`
        (one breakpoint per stage boundary).
    """
    m, s = sc.move, sc.simulation
    if profile not in ("AL", "JL"):
        raise ValueError(f"base profile must be AL or JL, got {profile!r}")
    params: dict[str, Any] = {
        "profile": fmu_spec.PROFILE_CODES[profile], "Te": s.Te, "t_start": m.t_start, "x0": m.x0,
        "distance": m.distance if distance is None else float(distance), "v_max": m.v_max,
        "a_max": m.a_max, "d_max": m.d_max, "short_stage": s.short_stage}
    if profile == "JL":
        if T_F is None:
            raise ValueError("JL needs its jerk time T_F")
        params.update({f"T_F{i}": float(T_F) for i in range(1, 5)})
    if session is not None:
        ms = session.axis.sample(params)
        mot = PiecewiseJerk.from_samples(ms.t, ms.x, ms.v, ms.a, ms.j, name=profile,
                                         params=params)
    else:
        tr = generate(params, fmu=s.fmu if fmu is None else fmu, fmi_version=fmi_version)
        mot = from_fmu(tr, name=profile).to_motion()  # type: ignore[assignment]
    return mot.simplified()
