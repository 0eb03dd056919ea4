"""Release artefacts (``python -m harness.release``): a wheel that runs without a C compiler.

In CI (about half a minute): a wheel is built as the release builds it (prebuilt host FMUs
staged and passed to CMake), checked to hold the engine and both prebuilt FMUs, unpacked
and run from a process with no compiler on ``PATH`` and ``CC`` unset: the FMUs ``simulate``
writes are the prebuilt ones.

On demand (a few minutes: the release, and a fresh venv that downloads the dependencies):
``DJL_FMU_RELEASE_TEST=1 pytest tests/test_release.py`` runs ``python -m harness.release``
(needs the ``[release]`` extra), or ``DJL_FMU_RELEASE_TEST=<folder>`` takes the artefacts
already in that folder; then the manylinux wheel is installed in a new venv and
``djl-fmu simulate`` runs on its default scenarios without a compiler.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from harness import release
from harness.fmu import build

ROOT = Path(__file__).resolve().parent.parent
ON_DEMAND = os.environ.get("DJL_FMU_RELEASE_TEST", "").strip()
"""``1``: make the release and test it; a folder: test the release already in it."""

needs_cc = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not installed")


def _no_compiler_env(tmp: Path, path: str, **extra: str) -> dict[str, str]:
    """Environment without a C compiler: ``PATH`` is ``path`` (plus an empty folder)."""
    empty = tmp / "no-compiler"
    empty.mkdir(exist_ok=True)
    env = {"PATH": os.pathsep.join(p for p in (path, str(empty)) if p),
           "HOME": str(tmp), "DJL_FMU_CACHE": str(tmp / "cache"), "MPLBACKEND": "Agg",
           "LANG": "C.UTF-8", **extra}
    for cc in build.HOST_COMPILERS:
        assert shutil.which(cc, path=env["PATH"]) is None, f"{cc} on the test's PATH"
    return env


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


# ------------------------------------------------------------------ prebuilt FMUs


@pytest.fixture(scope="module")
def staged(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Prebuilt host FMUs and manifest, as the release stages them (gcc here: faster)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not installed")
    folder = tmp_path_factory.mktemp("prebuilt")
    release.stage_prebuilt(folder, cc="gcc")
    return folder


def test_prebuilt_fmu_is_taken_only_if_it_fits(staged, tmp_path):
    for v in (2, 3):
        assert build.prebuilt_fmu(v, staged) == staged / release.prebuilt_name(v)
    assert build.prebuilt_fmu(2, tmp_path) is None  # no manifest
    manifest = json.loads((staged / build.PREBUILT_MANIFEST).read_text(encoding="utf-8"))
    changes = [
        ("platform", lambda m: m.update(platform="aarch64-darwin")),
        ("sources", lambda m: m["fmus"]["2"].update(sources_digest="0" * 64)),
        ("bytes", lambda m: m["fmus"]["2"].update(sha256="0" * 64)),
        ("entry", lambda m: m["fmus"].pop("2")),
    ]
    for what, change in changes:
        folder = tmp_path / what
        shutil.copytree(staged, folder)
        m = json.loads(json.dumps(manifest))
        change(m)
        (folder / build.PREBUILT_MANIFEST).write_text(json.dumps(m), encoding="utf-8")
        assert build.prebuilt_fmu(2, folder) is None, what
        if what != "platform":  # the other version's FMU still serves
            assert build.prebuilt_fmu(3, folder) == folder / release.prebuilt_name(3), what


def test_default_fmu_copies_the_prebuilt_into_the_cache(staged, tmp_path, monkeypatch):
    monkeypatch.setenv("DJL_FMU_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(build, "prebuilt_dir", lambda: staged)
    monkeypatch.setenv("PATH", str(tmp_path))  # no compiler: only the prebuilt can serve
    monkeypatch.delenv("CC", raising=False)
    for v in (2, 3):
        path = build.default_fmu(v)
        assert path.parent == tmp_path / "cache"
        assert path.read_bytes() == (staged / release.prebuilt_name(v)).read_bytes()
        assert build.default_fmu(v) == path  # cached from now on
    with pytest.raises(build.BuildError, match="not found on PATH"):
        build.default_fmu(2, extra_cflags=("-O0",))  # other flags: compiled, never prebuilt


# ------------------------------------------------------------------ the wheel (CI)


@pytest.fixture(scope="module")
def wheel(staged: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A wheel built as the release builds it (CMake gets the staged FMUs), from a copy of
    the checkout without its compiled engine (which a wheel of the folder would take)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", "_engine*.so", "_engine*.pyd", "build", "dist", "__pycache__", ".*_cache",
        ".hypothesis", "djl-fmu-out", "*.fmu"))
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp / "out"),
         f"--config-settings=cmake.define.DJL_PREBUILT_DIR={staged}", str(src)],
        capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (whl,) = (tmp / "out").glob("djl_fmu-*.whl")
    return whl


@pytest.mark.slow
def test_wheel_holds_the_engine_and_the_prebuilt_fmus(wheel, staged):
    assert release.check_wheel(wheel, manylinux=False) == []
    names = zipfile.ZipFile(wheel).namelist()
    engines = [n for n in names if n.startswith("harness/_engine")]
    assert len(engines) == 1 and engines[0].endswith(".so")  # and no stray one
    if sys.version_info >= (3, 11):
        assert "-abi3-" in wheel.name and engines[0] == "harness/_engine.abi3.so"
    assert "harness/_engine.c" not in names
    assert {"harness/programs/pick-place-X.csv", "harness/programs/pick-place-X.nc",
            "harness/scenarios/X.toml"} <= set(names)  # the embedded data files
    with zipfile.ZipFile(wheel) as z:
        for v in (2, 3):
            name = f"harness/_data/prebuilt/{release.prebuilt_name(v)}"
            assert z.read(name) == (staged / release.prebuilt_name(v)).read_bytes()


@pytest.mark.slow
@needs_cc
def test_simulate_from_the_wheel_needs_no_compiler(wheel, staged, tmp_path):
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)  # what pip installs of it (no scripts: -m)
    env = _no_compiler_env(tmp_path, "", PYTHONPATH=str(site))
    where = subprocess.run(
        [sys.executable, "-c", "import harness, harness._engine as e; "
         "print(harness.__file__); print(e.__file__)"],
        capture_output=True, text=True, env=env, cwd=tmp_path)
    assert where.returncode == 0, where.stderr
    assert all(line.startswith(str(site)) for line in where.stdout.split()), where.stdout
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "harness.cli", "simulate", "X", "--no-plot", "-q",
         "-o", str(out)], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (out / "X.csv").is_file()
    (cached,) = (tmp_path / "cache").glob("JerkLimitedTrajectory-fmi2-*.fmu")  # X's FMU
    assert cached.read_bytes() == (staged / release.prebuilt_name(2)).read_bytes()


# ------------------------------------------------------------------ the release (on demand)


@pytest.fixture(scope="module")
def released(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if ON_DEMAND != "1":
        return Path(ON_DEMAND).resolve()
    out = tmp_path_factory.mktemp("dist")
    proc = subprocess.run([sys.executable, "-m", "harness.release", str(out)], cwd=ROOT,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


@pytest.mark.skipif(not ON_DEMAND, reason="on demand: DJL_FMU_RELEASE_TEST=1 (or a folder)")
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the manylinux wheel")
def test_release_wheel_installs_and_simulates_in_a_fresh_venv_without_compiler(released,
                                                                               tmp_path):
    sums = (released / "SHA256SUMS").read_text(encoding="ascii").split("\n")
    listed = dict(reversed(line.split("  ")) for line in sums if line)
    assert {n.rsplit("-", 1)[-1] for n in listed if n.endswith(".fmu")} == {"fmi2.fmu",
                                                                             "fmi3.fmu"}
    assert any(n.endswith(".tar.gz") for n in listed)
    for name, digest in listed.items():
        assert _sha(released / name) == digest, name
    (whl,) = [released / n for n in listed if n.endswith(".whl")]
    assert "manylinux" in whl.name and release.check_wheel(whl) == []
    for n in listed:
        if n.endswith(".fmu"):  # all six platforms
            names = zipfile.ZipFile(released / n).namelist()
            assert sum(n.startswith("binaries/") for n in names) >= 5

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    pip = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q", str(whl)],
                         capture_output=True, text=True)
    assert pip.returncode == 0, pip.stdout + pip.stderr
    env = _no_compiler_env(tmp_path, str(venv / "bin"))
    out = tmp_path / "out"
    proc = subprocess.run(["djl-fmu", "simulate", "-q", "-o", str(out)], capture_output=True,
                          text=True, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    assert all(f"{s}" in summary for s in ("X", "Y", "sweep-X", "sweep-Y"))
    prebuilt = Path(subprocess.run(
        [str(venv / "bin" / "python"), "-c",
         "from harness._resources import prebuilt_dir; print(prebuilt_dir())"],
        capture_output=True, text=True, env=env, cwd=tmp_path, check=True).stdout.strip())
    for v in (2, 3):
        assert ((out / f"JerkLimitedTrajectory-fmi{v}.fmu").read_bytes()
                == (prebuilt / release.prebuilt_name(v)).read_bytes())
