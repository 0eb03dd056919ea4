"""The FMU as a file: validation, contents, exported symbols, rebuild from sources, CLI."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from harness.fmu import codegen, spec
from harness.fmu.runner import generate

PLATFORM_DIR = {2: "binaries/linux64", 3: "binaries/x86_64-linux"}


@pytest.mark.parametrize("version", [2, 3])
def test_validates_without_problems(fmus, version):
    assert validate_fmu(str(fmus[version])) == []


@pytest.mark.parametrize("version", [2, 3])
def test_contents(fmus, version):
    names = set(zipfile.ZipFile(fmus[version]).namelist())
    assert "modelDescription.xml" in names
    assert f"{PLATFORM_DIR[version]}/JerkLimitedTrajectory.so" in names
    srcs = {f"sources/{f}" for f in codegen.SOURCES[version] + codegen.HEADERS}
    assert srcs <= names
    if version == 3:
        assert "sources/buildDescription.xml" in names
    # nothing third-party: no FMI headers shipped
    assert not any(re.search(r"fmi[23]\w*\.h$", n) for n in names)


@pytest.mark.parametrize("version", [2, 3])
def test_model_description_declares_capabilities(fmus, version):
    md = read_model_description(str(fmus[version]))
    cs = md.coSimulation
    assert cs.modelIdentifier == "JerkLimitedTrajectory"
    assert cs.canHandleVariableCommunicationStepSize
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    if version == 3:
        # Te is a parameter and any step is exact: no fixed internal step is declared, and
        # fmpy's default communication step comes from the DefaultExperiment
        assert cs.fixedInternalStepSize is None
        assert float(md.defaultExperiment.stepSize) == pytest.approx(spec.DEFAULT_TE)
    assert md.guid == spec.INSTANTIATION_TOKEN
    declared = {getattr(c, "name", c) for c in md.logCategories}
    assert declared == {c for c, _ in spec.LOG_CATEGORIES}
    # the contract: names, causality, variability, type, unit
    by = {v.name: v for v in md.modelVariables}
    want = {"profile": ("parameter", None), "Te": ("parameter", "s"),
            "t_start": ("parameter", "s"), "x0": ("parameter", "m"),
            "distance": ("parameter", "m"), "v_max": ("parameter", "m/s"),
            "a_max": ("parameter", "m/s2"), "d_max": ("parameter", "m/s2"),
            "T_F1": ("parameter", "s"), "T_F2": ("parameter", "s"), "T_F3": ("parameter", "s"),
            "T_F4": ("parameter", "s"), "x": ("output", "m"), "v": ("output", "m/s"),
            "a": ("output", "m/s2"), "j": ("output", "m/s3"), "done": ("output", None)}
    for name, (causality, unit) in want.items():
        v = by[name]
        assert v.causality == causality, name
        if causality == "parameter":
            assert v.variability == "fixed", name
        if unit:
            assert v.unit == unit, name
    assert by["done"].type == "Boolean"
    # issue #11: enumerations, declared types with quantities and display units, bounds
    assert by["profile"].type == by["short_stage"].type == "Enumeration"
    items = {t.name: [(i.name, int(i.value)) for i in t.items]
             for t in md.typeDefinitions if t.type == "Enumeration"}
    assert items == {"Profile": [("AL", 1), ("JL", 2), ("DJL", 3), ("table", 4)],
                     "ShortStage": [("stretch", 1), ("overlap", 2)],
                     "JerkSource": [("parameters", 1), ("f_mode", 2), ("f_mode_ahead", 3)],
                     "Shaper": [("none", 0), ("ZV", 1), ("ZVD", 2), ("EI", 3), ("custom", 4)],
                     "ShaperSource": [("f_shaper", 1), ("f_mode", 2)],
                     # issue 34: 0 = the parameter's value
                     "CmdProfile": [("parameter", 0), ("AL", 1), ("JL", 2), ("DJL", 3)],
                     "CmdShaper": [("parameter", 0), ("ZV", 1), ("ZVD", 2), ("EI", 3),
                                   ("custom", 4), ("none", 5)],
                     # issue 34, items 2 and 4
                     "BufferMode": [("aborting", 0), ("buffered", 1), ("blending", 2)]}
    assert by["profile"].declaredType.name == "Profile"
    assert by["cmd_profile"].declaredType.name == "CmdProfile"
    display = {u.name: {d.name: d.factor for d in u.displayUnits} for u in md.unitDefinitions}
    quantity = {"m": ("Position", "mm"), "m/s": ("Velocity", "mm/s"),
                "m/s2": ("Acceleration", "mm/s2"), "m/s3": ("Jerk", "mm/s3"),
                "s": ("Time", "ms")}
    for v in md.modelVariables:
        if v.type in ("Real", "Float64") and v.causality != "independent":
            if v.unit == "Hz":  # f_mode: a frequency, displayed in Hz
                assert v.declaredType.quantity == "Frequency", v.name
                continue
            if v.unit is None:  # dimensionless: zeta_shaper, (cmd_)shaper_amplitude
                assert v.name.startswith(("zeta_shaper", "shaper_amplitude",
                                          "cmd_shaper_amplitude")), v.name
                continue
            q, disp = quantity[v.unit]
            assert v.declaredType is not None and v.declaredType.quantity == q, v.name
            assert v.declaredType.displayUnit == disp, v.name
            assert float(display[v.unit][disp]) == 1000.0
    bounds = {"profile": (1, 4), "short_stage": (1, 2), "n_segments": (0, spec.MAX_SEGMENTS),
              "Te": (0.0, spec.MAX_TE), "x0": (-spec.MAX_POSITION, spec.MAX_POSITION),
              "distance": (-spec.MAX_POSITION, spec.MAX_POSITION)}
    for name, (lo, hi) in bounds.items():
        assert float(by[name].min) == lo and float(by[name].max) == hi, name
    for name in ("v_max", "a_max", "d_max", "T_F1", "T_F2", "T_F3", "T_F4"):
        assert float(by[name].min) == 0.0, name
    # every parameter's start lies within its declared bounds
    for v in md.modelVariables:
        if v.causality == "parameter" and v.start is not None and v.type != "Boolean":
            for x in str(v.start).split():
                assert v.min is None or float(v.min) <= float(x), v.name
                assert v.max is None or float(x) <= float(v.max), v.name
    # issue #12: the inputs, with their declared start values
    inputs = {v.name: v for v in md.modelVariables if v.causality == "input"}
    assert set(inputs) == {"target", "execute", "stop", "f_mode"} | {
        n for n in inputs if n.startswith("cmd_")} | {  # issue 34's per-command values
        "buffer_mode", "min_duration"} | (  # issue 34's buffer modes and synchronisation
        {"buffer_mode_code"} if version == 2 else set())
    assert {n.split("[")[0] for n in inputs if n.startswith("cmd_")} == {
        "cmd_v_max", "cmd_a_max", "cmd_d_max", "cmd_profile", "cmd_T_F", "cmd_shaper",
        "cmd_shaper_n", "cmd_shaper_amplitude", "cmd_shaper_delay"} | (
        {"cmd_profile_code", "cmd_shaper_code"} if version == 2 else set())
    assert inputs["execute"].type == inputs["stop"].type == "Boolean"
    assert inputs["target"].unit == "m" and inputs["f_mode"].unit == "Hz"
    assert inputs["min_duration"].unit == "s"
    assert inputs["buffer_mode"].declaredType.name == "BufferMode"
    for name, typ in (("active", "Boolean"), ("command_aborted", "Boolean"),
                      ("queue_length", "Integer"), ("time_to_rest", "Real")):
        assert by[name].causality == "output" and by[name].type in (typ, "Int32", "Float64")
    assert by["jerk_source"].declaredType.name == "JerkSource"
    assert by["busy"].type == "Boolean" and by["stage"].causality == "output"
    # ModelStructure: every output, without direct feedthrough (no states; an input acts
    # from the next step: tests/test_fmu_importers.py)
    outs = md.outputs
    assert {u.variable.name for u in outs} == {v.name for v in md.modelVariables
                                               if v.causality == "output"}
    assert all(u.dependencies == [] for u in outs)
    assert {u.variable.name for u in md.initialUnknowns} >= {"motion_time", "N_F1", "x"}


@pytest.mark.parametrize("version", [2, 3])
def test_display_units_and_enumerations_through_fmpy(fmus, version):
    """A user sets a distance in mm and a profile by its enumeration value, as tools do."""
    from fmpy import simulate_fmu

    res = simulate_fmu(str(fmus[version]), stop_time=1.2,
                       start_values={"distance": (250.0, "mm"), "v_max": (800.0, "mm/s"),
                                     "profile": 2, "T_F1": (40.0, "ms")},
                       output=["x", "v"])
    assert res["x"][-1] == pytest.approx(0.25, rel=1e-9)
    assert max(res["v"]) <= 0.8 * (1 + 1e-12)


@pytest.mark.parametrize("version", [2, 3])
def test_only_fmi_functions_are_exported(fmus, version, tmp_path):
    if shutil.which("nm") is None:
        pytest.skip("nm not available")
    with zipfile.ZipFile(fmus[version]) as z:
        z.extract(f"{PLATFORM_DIR[version]}/JerkLimitedTrajectory.so", tmp_path)
    lib = tmp_path / PLATFORM_DIR[version] / "JerkLimitedTrajectory.so"
    out = subprocess.run(["nm", "-D", "--defined-only", str(lib)], capture_output=True,
                         text=True, check=True).stdout
    names = [line.split()[-1] for line in out.splitlines() if line.strip()]
    assert names, "no exported symbol at all"
    assert all(n.startswith(f"fmi{version}") for n in names), [
        n for n in names if not n.startswith(f"fmi{version}")]
    for required in ("DoStep", "Instantiate" if version == 2 else "InstantiateCoSimulation",
                     "GetFMUstate" if version == 2 else "GetFMUState",
                     "SerializeFMUstate" if version == 2 else "SerializeFMUState"):
        assert f"fmi{version}{required}" in names


@pytest.mark.parametrize("version", [2, 3])
def test_rebuild_from_sources_with_fmpy(fmus, version, tmp_path):
    """`fmpy compile` route: CMake over the FMU's sources/, then identical outputs."""
    if shutil.which("cmake") is None:
        try:
            import cmake  # noqa: F401  (PyPI cmake, a dependency of fmpy)
        except ImportError:
            pytest.skip("cmake not available")
    from fmpy import extract
    from fmpy.build import build_platform_binary

    unzip = Path(extract(str(fmus[version]), unzipdir=str(tmp_path / "unz")))
    lib = unzip / PLATFORM_DIR[version] / "JerkLimitedTrajectory.so"
    lib.unlink()
    (tmp_path / "build").mkdir()
    build_platform_binary(unzip, build_dir=tmp_path / "build")
    assert lib.is_file()
    if shutil.which("nm"):
        # CMake builds without -fvisibility=hidden: the headers' pragmas keep the core hidden
        out = subprocess.run(["nm", "-D", "--defined-only", str(lib)], capture_output=True,
                             text=True, check=True).stdout
        names = [line.split()[-1] for line in out.splitlines() if line.strip()]
        assert names and all(n.startswith(f"fmi{version}") for n in names), names
    rebuilt = tmp_path / f"rebuilt{version}.fmu"
    with zipfile.ZipFile(rebuilt, "w") as z:
        for p in sorted(unzip.rglob("*")):
            if p.is_file():
                z.write(p, p.relative_to(unzip).as_posix())
    assert validate_fmu(str(rebuilt)) == []
    params = {"profile": 3, "distance": 0.25, "T_F2": 0.1}
    a = generate(params, fmu=fmus[version])
    b = generate(params, fmu=rebuilt)
    for name in ("x", "v", "a", "j", "done"):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-14, atol=1e-15)


