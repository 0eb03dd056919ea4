"""``djl-fmu tune`` and :mod:`harness.tuning.tables`: tuned jerk times, their CSV, the FMU round
trip.

Every number of the table is checked against an independent recomputation:
the jerk times against ``tune_profile``, the residuals against a full
co-simulation (``Session.run(...).free_amplitude``, on the fast engine and on
the generator FMU), the worst cases against ``harness.robustness``, and the
file is read back and fed to the FMU, which must apply exactly those jerk
times and reproduce the residual.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from harness.scenario import load_scenario, parse_scenario
from harness.tuning.tables import (
    COLUMN_NAMES,
    COLUMNS,
    FORMAT,
    MAGIC,
    JerkTimeTable,
    fmu_parameters,
    load_jerk_times,
    parse_tuning,
    tune_table,
)
from harness.tuning.tune import tune_profile

from _scenarios import SMALL_AXIS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

pytest.importorskip("harness._engine", reason="the tuning searches run on the compiled engine")

SCENARIO = """\
name = "tune-test"

""" + SMALL_AXIS + """
[map]
z0 = [0.0, 0.1]
z_distance = [0.2]
distance = [0.12, -0.25]
v_max = [2.0, 0.4]
"""
# 2 x 1 x 2 x 2 = 8 moves; distance and v_max deliberately not sorted

SWEEP = SCENARIO[:SCENARIO.index("[map]")] + """\
[sweep]
distance = [0.1, 0.3]
z_distance = [0.1, 0.4]
v_max = [0.5]
"""

REL = 1e-9


def _scenario(text: str = SCENARIO):
    return parse_scenario(tomllib.loads(text), "tune-test.toml")


def _methods(sc, djl: str, jl: str, e: float = 0.1):
    return dataclasses.replace(sc, compare=dataclasses.replace(
        sc.compare, djl_tuning=djl, jl_tuning=jl),
        uncertainty=dataclasses.replace(sc.uncertainty, map_scale=e))


def _close(a: float, b: float, rel: float = REL) -> bool:
    return abs(a - b) <= rel * max(abs(a), abs(b))


@pytest.fixture(scope="module")
def session():
    from harness.simulation.session import Session

    s = Session(engine="fast")
    yield s
    s.close()


@pytest.fixture(scope="module")
def x_robust():
    """Scenario X's own move, DJL robust (map error 10 %), JL end."""
    return tune_table("X", single=True)


@pytest.fixture(scope="module")
def x_csv(x_robust, tmp_path_factory):
    return x_robust.to_csv(tmp_path_factory.mktemp("tune") / "X-jerk-times.csv")


@pytest.fixture(scope="module")
def map_serial():
    return tune_table(_scenario(), djl_method="optimal", jl_method="end", workers=1)


# ------------------------------------------------------------ the methods


def test_parse_tuning():
    assert parse_tuning(None) == ("robust", "end")
    assert parse_tuning("") == ("robust", "end")
    assert parse_tuning("paper") == ("paper", "end")
    assert parse_tuning("optimal") == ("optimal", "end")
    assert parse_tuning("end") == ("robust", "end")
    assert parse_tuning("djl=optimal,jl=optimal") == ("optimal", "optimal")
    assert parse_tuning(" jl=optimal , robust ") == ("robust", "optimal")
    for bad, msg in (("fast", "'fast' is not a tuning method"),
                     ("jl=robust", "unknown JL tuning method 'robust'"),
                     ("djl=end", "unknown DJL tuning method 'end'"),
                     ("xl=paper", "unknown profile 'xl'"),
                     ("paper,robust", "a table has one DJL method, 'paper' and 'robust' "
                                      "are given")):
        with pytest.raises(ValueError, match=msg):
            parse_tuning(bad)


def test_tune_table_refuses_bad_arguments():
    sc = _scenario()
    for kw, msg in (({"djl_method": "best"}, "unknown DJL tuning method"),
                    ({"jl_method": "start"}, "unknown JL tuning method"),
                    ({"map_error": 1.0}, r"\[0, 1\)"),
                    ({"map_error": -0.01}, r"\[0, 1\)"),
                    ({"map_error": math.nan}, r"\[0, 1\)"),
                    ({"max_moves": 0}, "max_moves"),
                    ({"batch": 0}, "batch")):
        with pytest.raises(ValueError, match=msg):
            tune_table(sc, workers=1, **kw)


