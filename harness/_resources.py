"""Locate the C sources and model descriptions shipped with the package."""

from __future__ import annotations

from pathlib import Path

_PKG = Path(__file__).resolve().parent


def _first_existing(*candidates: Path) -> Path:
    for c in candidates:
        if c.is_dir():
            return c
    raise FileNotFoundError(
        "cannot find the FMU sources; looked in: " + ", ".join(str(c) for c in candidates)
    )


def fmu_src_dir() -> Path:
    """Directory holding the generator's C sources (``fmu_src/``)."""
    return _first_existing(_PKG / "_data" / "fmu_src", _PKG.parent / "fmu_src")


def modeldesc_dir() -> Path:
    """Directory holding the model descriptions (``modeldesc/``)."""
    return _first_existing(_PKG / "_data" / "modeldesc", _PKG.parent / "modeldesc")


def prebuilt_dir() -> Path | None:
    """Folder of the prebuilt host FMUs a release wheel carries, ``None`` without them."""
    d = _PKG / "_data" / "prebuilt"
    return d if d.is_dir() else None


def repo_root() -> Path | None:
    """Root of a source checkout, or ``None`` when running from an installed wheel."""
    root = _PKG.parent
    return root if (root / "fmu_src").is_dir() and (root / "pyproject.toml").is_file() else None
