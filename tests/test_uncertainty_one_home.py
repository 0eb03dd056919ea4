"""One uncertainty: the run's map scale reaches every output of every command (issue 36).

``[uncertainty] map_scale`` (or ``--uncertainty map_scale=E``) is the only home of the
relative error of the whole mode map; ``[compare] map_error`` and ``--map-error`` are its
deprecated aliases, read once with a note on stderr, refused when they disagree with it.
Each command that takes an uncertainty (simulate, compare, map, tune) runs here on a
small scenario with map_scale 0.15, each way of giving it covered, and the value is
looked for where a user reads it: the printed tables and legends (+/-15 %, never
+/-10 %), the CSV columns and metadata, the figures' shaded span, and the robust
tuning itself.  That the tuning ran at 0.15 is checked from its jerk times alone: they
leave the least worst residual over a +/-15 % grid the test writes out (and the default
run's over +/-10 %), the plant re-run for each by the test.  The default run keeps
today's labels, written out here as literals.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

import harness.commands.compare
import harness.commands.simulate
from harness.cli import main
from harness.scenario import load_scenario
from harness.simulation.session import Session

from _scenarios import SMALL_AXIS

SMALL = 'name = "small"\n\n' + SMALL_AXIS
"""The small scenario, its default uncertainty (map scale 0.1)."""

MAP = "\n[map]\ndistance = [0.2, 0.3]\n"
"""A two-move [map] grid: the scenario's own move (0.3 m) and a shorter one."""

U15 = "\n[uncertainty]\nmap_scale = 0.15\n"
ALIAS15 = "\n[compare]\nmap_error = 0.15\n"

NO_10 = ("+/-10", "±10", "|e| <= 10", "10pct", "10 %")
"""What no output of a 0.15 run may print (the column names aside: they are kept)."""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _run(capsys, argv: list[str]) -> tuple[str, str]:
    assert main(argv) == 0, capsys.readouterr().err
    got = capsys.readouterr()
    return got.out, got.err


def _csv(path: Path) -> tuple[dict[str, str], list[dict[str, str]]]:
    """A CSV's '#' metadata (key: value) and its rows."""
    lines = path.read_text(encoding="utf-8").splitlines()
    meta = dict(line[2:].split(": ", 1) for line in lines if line.startswith("# ")
                and ": " in line)
    rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    return meta, rows


def _no_10(text: str) -> None:
    """No span of +/-10 % anywhere in a 0.15 run's printed text (the kept column names
    ``..._10pct_...`` and ``..._map10_...`` in the legend's note aside)."""
    text = re.sub(r"\b\w*(10pct|map10)\w*\b", "<column>", text)
    for bad in NO_10:
        assert bad not in text, (bad, text)


def _span(ax) -> tuple[float, float]:
    """The x extent (data units) of the axes' one shaded span (axvspan)."""
    (patch,) = ax.patches
    xy = patch.get_patch_transform().transform(patch.get_path().vertices)
    return float(xy[:, 0].min()), float(xy[:, 0].max())


@pytest.fixture
def figures(monkeypatch):
    """The figures simulate and compare save (their runs are in this process)."""
    saved: dict[str, object] = {}
    for module in (harness.commands.simulate, harness.commands.compare):
        original = module.save_figure

        def keep(fig, path, *args, _original=original, **kw):
            saved[Path(path).name] = fig
            return _original(fig, path, *args, **kw)

        monkeypatch.setattr(module, "save_figure", keep)
    return saved


def _djl(row: dict[str, object], keys: tuple[str, ...]) -> tuple[float, ...]:
    return tuple(round(float(row[k]), 9) for k in keys)


TUNE_KEYS = tuple(f"djl_T_F{i}_s" for i in range(1, 5))
ROW_KEYS = tuple(f"T_F{i}_s" for i in range(1, 5))


