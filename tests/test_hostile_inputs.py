"""Issue #10 item 9: a user's bad input is a one-line error (exit 2) or a failure (exit 1),
never a traceback or a silent wrong result; nothing is written."""

from __future__ import annotations

import gc
import os
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import pytest

from harness.cli import main
from harness.scenario import ScenarioError, load_scenario

from _scenarios import SMALL_AXIS

BASE = """\
name = "hostile"

""" + SMALL_AXIS

BIG = "1" + "0" * 400


def _write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def _refused(path: Path, key: str) -> str:
    with pytest.raises(ScenarioError) as ei:
        load_scenario(path)
    msg = str(ei.value)
    assert str(path) in msg and key in msg and "\n" not in msg
    return msg


# ------------------------------------------------------------ 1. encoding, huge integers

def test_not_utf8_is_a_scenario_error(tmp_path, capsys):
    p = tmp_path / "latin.toml"
    p.write_bytes(BASE.replace("hostile", "h\xe9").encode("latin-1"))
    with pytest.raises(ScenarioError, match="not UTF-8"):
        load_scenario(p)
    out = tmp_path / "out"
    assert main(["simulate", str(p), "-o", str(out)]) == 2
    assert "UTF-8" in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize("text, key", [
    (BASE.replace("distance = 0.3\nv_max", f"distance = {BIG}\nv_max"), "move.distance"),
    (BASE + f"\n[sweep]\ndistance = [0.1, {BIG}]\n", "sweep.distance"),
    (BASE + f"\n[sweep]\nv_max = [{BIG}]\n", "sweep.v_max"),
    (BASE.replace("[simulation]", f"[simulation]\nfmi_version = {BIG}"),
     "simulation.fmi_version"),
], ids=["distance", "sweep-distance", "sweep-v_max", "fmi_version"])
def test_400_digit_integer_names_the_key(tmp_path, text, key):
    msg = _refused(_write(tmp_path, text), key)
    assert len(msg) < 400  # the integer is not echoed in full


# ------------------------------------------------------------ 2. strict FMU parameters

@pytest.mark.parametrize("params, name, exc", [
    ({"profile": 2.9}, "profile", TypeError),
    ({"profile": 2.0}, "profile", TypeError),
    ({"short_stage": 1.5}, "short_stage", TypeError),
    ({"n_segments": 0.5}, "n_segments", TypeError),
    ({"profile": True}, "profile", TypeError),
    ({"distance": True}, "distance", TypeError),
    ({"distance": "0.3"}, "distance", TypeError),
    ({"profile": 2**40}, "profile", ValueError),
])
@pytest.mark.parametrize("version", [2, 3])
def test_generate_rejects_wrong_types(params, name, exc, version):
    from harness.fmu.runner import generate

    with pytest.raises(exc, match=name):
        generate(params, fmi_version=version)


@pytest.mark.parametrize("version", [2, 3])
def test_set_rejects_any_float_for_an_integer(version):
    """Strict types: 2.9 and 2.0 alike are refused for an Integer or Enumeration variable,
    naming it, and nothing is set; an int (or numpy integer) is taken."""
    import numpy as np

    from harness.fmu.runner import GeneratorFMU

    for bad in ({"profile": 2.9}, {"profile": 2.0}, {"short_stage": 1.0},
                {"n_segments": np.float64(0.0)}):
        with GeneratorFMU(fmi_version=version) as g:
            with pytest.raises(TypeError, match=next(iter(bad))):
                g.set({"distance": 0.3, **bad})
            g.initialize()
            assert g.get("distance") == pytest.approx(0.4)  # nothing was set
    with GeneratorFMU(fmi_version=version) as g:
        g.set({"profile": np.int64(2), "short_stage": 2, "distance": 0.1})
        g.initialize()
        assert g.get("profile") == 2 and g.get("short_stage") == 2


# ------------------------------------------------------------ 3. bad FMU files

def _remade(tmp_path: Path, name: str, fn) -> Path:
    from harness.fmu.build import default_fmu

    dst = tmp_path / name
    with zipfile.ZipFile(default_fmu(2)) as zi, zipfile.ZipFile(dst, "w") as zo:
        for it in zi.infolist():
            data = fn(it.filename, zi.read(it))
            if data is not None:
                zo.writestr(it.filename, data)
    return dst


