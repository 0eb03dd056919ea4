"""Binaries for six platforms, cross-compiled here by zig (issue #11, items 1, 2 and 5).

The export tables, library dependencies and headers of the PE, ELF and Mach-O files are
read by the small parsers below (no binutils needed).  Where wine or qemu-user is
installed, the Windows and aarch64 Linux binaries run the default move through a small
driver (tests/c/platform_driver.c) and must give the host binary's outputs.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import struct
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy.validation import validate_fmu

from harness._resources import fmu_src_dir
from harness.fmu import spec
from harness.fmu.build import (
    ALL_PLATFORMS,
    PLATFORMS,
    BuildError,
    build_fmu,
    fmi_include_dir,
    host_platform,
    resolve_platforms,
    zig_command,
)

pytest.importorskip("ziglang")

ID = spec.MODEL_IDENTIFIER
HERE = Path(__file__).resolve().parent
DRIVER = HERE / "c" / "platform_driver.c"

FMI3_FILES = {p: f"binaries/{p}/{ID}{PLATFORMS[p].extension}" for p in ALL_PLATFORMS}
FMI2_FILES = {"x86_64-windows": f"binaries/win64/{ID}.dll",
              "x86-windows": f"binaries/win32/{ID}.dll",
              "x86_64-linux": f"binaries/linux64/{ID}.so",
              "aarch64-linux": f"binaries/aarch64-linux/{ID}.so",
              "x86_64-darwin": f"binaries/darwin64/{ID}.dylib",
              "aarch64-darwin": f"binaries/darwin64/{ID}.dylib"}
FILES = {2: FMI2_FILES, 3: FMI3_FILES}

MACHO_LINKER_SYMBOLS = {"__mh_dylib_header", "___dso_handle"}
"""Exported by zig's Mach-O linker into every dylib (no flag removes them; both are
per-image symbols that dyld's two-level namespace keeps apart)."""


def fmi_functions(version: int) -> set[str]:
    """Every function the FMI headers declare for ``version``: what a binary must export."""
    text = (fmi_include_dir() / f"fmi{version}Functions.h").read_text()
    names = set(re.findall(rf"FMI{version}_Export\s+\w+TYPE\s+(fmi{version}\w+)\s*;", text))
    assert len(names) == {2: 44, 3: 75}[version], len(names)
    return names


# ----------------------------------------------------------------------------- ELF


def _cstr(b: bytes, off: int) -> str:
    return b[off:b.index(b"\0", off)].decode()


