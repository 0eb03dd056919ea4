"""Scenario files: the embedded defaults, and every kind of bad input caught before running."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.modemap import CantileverLaw, LinearLaw, TableLaw
from harness.scenario import (
    DEFAULT_SCENARIOS,
    ScenarioError,
    embedded_scenarios,
    load_scenario,
    parse_scenario,
)

GOOD = """\
name = "small"
description = "a test scenario"

[simulation]
Te = 0.001
step = 0.002
t_after = 0.5
fmi_version = 3

[move]
distance = -0.2
v_max = 0.5
a_max = 4.0

[z]
z0 = 0.1
distance = 0.3
a_max = 8.0
v_max = 2.0
T_F = 0.04

[[mode]]
name = "first"
zeta = 0.03
law = "table"
z = [0.0, 0.2, 0.5]
f = [9.0, 8.0, 6.5]

[[mode]]
zeta = 0.05
law = "cantilever"
f_ref = 40.0
L_ref = 0.5
mass_ratio = 2.0

[compare]
profiles = ["JL", "DJL"]
tune_mode = 1
"""


def write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def replace_line(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


# ------------------------------------------------------------ embedded


def test_embedded_default_scenarios_follow_section_4_of_the_paper():
    names = embedded_scenarios()
    assert set(DEFAULT_SCENARIOS) <= set(names)
    x, y = load_scenario("X"), load_scenario("Y")
    assert (x.move.distance, x.move.v_max, x.move.a_max) == (0.4, 0.5, 4.0)
    assert (y.move.distance, y.move.v_max, y.move.a_max) == (0.3, 2.0, 4.0)
    for sc, lo, hi in ((x, 20.0, 25.0), (y, 28.0, 33.0)):
        law = sc.modemap.tuned.law
        assert isinstance(law, LinearLaw)
        # first mode drops linearly with Z over 0.5 m
        assert law.z == (0.0, 0.5) and law.f[1] < law.f[0]
        f0, f1 = sc.modemap.tuned.f(sc.z.z0), sc.modemap.tuned.f(sc.z.z0 + sc.z.distance)
        assert lo <= 100 * (f0 - f1) / f0 <= hi
        assert 0.02 <= sc.modemap.tuned.zeta <= 0.08
        assert sc.compare.profiles == ("AL", "JL", "DJL")
    # X has a constant-velocity stage, Y does not (d < v_max^2 / a_max)
    assert x.move.distance > x.move.v_max**2 / x.move.a_max
    assert y.move.distance < y.move.v_max**2 / y.move.a_max
    sw = load_scenario("sweep-X")
    cases = sw.cases()
    assert len(cases) == 5 * 5 * 2
    assert {c.move.distance for c in cases} == {0.1, 0.2, 0.3, 0.4, 0.5}
    assert {c.z.distance for c in cases} == {0.1, 0.2, 0.3, 0.4, 0.5}
    assert {c.move.v_max for c in cases} == {0.5, 2.0}
    assert load_scenario("x").name == "X"  # names are case-insensitive


def test_good_file_parses(tmp_path):
    sc = load_scenario(write(tmp_path, GOOD))
    assert sc.name == "small" and sc.simulation.step == 0.002
    assert sc.simulation.fmi_version == 3 and sc.simulation.band is None
    assert sc.move.d_max == 4.0 and sc.move.target == -0.2
    assert isinstance(sc.modemap.modes[0].law, TableLaw)
    law = sc.modemap.modes[1].law
    assert isinstance(law, CantileverLaw) and law.direction == 1
    assert sc.modemap.modes[1].f(0.0) == pytest.approx(40.0 / 2**0.5)
    assert sc.compare.profiles == ("JL", "DJL") and sc.compare.djl_rule == "start"
    assert not sc.is_sweep and sc.cases() == [sc]


# -------------------------------------------------------------- errors

BAD = [
    # (old, new, key in the message, value in the message)
    ('name = "small"', 'name = "small"\ncolour = "red"', "colour", "'red'"),
    ("T_F = 0.04", "T_F = 0.04\nspeed = 3", "z.speed", "3"),
    ("distance = -0.2\n", "", "move.distance", "missing"),
    ("zeta = 0.03\n", "", "mode[1].zeta", "missing"),
    ("zeta = 0.03", "zeta = 1.0", "mode[1].zeta", "1.0"),
    ("zeta = 0.03", "zeta = -0.1", "mode[1].zeta", "-0.1"),
    ("f = [9.0, 8.0, 6.5]", "f = [9.0, -8.0, 6.5]", "mode[1].f", "-8.0"),
    ("f_ref = 40.0", "f_ref = -40.0", "mode[2].f_ref", "-40.0"),
    ("z = [0.0, 0.2, 0.5]", "z = [0.0, 0.5, 0.2]", "mode[1].z", "[0.0, 0.5, 0.2]"),
    ("z = [0.0, 0.2, 0.5]", "z = [0.2, 0.3, 0.5]", "mode[1].z", "[0.2, 0.3, 0.5]"),
    ("z0 = 0.1\ndistance = 0.3", "z0 = 0.1\ndistance = 0.5", "mode[1].z", "[0.0, 0.2, 0.5]"),
    ("step = 0.002", "step = 0.0015", "simulation.step", "0.0015"),
    ("Te = 0.001", "Te = -0.001", "simulation.Te", "-0.001"),
    ("fmi_version = 3", "fmi_version = 4", "simulation.fmi_version", "4"),
    ("v_max = 0.5", "v_max = 0.0", "move.v_max", "0.0"),
    ("a_max = 4.0", 'a_max = "fast"', "move.a_max", "'fast'"),
    ('law = "table"', 'law = "spline"', "mode[1].law", "'spline'"),
    ('profiles = ["JL", "DJL"]', 'profiles = ["JL", "SCURVE"]', "compare.profiles", "SCURVE"),
    ("tune_mode = 1", "tune_mode = 3", "compare.tune_mode", "3"),
    ("L_ref = 0.5", "L_ref = 0.5\ndirection = 0", "mode[2].direction", "0"),
    ("mass_ratio = 2.0", "mass_ratio = -2.0", "mode[2].mass_ratio", "-2.0"),
    ("[compare]", "[compare]\nDJL_T_F = [0.1, 0.1, 0.1]", "compare.DJL_T_F", "0.1"),
    ("fmi_version = 3", 'fmi_version = 3\nfmu = "nowhere.fmu"', "simulation.fmu", "nowhere.fmu"),
    ("mass_ratio = 2.0", 'mass_ratio = 2.0\nfmu = "x.fmu"', "mode[2].fmu", "x.fmu"),
]


@pytest.mark.parametrize("old, new, key, value", BAD, ids=[b[2] + ":" + b[3] for b in BAD])
def test_bad_input_names_file_key_and_value(tmp_path, old, new, key, value):
    path = write(tmp_path, replace_line(GOOD, old, new))
    with pytest.raises(ScenarioError) as ei:
        load_scenario(path)
    msg = str(ei.value)
    assert str(path) in msg
    assert key in msg
    assert value in msg


def test_unreadable_toml_and_unknown_scenario(tmp_path):
    path = write(tmp_path, "name = [unclosed\n")
    with pytest.raises(ScenarioError, match="not valid TOML"):
        load_scenario(path)
    with pytest.raises(ScenarioError, match="embedded scenario"):
        load_scenario(tmp_path / "missing.toml")
    with pytest.raises(ScenarioError, match="at least one"):
        load_scenario(write(tmp_path, GOOD.split("[[mode]]")[0] + "[compare]\n"))


def _fmu_without(src: Path, dst: Path, variable: str) -> Path:
    """Copy of a generator FMU whose model description renames one variable."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = data.replace(f'name="{variable}"'.encode(),
                                    f'name="{variable}_renamed"'.encode())
            zout.writestr(item, data)
    return dst


