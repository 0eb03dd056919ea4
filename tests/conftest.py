"""Shared fixtures: the two FMUs are built once per test session."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings

# default: reproducible examples (CI runs the same cases every time);
# HYPOTHESIS_PROFILE=thorough: fresh random examples, ten times as many.
settings.register_profile("default", derandomize=True, deadline=None)
settings.register_profile("thorough", max_examples=2000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

matplotlib.use("Agg")

# Builds made through harness.fmu.build.default_fmu go to a private cache.
_CACHE = tempfile.mkdtemp(prefix="djl-fmu-test-cache-")
os.environ.setdefault("DJL_FMU_CACHE", _CACHE)


@pytest.fixture(autouse=True)
def _close_figures():
    """Results hand out open matplotlib figures (``.plot()``): close them after each test."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fmus")


def _extra_cflags(fmi_version: int) -> tuple[str, ...]:
    """Extra flags for the session's FMU binaries from ``DJL_TEST_FMU_CFLAGS``.

    ``{fmi}`` is replaced by the FMI version; tests/c/coverage.sh builds them with
    ``--coverage -dumpdir DIR/fmu{fmi}/`` (empty, the default: the FMU as shipped).  With
    extra flags the host binary is built by gcc (its coverage runtime is linked in).
    """
    flags = os.environ.get("DJL_TEST_FMU_CFLAGS", "").replace("{fmi}", str(fmi_version))
    return tuple(flags.split())


@pytest.fixture(scope="session")
def fmu2(fmu_dir: Path) -> Path:
    from harness.fmu.build import build_fmu

    extra = _extra_cflags(2)
    return build_fmu(2, fmu_dir / "JerkLimitedTrajectory-fmi2.fmu", extra_cflags=extra,
                     cc="gcc" if extra else None)


@pytest.fixture(scope="session")
def fmu3(fmu_dir: Path) -> Path:
    from harness.fmu.build import build_fmu

    extra = _extra_cflags(3)
    return build_fmu(3, fmu_dir / "JerkLimitedTrajectory-fmi3.fmu", extra_cflags=extra,
                     cc="gcc" if extra else None)


@pytest.fixture(scope="session")
def fmus(fmu2: Path, fmu3: Path) -> dict[int, Path]:
    return {2: fmu2, 3: fmu3}


@pytest.fixture(params=[2, 3], ids=["fmi2", "fmi3"])
def fmu(request: pytest.FixtureRequest, fmus: dict[int, Path]) -> Path:
    """Each FMI version in turn."""
    return fmus[request.param]