# ------------------------------------------------ one move, recomputed


def test_single_move_against_independent_recomputation(x_robust, session):
    from harness.robustness import map_error_residuals

    assert len(x_robust) == 1 and x_robust.kind == "move"
    r = x_robust.rows[0]
    sc = _methods(load_scenario("X"), "robust", "end")
    djl = tune_profile(session, sc, "DJL")
    jl = tune_profile(session, sc, "JL")
    assert djl.rule == "robust" and jl.rule == "end"
    # the jerk times
    assert tuple(r[f"djl_N_F{i}"] for i in range(1, 5)) == djl.N_F
    assert r["jl_N_F"] == jl.N_F[0] == round(jl.periods[0] / 1e-3)
    for i in range(4):
        assert r[f"djl_T_F{i + 1}_s"] == pytest.approx(djl.T_F[i], abs=1e-15)
        assert r[f"djl_period{i + 1}_s"] == djl.periods[i]
    assert r["jl_T_F_s"] == pytest.approx(jl.T_F[0], abs=1e-15)
    assert r["jl_period_s"] == jl.periods[0]
    assert (r["method"], r["jl_method"]) == ("robust", "end")
    # the residuals, by a full co-simulation of each profile with those jerk times
    run_d = session.run(sc, "DJL", djl.T_F)
    run_j = session.run(sc, "JL", jl.T_F)
    assert _close(r["residual_m"], run_d.free_amplitude)
    assert _close(r["jl_residual_m"], run_j.free_amplitude)
    assert r["motion_time_s"] == pytest.approx(run_d.motion_time, abs=1e-12)
    assert r["jl_motion_time_s"] == pytest.approx(run_j.motion_time, abs=1e-12)
    assert r["z_v_max_m_s"] == pytest.approx(run_d.z_v_max, rel=1e-12)
    assert r["jl_z_v_max_m_s"] == pytest.approx(run_j.z_v_max, rel=1e-12)
    # the worst cases, by harness.robustness over the scoring set: 41 map scales in +/-10 %
    # (not the 9 the robust DJL was tuned on)
    e = np.linspace(-0.1, 0.1, 41)
    assert np.allclose(sorted(p.scale for p in sc.uncertainty.scoring_set().points), e)
    w_d = map_error_residuals(sc, session, "DJL", djl.T_F, e)
    w_j = map_error_residuals(sc, session, "JL", jl.T_F, e)
    assert _close(r["worst_residual_m"], float(np.max(w_d)))
    assert _close(r["jl_worst_residual_m"], float(np.max(w_j)))
    # and as the search reported them
    assert _close(r["worst_residual_m"], djl.search.worst)
    assert _close(r["jl_worst_residual_m"], djl.search.jl_worst)
    # what robust is for: a smaller worst case than JL's
    assert r["worst_residual_m"] < r["jl_worst_residual_m"]
    assert r["worst_residual_m"] >= r["residual_m"]


def test_paper_method_gives_the_documented_table1_numbers():
    # docs/cli.md / docs/harness.md, scenario X: DJL 118/120/142/147 ms, residual 0.098 mm,
    # worst over +/-10 % 0.490 mm; JL 152 ms, 0.171 mm, worst 0.326 mm
    r = tune_table("X", djl_method="paper", single=True).rows[0]
    assert tuple(r[f"djl_N_F{i}"] for i in range(1, 5)) == (118, 120, 142, 147)
    assert r["jl_N_F"] == 152 and not r["merged"] and r["converged"]
    assert r["residual_m"] == pytest.approx(0.098e-3, abs=0.5e-6)
    assert r["worst_residual_m"] == pytest.approx(0.490e-3, abs=0.5e-6)
    assert r["jl_residual_m"] == pytest.approx(0.171e-3, abs=0.5e-6)
    assert r["jl_worst_residual_m"] == pytest.approx(0.326e-3, abs=0.5e-6)
    y = tune_table("Y", djl_method="paper", single=True).rows[0]
    assert tuple(y[f"djl_N_F{i}"] for i in range(1, 5)) == (95, 104, 104, 130)
    assert y["merged"] and y["jl_N_F"] == 135