def test_fmu_lacking_variables_is_refused_before_running(tmp_path, fmu2):
    bad = _fmu_without(fmu2, tmp_path / "bad.fmu", "a_AL")
    text = GOOD.replace("fmi_version = 3", 'fmi_version = 3\nfmu = "bad.fmu"')
    path = write(tmp_path, text)
    with pytest.raises(ScenarioError) as ei:
        load_scenario(path)
    msg = str(ei.value)
    assert str(path) in msg and "simulation.fmu" in msg and str(bad) in msg and "a_AL" in msg
    # the same through the command-line override
    sc = load_scenario(write(tmp_path, GOOD, "ok.toml"))
    with pytest.raises(ScenarioError, match="a_AL"):
        sc.with_fmu(bad)
    # and a good FMU file, relative to the scenario file, is accepted
    good = tmp_path / "gen.fmu"
    good.write_bytes(Path(fmu2).read_bytes())
    sc = load_scenario(write(tmp_path, GOOD.replace("fmi_version = 3",
                                                    'fmu = "gen.fmu"'), "rel.toml"))
    assert sc.simulation.fmu == good


def test_sweep_table(tmp_path):
    text = GOOD + "\n[sweep]\ndistance = [0.1, -0.2]\nz_distance = [0.1, 0.2, 0.3]\n"
    sc = load_scenario(write(tmp_path, text))
    assert sc.is_sweep and len(sc.cases()) == 6
    assert {c.move.v_max for c in sc.cases()} == {0.5}
    with pytest.raises(ScenarioError, match="sweep.distance"):
        load_scenario(write(tmp_path, GOOD + "\n[sweep]\ndistance = [0.0]\n", "b.toml"))
    with pytest.raises(ScenarioError, match="sweep"):
        load_scenario(write(tmp_path, GOOD + "\n[sweep]\n", "c.toml"))
    # a table law must cover every case of the sweep
    text = GOOD + "\n[sweep]\nz_distance = [0.1, 0.45]\n"
    with pytest.raises(ScenarioError, match="mode\\[1\\].z"):
        load_scenario(write(tmp_path, text, "d.toml"))