def elf_info(b: bytes) -> dict:
    """Machine, defined global dynamic symbols, DT_NEEDED, required symbol versions, .comment
    of a 64-bit little-endian ELF shared object."""
    assert b[:4] == b"\x7fELF" and b[4] == 2 and b[5] == 1, "not an ELF64 LE file"
    e_type, e_machine = struct.unpack_from("<HH", b, 16)
    e_shoff = struct.unpack_from("<Q", b, 40)[0]
    e_shentsize, e_shnum, e_shstrndx = struct.unpack_from("<HHH", b, 58)
    secs = [struct.unpack_from("<IIQQQQIIQQ", b, e_shoff + i * e_shentsize) for i in range(e_shnum)]
    shstr = secs[e_shstrndx][4]
    by_name = {_cstr(b, shstr + s[0]): s for s in secs}
    info: dict = {"type": e_type, "machine": e_machine, "exports": set(), "needed": set(),
                  "versions": set(), "comment": ""}
    for s in secs:
        name, typ, _, _, off, size, link, _, _, entsize = s
        strtab = secs[link][4]
        if typ == 11:  # SHT_DYNSYM
            for i in range(1, size // entsize):
                st_name, st_info, st_other, st_shndx = struct.unpack_from("<IBBH", b, off + i * 24)
                bind, vis = st_info >> 4, st_other & 3
                if st_shndx != 0 and bind in (1, 2) and vis in (0, 3):  # defined GLOBAL/WEAK
                    info["exports"].add(_cstr(b, strtab + st_name))
        elif typ == 6:  # SHT_DYNAMIC
            for i in range(size // 16):
                tag, val = struct.unpack_from("<qQ", b, off + i * 16)
                if tag == 1:
                    info["needed"].add(_cstr(b, strtab + val))
        elif typ == 0x6FFFFFFE:  # SHT_GNU_verneed
            p = off
            while True:
                _, cnt, _, aux, nxt = struct.unpack_from("<HHIII", b, p)
                a = p + aux
                for _ in range(cnt):
                    _, _, _, vname, anext = struct.unpack_from("<IHHII", b, a)
                    info["versions"].add(_cstr(b, strtab + vname))
                    a += anext
                if not nxt:
                    break
                p += nxt
    if ".comment" in by_name:
        s = by_name[".comment"]
        info["comment"] = b[s[4]:s[4] + s[5]].replace(b"\0", b" ").decode(errors="replace")
    return info


# ----------------------------------------------------------------------------- PE


def pe_info(b: bytes) -> dict:
    """Machine, DLL flag, export names and imported DLLs of a PE32 / PE32+ file."""
    assert b[:2] == b"MZ"
    pe = struct.unpack_from("<I", b, 0x3C)[0]
    assert b[pe:pe + 4] == b"PE\0\0"
    machine, nsec = struct.unpack_from("<HH", b, pe + 4)
    opt_size, characteristics = struct.unpack_from("<HH", b, pe + 20)
    opt = pe + 24
    magic = struct.unpack_from("<H", b, opt)[0]
    dirs = opt + (96 if magic == 0x10B else 112)
    sections = [struct.unpack_from("<8sIIII", b, opt + opt_size + 40 * i) for i in range(nsec)]

    def at(rva: int) -> int:
        for _, vsize, va, rawsize, raw in sections:
            if va <= rva < va + max(vsize, rawsize):
                return raw + rva - va
        raise ValueError(f"RVA {rva:#x} outside the sections")

    exp_rva, exp_size = struct.unpack_from("<II", b, dirs)
    imp_rva, _ = struct.unpack_from("<II", b, dirs + 8)
    exports: set[str] = set()
    if exp_size:
        e = at(exp_rva)
        n_names, _, names_rva = struct.unpack_from("<III", b, e + 24)
        for i in range(n_names):
            exports.add(_cstr(b, at(struct.unpack_from("<I", b, at(names_rva) + 4 * i)[0])))
    imports: set[str] = set()
    p = at(imp_rva) if imp_rva else None
    while p is not None:
        desc = struct.unpack_from("<5I", b, p)
        if not any(desc):
            break
        imports.add(_cstr(b, at(desc[3])))
        p += 20
    return {"machine": machine, "dll": bool(characteristics & 0x2000), "pe32+": magic == 0x20B,
            "exports": exports, "imports": imports}


# ----------------------------------------------------------------------------- Mach-O


def _uleb(b: bytes, i: int) -> tuple[int, int]:
    r = s = 0
    while True:
        x = b[i]
        i += 1
        r |= (x & 0x7F) << s
        s += 7
        if x < 0x80:
            return r, i


def _export_trie(b: bytes, start: int) -> set[str]:
    out, stack = set(), [(0, "")]
    while stack:
        node, prefix = stack.pop()
        size, i = _uleb(b, start + node)
        if size:  # a terminal node: prefix is an exported name
            out.add(prefix)
        i += size
        n_children, i = b[i], i + 1
        for _ in range(n_children):
            j = b.index(0, i)
            label = b[i:j].decode()
            child, i = _uleb(b, j + 1)
            stack.append((child, prefix + label))
    return out


def macho_slices(b: bytes) -> list[bytes]:
    """The thin images of a Mach-O file (one, or each slice of a universal file)."""
    if b[:4] == b"\xca\xfe\xba\xbe":
        n = struct.unpack_from(">I", b, 4)[0]
        out = []
        for i in range(n):
            _, _, off, size, align = struct.unpack_from(">5I", b, 8 + 20 * i)
            assert off % (1 << align) == 0
            out.append(b[off:off + size])
        return out
    return [b]


def macho_info(b: bytes) -> dict:
    """CPU, file type, exported names (export trie), minimum macOS, dylibs, code signature of a
    thin 64-bit Mach-O image."""
    magic, cpu, _, filetype, ncmds = struct.unpack_from("<IiIII", b, 0)
    assert magic == 0xFEEDFACF, hex(magic)
    info: dict = {"cpu": cpu & 0xFFFFFFFF, "filetype": filetype, "exports": set(), "dylibs": set(),
                  "minos": None, "signed": False}
    i = 32
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", b, i)
        if cmd in (0x22, 0x80000022):  # LC_DYLD_INFO(_ONLY): export_off at +40
            off, n = struct.unpack_from("<II", b, i + 40)
            if n:
                info["exports"] |= _export_trie(b, off)
        elif cmd == 0x80000033:  # LC_DYLD_EXPORTS_TRIE
            off, n = struct.unpack_from("<II", b, i + 8)
            if n:
                info["exports"] |= _export_trie(b, off)
        elif cmd == 0x32:  # LC_BUILD_VERSION
            minos = struct.unpack_from("<I", b, i + 12)[0]
            info["minos"] = (minos >> 16, (minos >> 8) & 0xFF)
        elif cmd in (0xC, 0x80000018):  # LC_LOAD_DYLIB, LC_LOAD_WEAK_DYLIB
            info["dylibs"].add(_cstr(b, i + struct.unpack_from("<I", b, i + 8)[0]))
        elif cmd == 0x1D:  # LC_CODE_SIGNATURE
            info["signed"] = True
        i += size
    return info


# ----------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def all_fmus(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    """One FMU of each FMI version with every platform's binary (zig's cache: ~1-2 s each)."""
    d = tmp_path_factory.mktemp("platforms")
    return {v: build_fmu(v, d / f"{ID}-fmi{v}-all.fmu", platforms="all") for v in (2, 3)}


@pytest.fixture(scope="module")
def unzipped(all_fmus: dict[int, Path],
             tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    out = {}
    for v, fmu in all_fmus.items():
        d = tmp_path_factory.mktemp(f"unz{v}")
        with zipfile.ZipFile(fmu) as z:
            z.extractall(d)
        out[v] = d
    return out


def _read(unzipped: dict[int, Path], version: int, platform: str) -> bytes:
    return (unzipped[version] / FILES[version][platform]).read_bytes()


# ----------------------------------------------------------------------------- contents

CASES = [(v, p) for v in (2, 3) for p in ALL_PLATFORMS]
IDS = [f"fmi{v}-{p}" for v, p in CASES]


@pytest.mark.parametrize("version", [2, 3])
def test_all_platform_fmu_validates_and_holds_every_binary(all_fmus, version):
    assert validate_fmu(str(all_fmus[version])) == []
    names = set(zipfile.ZipFile(all_fmus[version]).namelist())
    binaries = {n for n in names if n.startswith("binaries/")}
    assert binaries == set(FILES[version].values())
    assert not any(n.endswith((".pdb", ".lib", ".a", ".exp")) for n in names)


@pytest.mark.parametrize(("version", "platform"), CASES, ids=IDS)
def test_binary_is_for_its_folder_and_exports_exactly_the_fmi_functions(unzipped, version,
                                                                          platform):
    b = _read(unzipped, version, platform)
    want = fmi_functions(version)
    system = platform.split("-")[1]
    arch = platform.split("-")[0]
    if system == "linux":
        info = elf_info(b)
        assert info["type"] == 3  # ET_DYN
        assert info["machine"] == {"x86_64": 62, "aarch64": 183}[arch]
        assert info["exports"] == want, sorted(info["exports"] ^ want)
    elif system == "windows":
        info = pe_info(b)
        assert info["dll"]
        assert info["machine"] == {"x86_64": 0x8664, "x86": 0x14C}[arch]
        assert info["pe32+"] == (arch == "x86_64")
        assert info["exports"] == want, sorted(info["exports"] ^ want)
    else:
        cpu = {"x86_64": 0x01000007, "aarch64": 0x0100000C}[arch]
        (image,) = [s for s in macho_slices(b) if macho_info(s)["cpu"] == cpu]
        info = macho_info(image)
        assert info["filetype"] == 6  # MH_DYLIB
        exported = info["exports"] - MACHO_LINKER_SYMBOLS
        assert exported == {"_" + n for n in want}, sorted(exported ^ {"_" + n for n in want})


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("platform", ["x86_64-linux", "aarch64-linux"])
def test_linux_binaries_need_nothing_newer_than_glibc_2_17(unzipped, version, platform):
    info = elf_info(_read(unzipped, version, platform))
    assert info["needed"] <= {"libc.so.6", "libm.so.6"}, info["needed"]
    glibc = [tuple(int(x) for x in v[6:].split(".")) for v in info["versions"]]
    assert info["versions"] and all(v.startswith("GLIBC_") for v in info["versions"])
    assert max(glibc) <= (2, 17), sorted(info["versions"])


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("platform", ["x86_64-windows", "x86-windows"])
def test_windows_dlls_import_only_system_dlls(unzipped, version, platform):
    """No MinGW runtime DLL (libgcc_s, libwinpthread): the Universal CRT and kernel32 only."""
    imports = {n.lower() for n in pe_info(_read(unzipped, version, platform))["imports"]}
    assert "kernel32.dll" in imports
    assert all(n == "kernel32.dll" or n.startswith("api-ms-win-crt-") for n in imports), imports


def test_macos_binaries_minimum_versions_and_signature(unzipped):
    want = {0x01000007: (10, 15), 0x0100000C: (11, 0)}
    for platform in ("x86_64-darwin", "aarch64-darwin"):
        (info,) = [macho_info(s) for s in macho_slices(_read(unzipped, 3, platform))]
        assert info["minos"] == want[info["cpu"]]
        assert info["dylibs"] == {"/usr/lib/libSystem.B.dylib"}
        if info["cpu"] == 0x0100000C:
            assert info["signed"], "arm64 code must carry (ad-hoc) a code signature"
    # FMI 2: one universal darwin64 library, both slices as in the FMI 3 FMU
    slices = macho_slices(_read(unzipped, 2, "x86_64-darwin"))
    assert sorted(macho_info(s)["cpu"] for s in slices) == [0x01000007, 0x0100000C]
    assert {macho_info(s)["minos"] for s in slices} == {(10, 15), (11, 0)}


# ----------------------------------------------------------------------------- choosing


def test_resolve_platforms():
    host = host_platform()
    assert resolve_platforms("host") == (host,)
    assert resolve_platforms("all") == ALL_PLATFORMS == (
        "x86_64-windows", "x86-windows", "x86_64-linux", "aarch64-linux", "x86_64-darwin",
        "aarch64-darwin")
    assert resolve_platforms("aarch64-darwin, x86_64-windows") == ("x86_64-windows",
                                                                    "aarch64-darwin")
    assert set(resolve_platforms("host,x86-windows")) == {host, "x86-windows"}
    assert resolve_platforms(["x86-windows", "x86-windows"]) == ("x86-windows",)
    for bad in ("", "win64", "x86_64-windows,nope"):
        with pytest.raises(BuildError, match="platform"):
            resolve_platforms(bad)


def _fake_compiler(tmp_path: Path, name: str, says: str, target: str) -> Path:
    """A 'compiler' that answers -dumpmachine with ``says`` and compiles with zig for
    ``target``: stands for a cross gcc such as x86_64-w64-mingw32-gcc."""
    script = tmp_path / name
    zig = " ".join(f"'{a}'" for a in zig_command())
    script.write_text(f"""#!/bin/sh
if [ "$1" = "-dumpmachine" ]; then echo {says}; exit 0; fi
exec {zig} -target {target} "$@"
""")
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    return script


def test_a_cross_compiler_fills_its_own_platform_folder(tmp_path):
    """The issue's case: `--cc x86_64-w64-mingw32-gcc` once wrote a DLL as the Linux .so."""
    cc = _fake_compiler(tmp_path, "x86_64-w64-mingw32-gcc", "x86_64-w64-mingw32",
                        "x86_64-windows-gnu")
    fmu = build_fmu(3, tmp_path / "w.fmu", platforms="x86_64-windows,host", cc=str(cc))
    with zipfile.ZipFile(fmu) as z:
        dll = z.read(FMI3_FILES["x86_64-windows"])
        so = z.read(FMI3_FILES[host_platform()])
    assert pe_info(dll)["exports"] == fmi_functions(3)
    assert so[:4] == b"\x7fELF"
    # the host binary is zig's, not the cross compiler's
    assert "clang" in elf_info(so)["comment"]
    # only the host asked for: the cross compiler has no platform to build
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "build", "--fmi-version", "3",
                           "--platforms", "host", "--cc", str(cc), "-o", str(tmp_path / "h.fmu")],
                          capture_output=True, text=True)
    assert proc.returncode == 1
    assert "builds for x86_64-windows, which is not among the platforms" in proc.stderr
    assert not (tmp_path / "h.fmu").exists()


def test_a_compiler_that_builds_for_another_platform_than_it_says_is_refused(tmp_path):
    cc = _fake_compiler(tmp_path, "liar-gcc", "x86_64-linux-gnu", "x86_64-windows-gnu")
    if host_platform() != "x86_64-linux":
        pytest.skip("the liar claims to build for x86_64-linux, this host")
    with pytest.raises(BuildError, match="built a library for x86_64-windows, not for "
                                         "x86_64-linux"):
        build_fmu(2, tmp_path / "x.fmu", platforms="host", cc=str(cc))
    assert not (tmp_path / "x.fmu").exists()


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not installed")
def test_host_gcc_builds_the_host_binary_the_rest_from_zig(tmp_path):
    host = host_platform()
    fmu = build_fmu(2, tmp_path / "g.fmu", platforms=[host, "x86-windows"], cc="gcc")
    assert validate_fmu(str(fmu)) == []
    with zipfile.ZipFile(fmu) as z:
        names = {n for n in z.namelist() if n.startswith("binaries/")}
        assert names == {FMI2_FILES[host], FMI2_FILES["x86-windows"]}
        if host.endswith("linux"):
            assert "GCC:" in elf_info(z.read(FMI2_FILES[host]))["comment"]


def test_cli_builds_every_platform_by_default(tmp_path):
    out = tmp_path / "g2.fmu"
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "build", "--fmi-version", "2",
                           "-o", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "binaries for " + ", ".join(ALL_PLATFORMS) in proc.stdout
    names = {n for n in zipfile.ZipFile(out).namelist() if n.startswith("binaries/")}
    assert names == set(FMI2_FILES.values())
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "build", "--fmi-version", "2",
                           "--platforms", "mars-linux", "-o", str(out)], capture_output=True,
                          text=True)
    assert proc.returncode == 1 and "unknown platform 'mars-linux'" in proc.stderr


