"""``djl-fmu map``: the [map] grid, the executors, determinism, the CLI and its refusals."""

from __future__ import annotations

import copy
import csv
import dataclasses
import math
import socket
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from harness.scenario import ScenarioError, load_scenario, parse_scenario

from _scenarios import SMALL_AXIS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def _engine() -> str:
    """The compiled engine when it is built here, else the FMU engine (same results)."""
    from harness.workspace import check_engine

    try:
        check_engine("fast")
    except ValueError:
        return "fmu"
    return "fast"


ENGINE = _engine()

SCENARIO = """\
name = "map-test"

""" + SMALL_AXIS + """
[map]
z0 = [0.0, 0.1]
z_distance = [0.15, 0.4]
distance = [0.12, -0.25]
v_max = [2.0, 0.4]
"""
# 2 x 2 x 2 x 2 = 16 moves; distance and v_max deliberately not sorted


def _scenario(text: str = SCENARIO):
    return parse_scenario(tomllib.loads(text), "map-test.toml")


def _with_map(table: str) -> str:
    return SCENARIO[:SCENARIO.index("[map]")] + table


def _same(a, b) -> bool:
    """Exact equality of two CSV values, NaN equal to NaN."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


def _assert_rows_identical(rows_a, rows_b) -> None:
    assert len(rows_a) == len(rows_b)
    for ra, rb in zip(rows_a, rows_b, strict=True):
        assert list(ra) == list(rb)
        bad = [k for k in ra if not _same(ra[k], rb[k])]
        assert not bad, (ra["move_index"], ra["profile"], {k: (ra[k], rb[k]) for k in bad})


@pytest.fixture(scope="module")
def serial():
    """The small map run in this process (the reference of the parallel runs)."""
    from harness.workspace import run_workspace_map

    return run_workspace_map(_scenario(), engine=ENGINE, workers=1)


# ------------------------------------------------------------------ the grid


def test_grid_order_count_and_cases():
    sc = _scenario()
    axes = sc.map_axes()
    assert axes == ((0.0, 0.1), (0.15, 0.4), (0.12, -0.25), (2.0, 0.4))
    assert sc.map_size == 16
    pts = sc.map_points()
    assert len(pts) == 16 and len(set(pts)) == 16
    # documented order: k = ((i_z0 * n_dz + i_dz) * n_d + i_d) * n_v + i_v, v_max fastest
    for i0, z0 in enumerate(axes[0]):
        for i1, dz in enumerate(axes[1]):
            for i2, d in enumerate(axes[2]):
                for i3, v in enumerate(axes[3]):
                    k = ((i0 * 2 + i1) * 2 + i2) * 2 + i3
                    assert pts[k] == (z0, dz, d, v)
    assert pts[:3] == [(0.0, 0.15, 0.12, 2.0), (0.0, 0.15, 0.12, 0.4), (0.0, 0.15, -0.25, 2.0)]
    cases = sc.map_cases()
    assert len(cases) == 16
    c = cases[13]  # (1, 1, 0, 1)
    assert (c.z.z0, c.z.distance, c.move.distance, c.move.v_max) == (0.1, 0.4, 0.12, 0.4)
    assert c.map is None and c.sweep is None and not c.is_sweep
    assert c.name == "map-test z0=0.1 dz=0.4 d=0.12 v=0.4"
    # everything else is the scenario's
    assert c.move.a_max == 4.0 and c.z.a_max == 8.0 and c.modemap == sc.modemap
    assert c.simulation == sc.simulation


def test_max_moves_takes_the_first_moves_unless_spread():
    sc = _scenario()
    assert sc.map_points(5) == sc.map_points()[:5]
    assert sc.map_points(1000) == sc.map_points()
    assert sc.map_points(1000, spread=True) == sc.map_points()
    assert [c.name for c in sc.map_cases(3)] == [c.name for c in sc.map_cases()[:3]]
    assert sc.map_indices(5, spread=False) == [0, 1, 2, 3, 4]
    pts = sc.map_points()
    assert sc.map_points(5, spread=True) == [pts[k] for k in sc.map_indices(5)]
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="max_moves"):
            sc.map_points(bad)
        with pytest.raises(ValueError, match="max_moves"):
            sc.map_indices(bad)


@pytest.mark.parametrize("n", [1, 3, 7, 12, 20, 50, 200, 1000, 9999])
def test_spread_moves_cover_the_whole_grid(n):
    """--max-moves N on X's 5 x 20 x 25 x 4 grid: N distinct moves, in grid order, the same
    every time, shared evenly among the heat maps' panels (z0 rows, v_max columns) and
    spread over Z travel and move length, not the first rows of the grid."""
    sc = load_scenario("X")
    sizes = [len(a) for a in sc.map_axes()]
    idx = sc.map_indices(n)
    assert len(idx) == len(set(idx)) == n and idx == sorted(idx)
    assert idx == sc.map_indices(n)  # deterministic
    multi = np.array(np.unravel_index(idx, sizes)).T  # (i_z0, i_dz, i_d, i_v), v_max fastest
    for axis, size in enumerate(sizes):
        counts = np.bincount(multi[:, axis], minlength=size)
        if n >= size:  # every value gets its share, give or take one
            assert counts.min() >= n // size - 1 and counts.max() <= -(-n // size) + 1
        else:  # distinct values, across the range (not the first ones)
            assert counts.max() <= 1 or axis >= 2
    panels = np.bincount(multi[:, 0] * sizes[3] + multi[:, 3], minlength=sizes[0] * sizes[3])
    if n >= panels.size:
        assert panels.max() - panels.min() <= 1  # every panel of the heat maps filled evenly
    else:
        assert panels.max() == 1
    if n >= 12:  # the moves reach both ends of every axis' range
        for axis, size in enumerate(sizes):
            lo, hi = multi[:, axis].min(), multi[:, axis].max()
            assert lo <= size // 4 and hi >= size - 1 - size // 4
    assert sc.map_indices(n, spread=False) == list(range(n))


def test_missing_lists_take_the_scenario_values():
    sc = _scenario(_with_map("[map]\nv_max = [0.5, 1.0, 1.5]\n"))
    assert sc.map_axes() == ((0.0,), (0.3,), (0.3,), (0.5, 1.0, 1.5))
    assert sc.map_size == 3
    plain = _scenario(_with_map(""))
    assert plain.map is None and plain.map_size == 1
    assert plain.map_points() == [(0.0, 0.3, 0.3, 2.0)]


@pytest.mark.parametrize("name", ["X", "Y"])
def test_embedded_default_grids(name):
    sc = load_scenario(name)  # 10^4 moves, but the Z ranges are checked per (z0, dz) pair
    assert sc.map is not None and sc.map_size >= 10_000
    z0, dz, d, v = sc.map_axes()
    assert min(z0) == 0.0 and max(z0) == pytest.approx(0.1)
    assert min(dz) > 0 and max(dz) == pytest.approx(0.5)
    assert min(d) > 0 and max(d) == pytest.approx(0.5)
    assert all(x > 0 for x in v) and len(v) >= 2
    # the mode stays positive over every Z move of the grid
    assert sc.modemap.tuned.f(max(z0) + max(dz)) > 0
    # the Table 1 move itself is unchanged by the [map] table
    assert (sc.move.distance, sc.z.distance) == ((0.4, 0.45) if name == "X" else (0.3, 0.45))


@pytest.mark.parametrize(("table", "key", "words"), [
    ("[map]\nz0 = []\n", "map.z0", "at least 1 finite"),
    ("[map]\ndistance = [0.1, \"a\"]\n", "map.distance", "finite number"),
    ("[map]\ndistance = [0.1, nan]\n", "map.distance", "finite number"),
    ("[map]\nv_max = 2.0\n", "map.v_max", "list"),
    ("[map]\ndistance = [0.1, 0.0]\n", "map.distance", "must not be 0"),
    ("[map]\nv_max = [0.5, 0.0]\n", "map.v_max", "must be > 0"),
    ("[map]\nv_max = [-1.0]\n", "map.v_max", "must be > 0"),
    ("[map]\nz_distance = [0.1, 0.1]\n", "map.z_distance", "distinct"),
    ("[map]\nz_travel = [0.1]\n", "map.z_travel", "unknown key"),
    ("[map]\n", "map", "at least one of"),
    ("map = 3\n", "map", "must be a table"),
    # f(z) = 10.5 - 6.93 z is 0 at z = 1.52 m: a Z move of the grid goes past it
    ("[map]\nz0 = [0.0, 1.0]\nz_distance = [0.1, 0.6]\n", "mode[1].f", "z0|Z moves from 1 m"),
])
def test_map_parse_errors(table, key, words):
    text = _with_map(table) if not table.startswith("map =") else table + _with_map("")
    with pytest.raises(ScenarioError) as ei:
        _scenario(text)
    e = ei.value
    assert e.key == key, str(e)
    assert any(w in str(e) for w in words.split("|")), str(e)
    assert "map-test.toml" in str(e)


def test_table_law_must_cover_every_z_move_of_the_grid():
    text = _with_map("[map]\nz0 = [0.0, 0.3]\nz_distance = [0.1, 0.25]\n").replace(
        'law = "linear"', 'law = "table"')
    with pytest.raises(ScenarioError) as ei:
        _scenario(text)
    assert ei.value.key == "mode[1].z"
    assert "Z moves from 0.3 m by 0.25 m in the [map] grid" in str(ei.value)
    # inside the table: accepted
    _scenario(_with_map("[map]\nz0 = [0.0, 0.1]\nz_distance = [0.1, 0.4]\n").replace(
        'law = "linear"', 'law = "table"'))


# ----------------------------------------------------------------- executors


def test_executors():
    from harness.executors import ExecutorError, SerialExecutor, executor_workers, make_executor

    with make_executor(workers=1) as ex:
        assert isinstance(ex, SerialExecutor) and executor_workers(ex) == 1
        assert ex.submit(pow, 2, 10).result() == 1024
        fut = ex.submit(math.sqrt, -1.0)
        assert isinstance(fut.exception(), ValueError)
    with make_executor(workers=2) as ex:
        assert executor_workers(ex) == 2
        assert [f.result() for f in [ex.submit(pow, 3, k) for k in range(4)]] == [1, 3, 9, 27]
    for bad in (0, -2, 1.5):
        with pytest.raises(ExecutorError, match="workers"):
            with make_executor(workers=bad):
                pass
    with pytest.raises(ExecutorError, match="not both"):
        with make_executor(workers=2, scheduler="tcp://127.0.0.1:8786"):
            pass


class _StopError(Exception):
    pass


@pytest.mark.skipif(sys.platform == "win32", reason="kills the workers with SIGKILL")
def test_an_interrupted_pool_is_wound_down_before_make_executor_returns():
    """After an interrupt the pool's manager thread has ended when ``make_executor`` exits.

    Otherwise Python 3.11's exit hook may write to the manager's wake-up pipe while that
    thread closes it, printing "OSError: [Errno 9] Bad file descriptor" after the
    command's message (seen once in CI, test_sigterm_to_a_pooled_map_exits_quietly).
    """
    import os
    import signal

    from harness.executors import make_executor

    with pytest.raises(_StopError):
        with make_executor(workers=2) as ex:
            futs = [ex.submit(time.sleep, 30.0) for _ in range(6)]
            deadline = time.monotonic() + 30
            while len(ex._processes) < 2 and time.monotonic() < deadline:  # type: ignore[attr-defined]
                time.sleep(0.05)
            manager = ex._executor_manager_thread  # type: ignore[attr-defined]
            wakeup = ex._executor_manager_thread_wakeup  # type: ignore[attr-defined]
            assert manager is not None and manager.is_alive()
            for pid in list(ex._processes):  # type: ignore[attr-defined]
                os.kill(pid, signal.SIGKILL)  # the workers die with the group, as on SIGTERM
            raise _StopError
    assert not manager.is_alive()
    assert wakeup._closed  # the exit hook's wakeup() is then a no-op
    assert all(f.done() for f in futs)


def _closed_port() -> int:
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_unreachable_scheduler_is_a_clear_error():
    from harness.executors import ExecutorError, make_executor

    addr = f"tcp://127.0.0.1:{_closed_port()}"
    t = time.perf_counter()
    with pytest.raises(ExecutorError) as ei:
        with make_executor(scheduler=addr, timeout=1.0):
            pass
    assert time.perf_counter() - t < 8.0
    assert addr in str(ei.value) and "dask scheduler" in str(ei.value)
    with pytest.raises(ExecutorError, match="foo://bar"):
        with make_executor(scheduler="foo://bar", timeout=1.0):
            pass


# ------------------------------------------------------------------ results


def test_serial_map_rows_are_the_sweep_rows_of_each_move(serial):
    from harness.evaluation import run_case
    from harness.results import SweepResult
    from harness.simulation.session import Session

    sc = _scenario()
    assert serial.n_moves == 16 and serial.workers == 1
    rows = serial.rows()
    assert len(rows) == 16 * 3
    assert [r["move_index"] for r in rows] == [k for k in range(16) for _ in range(3)]
    assert [r["profile"] for r in rows[:3]] == ["AL", "JL", "DJL"]
    assert {r["sweep"] for r in rows} == {"map-test"}
    # move 11 = (i_z0, i_dz, i_d, i_v) = (1, 0, 1, 1), computed here independently
    case = dataclasses.replace(
        sc, map=None, move=dataclasses.replace(sc.move, distance=-0.25, v_max=0.4),
        z=dataclasses.replace(sc.z, z0=0.1, distance=0.15),
        name="map-test z0=0.1 dz=0.15 d=-0.25 v=0.4")
    with Session(engine=ENGINE) as ses:
        ref = SweepResult(sc, [run_case(case, ses, keep_runs=False)]).rows()
    # same columns as the sweep CSV of 'djl-fmu simulate', plus move_index
    assert list(rows[0]) == list(ref[0]) + ["move_index"]
    got = rows[33:36]
    for r in ref:
        r["move_index"] = 11
    _assert_rows_identical(got, ref)
    assert got[0]["distance_m"] == -0.25 and got[0]["z0_m"] == 0.1
    assert got[1]["residual_m"] < got[0]["residual_m"]  # JL leaves less than AL
    # the grid view puts the move at its indices
    assert serial.grid("residual_m", "JL")[1, 0, 1, 1] == got[1]["residual_m"]
    assert serial.values("case_djl_vs_jl_residual_pct")[11] == pytest.approx(
        (got[2]["residual_m"] / got[1]["residual_m"] - 1.0) * 100.0, rel=1e-12)


def test_moves_are_different(serial):
    res = serial.values("residual_m", "DJL")
    assert np.all(np.isfinite(res)) and np.all(res > 0)
    assert len(set(res.tolist())) > 8  # not one move computed sixteen times


def test_identical_on_a_process_pool(serial, tmp_path):
    from harness.workspace import run_workspace_map

    sc = _scenario()
    with ProcessPoolExecutor(2) as ex:
        pool = run_workspace_map(sc, engine=ENGINE, executor=ex, batch=3)
    assert pool.batch == 3 and pool.executor == "local process pool"
    _assert_rows_identical(pool.rows(), serial.rows())
    a, b = serial.to_csv(tmp_path / "a.csv"), pool.to_csv(tmp_path / "b.csv")
    assert a.read_bytes() == b.read_bytes()
    # run_workspace_map's own pool, with another batch size and worker count
    own = run_workspace_map(sc, engine=ENGINE, workers=2, batch=5, max_moves=9)
    assert own.workers == 2
    _assert_rows_identical(own.rows(), _rows_of(serial, sc.map_indices(9)))


def _rows_of(res, indices):
    """The rows of the given grid moves of a whole map, duplicates marked among them only."""
    out = [copy.deepcopy(res.move_rows[k]) for k in indices]
    firsts: dict[str, str] = {}
    for rows in out:
        orig = rows[0]["duplicate_of"]
        key = orig or rows[0]["scenario"]
        dup = firsts.setdefault(key, rows[0]["scenario"])
        for r in rows:
            r["duplicate_of"] = dup if dup != rows[0]["scenario"] else ""
    return [r for rows in out for r in rows]


def test_max_moves_runs_moves_across_the_grid(serial):
    from harness.workspace import run_workspace_map

    sc = _scenario()
    part = run_workspace_map(sc, engine=ENGINE, workers=1, max_moves=5)
    idx = sc.map_indices(5)
    assert part.n_moves == 5 and part.points == [sc.map_points()[k] for k in idx]
    assert part.indices == idx and idx != [0, 1, 2, 3, 4]
    assert [rows[0]["move_index"] for rows in part.move_rows] == idx
    _assert_rows_identical(part.rows(), _rows_of(serial, idx))
    g = part.grid("residual_m", "AL").ravel()
    assert np.isfinite(g[idx]).all()
    assert np.isnan(np.delete(g, idx)).all()
    np.testing.assert_array_equal(g[idx], serial.grid("residual_m", "AL").ravel()[idx])


@pytest.mark.slow
def test_identical_on_a_dask_local_cluster(serial):
    from distributed import LocalCluster

    from harness.workspace import run_workspace_map

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        res = run_workspace_map(_scenario(), engine=ENGINE, scheduler=cluster.scheduler_address,
                      batch=2)
    assert res.executor.startswith("Dask cluster tcp://127.0.0.1:")
    assert res.workers == 2
    assert len(res.worker_ids) == 2  # both workers ran batches
    _assert_rows_identical(res.rows(), serial.rows())


def test_map_needs_a_map_table_and_a_known_engine():
    from harness.workspace import run_workspace_map

    with pytest.raises(ScenarioError, match=r"no \[map\] table"):
        run_workspace_map(_scenario(_with_map("")), engine=ENGINE, workers=1)
    with pytest.raises(ValueError, match="unknown engine"):
        run_workspace_map(_scenario(), engine="warp", workers=1)


def test_failing_move_is_named(monkeypatch):
    import harness.workspace
    from harness.workspace import WorkspaceMapError, run_workspace_map

    real = harness.workspace.run_case

    def flaky(case, session, **kw):
        if case.move.distance < 0 and case.z.z0 > 0:
            raise ValueError("planner refused")
        return real(case, session, **kw)

    monkeypatch.setattr(harness.workspace, "run_case", flaky)
    with pytest.raises(WorkspaceMapError) as ei:
        run_workspace_map(_scenario(), engine=ENGINE, workers=1)
    assert "move 10 " in str(ei.value) and "distance = -0.25 m" in str(ei.value)
    assert "planner refused" in str(ei.value)


def test_table_and_heat_maps(serial):
    txt = serial.table()
    assert "Map map-test: 16 of 16 moves" in txt and "per move" in txt
    for p in ("AL", "JL", "DJL"):
        med = np.median(serial.values("residual_m", p)) * 1e3
        assert f"{med:.4g}" in txt
    figs = serial.figures()
    assert list(figs) == ["djl-vs-jl", "JL-residual", "DJL-residual", "djl-vs-jl-settling"]
    # panel (z0 = 0.1, v_max = 0.4): rows z0, columns v_max; distance sorted on x
    fig = figs["DJL-residual"]
    ax = fig.axes[1 * 2 + 1]
    assert "z0 = 0.1 m, v_max = 0.4 m/s" in ax.get_title()
    shown = np.asarray(ax.collections[0].get_array()).reshape(2, 2)
    expect = serial.grid("residual_pct_of_AL", "DJL")[1][:, :, 1][:, [1, 0]]  # d: -0.25, 0.12
    np.testing.assert_array_equal(shown, expect)
    main_fig = serial.plot()
    assert "DJL compared with JL" in main_fig._suptitle.get_text()


# ----------------------------------------------------------------------- CLI


def test_cli_help(capsys):
    with pytest.raises(SystemExit) as ei:
        main(["map", "--help-full"])
    assert ei.value.code == 0
    out = capsys.readouterr().out
    for word in ("SCENARIO", "[map]", "--workers", "--scheduler", "--max-moves", "--engine",
                 "dask scheduler", "dask worker", "djl-fmu-out/map", "-map.csv", "-map.png",
                 "summary.txt", "identical", "Exit status"):
        assert word in out, word
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "djl-fmu map" in capsys.readouterr().out


def _bad_cases(tmp_path: Path) -> list[tuple[list[str], str]]:
    good = tmp_path / "good.toml"
    good.write_text(SCENARIO)
    nomap = tmp_path / "nomap.toml"
    nomap.write_text(_with_map(""))
    broken = tmp_path / "broken.toml"
    broken.write_text(_with_map("[map]\nv_max = [0.0]\n"))
    afile = tmp_path / "afile"
    afile.write_text("x")
    return [
        ([str(good), "--workers", "0"], "--workers must be >= 1"),
        ([str(good), "--max-moves", "0"], "--max-moves must be >= 1"),
        ([str(good), "--max-moves", "-3"], "--max-moves must be >= 1"),
        ([str(good), "--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"], "not both"),
        ([str(nomap)], "has no [map] table"),
        ([str(broken)], "map.v_max = [0.0]"),
        ([str(tmp_path / "missing.toml")], "no such scenario file"),
        ([str(good), "--out", str(afile)], "is not a directory"),
        ([str(good), "--scheduler", f"tcp://127.0.0.1:{_closed_port()}"],
         "cannot reach the Dask scheduler at tcp://127.0.0.1:"),
    ]


def test_cli_bad_inputs_exit_2_and_write_nothing(tmp_path, capsys, monkeypatch):
    import harness.executors

    monkeypatch.setattr(harness.executors, "CONNECT_TIMEOUT", 1.0)
    for args, message in _bad_cases(tmp_path):
        out = tmp_path / "out"
        if "--out" not in args:
            args = [*args, "--out", str(out)]
        rc = main(["map", *args, "--engine", ENGINE, "-q"])
        err = capsys.readouterr().err
        assert rc == 2, (args, err)
        assert message in err, (args, err)
        assert err.startswith("djl-fmu map: ") and err.count("\n") == 1, err
        assert "Traceback" not in err
        assert not out.exists()


def test_cli_argparse_refusals(capsys):
    for args in (["map"], ["map", "X", "--workers", "two"], ["map", "X", "--engine", "warp"]):
        with pytest.raises(SystemExit) as ei:
            main(args)
        assert ei.value.code == 2
        assert "Traceback" not in capsys.readouterr().err


def test_cli_failing_move_exit_1_and_writes_nothing(tmp_path, capsys, monkeypatch):
    import harness.workspace

    def broken(case, session, **kw):
        raise ValueError("no plan")

    monkeypatch.setattr(harness.workspace, "run_case", broken)
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    out = tmp_path / "out"
    rc = main(["map", str(scen), "--workers", "1", "--engine", ENGINE, "-o", str(out), "-q"])
    err = capsys.readouterr().err
    assert rc == 1 and "map failed (map-test): move 0 " in err and "no plan" in err
    assert not out.exists() or not any(out.iterdir())


def test_cli_run_writes_csv_heat_maps_and_summary(tmp_path, capsys, serial):
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    out = tmp_path / "out"
    rc = main(["map", str(scen), "--max-moves", "6", "--workers", "1", "--engine", ENGINE,
               "-o", str(out)])
    assert rc == 0
    captured = capsys.readouterr()
    text = captured.out
    assert "Map map-test: 6 of 16 moves" in text and "wrote 6 files" in text
    # progress on stderr (not a terminal: lines), the last one when all moves are done
    assert captured.err.splitlines()[-1].startswith("map map-test: 6/6 moves done in ")
    assert sorted(p.name for p in out.iterdir()) == [
        "map-test-map-DJL-residual.png", "map-test-map-JL-residual.png",
        "map-test-map-djl-vs-jl-settling.png", "map-test-map.csv", "map-test-map.png",
        "summary.txt"]
    for p in out.glob("*.png"):
        assert p.read_bytes()[:4] == b"\x89PNG"
    rows = list(csv.DictReader((out / "map-test-map.csv").open()))
    assert len(rows) == 18
    assert list(rows[0]) == list(serial.rows()[0])
    # six moves across the 16-move grid (every z0 and v_max), numbered in the whole grid
    picked = _scenario().map_indices(6)
    assert picked == [0, 1, 6, 9, 14, 15]  # 3 moves per z0, 3 per v_max, both dz, both d
    multi = np.array(np.unravel_index(picked, (2, 2, 2, 2))).T
    assert [np.bincount(multi[:, a]).tolist() for a in range(4)] == [[3, 3]] * 4
    assert [int(r["move_index"]) for r in rows] == [k for k in picked for _ in range(3)]
    for r, ref in zip(rows, _rows_of(serial, picked), strict=True):
        assert float(r["residual_m"]) == pytest.approx(ref["residual_m"], rel=1e-9)
        assert float(r["settling_time_s"]) == pytest.approx(ref["settling_time_s"], rel=1e-9)
        assert float(r["motion_time_s"]) == pytest.approx(ref["motion_time_s"], rel=1e-9)
    assert "Map map-test" in (out / "summary.txt").read_text()
    # quiet, no plot
    out2 = tmp_path / "out2"
    assert main(["map", str(scen), "--max-moves", "2", "--workers", "1", "--engine", ENGINE,
                 "-o", str(out2), "--no-plot", "-q"]) == 0
    assert sorted(p.name for p in out2.iterdir()) == ["map-test-map.csv", "summary.txt"]
    captured = capsys.readouterr()
    assert "Map map-test" not in captured.out and captured.err == ""


def test_duplicate_moves_are_marked_and_counted_once():
    """v_max = 2 and 3 m/s are never reached on a 0.05 m move: JL and DJL plan the same moves,
    so the second is marked a duplicate of the first and counted once; 0.3 m/s is reached on
    a 0.4 m move, so that move differs from the 0.4 m move at 2 m/s."""
    from harness.workspace import run_workspace_map

    sc = _scenario(_with_map("[map]\ndistance = [0.05, 0.4]\nv_max = [2.0, 3.0, 0.3]\n"))
    res = run_workspace_map(sc, engine=ENGINE, workers=1)
    dup = [rows[0]["duplicate_of"] for rows in res.move_rows]
    names = [rows[0]["scenario"] for rows in res.move_rows]

    # independent expectation: the first earlier move whose JL and DJL results coincide
    def sig(rows):
        return tuple((r["profile"], r["residual_m"], r["motion_time_s"], r["T_F1_s"],
                      r["T_F2_s"], r["T_F3_s"], r["T_F4_s"], r["settling_time_paper_band_s"])
                     for r in rows if r["profile"] in ("JL", "DJL"))

    sigs = [sig(rows) for rows in res.move_rows]
    expected = [next((names[j] for j in range(i) if sigs[j] == sigs[i]), "")
                for i in range(len(sigs))]
    assert dup == expected
    assert dup[1] == names[0]  # 0.05 m: v_max 3 = v_max 2
    assert dup[3] == "" and dup[5] == ""  # 0.4 m at 2 m/s vs 0.3 m/s: different moves
    assert res.distinct.tolist() == [not d for d in dup]
    assert f"{sum(1 for d in dup if d)} duplicates merged" in res.table()
    assert f"{sum(1 for d in dup if not d)} distinct moves counted" in res.table()