def test_single_move_table_prints_the_numbers(x_robust):
    text = x_robust.table()
    r = x_robust.rows[0]
    assert "DJL N_F [samples]" in text and "local period [ms]" in text
    assert " ".join(str(r[f"djl_N_F{i}"]) for i in range(1, 5)) in " ".join(text.split())
    assert f"{r['jl_residual_m'] * 1e3:.4g}" in text
    assert f"{r['worst_residual_m'] * 1e3:.4g}" in text
    pct = (r["worst_residual_m"] - r["jl_worst_residual_m"]) / r["jl_worst_residual_m"] * 100
    assert f"{pct:+.1f} %" in text


# ------------------------------------------------------ the CSV format


def test_csv_header_documents_every_column(x_csv):
    lines = Path(x_csv).read_text(encoding="utf-8").splitlines()
    assert lines[0] == MAGIC
    comments = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    assert lines[:len(comments)] == comments  # the header comes first
    assert body[0].split(",") == list(COLUMN_NAMES)
    assert len(body) == 2
    head = "\n".join(comments)
    for key in ("format: 1", "scenario: X", "source: <embedded X>", "djl_method: robust",
                "jl_method: end", "map_error: 0.1", "Te_s: 0.001", "units: SI",
                "uncertainty: map scale +/-10 % (robust tuning: the 9-point tuning set; "
                "the worst_* columns: the 41-point scoring set)"):
        assert f"# {key}" in head, key
    for c in COLUMNS:  # every column has its line, with its unit
        assert any(ln.split()[1:3] == [c.name, f"[{c.unit}]"] for ln in comments), c.name
    assert "profile = 3, T_F1 = djl_T_F1_s, T_F2 = djl_T_F2_s" in head
    assert "profile = 2, T_F1 = jl_T_F_s" in head
    # the documented leading columns, and SI suffixes on every number
    assert COLUMN_NAMES[:22] == (
        "z0_m", "z_distance_m", "distance_m", "v_max_m_s", "jl_T_F_s", "djl_T_F1_s",
        "djl_T_F2_s", "djl_T_F3_s", "djl_T_F4_s", "djl_N_F1", "djl_N_F2", "djl_N_F3",
        "djl_N_F4", "residual_m", "worst_residual_m", "jl_residual_m", "jl_worst_residual_m",
        "motion_time_s", "jl_motion_time_s", "method", "jl_method", "jl_N_F")
    for c in COLUMNS:
        if c.kind == "float":
            assert c.name.endswith(("_m", "_s", "_m_s", "_m_s2")), c.name


def test_csv_round_trip_is_exact(x_robust, x_csv):
    back = load_jerk_times(x_csv)
    assert back.rows == x_robust.rows
    assert back.columns == COLUMN_NAMES
    assert back.meta["format"] == str(FORMAT) and back.meta["djl_method"] == "robust"
    assert back.to_text() == Path(x_csv).read_text(encoding="utf-8")
    # a plain CSV reader gets the same numbers once the comments are skipped
    import csv

    with open(x_csv, encoding="utf-8") as fh:
        rec = list(csv.DictReader(ln for ln in fh if not ln.startswith("#")))
    assert len(rec) == 1
    for c in COLUMNS:
        if c.kind == "float":
            assert float(rec[0][c.name]) == x_robust.rows[0][c.name]