@settings(max_examples=40, deadline=None)
@given(zeta=st.floats(-2.0, 2.0, allow_nan=False), f0=st.floats(-50.0, 50.0, allow_nan=False),
       step_ratio=st.floats(0.3, 4.0))
def test_random_values_are_accepted_exactly_when_valid(zeta, f0, step_ratio):
    step = round(step_ratio * 1e-3, 7)
    doc = {
        "move": {"distance": 0.3, "v_max": 1.0, "a_max": 4.0},
        "simulation": {"Te": 1e-3, "step": step},
        "mode": [{"zeta": zeta, "law": "linear", "z": [0.0, 0.5], "f": [f0, 6.0]}],
    }
    ratio = step / 1e-3
    valid = (0 <= zeta < 1) and f0 > 0 and abs(ratio - round(ratio)) <= 1e-9 * max(1, ratio) \
        and round(ratio) >= 1
    if valid:
        sc = parse_scenario(doc)
        assert sc.modemap.tuned.zeta == zeta
    else:
        with pytest.raises(ScenarioError):
            parse_scenario(doc)


# ------------------------------------------------------- settling band


def _with_settle(line: str, profiles: str | None = None) -> str:
    text = replace_line(GOOD, "fmi_version = 3", "fmi_version = 3\n" + line)
    if profiles is not None:
        text = replace_line(text, 'profiles = ["JL", "DJL"]', f"profiles = {profiles}")
    return text


@pytest.mark.parametrize("line, kind, value, band", [
    ("", "AL", 0.01, None),                                  # the documented default
    ("settle_band = 0.0005", "m", 0.0005, 0.0005),
    ("band = 0.0005", "m", 0.0005, 0.0005),                   # the old key, an alias
    ('settle_band = "paper"', "paper", None, None),
    ('settle_band = "2.5 % of AL"', "AL", 0.025, None),
    ('settle_band = "2.5% of AL"', "AL", 0.025, None),
    ('settle_band = "100 % of AL"', "AL", 1.0, None),
])
def test_settle_band_values(tmp_path, line, kind, value, band):
    from harness.metrics import SettleBand

    profiles = None if kind == "paper" else '["AL", "JL", "DJL"]'
    sim = load_scenario(write(tmp_path, _with_settle(line, profiles))).simulation
    assert sim.settle_band.kind == kind
    assert sim.band == band
    if value is not None:
        assert sim.settle_band.value == pytest.approx(value, rel=1e-15)
    # what it resolves to in a case (residuals in m)
    res = {"AL": 2e-3, "JL": 2e-4, "DJL": 1e-4}
    expected = {"AL": 2e-3 * (value or 0), "m": value, "paper": 1e-4}[kind]
    assert sim.settle_band.resolve(res) == pytest.approx(expected, rel=1e-15)
    assert SettleBand(kind, sim.settle_band.value) == sim.settle_band