# ----------------------------------------------------------------------------- running them

WINE64 = shutil.which("wine64") or next(
    (p for p in ("/usr/lib/wine/wine64", "/usr/lib64/wine/wine64") if os.access(p, os.X_OK)), None)
WINE32 = next((p for p in ("/usr/lib/wine/wine", "/usr/lib/i386-linux-gnu/wine/wine")
               if os.access(p, os.X_OK)), None)
QEMU_AARCH64 = shutil.which("qemu-aarch64") or shutil.which("qemu-aarch64-static")
AARCH64_SYSROOT = next((p for p in ("/usr/aarch64-linux-gnu",)
                        if Path(p, "lib", "ld-linux-aarch64.so.1").exists()), None)
INSTALL = "apt-get install wine64 qemu-user libc6-arm64-cross (docs/platforms.md)"


def _runner(platform: str) -> list[str]:
    """Command prefix that runs a program of ``platform`` here; skips when there is none."""
    if platform == host_platform():
        return []
    if platform == "x86_64-windows":
        if WINE64 is None:
            pytest.skip(f"wine64 is not installed: {INSTALL}")
        return [WINE64]
    if platform == "x86-windows":
        if WINE32 is None:
            pytest.skip("32-bit wine is not installed: dpkg --add-architecture i386 && "
                        "apt-get update && apt-get install wine32:i386 (docs/platforms.md)")
        return [WINE32]
    if platform == "aarch64-linux":
        if QEMU_AARCH64 is None:
            pytest.skip(f"qemu-aarch64 (qemu-user) is not installed: {INSTALL}")
        if AARCH64_SYSROOT is None:
            pytest.skip(f"no aarch64 glibc for qemu-aarch64 -L: {INSTALL}")
        return [QEMU_AARCH64, "-L", AARCH64_SYSROOT]
    pytest.skip(f"no emulator for {platform} on this machine")


