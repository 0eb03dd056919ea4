"""One source of truth: the committed interface files equal what the spec generates."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from fmpy import read_model_description

from harness._resources import fmu_src_dir, modeldesc_dir
from harness.fmu import codegen, spec


@pytest.fixture(scope="module")
def root() -> Path:
    """The checkout the tests belong to (the package itself may be installed elsewhere)."""
    r = Path(__file__).resolve().parents[1]
    assert (r / "fmu_src" / "djl_core.h").is_file(), r
    return r


def test_installed_sources_are_the_checkouts(root):
    """An installed package ships exactly the checkout's C sources and model descriptions."""
    for sub, installed in (("fmu_src", fmu_src_dir()), ("modeldesc", modeldesc_dir())):
        for f in sorted((root / sub).rglob("*")):
            if f.is_file():
                twin = installed / f.relative_to(root / sub)
                assert twin.read_bytes() == f.read_bytes(), twin


def test_committed_files_are_generated_from_the_spec(root):
    stale = [str(p.relative_to(root)) for p, text in codegen.generated_files(root).items()
             if not p.is_file() or p.read_text() != text]
    assert not stale, f"regenerate with `python -m harness.fmu.codegen`: {stale}"


def test_c_enum_matches_both_model_descriptions():
    header = (fmu_src_dir() / "djl_vars.h").read_text()
    enum = {m.group(1): int(m.group(2)) for m in re.finditer(r"VR_(\w+) = (\d+),", header)}
    token = re.search(r'DJL_INSTANTIATION_TOKEN "([^"]+)"', header).group(1)
    for version in (2, 3):
        md = read_model_description(str(modeldesc_dir() / f"fmi{version}" /
                                        "modelDescription.xml"), validate=False)
        assert md.guid == token
        names = {v.name: v.valueReference for v in md.modelVariables}
        for var in spec.VARIABLES:
            c_name = var.enum[3:]
            assert enum[c_name] == var.vr
            if version == 3 or var.size == 1:
                assert names[var.name] == var.vr
            else:
                for i in range(var.size):
                    assert names[f"{var.name}[{i + 1}]"] == var.vr + i


def test_value_references_are_unique():
    vrs = [vr for v in spec.VARIABLES for _, vr in spec.fmi2_scalars(v)]
    assert len(vrs) == len(set(vrs))


def test_token_changes_with_the_interface(monkeypatch):
    before = spec._fingerprint()
    monkeypatch.setattr(spec, "VARIABLES", spec.VARIABLES[:-1])
    assert spec._fingerprint() != before


def test_core_capacity_matches_spec():
    core = (fmu_src_dir() / "djl_core.h").read_text()
    assert f"#define DJL_MAX_SEGMENTS {spec.MAX_SEGMENTS}" in core
    # the bounds the model descriptions declare are the ones the C code enforces
    assert f"#define DJL_MAX_FILTER_SAMPLES {spec.MAX_FILTER_SAMPLES}" in core
    position = re.search(r"#define DJL_MAX_POSITION (\S+)", core).group(1)
    assert float(position) == spec.MAX_POSITION
    assert f"#define DJL_MAX_SHAPER_IMPULSES {spec.MAX_SHAPER_IMPULSES}" in core
    assert f"#define DJL_MAX_SHAPER_DELAY_SAMPLES {spec.MAX_SHAPER_DELAY_SAMPLES}" in core
    tol = re.search(r"#define DJL_SHAPER_SUM_TOLERANCE (\S+)", core).group(1)
    assert float(tol) == spec.SHAPER_AMPLITUDE_TOLERANCE
    assert f"#define DJL_MAX_TABLE {spec.MAX_TABLE}" in core
    for name, value in (("DJL_TABLE_END_TOLERANCE", spec.TABLE_END_TOLERANCE),
                        ("DJL_TABLE_LIMIT_TOLERANCE", spec.TABLE_LIMIT_TOLERANCE)):
        assert float(re.search(rf"#define {name} (\S+)", core).group(1)) == value
    # a table's plan: one piece per entry and the rest, one step per entry
    assert spec.MAX_TABLE + 1 <= 2 * 4 * spec.MAX_SEGMENTS + spec.MAX_SEGMENTS + 2
    horizon = int(re.search(r"#define DJL_MAX_MOTION_SAMPLES (\d+)LL", core).group(1))
    # fmu_model.c refuses Te * DJL_MAX_MOTION_SAMPLES > DJL_MAX_POSITION: MAX_TE passes
    assert spec.MAX_TE * horizon <= spec.MAX_POSITION


def test_readme_variable_table_is_current(root):
    """The variable table, once in the README, is docs/variables.md's (issue 36)."""
    doc = (root / "docs" / "variables.md").read_text()
    assert codegen.readme_table() in doc, (
        "docs/variables.md: paste the output of `python -c 'from harness.fmu.codegen import "
        "readme_table; print(readme_table())'` over its table")


