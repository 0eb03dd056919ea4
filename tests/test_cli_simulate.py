"""``djl-fmu simulate``: help, listing, a run with its outputs, and refusals."""

from __future__ import annotations

import csv
import shutil
import zipfile
from pathlib import Path

import pytest

from harness.cli import main

from _scenarios import SMALL_AXIS

SCENARIO = """\
name = "cli-test"

""" + SMALL_AXIS


def test_help_explains_inputs_outputs_and_defaults(capsys):
    with pytest.raises(SystemExit) as ei:
        main(["simulate", "--help-full"])
    assert ei.value.code == 0
    out = capsys.readouterr().out
    for word in ("SCENARIO", "TOML", "sweep-X", "--out", "djl-fmu-out/simulate", ".csv", ".png",
                 "--fmi-version", "--fmu", "Exit status"):
        assert word in out


def test_list_embedded(capsys):
    assert main(["simulate", "--list"]) == 0
    out = capsys.readouterr().out
    for name in ("X", "Y", "sweep-X", "sweep-Y"):
        assert name in out


def test_run_writes_table_csv_and_plot(tmp_path, capsys, fmu2):
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    out = tmp_path / "out"
    rc = main(["simulate", str(scen), "--fmu", str(fmu2), "-o", str(out)])
    assert rc == 0
    captured = capsys.readouterr()
    text = captured.out
    assert "Residual vibration [mm]" in text and "DJL compared with JL" in text
    # a progress line on stderr as the scenario finishes
    assert "simulate: cli-test (one move) done in " in captured.err
    assert sorted(p.name for p in out.iterdir()) == [
        "cli-test-degradation.csv", "cli-test-degradation.png", "cli-test-robustness.csv",
        "cli-test-robustness.png", "cli-test-signals.csv", "cli-test.csv", "cli-test.png",
        "summary.txt"]
    # the recommended profile's and the textbook shapers' worst case at every width (issue 33)
    deg = list(csv.DictReader((out / "cli-test-degradation.csv").open()))
    methods = {r["method"] for r in deg}
    assert methods == {"recommended", "JL*ZV", "JL*ZVD", "JL*EI", "JL*SI"}
    widths = sorted({float(r["width"]) for r in deg})
    assert widths[0] == 0.0 and widths[-1] == pytest.approx(2.0) and len(widths) == 81
    assert "Wider than stated (map scale)" in text and "Why the recommended profile" in text
    rows = list(csv.DictReader((out / "cli-test.csv").open()))
    # the robustness curves pass through the nominal residual at e = 0 and their worst case
    # over +/-10 % is the CSV's
    rob = list(csv.DictReader((out / "cli-test-robustness.csv").open()))
    for r in rows:
        mine = [x for x in rob if x["profile"] == r["profile"]]
        assert len(mine) == 41
        nominal = [float(x["residual_m"]) for x in mine if abs(float(x["map_error"])) < 1e-12]
        assert nominal == [pytest.approx(float(r["residual_m"]), rel=1e-9)]
        worst = max(float(x["residual_m"]) for x in mine if abs(float(x["map_error"])) <= 0.1001)
        assert worst == pytest.approx(float(r["residual_worst_map10_m"]), rel=1e-9)
    assert [r["profile"] for r in rows] == ["AL", "JL", "DJL", "recommended"]
    assert float(rows[0]["residual_pct_of_AL"]) == pytest.approx(100.0)
    assert (out / "cli-test.png").read_bytes()[:4] == b"\x89PNG"
    assert "Residual vibration" in (out / "summary.txt").read_text()


def test_fmi3_option(tmp_path, capsys, fmu3):
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    rc = main(["simulate", str(scen), "--fmu", str(fmu3), "-o", str(tmp_path / "o"),
               "--no-plot", "-q"])
    assert rc == 0
    assert capsys.readouterr().err == ""  # -q: no progress line
    assert "FMU " + str(fmu3) in (tmp_path / "o" / "summary.txt").read_text()
    assert not (tmp_path / "o" / "cli-test.png").exists()


def test_bad_scenario_exits_non_zero_and_writes_nothing(tmp_path, capsys):
    good = tmp_path / "good.toml"
    good.write_text(SCENARIO)
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENARIO.replace("zeta = 0.04", "zeta = 1.5"))
    out = tmp_path / "out"
    # the bad file comes second: the good one must not have been run or written either
    rc = main(["simulate", str(good), str(bad), "-o", str(out)])
    assert rc == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "mode[1].zeta" in err and "1.5" in err
    assert not out.exists()
    assert main(["simulate", "no-such-scenario", "-o", str(out)]) == 2
    assert "no such scenario" in capsys.readouterr().err
    assert not out.exists()


def test_fmu_without_the_variables_is_refused(tmp_path, capsys, fmu2):
    bad = tmp_path / "bad.fmu"
    with zipfile.ZipFile(fmu2) as zin, zipfile.ZipFile(bad, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = data.replace(b'name="motion_time"', b'name="duration"')
            zout.writestr(item, data)
    scen = tmp_path / "s.toml"
    scen.write_text(SCENARIO)
    out = tmp_path / "out"
    assert main(["simulate", str(scen), "--fmu", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "simulation.fmu" in err and str(bad) in err and "motion_time" in err
    assert not out.exists()
    notfmu = tmp_path / "x.fmu"
    shutil.copy(scen, notfmu)
    assert main(["simulate", str(scen), "--fmu", str(notfmu), "-o", str(out)]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_embedded_name_runs(tmp_path, capsys, fmu2):
    rc = main(["simulate", "Y", "--fmu", str(fmu2), "-o", str(tmp_path), "-q", "--no-plot"])
    assert rc == 0
    assert Path(tmp_path / "Y.csv").exists()


@pytest.mark.parametrize("command", ["build", "demo", "simulate", "map", "tune", "online",
                                     "report", "compare"])
def test_short_help_points_to_the_full_help_and_the_docs(command, capsys):
    from harness.cli import DOCS

    with pytest.raises(SystemExit):
        main([command, "--help"])
    short = capsys.readouterr().out
    with pytest.raises(SystemExit):
        main([command, "--help-full"])
    full = capsys.readouterr().out
    assert len(short.splitlines()) <= 65, len(short.splitlines())
    assert f"djl-fmu {command} --help-full" in " ".join(short.split())
    assert DOCS[command] in " ".join(short.split())
    assert (Path(__file__).resolve().parents[1] / DOCS[command]).is_file()
    assert "issue #" not in short + full
