"""The artefacts of a reference FMU (issue #11, item 4): licence, icon, documentation,
reference result in the cross-check and FMI-LS-REF layouts."""

from __future__ import annotations

import struct
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

from harness.fmu import artefacts, spec

ROOT = Path(__file__).resolve().parents[1]
REF = f"{spec.MODEL_IDENTIFIER}_ref"


def _png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG file"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def test_repository_licence_is_the_one_shipped():
    assert (ROOT / "LICENSE").read_text() == artefacts.LICENSE_TEXT
    assert 'license = { text = "BSD-3-Clause" }' in (ROOT / "pyproject.toml").read_text()
    assert artefacts.LICENSE_TEXT.startswith("BSD 3-Clause License")


def test_icon_is_a_png_that_decodes():
    import zlib

    data = artefacts.icon_png(64)
    assert _png_size(data) == (64, 64)
    # decode the pixel data: 64 rows of a filter byte + 64 RGBA pixels; some drawn, some not
    idat = data[data.index(b"IDAT") + 4:data.index(b"IEND") - 8]
    raw = zlib.decompress(idat)
    assert len(raw) == 64 * (1 + 4 * 64)
    alphas = {raw[r * 257 + 1 + 4 * c + 3] for r in range(64) for c in range(64)}
    assert alphas == {0, 255}


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_carries_its_artefacts(fmus, version):
    with zipfile.ZipFile(fmus[version]) as z:
        names = set(z.namelist())
        assert z.read("documentation/licenses/LICENSE.txt").decode() == artefacts.LICENSE_TEXT
        if version == 2:
            assert _png_size(z.read("model.png")) == (artefacts.ICON_SIZE,) * 2
        else:
            assert _png_size(z.read("terminalsAndIcons/icon.png")) == (artefacts.ICON_SIZE,) * 2
            tai = ET.fromstring(z.read("terminalsAndIcons/terminalsAndIcons.xml"))
            assert tai.tag == "fmiTerminalsAndIcons" and tai.get("fmiVersion") == "3.0"
            assert tai.find("GraphicalRepresentation/Icon") is not None
        page = z.read("documentation/index.html").decode()
        for v in spec.VARIABLES:
            if v.causality != "independent":
                assert f"<code>{v.name}" in page, v.name
        assert "Any communication step h &gt; 0" in page
        assert 'src="default_move.png"' in page and "documentation/default_move.png" in names
        _png_size(z.read("documentation/default_move.png"))
        csv = z.read(f"documentation/{REF}.csv")
        assert z.read(f"{artefacts.LS_REF_DIR}/{REF}.csv") == csv
        opt = z.read(f"documentation/{REF}.opt").decode()
        manifest = ET.fromstring(z.read(f"{artefacts.LS_REF_DIR}/fmi-ls-manifest.xml"))
    assert {"StartTime", "StopTime", "StepSize", "RelTol"} == {
        line.split(",")[0] for line in opt.splitlines()}
    ns = "{http://fmi-standard.org/fmi-ls-manifest}"
    assert manifest.get(f"{ns}fmi-ls-name") == "org.fmi-standard.fmi-ls-ref"
    ref = manifest.find("Experiment/References")
    assert ref is not None and ref.get("source") == f"{REF}.csv"
    for r in manifest.findall("Reference"):  # every file the manifest names is in the FMU
        target = (Path(artefacts.LS_REF_DIR) / r.get("source")).as_posix()
        parts: list[str] = []
        for p in target.split("/"):
            if p == "..":
                parts.pop()
            else:
                parts.append(p)
        assert "/".join(parts) in names, target


@pytest.mark.parametrize("version", [2, 3])
def test_reference_result_is_what_the_fmu_gives(fmus, version, tmp_path):
    """Simulated with the settings of _ref.opt, the FMU reproduces _ref.csv to the last bit."""
    from fmpy import simulate_fmu

    with zipfile.ZipFile(fmus[version]) as z:
        (tmp_path / "ref.csv").write_bytes(z.read(f"documentation/{REF}.csv"))
        opt = dict(line.split(", ") for line in z.read(f"documentation/{REF}.opt").decode()
                   .splitlines())
    ref = np.genfromtxt(tmp_path / "ref.csv", delimiter=",", names=True)
    res = simulate_fmu(str(fmus[version]), start_time=float(opt["StartTime"]),
                       stop_time=float(opt["StopTime"]), output_interval=float(opt["StepSize"]),
                       output=list(artefacts.REF_OUTPUTS))
    assert len(res) == len(ref)
    assert np.allclose(res["time"], ref["time"], rtol=0, atol=1e-12)
    for name in artefacts.REF_OUTPUTS:
        assert np.array_equal(res[name], ref[name]), name
    # and the move in it is the default one: 0.4 m, at rest at the end
    assert ref["x"][-1] == pytest.approx(0.4, rel=1e-12) and ref["v"][-1] == 0.0


def test_cross_check_files_beside_an_fmu(tmp_path):
    paths = artefacts.write_cross_check(tmp_path)
    assert sorted(p.name for p in paths) == [f"{REF}.csv", f"{REF}.opt"]
    header = paths[0].read_text().splitlines()[0]
    assert header == ",".join(f'"{n}"' for n in ("time", *artefacts.REF_OUTPUTS))


@pytest.mark.parametrize("version", [2, 3])
def test_reference_without_the_compiled_core(fmus, version, tmp_path, monkeypatch):
    """`python -m harness.cli build` from a source checkout cannot import harness._engine
    (the extension is installed elsewhere): the reference then comes from the FMU's own
    binary, the same samples bit for bit."""
    import sys

    with zipfile.ZipFile(fmus[version]) as z:
        z.extractall(tmp_path)
    time1, rows1 = artefacts.reference_result()
    import harness

    monkeypatch.setitem(sys.modules, "harness._engine", None)  # import blocked
    monkeypatch.delattr(harness, "_engine", raising=False)
    with pytest.raises(ImportError):
        artefacts.reference_result()
    time2, rows2 = artefacts.reference_result(fmu_dir=tmp_path)
    assert time2 == time1 and rows2 == rows1