def test_parameter_table_is_the_spec():
    """djl_vars.h says where every parameter is stored: the FMU and the extension module
    (harness/_engine.c) read and write parameters through that one table."""
    header = (fmu_src_dir() / "djl_vars.h").read_text()
    rows = re.findall(r'\{VR_(\w+), "(\w+)", \'(\w)\', (\d+), (DJL_HOME_\w+), ([^}]*)\}',
                      header)
    code = {"Real": "R", "Integer": "I", "Enumeration": "E"}
    assert [r[1] for r in rows] == [v.name for v in spec.PARAMETERS]
    for (c_name, name, typ, size, home, offset), var in zip(rows, spec.PARAMETERS, strict=True):
        assert var.enum == "VR_" + c_name
        assert typ == code[var.type] and int(size) == var.size
        in_struct = [(h, struct, fields[name]) for h, (struct, fields)
                     in codegen.C_PARAM_STRUCTS.items() if name in fields]
        if name in codegen.C_PARAM_HOMES:
            assert home == codegen.C_PARAM_HOMES[name] and offset == "0"
        elif in_struct:
            h, struct, field = in_struct[0]
            assert home == h and offset == f"offsetof({struct}, {field})"
        else:
            field = codegen.C_PARAM_FIELDS.get(name, name)
            assert home == "DJL_HOME_PARAMS" and offset == f"offsetof(djl_params, {field})"
    assert f"#define DJL_N_PARAMS {len(spec.PARAMETERS)}" in header


def test_enumeration_constants_are_the_spec():
    header = (fmu_src_dir() / "djl_vars.h").read_text()
    stems = {"Profile": "PROFILE", "ShortStage": "SHORT_STAGE", "JerkSource": "JERK_SOURCE",
             "Shaper": "SHAPER", "ShaperSource": "SHAPER_SOURCE",
             "CmdProfile": "CMD_PROFILE", "CmdShaper": "CMD_SHAPER",
             "BufferMode": "BUFFER_MODE"}
    assert set(stems) == set(spec.ENUMERATIONS)
    for name, items in spec.ENUMERATIONS.items():
        for item, value, _ in items:
            assert f"    {stems[name]}_{item.upper()} = {value},\n" in header
        by_value = {value: item for item, value, _ in items}
        names = ", ".join(f'"{by_value.get(i, "")}"' for i in range(max(by_value) + 1))
        assert f"djl_{stems[name].lower()}_names[] = {{{names}}};" in header
    # the core's own codes are checked against them at compile time
    assert "(int)PROFILE_DJL == (int)DJL_PROFILE_DJL" in header
    assert "(int)SHAPER_CUSTOM == (int)DJL_SHAPER_CUSTOM" in header
    assert "(int)SHAPER_SOURCE_F_MODE == (int)DJL_SHAPER_SOURCE_F_MODE" in header


def test_command_enumerations_share_the_codes_of_the_parameters():
    """cmd_profile and cmd_shaper: 0 is the parameter's value, the other codes are those of
    profile and shaper (cmd_shaper adds 5 = none, since 0 means the parameter's)."""
    for cmd, par in (("CmdProfile", "Profile"), ("CmdShaper", "Shaper")):
        codes = {n: v for n, v, _ in spec.ENUMERATIONS[cmd]}
        assert codes.pop("parameter") == 0
        pcodes = {n: v for n, v, _ in spec.ENUMERATIONS[par]}
        for name, value in codes.items():
            assert name == "none" and value == max(pcodes.values()) + 1 or pcodes[name] == value
    assert "table" not in {n for n, _, _ in spec.ENUMERATIONS["CmdProfile"]}


def test_command_error_codes_are_in_the_header_and_the_docs(root):
    """Every code of cmd_error_id: in djl_vars.h (CMD_ERR_<name>) and in the one table of
    docs/generator.md, with its meaning; consecutive from 1."""
    header = (fmu_src_dir() / "djl_vars.h").read_text()
    doc = (root / "docs" / "generator.md").read_text()
    assert [c for c, *_ in spec.CMD_ERRORS] == list(range(1, len(spec.CMD_ERRORS) + 1))
    assert spec.BY_NAME["cmd_error_id"].max == len(spec.CMD_ERRORS)
    for code, name, what, _ in spec.CMD_ERRORS:
        assert f"    CMD_ERR_{name} = {code}," in header
        assert re.search(rf"^\| {code} \| `{what}`", doc, re.M), (code, what)


def test_profile_codes_are_derived_from_the_enumeration():
    assert spec.PROFILE_CODES == {"AL": 1, "JL": 2, "DJL": 3, "table": 4}
    assert spec.PROFILE_CODES == {n: v for n, v, _ in spec.ENUMERATIONS["Profile"]}
    assert spec.PROFILE_NAMES == {v: n for n, v in spec.PROFILE_CODES.items()}