def test_fmu_applies_the_loaded_jerk_times_and_reproduces_the_residual(x_csv, session):
    from harness.fmu.runner import generate
    from harness.simulation.fast_axis import FastAxis
    from harness.simulation.session import Session

    row = load_jerk_times(x_csv).rows[0]
    sc = load_scenario("X")
    for profile, N in (("DJL", tuple(row[f"djl_N_F{i}"] for i in range(1, 5))),
                       ("JL", (row["jl_N_F"],) * 4)):
        params = fmu_parameters(row, profile)
        assert params["profile"] == (3 if profile == "DJL" else 2)
        T_F = tuple(params[f"T_F{i}"] for i in range(1, 5))
        # exactly the parameters the harness gives the FMU
        assert params == Session.move_params(sc, profile, T_F)
        # the generator FMU applies those jerk times and plans the same motion
        traj = generate(params, fmi_version=2)
        assert traj.N_F == N
        mt = row["motion_time_s"] if profile == "DJL" else row["jl_motion_time_s"]
        assert traj.motion_time == pytest.approx(mt, abs=1e-12)
        assert traj.x[-1] == pytest.approx(row["x0_m"] + row["distance_m"], abs=1e-12)
        fast = FastAxis()
        assert fast.plan(params) == pytest.approx(mt, abs=1e-12)
        assert fast.N_F() == N
        # and leaves the residual of the table (fast engine and the FMU engine)
        res = row["residual_m"] if profile == "DJL" else row["jl_residual_m"]
        run = session.run(sc, profile, T_F)
        assert run.N_F == N
        assert _close(run.free_amplitude, res)
    with Session(engine="fmu") as fmu_session:
        run = fmu_session.run(sc, "DJL", tuple(row[f"djl_T_F{i}_s"] for i in range(1, 5)))
    assert _close(run.free_amplitude, row["residual_m"])


def test_fmu_parameters_refuses_other_profiles(x_robust):
    with pytest.raises(ValueError, match="'DJL' or 'JL'"):
        fmu_parameters(x_robust.rows[0], "AL")


def test_load_refuses_what_it_cannot_read(tmp_path, x_csv):
    text = Path(x_csv).read_text(encoding="utf-8")
    cases = {
        "plain.csv": ("a,b\n1,2\n", "not a djl-fmu jerk-time table"),
        "v2.csv": (text.replace("# format: 1", "# format: 2"), "format 2"),
        "nofmt.csv": (text.replace("# format: 1\n", ""), "no '# format: N' line"),
        "nocol.csv": (text.replace(",jl_N_F,", ",jl_NF,"), "missing column(s) jl_N_F"),
        "badval.csv": (text.replace(",robust,end,152,", ",robust,end,x152,"),
                       f"line {len(text.splitlines())}, column jl_N_F"),
        "short.csv": (text.rstrip("\n") + "\n1,2,3\n", "3 values for"),
    }
    for name, (content, msg) in cases.items():
        p = tmp_path / name
        p.write_text(content, encoding="utf-8")
        with pytest.raises(ValueError, match=re_escape(msg)):
            load_jerk_times(p)


def re_escape(s: str) -> str:
    import re

    return re.escape(s)


def test_nearest_row():
    rows = []
    for k, (z0, dz, d, v) in enumerate([(0.0, 0.1, 0.1, 0.5), (0.0, 0.1, 0.3, 0.5),
                                        (0.1, 0.4, 0.1, 2.0), (0.1, 0.4, 0.3, 2.0)]):
        rows.append({"z0_m": z0, "z_distance_m": dz, "distance_m": d, "v_max_m_s": v,
                     "move_index": k})
    tab = JerkTimeTable(rows, [])
    assert tab.nearest(0.0, 0.1, 0.1, 0.5)["move_index"] == 0
    assert tab.nearest(0.01, 0.12, 0.26, 0.6)["move_index"] == 1
    assert tab.nearest(0.09, 0.35, 0.12, 1.7)["move_index"] == 2
    assert tab.nearest(1.0, 1.0, 1.0, 9.0)["move_index"] == 3
    with pytest.raises(ValueError, match="finite"):
        tab.nearest(math.nan, 0, 0, 0)
    with pytest.raises(ValueError, match="no rows"):
        JerkTimeTable([], []).nearest(0, 0, 0, 0)


# ------------------------------------------------- grids, executors