def test_default_settle_band_without_al_loads():
    """The default (1 % of AL) is not refused when AL is not compared: AL is then run for the
    band only (harness.evaluation.run_case)."""
    sc = parse_scenario({"move": {"distance": 0.3, "v_max": 1.0, "a_max": 4.0},
                         "mode": [{"zeta": 0.03, "law": "constant", "f": 7.0}],
                         "compare": {"profiles": ["JL", "DJL"]}})
    assert sc.simulation.settle_band.kind == "AL" and sc.simulation.band is None


@pytest.mark.parametrize("line, profiles, value, words", [
    ('settle_band = "0 % of AL"', None, "'0 % of AL'", "(0, 100]"),
    ('settle_band = "150 % of AL"', None, "'150 % of AL'", "(0, 100]"),
    ("settle_band = -0.001", None, "-0.001", "> 0"),
    ("settle_band = 0", None, "0", "> 0"),
    ('settle_band = "1 % of JL"', None, "'1 % of JL'", "paper"),
    ('settle_band = "tight"', None, "'tight'", "P % of AL"),
    ("settle_band = true", None, "True", "number"),
    ("settle_band = 0.001\nband = 0.002", None, "0.001", "not both"),
    ('settle_band = "1 % of AL"', None, "'1 % of AL'", "AL"),   # GOOD compares JL and DJL only
    ('settle_band = "paper"', '["AL", "JL"]', "'paper'", "DJL"),
])
def test_bad_settle_band_names_the_key(tmp_path, line, profiles, value, words):
    path = write(tmp_path, _with_settle(line, profiles))
    with pytest.raises(ScenarioError) as ei:
        load_scenario(path)
    msg = str(ei.value)
    assert str(path) in msg and "simulation.settle_band" in msg and value in msg, msg
    assert words in msg, msg
    assert ei.value.key == "simulation.settle_band"


DID_YOU_MEAN = [
    # a required key misspelt: the typo is named, not "v_max is missing"
    ("v_max = 0.5\na_max = 4.0", "vmax = 0.5\na_max = 4.0", "move.vmax", "v_max"),
    ("distance = -0.2\nv_max", "Distance = -0.2\nv_max", "move.Distance", "distance"),
    # an optional key misspelt: unknown, with the nearest known key
    ("zeta = 0.03", "zeta = 0.03\nzetta = 0.04", "mode[1].zetta", "zeta"),
    ("tune_mode = 1", "tune_mode = 1\ntunemode = 2", "compare.tunemode", "tune_mode"),
    ("t_after = 0.5", "t_after = 0.5\nt_aftr = 0.7", "simulation.t_aftr", "t_after"),
]


@pytest.mark.parametrize("old, new, key, meant", DID_YOU_MEAN, ids=[d[2] for d in DID_YOU_MEAN])
def test_unknown_key_gets_a_did_you_mean(tmp_path, old, new, key, meant):
    path = write(tmp_path, replace_line(GOOD, old, new))
    with pytest.raises(ScenarioError) as ei:
        load_scenario(path)
    msg = str(ei.value)
    assert f"{key} = " in msg and "unknown key" in msg, msg
    assert f"did you mean {meant}?" in msg, msg
    assert "is missing" not in msg


def test_no_did_you_mean_for_a_key_unlike_any(tmp_path):
    path = write(tmp_path, replace_line(GOOD, "tune_mode = 1", "tune_mode = 1\nbanana = 2"))
    with pytest.raises(ScenarioError) as ei:
        load_scenario(path)
    assert "compare.banana" in str(ei.value) and "did you mean" not in str(ei.value)
    # a missing key with no look-alike is still reported as missing
    path = write(tmp_path, replace_line(GOOD, "v_max = 0.5\na_max = 4.0", "a_max = 4.0"))
    with pytest.raises(ScenarioError, match=r"move\.v_max is missing"):
        load_scenario(path)