def test_cli_build_writes_a_valid_fmu(tmp_path):
    out = tmp_path / "sub" / "g3.fmu"
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "build", "--fmi-version", "3",
                           "-o", str(out)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "validated" in proc.stdout
    assert validate_fmu(str(out)) == []


def test_cli_build_to_an_unwritable_place(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "build", "--fmi-version", "2",
                           "-o", str(blocker / "x.fmu")], capture_output=True, text=True)
    assert proc.returncode == 1
    assert "cannot write" in proc.stderr and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == [blocker]


def test_cli_build_refuses_bad_version(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "build", "--fmi-version", "4",
                           "-o", str(tmp_path / "x.fmu")], capture_output=True, text=True)
    assert proc.returncode != 0
    assert "invalid choice" in proc.stderr
    assert not (tmp_path / "x.fmu").exists()


def test_cli_help_explains_commands():
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "--help"], capture_output=True,
                          text=True)
    assert proc.returncode == 0
    assert "build" in proc.stdout and "demo" in proc.stdout
    proc = subprocess.run([sys.executable, "-m", "harness.cli", "build", "--help"],
                          capture_output=True, text=True)
    assert "--fmi-version" in proc.stdout and "sources/" in proc.stdout


@pytest.mark.parametrize("version", [2, 3])
def test_model_description_carries_the_generation_date(fmus, version):
    import datetime as dt

    from fmpy import read_model_description

    md = read_model_description(str(fmus[version]))
    stamp = md.generationDateAndTime
    assert stamp is not None and re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", stamp), stamp
    when = dt.datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=dt.timezone.utc)
    assert abs((dt.datetime.now(dt.timezone.utc) - when).total_seconds()) < 24 * 3600
    assert validate_fmu(str(fmus[version])) == []


def test_source_date_epoch_fixes_the_generation_date(monkeypatch):
    from harness.fmu.build import stamped_model_description

    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    assert 'generationDateAndTime="2023-11-14T22:13:20Z"' in stamped_model_description(3)
