"""What other importers need: every parameter settable without Enumeration support (FMI 2),
outputs declared without direct feedthrough, and a wrong array count refused, not fatal (FMI 3).

The importers' habits are recorded in docs/platforms.md ("Importers"): the FMI Library (libcosim,
ecos) skips FMI 2 Enumeration variables; OMSimulator reads FMI 3 ``dependencies`` as indices
and reads every variable, arrays included, with nValues = 1.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from harness.fmu import spec
from harness.fmu.runner import FMUError, GeneratorFMU

ENUM_PARAMETERS = [v for v in spec.PARAMETERS if v.type == "Enumeration"]
ENUM_ALIASED = [v for v in spec.VARIABLES if v.type == "Enumeration"]
"""Every Enumeration with an FMI 2 Integer alias: the parameters and (issue 34) the inputs
cmd_profile, cmd_shaper, buffer_mode."""


def _model_description_xml(fmu) -> ET.Element:
    with zipfile.ZipFile(fmu) as z:
        return ET.fromstring(z.read("modelDescription.xml"))


def test_the_enumeration_parameters_are_the_five_expected():
    assert [v.name for v in ENUM_PARAMETERS] == [
        "profile", "short_stage", "jerk_source", "shaper", "shaper_source"]


def test_fmi2_every_parameter_is_reachable_without_enumerations(fmu2):
    """An importer that drops the Enumeration variables still finds every parameter, with a
    type it can set (Real, Integer or Boolean), under its own name or ``<name>_code``."""
    root = _model_description_xml(fmu2)
    kept: dict[str, tuple[str, int, str]] = {}
    for sv in root.iter("ScalarVariable"):
        typ = next(iter(sv)).tag
        if typ == "Enumeration":
            continue  # what the FMI Library skips
        kept[sv.get("name")] = (typ, int(sv.get("valueReference")), sv.get("causality"))
    for v in spec.PARAMETERS:
        for name, vr in spec.fmi2_scalars(v):
            if v.type == "Enumeration":
                name = v.name + "_code"
            assert name in kept, name
            typ, got_vr, causality = kept[name]
            assert got_vr == vr and causality == "parameter", name
            assert typ in ("Real", "Integer", "Boolean"), (name, typ)
            if v.type == "Enumeration":
                assert typ == "Integer"


def test_fmi2_integer_aliases_declare_the_enumerations_values(fmu2):
    md = read_model_description(str(fmu2))
    by_name = {v.name: v for v in md.modelVariables}
    assert {v.name for v in ENUM_ALIASED} - {v.name for v in ENUM_PARAMETERS} == {
        "cmd_profile", "cmd_shaper", "buffer_mode"}
    for v in ENUM_ALIASED:
        alias, enum = by_name[v.name + "_code"], by_name[v.name]
        assert alias.type == "Integer" and enum.type == "Enumeration"
        assert alias.valueReference == enum.valueReference
        assert (alias.causality, alias.variability) == (enum.causality, enum.variability)
        assert int(alias.start) == int(enum.start) == v.start
        assert (int(alias.min), int(alias.max)) == (v.min, v.max)
        for item, value, _ in spec.ENUMERATIONS[v.declared_type]:
            assert f"{value} = {item}" in alias.description
    # the aliases come last: the indices the model structure refers to are the spec's
    names = [v.name for v in md.modelVariables]
    n = len(ENUM_ALIASED)
    assert names[-n:] == [v.name + "_code" for v in ENUM_ALIASED]
    assert all(u.variable.causality == "output" for u in md.outputs)


@pytest.mark.parametrize("param", [v.name for v in ENUM_PARAMETERS])
def test_fmi2_each_enumeration_is_set_through_its_integer_alias(fmu2, param):
    """fmi2SetInteger on the alias (what an FMI-Library importer calls) sets the parameter:
    read back through the Enumeration, and every other value of the type accepted."""
    var = spec.BY_NAME[param]
    for _, value, _ in spec.ENUMERATIONS[var.declared_type]:
        with GeneratorFMU(fmu2) as g:
            g.set({param + "_code": value})
            g._call(g.fmu.enterInitializationMode)  # getters are allowed from here
            assert g.get(param) == value
            assert g.get(param + "_code") == value


def _run_fmi2(fmu2, params: dict, n: int = 700) -> dict[str, np.ndarray]:
    with GeneratorFMU(fmu2, params=params) as g:
        g.initialize()
        return g.record(n, 1e-3, ["x", "v", "a", "j"])[1]


def test_fmi2_profile_and_shaper_through_the_aliases_act(fmu2):
    """The alias changes the motion as the Enumeration does (same outputs, bit for bit), and
    the motion is the one asked for: AL has no jerk; ZV lengthens the motion by Td/2."""
    base = {"distance": 0.2, "v_max": 0.5, "a_max": 5.0, "d_max": 5.0}
    via_alias = _run_fmi2(fmu2, {**base, "profile_code": 1})
    via_enum = _run_fmi2(fmu2, {**base, "profile": 1})
    for k in ("x", "v", "a", "j"):
        np.testing.assert_array_equal(via_alias[k], via_enum[k])
    assert np.all(via_alias["j"] == 0.0)
    assert set(np.round(np.unique(via_alias["a"]), 9)) <= {-5.0, 0.0, 5.0}
    with GeneratorFMU(fmu2, params={**base, "profile_code": 2}) as g:
        g.initialize()
        t_jl = g.get("motion_time")
    with GeneratorFMU(fmu2, params={**base, "profile_code": 2, "shaper_code": 1,
                                    "f_shaper": 10.0, "shaper_source_code": 1}) as g:
        g.initialize()
        assert g.get("shaper") == 1
        assert g.get("motion_time") == pytest.approx(t_jl + 0.05, abs=1e-3)


def test_fmi2_jerk_source_and_short_stage_through_the_aliases(fmu2):
    with GeneratorFMU(fmu2, params={"profile": 3, "jerk_source_code": 2,
                                    "short_stage_code": 2}) as g:
        g.set_inputs(f_mode=20.0)
        g.initialize()
        assert g.get("jerk_source") == 2 and g.get("short_stage") == 2
        g.do_step(1e-3)


def test_fmi2_alias_out_of_range_is_refused_at_initialisation(fmu2):
    with GeneratorFMU(fmu2, params={"profile_code": 7}) as g:
        with pytest.raises(FMUError) as info:
            g.initialize()
        assert "profile = 7" in str(info.value)


@pytest.mark.parametrize("version", [2, 3])
def test_outputs_are_declared_without_input_dependencies(fmus, version):
    root = _model_description_xml(fmus[version])
    tag = "Output" if version == 3 else "Unknown"
    parent = root.find("ModelStructure") if version == 3 else root.find("ModelStructure/Outputs")
    outs = parent.findall(tag)
    assert len(outs) == len(spec.OUTPUTS)
    for o in outs:
        # present and empty: depends on none of the knowns (absent would mean "on all")
        assert o.get("dependencies") == "", ET.tostring(o)
        assert o.get("dependenciesKind") is None
    md = read_model_description(str(fmus[version]))
    assert all(u.dependencies == [] for u in md.outputs)
    assert validate_fmu(str(fmus[version])) == []


@pytest.mark.parametrize("version", [2, 3])
def test_inputs_do_not_feed_through_at_the_communication_point(fmus, version):
    """The declaration is true: inputs set at a communication point leave every output as it
    was until the next step, which then reacts."""
    outputs = [v.name for v in spec.OUTPUTS]
    with GeneratorFMU(fmus[version], params={"distance": 0.0, "jerk_source": 1}) as g:
        g.initialize()
        for _ in range(5):
            g.do_step(1e-3)
        before = {n: g.get(n) for n in outputs}
        g.set_inputs(target=0.3, execute=True, f_mode=25.0)
        after = {n: g.get(n) for n in outputs}
        assert after == before
        for _ in range(20):
            g.do_step(1e-3)
        assert g.get("busy") and g.get("x") > 0.0


def test_fmi3_array_read_with_a_wrong_count_is_refused_and_the_instance_goes_on(fmu3):
    """OMSimulator reads every variable with nValues = 1: fmi3Error (an illegal argument, as the
    standard requires), nothing written, and the instance stays usable (not in its Error
    state), like a NULL pointer."""
    with GeneratorFMU(fmu3, params={"n_segments": 2, "seg_distance": [0.1, 0.05],
                                    "seg_v_end": [0.2, 0.0]}) as g:
        vr = g.variable("seg_distance").valueReference
        g.initialize()
        g.do_step(1e-3)
        with pytest.raises(FMUError) as info:
            g._call(g.fmu.getFloat64, [vr], 1)
        assert "nValues = 1" in str(info.value) and "32 values" in str(info.value)
        assert "nothing was read or written" in str(info.value)
        with pytest.raises(FMUError):
            g._call(g.fmu.setFloat64, [vr], [0.3])
        # still stepping, the arrays unchanged
        np.testing.assert_array_equal(g.get("seg_distance")[:2], [0.1, 0.05])
        for _ in range(2000):
            g.do_step(1e-3)
        assert g.get("done") and g.get("x") == pytest.approx(0.15, abs=1e-12)