@pytest.fixture(scope="module")
def tuned(tmp_path_factory):
    """``tune --single`` of the small move: the default, 0.15 given the four ways, 0.25.

    ``way -> (stdout, stderr, the CSV's metadata, its one row)``; ``"dir"``: the folder of
    the scenario files.
    """
    tmp = tmp_path_factory.mktemp("tune")
    plain = _write(tmp, "plain.toml", SMALL)
    ways = {
        "default": [str(plain)],
        "file": [str(_write(tmp, "u15.toml", SMALL + U15))],
        "option": [str(plain), "--uncertainty", "map_scale=0.15"],
        "deprecated option": [str(plain), "--map-error", "0.15"],
        "deprecated key": [str(_write(tmp, "a15.toml", SMALL + ALIAS15))],
        "0.25": [str(plain), "--uncertainty", "map_scale=0.25"],
    }
    got: dict[str, object] = {"dir": tmp}
    for way, args in ways.items():
        o = tmp / f"tune-{way.replace(' ', '-')}"
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = main(["tune", *args, "--single", "-o", str(o)])
        assert rc == 0, err.getvalue()
        meta, (row,) = _csv(o / "small-jerk-times.csv")
        got[way] = (out.getvalue(), err.getvalue(), meta, row)
    return got


def test_tune_takes_the_uncertainty_every_way(tuned):
    """tune at 0.15 (file, --uncertainty, --map-error, [compare] map_error) and at 0.25:
    the metadata, the printed table, the rows, and a robust tuning done at that scale."""
    for way in ("file", "option", "deprecated option", "deprecated key"):
        text, err, meta, row = tuned[way]
        assert meta["map_error"] == "0.15", way
        assert meta["uncertainty"].startswith("map scale +/-15 %"), way
        assert "worst, map +/-15 % [mm]" in text and "map scale +/-15 %" in text, way
        _no_10(text)
        # the same tuning whichever way 0.15 was given
        assert row == tuned["file"][3], way
    assert tuned["0.25"][2]["map_error"] == "0.25"  # --uncertainty reaches tune (was 0.1)
    assert tuned["default"][2]["map_error"] == "0.1"
    assert "worst, map +/-10 % [mm]" in tuned["default"][0]

    # the robust tuning ran at the scale asked: each run's jerk times leave the least worst
    # residual over its own 9-point grid (the tuning set's map scales), the plant re-run
    # for each set of jerk times on grids the test writes out
    sc = load_scenario(str(tuned["dir"] / "plain.toml"))
    runs = {"default": 0.10, "file": 0.15, "0.25": 0.25}
    T = {way: _djl(tuned[way][3], TUNE_KEYS) for way in runs}
    assert len(set(T.values())) == 3
    with Session(engine="fast") as s:
        for scale in runs.values():
            grid = np.linspace(-scale, scale, 9)
            worst = {way: float(np.max(s.map_error_residuals(sc, "DJL", T[way], grid)))
                     for way in runs}
            best = min(worst, key=worst.__getitem__)
            assert runs[best] == scale, (scale, worst)
        # the worst_* columns: the largest residual over the 41 points of +/-scale
        for way, scale in runs.items():
            row = tuned[way][3]
            grid = np.linspace(-scale, scale, 41)
            djl = float(np.max(s.map_error_residuals(sc, "DJL", T[way], grid)))
            jl = float(np.max(s.map_error_residuals(sc, "JL", (float(row["jl_T_F_s"]),) * 4,
                                                    grid)))
            assert float(row["worst_residual_m"]) == pytest.approx(djl, rel=1e-9)
            assert float(row["jl_worst_residual_m"]) == pytest.approx(jl, rel=1e-9)


def test_deprecated_aliases_are_read_with_a_note(tuned):
    """One line on stderr for a deprecated alias, none for the new keys."""
    assert tuned["deprecated option"][1] == (
        "djl-fmu: note: --map-error is deprecated: write --uncertainty map_scale=0.15 "
        "instead (read as that)\n")
    err = tuned["deprecated key"][1]
    assert err.count("\n") == 1 and err.startswith("djl-fmu: note: ")
    assert "a15.toml: [compare] map_error is deprecated: write [uncertainty] map_scale = 0.15" \
        in err
    for way in ("default", "file", "option", "0.25"):
        assert "note" not in tuned[way][1], way


