"""Build the generator FMU (FMI 2.0 or 3.0, co-simulation) with gcc.

The FMU carries the binary for this platform and the C sources from which any
importer (``fmpy compile``) can rebuild it.  The FMI headers are the ones that
ship with fmpy (``fmpy/c-code``): nothing third-party is copied into the
repository or into the FMU.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

from .._resources import fmu_src_dir, modeldesc_dir
from . import codegen, spec

CFLAGS = ("-std=c99", "-O2", "-fPIC", "-fvisibility=hidden", "-Wall", "-Wextra", "-Wpedantic",
          "-Werror")
LDFLAGS = ("-shared", "-lm")


class BuildError(RuntimeError):
    """The compiler failed, or the sources are incomplete."""


def fmi_include_dir() -> Path:
    """Directory of the FMI 2 / FMI 3 headers shipped with fmpy."""
    import fmpy

    d = Path(fmpy.__file__).resolve().parent / "c-code"
    if not (d / "fmi2Functions.h").is_file() or not (d / "fmi3Functions.h").is_file():
        raise BuildError(f"FMI headers not found in {d} (is fmpy installed?)")
    return d


def binary_dir(fmi_version: int) -> str:
    """Platform folder of the binary inside the FMU (``linux64`` / ``x86_64-linux`` here)."""
    import fmpy

    return fmpy.platform if fmi_version == 2 else fmpy.platform_tuple


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


def check_compiler(cc: str = "gcc") -> str:
    """Full path of the C compiler ``cc``.

    Raises
    ------
    BuildError
        If it is not on ``PATH``: the message says gcc is needed to build the FMU.
    """
    found = shutil.which(cc)
    if found is None:
        raise BuildError(f"the C compiler {cc!r} is needed to build the generator FMU and was "
                         f"not found on PATH: install gcc (e.g. apt-get install gcc), or give "
                         f"an FMU file built elsewhere (--fmu / simulation.fmu)")
    return found


def compile_binary(fmi_version: int, out: Path, *, cc: str = "gcc",
                   extra_cflags: tuple[str, ...] = ()) -> Path:
    """Compile the shared library of the FMU into ``out``."""
    files = [f for f in source_files(fmi_version) if f.suffix == ".c"]
    cmd = [cc, *CFLAGS, *extra_cflags, f"-I{fmi_include_dir()}", f"-I{fmu_src_dir()}",
           *map(str, files), "-o", str(out), *LDFLAGS]
    check_compiler(cc)
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError as e:
        raise BuildError(f"the C compiler {cc!r} is needed to build the generator FMU and was "
                         f"not found: install gcc") from e
    except OSError as e:
        raise BuildError(f"cannot run the C compiler {cc!r}: {e}") from e
    if proc.returncode != 0:
        raise BuildError(f"compilation failed ({' '.join(cmd)}):\n{proc.stderr}")
    return out


def build_fmu(fmi_version: int, out_path: str | os.PathLike, *, cc: str = "gcc",
              extra_cflags: tuple[str, ...] = ()) -> Path:
    """Write a complete co-simulation FMU to ``out_path``.

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI version of the FMU.
    out_path : path-like
        Destination ``.fmu`` file (parent folders are created).
    cc : str
        C compiler.
    extra_cflags : tuple of str
        Extra compiler flags (e.g. sanitizers).

    Returns
    -------
    pathlib.Path
        ``out_path``.
    """
    _check_version(fmi_version)
    check_compiler(cc)  # before creating anything
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="djl-fmu-build-") as tmp:
        root = Path(tmp) / "fmu"
        (root / "sources").mkdir(parents=True)
        (root / "binaries" / binary_dir(fmi_version)).mkdir(parents=True)
        (root / "documentation").mkdir()
        shutil.copyfile(model_description(fmi_version), root / "modelDescription.xml")
        for f in source_files(fmi_version):
            shutil.copyfile(f, root / "sources" / f.name)
        if fmi_version == 3:
            shutil.copyfile(modeldesc_dir() / "fmi3" / "buildDescription.xml",
                            root / "sources" / "buildDescription.xml")
        import fmpy

        lib = root / "binaries" / binary_dir(fmi_version) / (
            spec.MODEL_IDENTIFIER + fmpy.sharedLibraryExtension)
        compile_binary(fmi_version, lib, cc=cc, extra_cflags=extra_cflags)
        (root / "documentation" / "index.html").write_text(_documentation(fmi_version))
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


def _documentation(fmi_version: int) -> str:
    rows = "\n".join(
        f"<tr><td><code>{v.name}</code>{'[' + str(v.size) + ']' if v.size > 1 else ''}</td>"
        f"<td>{v.causality}</td><td>{v.type}</td><td>{v.unit or '-'}</td>"
        f"<td>{'' if v.start is None else v.start}</td><td>{v.description}</td></tr>"
        for v in spec.VARIABLES
    )
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{spec.MODEL_NAME}</title></head>
<body>
<h1>{spec.MODEL_NAME} (FMI {fmi_version}.0, co-simulation)</h1>
<p>{codegen.DESCRIPTION}</p>
<p>Any communication step h &gt; 0 is accepted. Outputs at a communication point are the exact
values of the planned profile at that time (x, v, a of the piecewise cubic; j and a_al of the
sampling interval of <code>Te</code> that contains it); a step that is a whole multiple of
<code>Te</code> gives the samples themselves.</p>
<table border="1" cellpadding="3">
<tr><th>name</th><th>causality</th><th>type</th><th>unit</th><th>start</th><th>meaning</th></tr>
{rows}
</table>
</body></html>
"""


def _sources_digest(fmi_version: int, cc: str, extra_cflags: tuple[str, ...]) -> str:
    h = hashlib.sha256()
    for f in [*source_files(fmi_version), model_description(fmi_version)]:
        h.update(f.name.encode())
        h.update(f.read_bytes())
    h.update(" ".join((cc, *CFLAGS, *extra_cflags, *LDFLAGS)).encode())
    return h.hexdigest()[:16]


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

    Builds are cached by a digest of the sources, model description and flags,
    so editing the C code rebuilds automatically.
    """
    digest = _sources_digest(fmi_version, cc, extra_cflags)
    path = cache_dir() / f"{spec.MODEL_IDENTIFIER}-fmi{fmi_version}-{digest}.fmu"
    if not path.is_file():
        check_compiler(cc)  # before creating anything
        build_fmu(fmi_version, path, cc=cc, extra_cflags=extra_cflags)
    return path
