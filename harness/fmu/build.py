"""Build the generator FMU (FMI 2.0 or 3.0, co-simulation) for one or several platforms.

The FMU carries a binary for each chosen platform and the C sources from which
any importer (``fmpy compile``) can rebuild it.  Binaries for every platform are
cross-compiled on this machine by the clang of PyPI's ``ziglang`` (the optional
``[platforms]`` extra); without it, the host's binary comes from the C compiler
found on this machine (:func:`host_compiler`), and the host's own compiler
(``gcc`` by default in :func:`default_fmu`) may always build the binary of the
platform it targets.  The platform folder of a binary is read
from the binary itself (ELF, PE or Mach-O header), never assumed from the host.

The FMI headers are the ones that ship with fmpy (``fmpy/c-code``): nothing
third-party is copied into the repository or into the FMU.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

from .._resources import fmu_src_dir, modeldesc_dir, prebuilt_dir
from ..errors import BuildError
from . import codegen, spec
from .artefacts import write_artefacts

CFLAGS = ("-std=c99", "-O2", "-fPIC", "-fvisibility=hidden", "-Wall", "-Wextra", "-Wpedantic",
          "-Werror")
LDFLAGS = ("-shared", "-lm")
PORTABLE_CFLAGS = ("-Wno-strict-prototypes", "-ffp-contract=off")
"""Added for every compiler: fmpy's ``fmi3FunctionTypes.h`` has two prototype-less
declarations that clang flags; no fused multiply-add, so that every platform computes the
same bits (gcc's ``-std=c99`` implies it, clang does not)."""
ZIG_CFLAGS = ("-s",)
"""Added for zig's clang: stripped (no debug info, no ``.pdb`` beside a DLL)."""

ZIG = "zig"
"""The ``cc`` that names the cross compiler of PyPI's ``ziglang`` (``python -m ziglang cc``)."""


@dataclass(frozen=True)
class Platform:
    """A platform the FMU can carry a binary for.

    Attributes
    ----------
    name : str
        FMI 3 platform tuple, also the binary folder of an FMI 3 FMU.
    fmi2_dir : str
        Binary folder of an FMI 2 FMU.
    zig_target : str
        ``-target`` of ``zig cc`` (glibc 2.17 for Linux, macOS 10.15 / 11.0 at least).
    extension : str
        File extension of the shared library.
    """

    name: str
    fmi2_dir: str
    zig_target: str
    extension: str

    def folder(self, fmi_version: int) -> str:
        """Folder under ``binaries/`` for an FMU of ``fmi_version``."""
        return self.fmi2_dir if fmi_version == 2 else self.name


PLATFORMS: dict[str, Platform] = {p.name: p for p in (
    Platform("x86_64-windows", "win64", "x86_64-windows-gnu", ".dll"),
    Platform("x86-windows", "win32", "x86-windows-gnu", ".dll"),
    Platform("x86_64-linux", "linux64", "x86_64-linux-gnu.2.17", ".so"),
    # FMI 2 names no aarch64 Linux folder; this one carries the FMI 3 tuple (docs/platforms.md)
    Platform("aarch64-linux", "aarch64-linux", "aarch64-linux-gnu.2.17", ".so"),
    # FMI 2: both macOS binaries go into darwin64 as one universal (x86_64 + arm64) Mach-O
    Platform("x86_64-darwin", "darwin64", "x86_64-macos.10.15", ".dylib"),
    Platform("aarch64-darwin", "darwin64", "aarch64-macos.11.0", ".dylib"),
)}
"""Every platform ``build_fmu`` can target, by FMI 3 platform tuple."""

ALL_PLATFORMS: tuple[str, ...] = tuple(PLATFORMS)
"""The platforms ``--platforms all`` builds, in the order above."""


def host_platform() -> str:
    """FMI 3 platform tuple of this machine (``x86_64-linux`` here).

    Raises
    ------
    BuildError
        If this machine is none of :data:`PLATFORMS`.
    """
    import fmpy  # deferred: fmpy is heavy to import

    if fmpy.platform_tuple not in PLATFORMS:
        raise BuildError(f"this machine ({fmpy.platform_tuple}) is not a platform the FMU can be "
                         f"built for: {', '.join(ALL_PLATFORMS)}")
    return fmpy.platform_tuple


def resolve_platforms(platforms: str | Sequence[str]) -> tuple[str, ...]:
    """Platforms named by ``platforms``, without repetition, in :data:`PLATFORMS` order.

    Parameters
    ----------
    platforms : str or sequence of str
        ``"host"``, ``"all"``, a comma-separated list of FMI 3 platform tuples
        (``"x86_64-windows,aarch64-linux"``; ``host`` may be one of them), or a
        sequence of such names.

    Raises
    ------
    BuildError
        On an unknown name or an empty list.
    """
    names = platforms.split(",") if isinstance(platforms, str) else list(platforms)
    chosen: set[str] = set()
    for raw in names:
        name = raw.strip()
        if name == "all":
            chosen.update(ALL_PLATFORMS)
        elif name == "host":
            chosen.add(host_platform())
        elif name in PLATFORMS:
            chosen.add(name)
        else:
            raise BuildError(f"unknown platform {name!r}: choose host, all, or a comma-separated "
                             f"list of {', '.join(ALL_PLATFORMS)}")
    if not chosen:
        raise BuildError("no platform to build: choose host, all, or a list of platforms")
    return tuple(p for p in ALL_PLATFORMS if p in chosen)


def fmi_include_dir() -> Path:
    """Directory of the FMI 2 / FMI 3 headers shipped with fmpy."""
    import fmpy  # deferred: fmpy is heavy to import

    d = Path(fmpy.__file__).resolve().parent / "c-code"
    if not (d / "fmi2Functions.h").is_file() or not (d / "fmi3Functions.h").is_file():
        raise BuildError(f"FMI headers not found in {d} (is fmpy installed?)")
    return d


def binary_dir(fmi_version: int, platform: str | None = None) -> str:
    """Folder of a binary inside the FMU (``linux64`` / ``x86_64-linux`` for this host).

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI version of the FMU.
    platform : str, optional
        FMI 3 platform tuple; this machine's by default.
    """
    _check_version(fmi_version)
    return PLATFORMS[platform or host_platform()].folder(fmi_version)


def binary_path(fmi_version: int, platform: str | None = None) -> str:
    """Path of the shared library inside the FMU, e.g. ``binaries/win64/<id>.dll``."""
    p = PLATFORMS[platform or host_platform()]
    return f"binaries/{p.folder(fmi_version)}/{spec.MODEL_IDENTIFIER}{p.extension}"


def _check_version(fmi_version: int) -> None:
    if fmi_version not in (2, 3):
        raise ValueError(f"fmi_version must be 2 or 3, not {fmi_version!r}")


def source_files(fmi_version: int) -> list[Path]:
    """C sources and headers that go into the FMU's ``sources/`` folder."""
    _check_version(fmi_version)
    src = fmu_src_dir()
    files = [src / f for f in codegen.SOURCES[fmi_version] + codegen.HEADERS]
    missing = [f for f in files if not f.is_file()]
    if missing:
        raise BuildError("missing sources: " + ", ".join(map(str, missing)))
    return files


def model_description(fmi_version: int) -> Path:
    """Return the committed ``modelDescription.xml`` for ``fmi_version``."""
    _check_version(fmi_version)
    return modeldesc_dir() / f"fmi{fmi_version}" / "modelDescription.xml"


# ----------------------------------------------------------------------------- compilers


PLATFORMS_HINT = ("for all six platforms install the optional cross compiler: "
                  "pip install '.[platforms]' in the source checkout "
                  "(or pip install 'ziglang>=0.17.1,<0.18')")
"""How to get the binaries of every platform, for messages."""

HOST_COMPILERS = ("gcc", "cc", "clang")
"""C compilers :func:`host_compiler` looks for on ``PATH``, in order, after ``$CC``."""


def zig_available() -> bool:
    """Whether PyPI's ``ziglang`` (the ``[platforms]`` extra) is installed."""
    return importlib.util.find_spec("ziglang") is not None


def zig_command() -> list[str]:
    """Command line that runs zig's C compiler (``python -m ziglang cc``).

    Raises
    ------
    BuildError
        If PyPI's ``ziglang`` is not installed.
    """
    if not zig_available():
        raise BuildError("the cross compiler of PyPI's 'ziglang' builds the binaries of other "
                         f"platforms than this one and is not installed: {PLATFORMS_HINT}; or "
                         "build the host's binary only (--platforms host)")
    return [sys.executable, "-m", "ziglang", "cc"]


def default_platforms() -> str:
    """Return what ``djl-fmu build`` builds by default: ``"all"`` with zig, else ``"host"``."""
    return "all" if zig_available() else "host"


def host_compiler() -> str:
    """Return the C compiler for the host's binary without zig: ``$CC``, else gcc, cc, clang.

    Raises
    ------
    BuildError
        If none is found: the message says what to install.
    """
    env = os.environ.get("CC", "").strip()
    for cc in ((env,) if env else ()) + HOST_COMPILERS:
        if shutil.which(cc):
            return cc
    raise BuildError("no C compiler found to build the FMU's binary for this machine (looked "
                     f"for $CC, {', '.join(HOST_COMPILERS)}): install one (e.g. apt-get install "
                     f"gcc), or {PLATFORMS_HINT}")


def check_compiler(cc: str = "gcc") -> str:
    """Full path of the C compiler ``cc`` (for :data:`ZIG`, of the Python that runs it).

    Raises
    ------
    BuildError
        If it is not on ``PATH``: the message says gcc is needed to build the FMU.
    """
    if cc == ZIG:
        return zig_command()[0]
    found = shutil.which(cc)
    if found is None:
        raise BuildError(f"the C compiler {cc!r} is needed to build the generator FMU and was "
                         f"not found on PATH: install gcc (e.g. apt-get install gcc), or give "
                         f"an FMU file built elsewhere (--fmu / simulation.fmu)")
    return found


_ARCH = {"x86_64": "x86_64", "amd64": "x86_64", "x64": "x86_64", "i386": "x86", "i486": "x86",
         "i586": "x86", "i686": "x86", "x86": "x86", "aarch64": "aarch64", "arm64": "aarch64"}


def platform_of_triple(triple: str) -> str | None:
    """FMI 3 platform tuple of a compiler's target triple (``x86_64-w64-mingw32``), or None."""
    parts = triple.strip().lower().split("-")
    arch = _ARCH.get(parts[0])
    rest = "-".join(parts[1:])
    if "mingw" in rest or "windows" in rest or "cygwin" in rest or "msvc" in rest:
        system = "windows"
    elif "linux" in rest:
        system = "linux"
    elif "darwin" in rest or "macos" in rest or "apple" in rest:
        system = "darwin"
    else:
        return None
    name = f"{arch}-{system}"
    return name if arch and name in PLATFORMS else None


def compiler_platform(cc: str) -> str:
    """Platform that the C compiler ``cc`` builds for (from ``cc -dumpmachine``).

    :data:`ZIG` builds for any platform; its default is this machine's.

    Raises
    ------
    BuildError
        If ``cc`` cannot be run or its target is none of :data:`PLATFORMS`.
    """
    if cc == ZIG:
        return host_platform()
    path = check_compiler(cc)
    try:
        out = subprocess.run([path, "-dumpmachine"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError) as e:
        raise BuildError(f"cannot run the C compiler {cc!r}: {e}") from e
    plat = platform_of_triple(out.stdout) if out.returncode == 0 else None
    if plat is None:
        raise BuildError(f"cannot tell which platform {cc!r} builds for ('{cc} -dumpmachine' "
                         f"said {out.stdout.strip() or out.stderr.strip()!r}); the FMU can carry "
                         f"binaries for {', '.join(ALL_PLATFORMS)}")
    return plat


# ----------------------------------------------------------------------------- binaries

_ELF_MACHINE = {62: "x86_64", 3: "x86", 183: "aarch64"}
_PE_MACHINE = {0x8664: "x86_64", 0x14C: "x86", 0xAA64: "aarch64"}
_MACHO_CPU = {0x01000007: "x86_64", 0x0100000C: "aarch64"}


def binary_platforms(path: str | os.PathLike) -> tuple[str, ...]:
    """Platforms of a shared library, read from its header (several for a universal Mach-O).

    Raises
    ------
    BuildError
        If the file is no ELF shared object, PE DLL or Mach-O dylib of a known CPU.
    """
    b = Path(path).read_bytes()
    found: list[str | None] = []
    if b[:4] == b"\x7fELF" and len(b) >= 20:
        end = "<" if b[5] == 1 else ">"
        e_type, e_machine = struct.unpack_from(end + "HH", b, 16)
        found.append(f"{_ELF_MACHINE.get(e_machine)}-linux" if e_type == 3 else None)
    elif b[:2] == b"MZ" and len(b) >= 0x40:
        pe = struct.unpack_from("<I", b, 0x3C)[0]
        if b[pe:pe + 4] == b"PE\0\0":
            machine = struct.unpack_from("<H", b, pe + 4)[0]
            characteristics = struct.unpack_from("<H", b, pe + 22)[0]
            is_dll = bool(characteristics & 0x2000)
            found.append(f"{_PE_MACHINE.get(machine)}-windows" if is_dll else None)
    elif b[:4] == b"\xca\xfe\xba\xbe":  # universal Mach-O: the slices, each checked
        (n,) = struct.unpack_from(">I", b, 4)
        for i in range(n):
            _, _, off, size, _ = struct.unpack_from(">5I", b, 8 + 20 * i)
            found.extend(_macho_platform(b[off:off + size]))
    else:
        found.extend(_macho_platform(b))
    if not found or any(p is None or p not in PLATFORMS for p in found):
        raise BuildError(f"{path} is not a shared library for any of {', '.join(ALL_PLATFORMS)}")
    return tuple(p for p in found if p is not None)


def _macho_platform(b: bytes) -> list[str | None]:
    if b[:4] != b"\xcf\xfa\xed\xfe" or len(b) < 16:
        return [None]
    cpu, _, filetype = struct.unpack_from("<iII", b, 4)
    return [f"{_MACHO_CPU.get(cpu & 0xFFFFFFFF)}-darwin" if filetype == 6 else None]


def _universal_macho(slices: Sequence[Path], out: Path) -> Path:
    """Write a universal (fat) Mach-O holding the thin dylibs ``slices``, as ``lipo -create``."""
    align = 14  # slices on 16 KiB boundaries: the arm64 page (x86_64 needs 4 KiB)
    datas = [s.read_bytes() for s in slices]
    header = struct.pack(">II", 0xCAFEBABE, len(datas))
    offsets, end = [], 1 << align
    for d in datas:
        offsets.append(end)
        end += -(-len(d) >> align) << align
    for d, off in zip(datas, offsets, strict=True):
        cpu, sub = struct.unpack_from("<II", d, 4)
        header += struct.pack(">5I", cpu, sub, off, len(d), align)
    blob = bytearray(header)
    for d, off in zip(datas, offsets, strict=True):
        blob += bytes(off - len(blob)) + d
    out.write_bytes(bytes(blob))
    return out


def compile_binary(fmi_version: int, out: Path, *, cc: str = "gcc",
                   extra_cflags: tuple[str, ...] = (), platform: str | None = None) -> Path:
    """Compile the shared library of the FMU into ``out``.

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI version of the sources.
    out : pathlib.Path
        The library to write.
    cc : str
        C compiler; :data:`ZIG` for zig's clang, which builds for any platform.
    extra_cflags : tuple of str
        Extra compiler flags (e.g. sanitizers).
    platform : str, optional
        Target (FMI 3 platform tuple): the one ``cc`` builds for by default.

    Raises
    ------
    BuildError
        If the compiler fails, or builds for another platform than ``platform``.
    """
    target = PLATFORMS[platform or compiler_platform(cc)]
    files = [str(f) for f in source_files(fmi_version) if f.suffix == ".c"]
    flags = [f for f in CFLAGS if not (f == "-fPIC" and target.extension == ".dll")]
    if cc == ZIG:
        cmd = [*zig_command(), "-target", target.zig_target, *flags, *PORTABLE_CFLAGS,
               *ZIG_CFLAGS]
    else:
        cmd = [check_compiler(cc), *flags, *PORTABLE_CFLAGS]
    with tempfile.TemporaryDirectory(prefix="djl-fmu-cc-") as tmp:
        # in a folder of its own: a compiler's side files (.pdb, import .lib) stay out of the FMU
        lib = Path(tmp) / (spec.MODEL_IDENTIFIER + target.extension)
        cmd += [*extra_cflags, f"-I{fmi_include_dir()}", f"-I{fmu_src_dir()}", *files,
                "-o", str(lib), *LDFLAGS]
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True)
        except OSError as e:
            raise BuildError(f"cannot run the C compiler {cc!r}: {e}") from e
        if proc.returncode != 0:
            raise BuildError(f"compilation for {target.name} failed ({' '.join(cmd)}):\n"
                             f"{proc.stderr}")
        got = binary_platforms(lib)
        if got != (target.name,):
            raise BuildError(f"{cc!r} built a library for {', '.join(got)}, not for "
                             f"{target.name}")
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(lib, out)
    return out


def compilers(platforms: Sequence[str], cc: str | None = None) -> dict[str, str]:
    """Choose each platform's compiler: ``cc`` for the platform it builds for, zig for the rest.

    Raises
    ------
    BuildError
        If ``cc`` builds for none of ``platforms``.
    """
    chosen = {p: ZIG for p in platforms}
    if cc is None and not zig_available():
        cc = host_compiler()
    if cc is not None and cc != ZIG:
        own = compiler_platform(cc)
        if own not in chosen:
            raise BuildError(f"the C compiler {cc!r} builds for {own}, which is not among the "
                             f"platforms to build ({', '.join(platforms)}): add it to the "
                             f"platforms, or leave the compiler to zig")
        chosen[own] = cc
    if not zig_available():
        need = [p for p, c in chosen.items() if c == ZIG]
        if need:
            raise BuildError(f"no compiler for {', '.join(need)} here: {PLATFORMS_HINT}; or "
                             f"build the host's binary only (--platforms host)")
    return chosen


def _runtime_marker(platform: str) -> Path:
    """File recording that zig has compiled its C runtime for ``platform`` on this machine."""
    return cache_dir() / "zig-runtimes" / PLATFORMS[platform].zig_target


def first_zig_builds(ccs: dict[str, str]) -> list[str]:
    """Platforms that zig builds here for the first time (its C runtime not compiled yet).

    zig compiles a target's C runtime (MinGW's for Windows: minutes on a small machine) on
    first use and caches it (``~/.cache/zig``); a marker under :func:`cache_dir` records each
    target built, so only a first build is announced (a cleared zig cache is not noticed).
    """
    return [p for p, c in ccs.items() if c == ZIG and not _runtime_marker(p).is_file()]


def build_binaries(fmi_version: int, root: Path, platforms: str | Sequence[str] = "host", *,
                   cc: str | None = None, extra_cflags: tuple[str, ...] = (),
                   progress: Callable[[str], None] | None = None) -> list[Path]:
    """Compile the binaries of ``platforms`` into the unpacked FMU folder ``root``.

    Each platform's binary goes to ``binaries/<folder>/<modelIdentifier><ext>``: the
    FMI 3 tuple, or the FMI 2 name (``win64``, ``win32``, ``linux64``, ``aarch64-linux``,
    ``darwin64``; both macOS binaries make one universal ``darwin64`` library).

    Parameters
    ----------
    progress : callable, optional
        Called with a line of text: before a first zig build of a platform (its C runtime
        is compiled once), and as each platform's binary is done (compiler, seconds).

    Returns
    -------
    list of pathlib.Path
        The libraries written.
    """
    _check_version(fmi_version)
    names = resolve_platforms(platforms)
    ccs = compilers(names, cc)
    first = first_zig_builds(ccs)
    if progress is not None and first:
        progress(f"first build here for {', '.join(first)}: zig compiles the C runtime of "
                 "each once (the two Windows runtimes take minutes on a small machine, "
                 "other jobs running: up to a quarter of an hour); later builds take seconds")
    with tempfile.TemporaryDirectory(prefix="djl-fmu-bin-") as tmp:
        thin = {p: Path(tmp) / p / (spec.MODEL_IDENTIFIER + PLATFORMS[p].extension)
                for p in names}

        def one(p: str) -> Path:
            t0 = time.perf_counter()
            out = compile_binary(fmi_version, thin[p], cc=ccs[p], extra_cflags=extra_cflags,
                                 platform=p)
            if ccs[p] == ZIG:
                marker = _runtime_marker(p)
                marker.parent.mkdir(parents=True, exist_ok=True)
                marker.touch()
            if progress is not None:
                who = "zig" if ccs[p] == ZIG else ccs[p]
                progress(f"  {p}: built by {who} in {time.perf_counter() - t0:.1f} s")
            return out

        workers = max(1, min(len(names), os.cpu_count() or 1))
        with ThreadPoolExecutor(max_workers=workers) as pool:
            list(pool.map(one, names))  # raises the first failure
        by_dest: dict[str, list[str]] = {}
        for p in names:
            by_dest.setdefault(binary_path(fmi_version, p), []).append(p)
        written = []
        for dest, plats in by_dest.items():
            target = root / dest
            target.parent.mkdir(parents=True, exist_ok=True)
            if len(plats) == 1:
                shutil.copyfile(thin[plats[0]], target)
            else:
                _universal_macho([thin[p] for p in plats], target)
            written.append(target)
    return written


def build_fmu(fmi_version: int, out_path: str | os.PathLike, *,
              platforms: str | Sequence[str] = "host", cc: str | None = None,
              extra_cflags: tuple[str, ...] = (),
              progress: Callable[[str], None] | None = None) -> Path:
    """Write a complete co-simulation FMU to ``out_path``.

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI version of the FMU.
    out_path : path-like
        Destination ``.fmu`` file (parent folders are created).
    platforms : str or sequence of str
        Platforms to carry binaries for: ``"host"`` (default), ``"all"`` (the six of
        :data:`PLATFORMS`), or a list of FMI 3 platform tuples (see
        :func:`resolve_platforms`).
    cc : str, optional
        A C compiler (``gcc``) for the binary of the platform it builds for (which must
        be among ``platforms``); every other binary, and all of them by default, comes
        from zig's clang (:data:`ZIG`).  Without ``ziglang`` installed, the host's binary
        comes from :func:`host_compiler` by default, and no other platform can be built.
    extra_cflags : tuple of str
        Extra compiler flags (e.g. sanitizers).
    progress : callable, optional
        Receives progress lines (see :func:`build_binaries`).

    Returns
    -------
    pathlib.Path
        ``out_path``.
    """
    _check_version(fmi_version)
    names = resolve_platforms(platforms)
    compilers(names, cc)  # every compiler found before anything is created
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="djl-fmu-build-") as tmp:
        root = Path(tmp) / "fmu"
        (root / "sources").mkdir(parents=True)
        (root / "documentation").mkdir()
        (root / "modelDescription.xml").write_text(
            stamped_model_description(fmi_version), encoding="utf-8")
        for f in source_files(fmi_version):
            shutil.copyfile(f, root / "sources" / f.name)
        if fmi_version == 3:
            shutil.copyfile(modeldesc_dir() / "fmi3" / "buildDescription.xml",
                            root / "sources" / "buildDescription.xml")
        build_binaries(fmi_version, root, names, cc=cc, extra_cflags=extra_cflags,
                       progress=progress)
        write_artefacts(root, fmi_version)
        tmp_zip = out_path.with_name(out_path.name + f".tmp{os.getpid()}")
        try:
            with zipfile.ZipFile(tmp_zip, "w", zipfile.ZIP_DEFLATED) as z:
                for p in sorted(root.rglob("*")):
                    if p.is_file():
                        z.write(p, p.relative_to(root).as_posix())
            os.replace(tmp_zip, out_path)
        finally:
            tmp_zip.unlink(missing_ok=True)
    return out_path