def test_map_rows_in_grid_order_and_each_row_is_its_move(map_serial, session):
    sc = _scenario()
    pts = sc.map_points()
    assert len(map_serial) == 8 and map_serial.kind == "map"
    assert [(r["z0_m"], r["z_distance_m"], r["distance_m"], r["v_max_m_s"])
            for r in map_serial.rows] == pts
    assert [r["move_index"] for r in map_serial.rows] == list(range(8))
    assert map_serial.meta["grid"].startswith("[map] z0 x z_distance x distance x v_max = "
                                              "2 x 1 x 2 x 2 = 8 moves")
    # two moves recomputed on their own
    for k in (3, 6):
        case = _methods(sc.map_case(*pts[k]), "optimal", "end")
        djl = tune_profile(session, case, "DJL")
        r = map_serial.rows[k]
        assert tuple(r[f"djl_N_F{i}"] for i in range(1, 5)) == djl.N_F
        assert _close(r["residual_m"], session.run(case, "DJL", djl.T_F).free_amplitude)
        assert _close(r["residual_m"], djl.search.nominal)
        # optimal never leaves more than JL tuned to the end of the motion
        assert r["residual_m"] <= r["jl_residual_m"]


def test_map_identical_whatever_the_executor(map_serial):
    sc = _scenario()
    with ProcessPoolExecutor(2) as ex:
        pooled = tune_table(sc, djl_method="optimal", executor=ex, batch=3)
    assert pooled.rows == map_serial.rows
    assert pooled.to_text() == map_serial.to_text()
    two = tune_table(sc, djl_method="optimal", workers=2, max_moves=5)
    assert two.rows == map_serial.rows[:5]
    assert two.meta["rows"] == "5 (the first 5 of 8)"


@pytest.mark.slow
def test_identical_on_a_dask_local_cluster(map_serial):
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        tab = tune_table(_scenario(), djl_method="optimal", scheduler=cluster.scheduler_address,
                         batch=2)
    assert tab.executor.startswith("Dask cluster tcp://127.0.0.1:") and tab.workers == 2
    assert tab.to_text() == map_serial.to_text()


def test_sweep_cases_in_order(session):
    sc = _scenario(SWEEP)
    tab = tune_table(sc, djl_method="paper", jl_method="optimal", workers=1)
    cases = sc.cases()
    assert tab.kind == "sweep" and len(tab) == len(cases) == 4
    for r, case in zip(tab.rows, cases, strict=True):
        assert (r["distance_m"], r["z_distance_m"], r["v_max_m_s"]) == (
            case.move.distance, case.z.distance, case.move.v_max)
        c = _methods(case, "paper", "optimal")
        djl, jl = tune_profile(session, c, "DJL"), tune_profile(session, c, "JL")
        assert tuple(r[f"djl_N_F{i}"] for i in range(1, 5)) == djl.N_F
        assert r["jl_N_F"] == jl.N_F[0] and jl.rule == "optimal"
        assert _close(r["jl_residual_m"], session.run(c, "JL", jl.T_F).free_amplitude)
        assert r["converged"] == djl.converged and r["merged"] == djl.merged
    assert tab.meta["djl_method"] == "paper" and tab.meta["jl_method"] == "optimal"


def test_map_error_zero_makes_worst_the_nominal():
    tab = tune_table(_scenario(), djl_method="robust", map_error=0.0, single=True)
    r = tab.rows[0]
    assert r["worst_residual_m"] == r["residual_m"]
    assert r["jl_worst_residual_m"] == r["jl_residual_m"]
    assert tab.meta["map_error"] == "0"


def test_imposed_jerk_times_are_ignored(session):
    sc = _scenario()
    sc = dataclasses.replace(sc, compare=dataclasses.replace(
        sc.compare, JL_T_F=0.2, DJL_T_F=(0.1, 0.1, 0.1, 0.1)))
    r = tune_table(sc, djl_method="paper", single=True).rows[0]
    plain = tune_table(_scenario(), djl_method="paper", single=True).rows[0]
    assert r == plain and r["djl_N_F1"] != 100


# ----------------------------------------------------------------- CLI


