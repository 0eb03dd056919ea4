"""Running generator axes with the flexible axis: the co-simulation layer.

=======================  ================================================================
module                   what it holds
=======================  ================================================================
:mod:`.axis`             the :class:`~.axis.Axis` protocol, :class:`~.axis.MoveSamples`,
                         :class:`~.axis.PlantInput`, the step rule
                         (:func:`~.axis.samples_per_step`), stage starts
:mod:`.fmu_axis`         :class:`~.fmu_axis.FMUAxis`: the generator FMU through fmpy
:mod:`.fast_axis`        :class:`~.fast_axis.FastAxis`: its C core compiled, a move per call
:mod:`.master`           the one master loop (:func:`~.master.cosimulate`),
                         :class:`~.master.CoSimResult`, map-error re-runs
:mod:`.session`          :class:`~.session.Session`: a scenario's two axes on one engine
:mod:`.jerk_table`       :class:`~.jerk_table.JerkTable`: a reference replayed sample by
                         sample (profile ``table``)
=======================  ================================================================
"""