@pytest.fixture
def bad_fmus(tmp_path):
    return {
        "no binary": _remade(tmp_path, "nobin.fmu",
                             lambda n, d: None if n.startswith("binaries/") else d),
        "cannot be loaded": _remade(tmp_path, "corrupt.fmu",
                                    lambda n, d: os.urandom(4096) if n.startswith("binaries/")
                                    else d),
    }


@pytest.mark.parametrize("kind", ["no binary", "cannot be loaded"])
def test_bad_fmu_binary_is_refused_at_load_time(tmp_path, capsys, bad_fmus, kind):
    fmu = bad_fmus[kind]
    scen = _write(tmp_path, BASE)
    out = tmp_path / "out"
    assert main(["simulate", str(scen), "--fmu", str(fmu), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(fmu) in err and kind in err and "Traceback" not in err and not out.exists()
    # the same via simulation.fmu
    scen2 = _write(tmp_path, BASE.replace("t_after = 0.5", f't_after = 0.5\nfmu = "{fmu.name}"'),
                   "s2.toml")
    _refused(scen2, "simulation.fmu")
    assert main(["report", "--fmu", str(fmu), "-o", str(tmp_path / "r.html")]) == 2
    assert kind in capsys.readouterr().err and not (tmp_path / "r.html").exists()
    from harness.fmu.runner import GeneratorFMU

    with pytest.raises(ValueError, match=kind):
        GeneratorFMU(fmu)


def test_oversized_fmu_is_refused_without_unpacking(tmp_path, monkeypatch):
    from harness.fmu import runner

    big = tmp_path / "big.fmu"
    with zipfile.ZipFile(big, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("modelDescription.xml", "<x/>")
        with z.open("resources/zeros.bin", "w") as f:
            chunk = bytes(2**20)
            for _ in range(runner.MAX_FMU_UNPACKED // 2**20 + 1):
                f.write(chunk)
    assert big.stat().st_size < 2**20
    with pytest.raises(ValueError, match="MAX_FMU_UNPACKED"):
        runner.check_fmu_archive(big)
    before = set(Path(tempfile.gettempdir()).glob("djl-fmu-*"))
    with pytest.raises(ValueError, match="MAX_FMU_UNPACKED"):
        runner.GeneratorFMU(big)
    assert set(Path(tempfile.gettempdir()).glob("djl-fmu-*")) == before
    scen = _write(tmp_path, BASE.replace("t_after = 0.5", 't_after = 0.5\nfmu = "big.fmu"'))
    _refused(scen, "simulation.fmu")


# ------------------------------------------------------------ 4. no gcc

def test_no_gcc_says_gcc_is_needed(tmp_path):
    empty, cache = tmp_path / "bin", tmp_path / "cache"
    empty.mkdir()
    cache.mkdir()
    scen = _write(tmp_path, BASE)
    env = dict(os.environ, PATH=str(empty), DJL_FMU_CACHE=str(cache))
    for argv in (["simulate", str(scen), "-o", str(tmp_path / "o1")],
                 ["report", "--fast", "--claims", "1", "-o", str(tmp_path / "r.html")],
                 # the host's gcc asked for by name (by default zig builds every platform)
                 ["build", "--fmi-version", "2", "--cc", "gcc",
                  "-o", str(tmp_path / "b" / "g.fmu")],
                 ["demo", "--out", str(tmp_path / "o2")]):
        proc = subprocess.run([sys.executable, "-m", "harness.cli", *argv], env=env,
                              capture_output=True, text=True, cwd=tmp_path, timeout=300)
        assert proc.returncode == 1, (argv, proc.stderr)
        assert "gcc" in proc.stderr and "Traceback" not in proc.stderr, (argv, proc.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin", "cache", "s.toml"]
    assert not any(cache.iterdir())


# ------------------------------------------------------------ 5. unwritable outputs

def _unwritable(tmp_path: Path) -> Path:
    if os.geteuid() == 0:
        return Path("/proc/djl-fmu-nowhere")  # not writable even by root
    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(0o500)
    return d / "sub"


def test_report_output_checked_first(tmp_path, capsys):
    d = tmp_path / "adir"
    d.mkdir()
    assert main(["report", "-o", str(d)]) == 2
    assert "directory" in capsys.readouterr().err
    f = tmp_path / "afile"
    f.write_text("x")
    assert main(["report", "-o", str(f / "r.html")]) == 2
    assert "not a directory" in capsys.readouterr().err
    assert main(["report", "-o", str(_unwritable(tmp_path) / "r.html")]) == 2
    assert "not writable" in capsys.readouterr().err


@pytest.mark.parametrize("cmd", [["simulate", "{s}"], ["map", "X"], ["compare", "X"],
                                 ["tune", "X", "--single"]])
def test_out_checked_first(tmp_path, capsys, cmd):
    scen = _write(tmp_path, BASE)
    f = tmp_path / "afile"
    f.write_text("x")
    argv = [a.replace("{s}", str(scen)) for a in cmd]
    for out, word in ((f, "not a directory"), (f / "sub", "is a file"),
                      (_unwritable(tmp_path), "not writable")):
        assert main([*argv, "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert word in err and str(out) in err
    assert f.read_text() == "x"


# ------------------------------------------------------------ 6. bounded work

@pytest.mark.parametrize("text, key, limit", [
    (BASE.replace("t_after = 0.5", "t_after = 1e12"), "simulation.t_after",
     "MAX_SAMPLES_PER_RUN"),
    (BASE.replace("t_after = 0.5", "t_after = 3.0\nTe = 1e-7\nstep = 1e-7"), "simulation.Te",
     "MAX_SAMPLES_PER_RUN"),
    (BASE.replace("v_max = 2.0\na_max = 4.0", "v_max = 1e-6\na_max = 4.0"), "move.v_max",
     "MAX_SAMPLES_PER_RUN"),
    (BASE + "\n[sweep]\nv_max = [1e-6, 1.0]\n", "sweep.v_max", "MAX_SAMPLES_PER_RUN"),
    (BASE + "\n[sweep]\ndistance = [" + ", ".join(f"{0.1 + i * 1e-4:.4f}" for i in range(1000))
     + "]\nv_max = [" + ", ".join(f"{0.5 + i * 1e-3:.3f}" for i in range(1000)) + "]\n",
     "sweep", "MAX_SWEEP_CASES"),
    (BASE + "\n[map]\nz0 = [0.0, 0.01]\ndistance = ["
     + ", ".join(f"{0.1 + i * 1e-4:.4f}" for i in range(1000)) + "]\nv_max = ["
     + ", ".join(f"{0.5 + i * 1e-3:.3f}" for i in range(1000)) + "]\n", "map", "MAX_MAP_MOVES"),
], ids=["t_after", "Te", "v_max", "sweep-v_max", "sweep-size", "map-size"])
def test_too_much_work_is_refused(tmp_path, capsys, text, key, limit):
    p = _write(tmp_path, text)
    msg = _refused(p, key)
    assert limit in msg
    out = tmp_path / "out"
    assert main(["simulate", str(p), "-o", str(out)]) == 2
    assert limit in capsys.readouterr().err and not out.exists()


# ------------------------------------------------------------ 7. absurd values

@pytest.mark.parametrize("text, key", [
    (BASE.replace("f = [10.5, 7.035]", "f = [10.5, 7.035]\ngain = 1e308"), "mode[1].gain"),
    (BASE.replace("f = [10.5, 7.035]", "f = [10.5, 1e300]"), "mode[1].f"),
    (BASE.replace('law = "linear"\nz = [0.0, 0.5]\nf = [10.5, 7.035]',
                  'law = "constant"\nf = 1e300'), "mode[1].f"),
    (BASE.replace("t_after = 0.5", "t_after = 0.5\nstep = 1e9"), "simulation.step"),
    (BASE.replace("f = [10.5, 7.035]", "f = [10.5, 7.035]\nmass_ratio = 1e300"),
     "mode[1].mass_ratio"),
], ids=["gain", "f-linear", "f-constant", "step", "mass_ratio"])
def test_absurd_values_are_refused(tmp_path, text, key):
    _refused(_write(tmp_path, text), key)


# ------------------------------------------------------------ 8. no temporary copy left

def _tmp_dirs() -> set[Path]:
    return set(Path(tempfile.gettempdir()).glob("djl-fmu-*"))


def test_generator_fmu_never_leaves_its_copy(tmp_path, bad_fmus, monkeypatch):
    from harness.fmu.runner import GeneratorFMU

    # a temporary folder of its own: other processes' copies in /tmp do not count
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))

    before = _tmp_dirs()
    with GeneratorFMU() as g:
        assert Path(g._tmp).is_dir()
    assert _tmp_dirs() == before
    with pytest.raises(TypeError):
        GeneratorFMU(params={"profile": 2.9})  # the constructor raises after unzipping
    with pytest.raises(KeyError):
        GeneratorFMU(params={"no_such_variable": 1.0})
    for fmu in bad_fmus.values():
        with pytest.raises(ValueError):
            GeneratorFMU(fmu)
    assert _tmp_dirs() == before
    g = GeneratorFMU()
    tmp = Path(g._tmp)
    assert tmp.is_dir()
    del g
    gc.collect()
    assert not tmp.exists() and _tmp_dirs() == before


def test_nan_metric_is_a_failure(tmp_path, capsys, monkeypatch):
    import math

    import harness.commands.simulate

    class Fake:
        def rows(self):
            return [{"scenario": "hostile", "profile": "DJL", "residual_m": math.nan,
                     "settling_time_s": math.nan}]

        def table(self):
            return ""

    monkeypatch.setattr(harness.commands.simulate, "run_scenario", lambda *a, **k: Fake())
    out = tmp_path / "out"
    assert main(["simulate", str(_write(tmp_path, BASE)), "-o", str(out), "--no-plot"]) == 1
    err = capsys.readouterr().err
    assert "residual_m" in err and "DJL" in err and not out.exists()


def test_an_undamped_mode_never_settles_and_that_is_not_a_failure(tmp_path, capsys):
    """An infinite settling time is a documented outcome ("never"), not a non-finite result:
    the run succeeds and the CSV says inf; the residual itself stays finite."""
    import csv

    scen = tmp_path / "undamped.toml"
    scen.write_text('name = "undamped"\n[move]\ndistance = 0.3\nv_max = 2.0\na_max = 4.0\n'
                    '[[mode]]\nzeta = 0.0\nlaw = "constant"\nf = 7.0\n')
    out = tmp_path / "out"
    assert main(["simulate", str(scen), "-o", str(out), "--no-plot", "--engine", "fast"]) == 0
    rows = list(csv.DictReader((out / "undamped.csv").open()))
    al = next(r for r in rows if r["profile"] == "AL")
    assert al["settling_time_s"] == "inf" and float(al["residual_m"]) > 0
    assert "never" in (out / "summary.txt").read_text()


# ------------------------------------------------------------ 9. NaN backstop in every table

def _nan_run(argv: list[str], out: Path, capsys) -> str:
    """Run with a NaN metric: exit 1, nothing written (not even the folder); return stderr."""
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "non-finite" in err and "nothing written" in err and "Traceback" not in err
    assert not out.exists()
    return err


def test_nan_metric_in_a_map_is_a_failure(tmp_path, capsys, monkeypatch):
    import math

    import harness.evaluation

    monkeypatch.setattr(harness.evaluation, "residual_peak", lambda *a, **k: math.nan)
    scen = _write(tmp_path, BASE + "\n[map]\nz0 = [0.0]\nz_distance = [0.3]\n"
                                   "distance = [0.2, 0.3]\nv_max = [2.0]\n")
    out = tmp_path / "out"
    err = _nan_run(["map", str(scen), "-o", str(out), "-q", "--workers", "1",
                    "--engine", "fmu"], out, capsys)
    assert "residual_peak_m = nan" in err and "hostile-map.csv" in err
    assert "row 1 (move_index = 0, profile = AL)" in err


def test_infinite_heat_map_value_is_a_failure(tmp_path, capsys, monkeypatch):
    """A percentage may be NaN (n/a: blank in the heat map), never infinite."""
    import math

    import harness.results

    monkeypatch.setattr(harness.results, "percent_of", lambda v, r: math.inf)
    scen = _write(tmp_path, BASE + "\n[map]\nz0 = [0.0]\nz_distance = [0.3]\n"
                                   "distance = [0.2]\nv_max = [2.0]\n")
    out = tmp_path / "out"
    err = _nan_run(["map", str(scen), "-o", str(out), "-q", "--workers", "1",
                    "--engine", "fmu"], out, capsys)
    assert "residual_pct_of_AL = inf" in err and "move_index = 0" in err


def test_nan_metric_in_compare_is_a_failure(tmp_path, capsys, monkeypatch):
    import dataclasses
    import math

    import harness.peers.compare
    from harness.peers.ruckig_ref import ruckig_available

    if not ruckig_available():
        pytest.skip("compare needs ruckig")
    real = harness.peers.compare.profile_metrics

    def nan_residual(*a, **k):  # the peers' metrics
        return dataclasses.replace(real(*a, **k), residual=math.nan)

    monkeypatch.setattr(harness.peers.compare, "profile_metrics", nan_residual)
    out = tmp_path / "out"
    err = _nan_run(["compare", "X", "--peers", "AL*ZV", "--no-tuned-djl", "--timeopt", "0",
                    "--no-stationary", "--no-bound", "--no-plot", "-q", "-o", str(out)], out,
                   capsys)
    assert "X.csv: residual_m = nan" in err and "method = AL*ZV" in err


def test_nan_in_compare_curves_and_timeopt_is_a_failure(tmp_path, capsys, monkeypatch):
    """The robustness curves and the time-optimal table are checked too (NaN in a curve)."""
    import math

    import numpy as np

    import harness.peers.compare as pc
    from harness.peers.ruckig_ref import ruckig_available

    if not ruckig_available():
        pytest.skip("compare needs ruckig")
    real = pc.robustness_curve

    def nan_curve(*a, **k):
        rc = real(*a, **k)
        for v in rc.residual.values():
            v[np.argmin(np.abs(rc.error))] = math.nan
        return rc

    monkeypatch.setattr(pc, "robustness_curve", nan_curve)
    out = tmp_path / "out"
    err = _nan_run(["compare", "X", "--peers", "AL*ZV", "--no-tuned-djl", "--timeopt", "0",
                    "--no-stationary", "--no-bound", "--no-plot", "-q", "-o", str(out)], out,
                   capsys)
    assert "X-robustness.csv: residual_m = nan" in err and "frequency_error = 0.0" in err


def test_nan_residual_in_tune_is_a_failure(tmp_path, capsys, monkeypatch):
    import math

    pytest.importorskip("harness._engine")
    from harness.simulation.session import Session

    real = Session.residuals_under  # what harness.tuning.tables.tune_move measures with

    def nan_residuals(self, *a, **k):
        return real(self, *a, **k) * math.nan

    monkeypatch.setattr(Session, "residuals_under", nan_residuals)
    out = tmp_path / "out"
    err = _nan_run(["tune", str(_write(tmp_path, BASE)), "--single", "--tuning", "paper",
                    "-q", "-o", str(out)], out, capsys)
    assert "hostile-jerk-times.csv: residual_m = nan in row 1 (move_index = 0" in err


def test_check_rows_finite_names_column_and_row():
    import math

    from harness.commands._common import CommandError, check_rows_finite

    rows = [{"k": 1, "a": 1.0, "b": math.nan}, {"k": 2, "a": math.inf, "b": 2.0}]
    check_rows_finite(rows, "t", finite=(), no_inf=("b",), keys=("k",))  # NaN allowed there
    with pytest.raises(CommandError, match=r"^t: a = inf in row 2 \(k = 2\)") as ei:
        check_rows_finite(rows, "t", finite=("a",), keys=("k",))
    assert ei.value.status == 1
    with pytest.raises(CommandError, match="b = nan in row 1"):
        check_rows_finite(rows, "t", finite=("b",))
    with pytest.raises(CommandError, match="a = inf in row 2"):
        check_rows_finite(rows, "t", finite=(), no_inf=("a",))


# ------------------------------------------------------------ 10. strict integers

@pytest.mark.parametrize("text, key", [
    (BASE.replace("[simulation]", "[simulation]\nfmi_version = 2.0"), "simulation.fmi_version"),
    (BASE.replace("[simulation]", "[simulation]\nshort_stage = 2.0"), "simulation.short_stage"),
    (BASE + "\n[compare]\ntune_mode = 1.0\n", "compare.tune_mode"),
], ids=["fmi_version", "short_stage", "tune_mode"])
def test_a_whole_float_for_an_integer_key_is_refused(tmp_path, capsys, text, key):
    """2.0 where an integer is expected is an error, as 2.9 is (never read as 2)."""
    p = _write(tmp_path, text)
    msg = _refused(p, key)
    assert "2.0" in msg or "1.0" in msg
    out = tmp_path / "out"
    assert main(["simulate", str(p), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert key in err and "integer" in err and not out.exists()


@pytest.mark.parametrize("value", [3.0, 2.5, True, "3"])
def test_python_api_fmi_version_must_be_an_int(value):
    from harness.simulation.session import Session
    from harness.sweeps import run_scenario

    sc = load_scenario("X")
    with pytest.raises(ScenarioError, match=r"simulation\.fmi_version = .*must be the integer"):
        sc.with_fmu(None, value)
    with pytest.raises(ScenarioError, match="fmi_version"):
        run_scenario(sc, fmi_version=value)
    with pytest.raises(ValueError, match=f"fmi_version must be the integer 2 or 3, got {value!r}"):
        Session(fmi_version=value)
    assert sc.with_fmu(None, 3).simulation.fmi_version == 3