def generation_date() -> str:
    """Return the FMU's ``generationDateAndTime``: now in UTC, or ``$SOURCE_DATE_EPOCH``'s date.

    The format is the one FMI asks for, ``YYYY-MM-DDThh:mm:ssZ``; ``SOURCE_DATE_EPOCH`` (the
    reproducible-builds convention, seconds since 1970) makes two builds byte-identical.
    """
    epoch = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    when = (datetime.fromtimestamp(int(epoch), tz=timezone.utc) if epoch.isdigit()
            else datetime.now(tz=timezone.utc))
    return when.strftime("%Y-%m-%dT%H:%M:%SZ")


def stamped_model_description(fmi_version: int) -> str:
    """Return the committed model description with ``generationDateAndTime`` of this build.

    The committed files (``modeldesc/``) carry no date, so that regenerating them from the
    spec changes nothing; the date is the FMU's, added as the FMU is written.
    """
    text = model_description(fmi_version).read_text(encoding="utf-8")
    tool = f'generationTool="{codegen.GENERATION_TOOL}"'
    if tool not in text:
        raise BuildError(f"{model_description(fmi_version)}: no {tool} to date")
    return text.replace(tool, f'{tool} generationDateAndTime="{generation_date()}"', 1)


def _digested_files(fmi_version: int) -> list[Path]:
    here = Path(__file__).resolve().parent
    return [*source_files(fmi_version), model_description(fmi_version),
            here / "build.py", here / "artefacts.py"]