@pytest.fixture(scope="module")
def drivers(tmp_path_factory: pytest.TempPathFactory):
    """Build tests/c/platform_driver.c for a platform with zig (once per platform)."""
    d = tmp_path_factory.mktemp("drivers")
    built: dict[str, Path] = {}

    def get(platform: str) -> Path:
        if platform not in built:
            p = PLATFORMS[platform]
            exe = d / (platform + (".exe" if p.extension == ".dll" else ""))
            cmd = [*zig_command(), "-target", p.zig_target, "-std=c99", "-O2", "-Wall",
                   "-Wextra", "-Wpedantic", "-Werror", "-Wno-strict-prototypes",
                   f"-I{fmi_include_dir()}", f"-I{fmu_src_dir()}", str(DRIVER), "-o", str(exe)]
            if p.extension == ".so":
                cmd.append("-ldl")  # glibc 2.17: dlopen lives in libdl
            proc = subprocess.run(cmd, capture_output=True, text=True)
            assert proc.returncode == 0, proc.stderr
            built[platform] = exe
        return built[platform]

    return get


def _wine_env() -> dict[str, str]:
    """A wine prefix kept between runs (the first start of a prefix takes ~15 s)."""
    env = dict(os.environ, WINEDEBUG="-all")
    env["WINEPREFIX"] = str(Path(tempfile.gettempdir()) / f"djl-fmu-wine-{os.getuid()}")
    return env


