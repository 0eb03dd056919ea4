"""``djl-fmu build`` without the optional cross compiler (ziglang, the ``[platforms]`` extra),
and its progress lines with it."""

from __future__ import annotations

import importlib.util
import shutil
import zipfile

import pytest
from fmpy.validation import validate_fmu

from harness.cli import main
from harness.fmu import build
from harness.fmu.runner import generate

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not installed")


@pytest.fixture
def no_zig(monkeypatch):
    """ziglang not installed, as far as anything asks (importlib's finder says no)."""
    real = importlib.util.find_spec

    def find_spec(name, *args, **kwargs):
        if name == "ziglang" or name.startswith("ziglang."):
            return None
        return real(name, *args, **kwargs)

    monkeypatch.setattr(importlib.util, "find_spec", find_spec)
    assert not build.zig_available()


def test_build_without_zig_makes_the_host_binary_and_says_how_to_get_six(no_zig, tmp_path,
                                                                         capsys, monkeypatch):
    monkeypatch.delenv("CC", raising=False)
    out = tmp_path / "g.fmu"
    assert main(["build", "--fmi-version", "2", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    host = build.host_platform()
    assert f"for {host} (gcc)" in text
    assert f"{host}: built by gcc in" in text
    assert f"binaries for {host})" in text
    assert "pip install '.[platforms]'" in text
    assert "first build" not in text  # no zig, nothing to announce
    names = zipfile.ZipFile(out).namelist()
    assert [n for n in names if n.startswith("binaries/")] == [build.binary_path(2)]
    assert validate_fmu(str(out)) == []
    tr = generate({"profile": 3, "distance": 0.2}, fmu=out)
    assert tr.x[-1] == pytest.approx(0.2, abs=1e-12)


def test_without_zig_other_platforms_are_refused_with_the_hint(no_zig, tmp_path, capsys):
    out = tmp_path / "g.fmu"
    assert main(["build", "--fmi-version", "3", "--platforms", "all", "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "x86_64-windows" in err and "pip install '.[platforms]'" in err
    assert not out.exists()


def test_help_says_the_default_that_applies(no_zig, capsys):
    with pytest.raises(SystemExit):
        main(["build", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "default: all when ziglang is installed, else host; here: host" in text


def test_quiet_build_prints_only_the_result(no_zig, tmp_path, capsys):
    out = tmp_path / "g.fmu"
    assert main(["build", "--fmi-version", "3", "-q", "-o", str(out)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("wrote ") and len(lines) == 2  # the result and the hint


def test_host_compiler_order(monkeypatch, tmp_path):
    monkeypatch.setenv("CC", "no-such-compiler-here")
    assert build.host_compiler() == "gcc"  # $CC not found: the next one
    monkeypatch.setenv("CC", "gcc")
    assert build.host_compiler() == "gcc"
    monkeypatch.setenv("PATH", str(tmp_path))  # an empty folder: no compiler at all
    with pytest.raises(build.BuildError, match=r"no C compiler found.*\[platforms\]"):
        build.host_compiler()


def test_with_zig_each_platform_reports_and_a_first_build_is_announced(tmp_path, monkeypatch):
    pytest.importorskip("ziglang")
    monkeypatch.setenv("DJL_FMU_CACHE", str(tmp_path / "cache"))  # no marker yet
    lines: list[str] = []
    plats = "x86_64-linux,aarch64-linux"
    build.build_fmu(2, tmp_path / "a.fmu", platforms=plats, progress=lines.append)
    assert "first build here for x86_64-linux, aarch64-linux" in lines[0]
    assert "C runtime" in lines[0]
    assert sorted(ln.split(":")[0].strip() for ln in lines[1:]) == ["aarch64-linux",
                                                                    "x86_64-linux"]
    assert all("built by zig in" in ln for ln in lines[1:])
    again: list[str] = []
    build.build_fmu(2, tmp_path / "b.fmu", platforms=plats, progress=again.append)
    assert len(again) == 2 and not any("first build" in ln for ln in again)