def test_cli_help_and_command_list(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "djl-fmu tune" in out
    with pytest.raises(SystemExit):
        main(["tune", "--help-full"])
    out = capsys.readouterr().out
    assert "default: DJL robust, JL end" in out and "--max-moves" in out


def test_cli_single_move(tmp_path, capsys):
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    out = tmp_path / "out"
    rc = main(["tune", str(scen), "--single", "--tuning", "paper", "-o", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert "Jerk times of tune-test" in text and "DJL N_F [samples]" in text
    tab = load_jerk_times(out / "tune-test-jerk-times.csv")
    assert len(tab) == 1 and tab.rows[0]["method"] == "paper"
    assert tab.meta["grid"] == "a single move"
    assert (out / "summary.txt").read_text(encoding="utf-8").startswith("Jerk times of")


def test_cli_map_serial_and_two_workers_write_the_same_file(tmp_path, capsys):
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    files = []
    for w in ("1", "2"):
        out = tmp_path / f"out{w}"
        rc = main(["tune", str(scen), "--tuning", "optimal", "--max-moves", "4",
                   "--workers", w, "-o", str(out), "-q"])
        assert rc == 0, capsys.readouterr().err
        files.append((out / "tune-test-jerk-times.csv").read_bytes())
    assert files[0] == files[1]
    assert len(load_jerk_times(tmp_path / "out1" / "tune-test-jerk-times.csv")) == 4


def test_cli_bad_inputs_exit_2_and_write_nothing(tmp_path, capsys, monkeypatch):
    import harness.executors

    monkeypatch.setattr(harness.executors, "CONNECT_TIMEOUT", 1.0)
    good = tmp_path / "s.toml"
    good.write_text(SCENARIO)
    broken = tmp_path / "b.toml"
    broken.write_text(SCENARIO.replace("zeta = 0.04", "zeta = 1.5"))
    afile = tmp_path / "afile"
    afile.write_text("x")
    cases = [
        ([str(good), "--tuning", "fastest"], "'fastest' is not a tuning method"),
        ([str(good), "--tuning", "jl=robust"], "unknown JL tuning method 'robust'"),
        ([str(good), "--map-error", "1"], "--map-error must be in [0, 1)"),
        ([str(good), "--map-error", "-0.1"], "--map-error must be in [0, 1)"),
        ([str(good), "--map-error", "nan"], "--map-error must be in [0, 1)"),
        ([str(good), "--workers", "0"], "--workers must be >= 1"),
        ([str(good), "--max-moves", "0"], "--max-moves must be >= 1"),
        ([str(good), "--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"], "not both"),
        ([str(broken)], "mode[1].zeta"),
        ([str(tmp_path / "missing.toml")], "no such scenario file"),
        ([str(good), "--out", str(afile)], "is not a directory"),
        ([str(good), "--out", str(afile / "sub")], "is a file, not a directory"),
        ([str(good), "--scheduler", "tcp://127.0.0.1:9"], "Dask scheduler"),
    ]
    for args, message in cases:
        out = tmp_path / "out"
        if "--out" not in args:
            args = [*args, "--out", str(out)]
        rc = main(["tune", *args, "-q"])
        err = capsys.readouterr().err
        assert rc == 2, (args, err)
        assert message in err, (args, err)
        assert err.startswith("djl-fmu tune: ") and err.count("\n") == 1, err
        assert "Traceback" not in err
        assert not out.exists()
    assert afile.read_text() == "x"


def test_cli_failing_move_exit_1_and_writes_nothing(tmp_path, capsys, monkeypatch):
    import harness.tuning.tables

    real = harness.tuning.tables.tune_move

    def flaky(case, session, index=0):
        if index == 2:
            raise ValueError("planner refused")
        return real(case, session, index)

    monkeypatch.setattr(harness.tuning.tables, "tune_move", flaky)
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    out = tmp_path / "out"
    rc = main(["tune", str(scen), "--tuning", "paper", "--workers", "1", "-o", str(out), "-q"])
    err = capsys.readouterr().err
    assert rc == 1
    assert "tuning failed (tune-test): move 2 (z0 = 0 m, z_distance = 0.2 m, distance = " \
           "-0.25 m, v_max = 2 m/s) failed: ValueError: planner refused" in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_cli_write_failure_exit_1_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    def no_space(self, path):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(JerkTimeTable, "to_csv", no_space)
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    out = tmp_path / "out"
    rc = main(["tune", str(scen), "--single", "--tuning", "paper", "-o", str(out), "-q"])
    err = capsys.readouterr().err
    assert rc == 1 and "cannot write the outputs" in err and "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())