def run_driver(drivers, platform: str, version: int, library: Path,
               steps: int = 1000) -> np.ndarray:
    """Run the default move through the driver of ``platform``: rows of t, x, v, a, j, done."""
    prefix = _runner(platform)
    env = _wine_env() if platform.endswith("windows") else None
    proc = subprocess.run([*prefix, str(drivers(platform)), str(version), str(library),
                           str(steps)], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    rows = np.array([[float(x) for x in line.split()] for line in proc.stdout.splitlines()
                     if line.strip()])
    assert rows.shape == (steps + 1, 6), (rows.shape, proc.stderr[-2000:])
    return rows


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("platform", ["x86_64-windows", "x86-windows", "aarch64-linux"])
def test_emulated_binary_gives_the_host_outputs(unzipped, drivers, version, platform):
    """Each foreign binary runs the default move (1 s at 1 ms) like the host's binary."""
    host = host_platform()
    ref = run_driver(drivers, host, version, unzipped[version] / FILES[version][host])
    got = run_driver(drivers, platform, version, unzipped[version] / FILES[version][platform])
    assert ref[-1, 5] == 1.0, "the default move ends within the default experiment"
    np.testing.assert_array_equal(got[:, 0], ref[:, 0])
    np.testing.assert_array_equal(got[:, 5], ref[:, 5])
    # bit for bit here, and no binary takes math from its platform's libm (fmu_src/djl_math.h);
    # the tolerance stays for the platforms not run here
    np.testing.assert_allclose(got[:, 1:5], ref[:, 1:5], rtol=1e-12, atol=1e-15)


# ----------------------------------------------------------------------------- sources/


@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_rebuild_from_sources_loads_from_a_c_program(unzipped, drivers, tmp_path, version):
    """`fmpy compile` route (CMake over sources/), then dlopen(RTLD_NOW) from a C program.

    fmpy 0.3.32's CMake links no libm (and reads no <Library> of a build description): the
    rebuilt library loads only because the C sources call no libm function
    (fmu_src/djl_math.h, tests/test_math_nolibm.py).
    """
    if host_platform() != "x86_64-linux":
        pytest.skip("checks the Linux rebuild")
    if shutil.which("cmake") is None:
        pytest.skip("cmake not available (PyPI cmake, a dependency of fmpy)")
    from fmpy.build import build_platform_binary

    unzip = tmp_path / "unz"
    shutil.copytree(unzipped[version], unzip)
    lib = unzip / FILES[version]["x86_64-linux"]
    lib.unlink()
    (tmp_path / "build").mkdir()
    build_platform_binary(unzip, build_dir=tmp_path / "build")
    assert lib.is_file()
    rebuilt = run_driver(drivers, "x86_64-linux", version, lib, steps=50)
    shipped = run_driver(drivers, "x86_64-linux", version,
                         unzipped[version] / FILES[version]["x86_64-linux"], steps=50)
    np.testing.assert_allclose(rebuilt, shipped, rtol=1e-12, atol=1e-15)
