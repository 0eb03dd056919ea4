"""Data out: ``<scenario>-signals.csv``, ``--mat`` and the results' table export.

The CSV written by ``djl-fmu simulate`` is read back and checked column by column
against the arrays of the result objects (:class:`~harness.simulation.master.CoSimResult`:
``t``, ``x``, ``v``, ``a``, ``j``, ``eps``, ``z``, ``f``) of the same scenario run in
this process; past the end of a shorter record, against the axes at rest and the
deflection's free response (:meth:`CoSimResult.extend`).  The ``.mat`` file is read with
:func:`scipy.io.loadmat` and compared with the CSV.
"""

from __future__ import annotations

import csv
import sys

import numpy as np
import pytest

from harness.cli import main
from harness.scenario import load_scenario
from harness.sweeps import run_scenario
from harness.tables import columns_of, mat_name, rows_of, to_pandas

from _scenarios import SMALL_AXIS

SCENARIO = 'name = "sig-test"\n\n' + SMALL_AXIS
ATTRS = {"x_m": "x", "v_m_s": "v", "a_m_s2": "a", "j_m_s3": "j", "eps_m": "eps", "z_m": "z"}


def read_csv(path):
    with path.open(encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


@pytest.fixture(scope="module")
def written(tmp_path_factory, fmu2):
    """The CLI's outputs (``--mat``) and the same scenario's result, run here."""
    d = tmp_path_factory.mktemp("sig")
    scen = d / "s.toml"
    scen.write_text(SCENARIO)
    out = d / "out"
    assert main(["simulate", str(scen), "--fmu", str(fmu2), "-o", str(out), "--mat",
                 "--no-plot", "-q"]) == 0
    res = run_scenario(load_scenario(scen).with_fmu(fmu2, None))
    return out, res


def test_signals_csv_columns_and_values_are_the_result_arrays(written):
    out, res = written
    header, data = read_csv(out / "sig-test-signals.csv")
    names = list(res.profiles)
    assert names == ["AL", "JL", "DJL", "recommended"]
    expected = ["t_s", "z_m", "f_Hz"] + [f"{p}_{s}" for p in names for s in (
        "x_m", "v_m_s", "a_m_s2", "j_m_s3", "eps_m", "z_m", "f_Hz")]
    assert header == expected
    col = {h: data[:, i] for i, h in enumerate(header)}
    runs = {n: p.run for n, p in res.profiles.items()}
    n_max = max(r.t.size for r in runs.values())
    assert data.shape[0] == n_max
    step = next(iter(runs.values())).step
    np.testing.assert_allclose(col["t_s"], step * np.arange(n_max), rtol=1e-9, atol=1e-12)
    tune = res.scenario.modemap.tune
    for n, r in runs.items():
        k = r.t.size
        for suffix, attr in ATTRS.items():
            np.testing.assert_allclose(col[f"{n}_{suffix}"][:k], getattr(r, attr),
                                       rtol=1e-9, atol=1e-15, err_msg=f"{n}_{suffix}")
        np.testing.assert_allclose(col[f"{n}_f_Hz"][:k], r.f[tune], rtol=1e-9)
        # after its record: at rest (last values held), the deflection's free response
        rest = n_max - k
        for suffix, attr in ATTRS.items():
            if suffix != "eps_m":
                assert np.all(col[f"{n}_{suffix}"][k:] == pytest.approx(getattr(r, attr)[-1],
                                                                        rel=1e-9, abs=1e-15))
        if rest:
            _, eps_more = r.extend(rest * r.step)
            np.testing.assert_allclose(col[f"{n}_eps_m"][k:], eps_more[:rest], rtol=1e-9,
                                       atol=1e-15)
    first = runs["AL"]
    np.testing.assert_allclose(col["z_m"][:first.t.size], first.z, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(col["f_Hz"][:first.t.size], first.f[tune], rtol=1e-9)
    # the Z move ends with the excited axis: z(t) depends on the profile
    assert not np.allclose(col["AL_z_m"], col["JL_z_m"])


def test_mat_file_round_trips(written):
    from scipy.io import loadmat

    out, res = written
    header, data = read_csv(out / "sig-test-signals.csv")
    m = loadmat(out / "sig-test.mat", simplify_cells=True)
    assert m["scenario"] == "sig-test"
    assert list(m["signal_columns"]) == header
    for i, h in enumerate(header):
        np.testing.assert_allclose(m["signals"][mat_name(h)], data[:, i], rtol=1e-9, atol=1e-15)
    with (out / "sig-test.csv").open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert list(m["metrics"]["profile"]) == [r["profile"] for r in rows]
    np.testing.assert_allclose(m["metrics"]["residual_m"],
                               [float(r["residual_m"]) for r in rows], rtol=1e-9)


def test_a_sweep_writes_no_signals_but_its_mat(tmp_path, fmu2):
    scen = tmp_path / "s.toml"
    scen.write_text('name = "sw"\n\n' + SMALL_AXIS + "\n[sweep]\ndistance = [0.2, 0.3]\n")
    out = tmp_path / "o"
    assert main(["simulate", str(scen), "--fmu", str(fmu2), "-o", str(out), "--mat",
                 "--no-plot", "-q", "--engine", "fast"]) == 0
    assert not (out / "sw-signals.csv").exists()
    from scipy.io import loadmat

    m = loadmat(out / "sw.mat", simplify_cells=True)
    with (out / "sw.csv").open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert "signals" not in m
    assert list(m["metrics"]["scenario"]) == [r["scenario"] for r in rows]


def test_result_tables(written):
    _, res = written
    sig = res.to_table()
    assert sig.keys() == res.signals().keys()
    np.testing.assert_array_equal(sig["DJL_x_m"][:res.profiles["DJL"].run.t.size],
                                  res.profiles["DJL"].run.x)
    met = res.to_table("metrics")
    rows = res.rows()
    assert list(met) == list(rows[0])
    assert met["profile"].tolist() == [r["profile"] for r in rows]
    np.testing.assert_array_equal(met["residual_m"], [r["residual_m"] for r in rows])
    assert np.isnan(met["T_F1_s"][0]) and met["T_F1_s"][1] == rows[1]["T_F1_s"]  # AL: blank
    with pytest.raises(ValueError, match="signals"):
        res.to_table("nope")


def test_columns_and_rows_round_trip():
    rows = [{"a": 1.5, "b": "x", "c": True, "d": ""}, {"a": 2, "b": "y", "c": False, "d": 3.0}]
    cols = columns_of(rows)
    assert cols["a"].dtype == float and cols["c"].dtype == bool and cols["b"].dtype == object
    assert np.isnan(cols["d"][0]) and cols["d"][1] == 3.0
    back = rows_of(cols)
    assert back[1] == {"a": 2.0, "b": "y", "c": False, "d": 3.0}
    assert mat_name("DJL-optimal_x_m") == "DJL_optimal_x_m" and mat_name("1x") == "x1x"
    with pytest.raises(ValueError):
        rows_of({"a": np.zeros(2), "b": np.zeros(3)})


def test_to_pandas_is_optional(monkeypatch):
    cols = {"t_s": np.arange(3.0), "p": np.array(["a", "b", "c"], dtype=object)}
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match="pip install pandas"):
        to_pandas(cols)


def test_to_pandas_when_installed():
    pd = pytest.importorskip("pandas")
    cols = {"t_s": np.arange(3.0), "p": np.array(["a", "b", "c"], dtype=object)}
    df = to_pandas(cols)
    assert isinstance(df, pd.DataFrame) and list(df.columns) == ["t_s", "p"]
    np.testing.assert_array_equal(df["t_s"].to_numpy(), cols["t_s"])


def test_line_progress_prints_as_it_goes_and_only_a_finished_total(capsys):
    import io

    from harness.executors import LineProgress

    s = io.StringIO()
    p = LineProgress(10, "map X", "moves", interval=0.0, stream=s)
    for _ in range(4):
        p.update(3 if p.n < 9 else 1)
    p.close()
    lines = s.getvalue().splitlines()
    assert [x.split(" (")[0].split(" done")[0] for x in lines] == [
        "map X: 3/10 moves", "map X: 6/10 moves", "map X: 9/10 moves", "map X: 10/10 moves"]
    assert "done in" in lines[-1] and "left" in lines[0]
    s2 = io.StringIO()
    p = LineProgress(10, "map X", interval=3600.0, stream=s2)
    p.update(2)
    p.update(2)  # within the interval: no line
    p.close()    # not finished (interrupted): no "done" line
    assert s2.getvalue().splitlines() == [s2.getvalue().splitlines()[0]]
    assert "done" not in s2.getvalue()