def _sources_digest(fmi_version: int, cc: str, extra_cflags: tuple[str, ...]) -> str:
    h = hashlib.sha256()
    for f in _digested_files(fmi_version):
        h.update(f.name.encode())
        h.update(f.read_bytes())
    h.update(" ".join((cc, *CFLAGS, *PORTABLE_CFLAGS, *extra_cflags, *LDFLAGS)).encode())
    return h.hexdigest()[:16]


def sources_digest(fmi_version: int) -> str:
    """SHA-256 of what the FMU is built from: C sources, model description, build code.

    The key of a prebuilt FMU (:func:`prebuilt_fmu`): the one a release wheel carries is
    used only while the installed sources still give this digest.
    """
    h = hashlib.sha256()
    for f in _digested_files(fmi_version):
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def cache_dir() -> Path:
    """Folder where :func:`default_fmu` keeps its builds (``$DJL_FMU_CACHE`` overrides)."""
    env = os.environ.get("DJL_FMU_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "djl-fmu"


def default_fmu(fmi_version: int = 2, *, cc: str = "gcc",
                extra_cflags: tuple[str, ...] = ()) -> Path:
    """Path of an FMU built from the installed sources, building it on first use.

    It carries this machine's binary only, compiled by ``cc`` (:data:`ZIG` for zig's
    clang): what the harness loads, built in about a second.  Builds are cached by a
    digest of the sources, model description, build code and flags, so editing the C
    code rebuilds automatically.  With the default compiler and flags, a release wheel's
    prebuilt FMU (:func:`prebuilt_fmu`) is copied into the cache instead of compiling,
    if it fits the installed sources: no C compiler is needed then.
    """
    digest = _sources_digest(fmi_version, cc, extra_cflags)
    path = cache_dir() / f"{spec.MODEL_IDENTIFIER}-fmi{fmi_version}-{digest}.fmu"
    if path.is_file():
        return path
    prebuilt = prebuilt_fmu(fmi_version) if (cc, extra_cflags) == ("gcc", ()) else None
    if prebuilt is not None:  # a release wheel's: no compiler needed
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + f".tmp{os.getpid()}")
        try:
            shutil.copyfile(prebuilt, tmp)
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
        return path
    check_compiler(cc)  # before creating anything
    build_fmu(fmi_version, path, platforms="host", cc=cc, extra_cflags=extra_cflags)
    return path


