"""Jerk times for JL and DJL: the paper's rule, the searches and tables of moves.

=======================  ================================================================
module                   what it holds
=======================  ================================================================
:mod:`.rule`             the paper's rule: JL to the end of the motion, DJL stage by stage
:mod:`.search`           ``optimal`` and ``robust``: pattern search on the time-varying model
:mod:`.tune`             :func:`~.tune.tune_profile`: a scenario's profile, by its method
:mod:`.tables`           a table of tuned moves (``djl-fmu tune``), as a CSV the FMU loads
:mod:`.remainder`        why the paper's rule leaves a remainder (closed forms)
=======================  ================================================================

The methods' names, :class:`~harness.tuning_options.TuningOptions` and the one
``--tuning`` grammar sit below, in :mod:`harness.tuning_options` (no
simulation: the scenario files read them).  The package imports none of its
modules: import the one you need (``from harness.tuning.tune import tune_profile``).
"""
