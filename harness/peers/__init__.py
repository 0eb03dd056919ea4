"""The methods a user would otherwise pick, on the same footing as AL / JL / DJL.

One module per method, all producing :class:`~harness.peers.trajectory.Motion`
objects (exact) that sample into :class:`~harness.peers.trajectory.SampledTrajectory`
(the FMU's :class:`~harness.fmu.runner.Trajectory` semantics):

* :mod:`~harness.peers.park` -- time-optimal jerk-limited rest-to-rest motion
  (Park et al. 2017, Cases I-III, plus the case IV the paper leaves out);
* :mod:`~harness.peers.ruckig_ref` -- the same from the ``ruckig`` package
  (optional dependency, imported lazily);
* :mod:`~harness.peers.sato` -- four jerk times under a fixed positioning time
  (Sato & Shirase 2021, Conditions I-III, Table 1, Fig. 8 and Fig. 10);
* :mod:`~harness.peers.shapers` -- ZV, ZVD, MZV, EI input shapers convolved with
  the FMU's AL (or JL) profile;
* :mod:`~harness.peers.tv_shaper` -- a time-varying ZV shaper whose impulses
  follow the mode along the Z move (after Chang & Park 2005);
* :mod:`~harness.peers.damped_jerk` -- the damped-jerk law (Béarée 2014 §4.2);
* :mod:`~harness.peers.residual` -- exact residual vibration on a second-order
  mode, and robustness curves;
* :mod:`~harness.peers.timeopt` -- FIR-built JL / DJL against the time-optimal
  motion;
* :mod:`~harness.peers.compare` -- every method through the harness's plant and
  metrics on a scenario (``djl-fmu compare``).

``docs/peers.md`` has the derivations and the numbers checked against the papers.
"""

from .trajectory import Motion, PiecewiseJerk, SampledTrajectory, from_fmu

__all__ = ["Motion", "PiecewiseJerk", "SampledTrajectory", "from_fmu"]