PREBUILT_MANIFEST = "manifest.json"
"""File beside the prebuilt FMUs (:func:`harness._resources.prebuilt_dir`) that describes
them: ``{"platform": ..., "fmus": {"2": {"file", "sources_digest", "sha256", "compiler"},
"3": {...}}}`` (written by :func:`harness.release.stage_prebuilt`)."""


def prebuilt_fmu(fmi_version: int, folder: Path | None = None) -> Path | None:
    """Return the packaged prebuilt FMU of ``fmi_version`` if it fits, else None.

    A release wheel carries this machine's FMUs (FMI 2 and 3, built with the wheel), so
    that :func:`default_fmu` needs no C compiler; one is used only if it was built for this
    platform from the installed sources (its :func:`sources_digest` matches) and its bytes
    are the recorded ones (SHA-256).

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI version of the FMU.
    folder : pathlib.Path, optional
        Folder of the prebuilt FMUs and their manifest; the package's by default
        (:func:`harness._resources.prebuilt_dir`; a source checkout has none).
    """
    _check_version(fmi_version)
    folder = prebuilt_dir() if folder is None else folder
    if folder is None or not (folder / PREBUILT_MANIFEST).is_file():
        return None
    try:
        manifest = json.loads((folder / PREBUILT_MANIFEST).read_text(encoding="utf-8"))
        entry = manifest["fmus"][str(fmi_version)]
        path = folder / entry["file"]
        fits = (manifest["platform"] == host_platform()
                and entry["sources_digest"] == sources_digest(fmi_version)
                and path.is_file()
                and hashlib.sha256(path.read_bytes()).hexdigest() == entry["sha256"])
    except (OSError, ValueError, KeyError, TypeError, BuildError):
        return None
    return path if fits else None
