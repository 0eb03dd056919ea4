"""Access to the compiled engine, :mod:`harness._engine`, imported when first used.

The extension is built by ``pip install`` (setup.py) from ``harness/_engine.c`` and the
FMU's generator core ``fmu_src/djl_*.c``.  A source checkout does not contain it, so
``python -m harness.cli ...`` run from the checkout's root (whose ``harness/`` shadows the
installed package) must still load every module: commands that need no engine (``build``,
``--help``) then work, and the ones that do fail with :class:`EngineMissingError`, which
says why and what to do, instead of an ``ImportError`` deep in an import chain.
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

from .errors import HarnessError

__all__ = ["EngineMissingError", "engine"]


class EngineMissingError(HarnessError, ImportError):
    """The compiled engine ``harness._engine`` cannot be imported."""


def engine() -> ModuleType:
    """Return the compiled engine module, importing it on first use.

    Returns
    -------
    module
        :mod:`harness._engine`.

    Raises
    ------
    EngineMissingError
        When the extension is not importable, e.g. from a source checkout whose
        ``harness/`` shadows the installed package.
    """
    try:
        from . import _engine  # deferred: absent from a source checkout
    except ImportError as e:
        where = Path(__file__).resolve().parent
        raise EngineMissingError(
            f"the compiled engine harness._engine is not importable from {where} ({e}); "
            "a source checkout does not contain it: after `pip install .`, run the "
            "installed `djl-fmu` command, or Python from outside the checkout") from None
    return _engine