@pytest.mark.parametrize("command", ["simulate", "compare", "map", "tune"])
def test_help_marks_map_error_deprecated(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert re.search(r"--map-error E deprecated: the same as --uncertainty map_scale=E", text)


@pytest.mark.parametrize("command", ["simulate", "compare", "map", "tune"])
def test_conflicting_option_and_alias_are_refused(command, tmp_path, capsys):
    """--map-error and --uncertainty map_scale disagreeing (also 'none': 0): exit 2, both
    named, nothing written."""
    out = tmp_path / "out"
    for unc, shown in (("map_scale=0.15", "--uncertainty map_scale = 0.15"),
                       ("none", "--uncertainty map_scale = 0.0")):
        rc = main([command, "X", "--map-error", "0.1", "--uncertainty", unc, "-o", str(out)])
        err = capsys.readouterr().err
        assert rc == 2, err
        assert "--map-error = 0.1 (deprecated)" in err and shown in err, err
        assert "disagree" in err and "note" not in err
        assert not out.exists()
    # agreeing: read as one (the note only)
    assert main(["tune", "X", "--single", "--map-error", "0.15", "--uncertainty",
                 "map_scale=0.15,map_slope=0.2", "-o", str(out), "-q"]) == 0
    meta, _ = _csv(out / "X-jerk-times.csv")
    assert meta["map_error"] == "0.15" and "map slope +/-20 %" in meta["uncertainty"]


@pytest.mark.parametrize("extra, words", [
    (ALIAS15.replace("0.15", "0.1") + U15,
     ("compare.map_error = 0.1 (deprecated)", "uncertainty.map_scale = 0.15", "disagree")),
    ("\n[compare]\ndamping = [0.5, 1.0, 2.0]\n[uncertainty]\ndamping = [0.5, 3.0]\n",
     ("compare.damping [0.5, 1.0, 2.0]", "uncertainty.damping = [0.5, 3.0]", "disagree")),
])
def test_conflicting_scenario_keys_are_refused(extra, words, tmp_path, capsys):
    path = _write(tmp_path, "c.toml", SMALL + extra)
    out = tmp_path / "out"
    assert main(["tune", str(path), "--single", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    for w in words:
        assert w in err, err
    assert str(path) in err and not out.exists()
    # agreeing values: read, with the note
    ok = _write(tmp_path, "ok.toml", SMALL + ALIAS15 + U15)
    assert main(["tune", str(ok), "--single", "-o", str(out), "-q"]) == 0
    assert "[compare] map_error is deprecated" in capsys.readouterr().err


def test_simulate_takes_the_run_uncertainty(tmp_path, capsys, figures, tuned):
    """simulate with [uncertainty] map_scale = 0.15: tables, legends, CSV, figure, robust."""
    path = _write(tmp_path, "u15.toml", SMALL + U15)
    out = tmp_path / "sim"
    text, err = _run(capsys, ["simulate", str(path), "--engine", "fast", "--tuning", "robust",
                              "-o", str(out)])
    assert "note" not in err
    for line in ("Worst residual, map error +/-15 % [mm]",
                 "Worst residual, map error +/-15 %: largest residual for every f(z) x "
                 "(1 + e), |e| <= 15 %",
                 "The CSV columns residual_worst_map10_m, residual_worst_map10_pct_of_AL keep "
                 "their names and hold this +/-15 % worst case.",
                 "worst residual over +/-15 % map error",
                 "Uncertainty: map scale +/-15 %; scoring set, 41 points"):
        assert line in text, line
    _no_10(text)
    assert "Worst residual, map error +/-15 % [mm]" in (out / "summary.txt").read_text()
    rows = {r["profile"]: r for r in csv.DictReader((out / "small.csv").open())}
    curves = list(csv.DictReader((out / "small-robustness.csv").open()))
    for name, r in rows.items():
        assert r["uncertainty"] == "map scale +/-15 %; scoring set, 41 points"
        mine = [(float(c["map_error"]), float(c["residual_m"])) for c in curves
                if c["profile"] == name]
        e = np.array([x for x, _ in mine])
        # the curves span +/-2 x 0.15 in 41 points; the worst case is over +/-0.15 of them
        np.testing.assert_allclose(e, np.linspace(-0.3, 0.3, 41), atol=1e-15)
        worst15 = max(v for x, v in mine if abs(x) <= 0.15 + 1e-12)
        worst10 = max(v for x, v in mine if abs(x) <= 0.10 + 1e-12)
        assert float(r["residual_worst_map10_m"]) == pytest.approx(worst15, rel=1e-9)
        if name == "JL":
            assert worst15 > worst10 * 1.05   # not the +/-10 % worst case
    # the robust DJL is tune's at 0.15
    assert _djl(rows["DJL-robust"], ROW_KEYS) == _djl(tuned["file"][3], TUNE_KEYS)
    fig = figures["small-robustness.png"]
    (ax,) = fig.axes
    assert _span(ax) == pytest.approx((-15.0, 15.0))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "+/-15 % (worst case)" in labels
    assert any(lab.startswith("JL: worst over +/-15 % ") for lab in labels)
    _no_10("\n".join(labels))


def test_compare_takes_the_run_uncertainty(tmp_path, capsys, figures, tuned):
    """compare with --uncertainty map_scale=0.15: the table's column, legend, verdict, the
    CSV, the map-error curves and their figure, the robust DJL."""
    path = _write(tmp_path, "plain.toml", SMALL)
    out = tmp_path / "cmp"
    text, err = _run(capsys, ["compare", str(path), "--uncertainty", "map_scale=0.15",
                              "--engine", "fast", "--no-stationary", "--timeopt", "0",
                              "--no-bound", "--peers", "AL*ZV", "-o", str(out)])
    assert "note" not in err
    for line in ("worst±15% [mm]", "worst±15%: largest residual over map errors e in +/-15 %",
                 "The CSV columns worst_residual_10pct_m, worst_residual_10pct_pct_of_AL keep "
                 "their names and hold this +/-15 % worst case.",
                 "smallest worst case over +/-15 % map error",
                 "worst settle: worst-case settling time over the map scale +/-15 %"):
        assert line in text, line
    _no_10(text)
    rows = {r["method"]: r for r in csv.DictReader((out / "small.csv").open())}
    curves = list(csv.DictReader((out / "small-map-error.csv").open()))
    for name, r in rows.items():
        assert r["uncertainty"].startswith("map scale +/-15 %")
        mine = [(float(c["map_error"]), float(c["residual_m"])) for c in curves
                if c["method"] == name]
        np.testing.assert_allclose([x for x, _ in mine], np.linspace(-0.3, 0.3, 41),
                                   atol=1e-15)
        worst15 = max(v for x, v in mine if abs(x) <= 0.15 + 1e-12)
        assert float(r["worst_residual_10pct_m"]) == pytest.approx(worst15, rel=1e-9)
    params = json.loads(rows["DJL (robust)"]["fmu_parameters"])
    assert _djl(params, ("T_F1", "T_F2", "T_F3", "T_F4")) == _djl(tuned["file"][3], TUNE_KEYS)
    fig = figures["small-map-error.png"]
    assert "(shaded: +/-15 %, the worst case)" in fig._suptitle.get_text()
    for ax in fig.axes[:2]:
        assert _span(ax) == pytest.approx((-15.0, 15.0))


def test_map_takes_the_run_uncertainty(tmp_path, capsys, tuned):
    """map with the deprecated --map-error 0.15: the note, the CSV's uncertainty and worst
    cases, and the robust DJL tuned at 0.15 (tune's, for the scenario's own move)."""
    path = _write(tmp_path, "m.toml", SMALL + MAP)
    out = tmp_path / "map"
    text, err = _run(capsys, ["map", str(path), "--map-error", "0.15", "--tuning", "robust",
                              "--workers", "1", "--no-plot", "-o", str(out)])
    assert "djl-fmu: note: --map-error is deprecated" in err
    _no_10(text)
    rows = list(csv.DictReader((out / "small-map.csv").open()))
    assert {r["uncertainty"] for r in rows} == {"map scale +/-15 %; scoring set, 41 points"}
    (robust,) = [r for r in rows if r["profile"] == "DJL-robust" and r["distance_m"] == "0.3"]
    assert _djl(robust, ROW_KEYS) == _djl(tuned["file"][3], TUNE_KEYS)
    assert _djl(robust, ROW_KEYS) != _djl(tuned["default"][3], TUNE_KEYS)


def test_the_default_run_keeps_its_labels(tmp_path, capsys, figures):
    """The default uncertainty (map scale 0.1): the labels of before, word for word."""
    path = _write(tmp_path, "plain.toml", SMALL)
    out = tmp_path / "sim"
    text, err = _run(capsys, ["simulate", str(path), "--engine", "fast", "-o", str(out)])
    assert "note" not in err
    for line in ("Worst residual, map error +/-10 % [mm]",
                 "Worst residual, map error +/-10 %: largest residual for every f(z) x "
                 "(1 + e), |e| <= 10 %, jerk times tuned on the nominal map (time-varying "
                 "plant (Z moving), whole map scaled by 1 + e).\n",
                 "worst residual over +/-10 % map error",
                 "Uncertainty: map scale +/-10 %; scoring set, 41 points"):
        assert line in text, line
    assert "keep their names" not in text
    curves = list(csv.DictReader((out / "small-robustness.csv").open()))
    e = [float(c["map_error"]) for c in curves if c["profile"] == "JL"]
    np.testing.assert_allclose(e, np.linspace(-0.2, 0.2, 41), atol=1e-15)  # CSV: 10 digits
    (ax,) = figures["small-robustness.png"].axes
    assert _span(ax) == pytest.approx((-10.0, 10.0))
    assert "+/-10 % (worst case)" in [t.get_text() for t in ax.get_legend().get_texts()]


def test_a_sweep_takes_the_run_uncertainty(tmp_path, capsys):
    """simulate on a [sweep] with map_scale 0.15: each case's worst case over the 21 points
    of +/-15 % (the plant re-run here on that grid), Table 2's label."""
    path = _write(tmp_path, "sw.toml", SMALL + U15 + "\n[sweep]\ndistance = [0.2, 0.3]\n")
    out = tmp_path / "sw"
    text, _ = _run(capsys, ["simulate", str(path), "--tuning", "robust", "--workers", "1",
                            "--no-plot", "-o", str(out)])
    assert "Worst residual, map error +/-15 % (time-varying plant, whole map x (1 + e))" in text
    assert "worst over +/-15 % map, % of JL's" in text
    _no_10(text)
    rows = list(csv.DictReader((out / "small.csv").open()))
    grid = np.linspace(-0.15, 0.15, 21)
    sc = load_scenario(str(path))
    checked = 0
    with Session(engine="fast") as s:
        for case in sc.cases():
            for r in rows:
                if r["scenario"] == case.name and r["profile"] in ("JL", "DJL-robust"):
                    T = tuple(float(r[k]) for k in ROW_KEYS)
                    expect = float(np.max(s.map_error_residuals(
                        case, r["profile"].split("-")[0], T, grid)))
                    assert float(r["residual_worst_map10_m"]) == pytest.approx(expect,
                                                                               rel=1e-9)
                    checked += 1
    assert checked == 4
    quantities = [r["quantity"] for r in csv.DictReader((out / "table2.csv").open())]
    assert "worst_residual_10pct" in quantities   # the name kept: the run's +/-15 %
