"""The harness's errors: one base, :class:`HarnessError`.

Every error the harness raises on purpose derives from :class:`HarnessError`,
so a script can catch them all with one ``except``; each also keeps the
built-in base its callers already catch (``ValueError`` for bad input,
``RuntimeError`` for a failure while running).  Where each is raised:

==========================  ==============  ============================================
error                       built-in base   raised by
==========================  ==============  ============================================
``ScenarioError``           ValueError      :mod:`harness.scenario` (file, key, value)
``PartProgramError``        ValueError      :mod:`harness.part_program` (every bad line)
``FMUError``                RuntimeError    :mod:`harness.fmu.runner` (an FMI call)
``BuildError``              RuntimeError    :mod:`harness.fmu.build` (compiler, sources)
``PlanError``               ValueError      :mod:`harness.simulation.fast_axis`
``ExecutorError``           ValueError      :mod:`harness.executors` (workers, cluster)
``BatchError``              RuntimeError    a map or a table of moves did not complete
``MoveError``               RuntimeError    one move of such a batch (names the move)
``CommandError``            --              :mod:`harness.commands` (exit status)
``RuckigMissingError``      ImportError     :mod:`harness.peers.ruckig_ref`
``EngineMissingError``      ImportError     :mod:`harness.compiled` (engine not built)
``DeprecatedAliasWarning``  FutureWarning   :mod:`harness.scenario` (a warning)
==========================  ==============  ============================================

The names that the earlier modules used for the batch errors stay available:
``WorkspaceMapError`` / ``MapError`` (:mod:`harness.workspace`) and
``TuneError`` (:mod:`harness.tuning.tables`) are :class:`BatchError` subclasses.
"""

from __future__ import annotations

__all__ = ["BatchError", "BuildError", "CommandError", "DeprecatedAliasWarning", "HarnessError",
           "MoveError"]


class HarnessError(Exception):
    """Base of every error the harness raises on purpose."""


class BatchError(HarnessError, RuntimeError):
    """A batch of moves (a workspace map, a table of jerk times) did not complete.

    A move failed, or a worker died; the message names the move when one did.
    """


class MoveError(BatchError):
    """One move of a batch failed (raised in the worker; the message names the move)."""


class BuildError(HarnessError, RuntimeError):
    """The FMU cannot be built: the compiler failed, or the sources are incomplete."""


class CommandError(HarnessError):
    """A command stops: ``status`` is its exit status, the message says why.

    Parameters
    ----------
    status : int
        Exit status of the command (1 a failure, 2 bad arguments).
    message : str
        What went wrong, for the user.
    """

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


class DeprecatedAliasWarning(HarnessError, FutureWarning):  # noqa: N818 - a warning
    """A deprecated spelling of a setting was used: its value was read as the new key's.

    ``[compare] map_error`` / ``damping`` of a scenario (:mod:`harness.scenario`) are
    read as ``[uncertainty] map_scale`` / ``damping``
    (:func:`harness.uncertainty.resolve_alias`); the message says what to write
    instead.  A warning (shown once per place by Python's default filter); the
    commands print each as one line on stderr (``djl-fmu: note: ...``).  It derives
    from :class:`HarnessError` too: with warnings turned into errors, one ``except``
    still catches everything the harness raises.
    """
