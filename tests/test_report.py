"""The claims report (harness.report) and ``djl-fmu report``."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from harness.claims import CATALOGUE, Check, ClaimResult, ClaimSpec
from harness.claims import base as claims_base
from harness.claims.registry import registered
from harness.cli import main
from harness.report import write_report


def _fake(kind: str, passed: bool):
    def run(settings):
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots()
        ax.plot([0, 1], [0, 1])
        return ClaimResult(1, "fake claim", "nowhere, eq. (0)", "it holds <always>",
                           checks=[Check.close("a number", 1.0, 1.0 if passed else 2.0, 0.1,
                                               kind=kind)], figures=[fig])
    return run


def _raises(settings):
    raise RuntimeError("boom in the claim")


def test_catalogue_matches_the_registry():
    specs = registered()
    assert [s.number for s in specs] == sorted(CATALOGUE)
    assert {s.number: s.title for s in specs} == {n: t for n, (_m, t) in CATALOGUE.items()}


def test_report_is_self_contained(tmp_path, fmu2):
    out = tmp_path / "sub" / "r.html"
    summary = write_report(out, fast=True, only=[1], fmu=fmu2)
    text = out.read_text(encoding="utf-8")
    assert summary.product_ok and summary.all_passed
    assert "Claim 1: The moving average is a comb notch" in text
    assert "eq. (5)" in text and "PASSED" in text
    assert text.count("data:image/png;base64,") == 1
    assert not (tmp_path / "sub" / "r_files").exists()
    assert "../shared" not in text
    # one verdict cell per check, plus the claim's row in the summary table
    assert len(re.findall(r"<td class='PASSED'>PASSED</td>", text)) == len(
        summary.results[0].checks) + 1


def _outside_svg(text: str) -> str:
    """The HTML with the inline SVG elements (the rendered equations) taken out."""
    return re.sub(r"<svg\b.*?</svg>", "", text, flags=re.DOTALL)


def test_equations_rendered_offline_as_svg(tmp_path, fmu2):
    """Every $...$ formula of the statements is an inline SVG (matplotlib mathtext): no raw
    TeX left where an equation is, no MathJax, no URL in the page; the papers are named,
    not tagged with their file numbers ("000 eq. (18)")."""
    from harness.claims import moving_average, residual, spectra, vibration_filters
    from harness.claims.formulas import DERIVATIONS
    from harness.report import math_svg, render_html, rich

    statements = [m.STATEMENT for m in (moving_average, residual, spectra, vibration_filters)]
    formulas = [f for st in statements for f in st.split("$")[1::2]]
    assert len(formulas) >= 20
    for f in formulas:  # each one parses (no fallback to code)
        svg = math_svg(f)
        assert svg.startswith("<svg ") and svg.endswith("</svg>") and "<path" in svg
    for st in statements:
        html = rich(st)
        assert html.count("<svg ") == st.count("$") // 2 and "<code>" not in html
        rest = _outside_svg(html)
        assert "$" not in rest
        assert not re.search(r"\\[a-zA-Z]+|[_^]\{", rest), rest  # \frac, e^{, sum_{ ...
    assert rich("costs $5") == "costs $5"  # an unpaired $ is text
    assert rich("a $\\notacommand{x}$ b") == "a <code>\\notacommand{x}</code> b"

    out = tmp_path / "r.html"
    write_report(out, fast=True, only=[1], fmu=fmu2, peers=False)
    text = out.read_text(encoding="utf-8")
    assert text.count("<svg ") >= moving_average.STATEMENT.count("$") // 2
    outside = _outside_svg(text)
    assert "$" not in outside and not re.search(r"[_^]\{|\\frac|\\sum", outside)
    assert not re.search(r"https?://|//cdn|mathjax", text, flags=re.IGNORECASE)
    assert "<style type=\"text/css\">*" not in text  # no page-wide style from the SVGs
    # the papers by name, not by their file numbers
    assert not re.search(r"\b00[03] (eq|§|Fig)", text)
    assert "Béarée &amp; Olabi 2013, eq. (18)" in text and "Béarée 2014, eq. (14)" in text
    assert set(DERIVATIONS)  # the keys keep the file numbers (used by the claims)
    assert "000 eq. (18)" not in render_html([], settings=claims_base.Settings(fast=True),
                                             elapsed=0.0)


def test_figures_beside(tmp_path, fmu2):
    out = tmp_path / "r.html"
    write_report(out, fast=True, only=[6], fmu=fmu2, embed=False)
    text = out.read_text(encoding="utf-8")
    assert "data:image/png" not in text
    pngs = sorted((tmp_path / "r_files").glob("*.png"))
    assert [p.name for p in pngs] == ["claim6_1.png"]
    assert 'src="r_files/claim6_1.png"' in text


def test_failures_are_shown_not_hidden(tmp_path, monkeypatch):
    monkeypatch.setitem(claims_base._REGISTRY, 1, ClaimSpec(1, "fake", _fake("paper", False)))
    monkeypatch.setitem(claims_base._REGISTRY, 2, ClaimSpec(2, "raises", _raises))
    out = tmp_path / "r.html"
    summary = write_report(out, fast=True, only=[1, 2])
    text = out.read_text(encoding="utf-8")
    r1, r2 = summary.results
    assert r1.verdict == "FAILED" and r1.product_passed  # a paper statement failed
    assert r2.verdict == "ERROR" and not r2.product_passed
    assert not summary.product_ok
    assert "boom in the claim" in text and "RuntimeError" in text
    # the paper statement refuted, every product check passed: a finding, not a FAILED badge
    assert r1.status == "REFUTED" and r2.status == "ERROR"
    assert "<td class='REFUTED'>REFUTED</td>" in text
    assert '<span class="badge REFUTED">paper statement refuted' in text
    assert "<td class='FAILED'>FAILED</td>" not in text.split("<h2", 2)[-1]
    assert "it holds &lt;always&gt;" in text  # escaped
    assert "What failed" in text


def test_cli_report(tmp_path, fmu2, capsys):
    out = tmp_path / "cli.html"
    assert main(["report", "-o", str(out), "--fast", "--claims", "1", "--fmu", str(fmu2)]) == 0
    assert out.is_file()
    captured = capsys.readouterr()
    # a progress line per claim on stderr, the result on stdout; -q: no progress line
    assert "claim 1: PASSED" in captured.err and str(out) in captured.out
    assert main(["report", "-o", str(out), "--fast", "--claims", "1", "--fmu", str(fmu2),
                 "-q"]) == 0
    captured = capsys.readouterr()
    assert captured.err == "" and "1/1 claims passed" in captured.out


def test_cli_exit_status(tmp_path, fmu2, monkeypatch, capsys):
    out = tmp_path / "x.html"
    monkeypatch.setitem(claims_base._REGISTRY, 1, ClaimSpec(1, "fake", _fake("paper", False)))
    args = ["report", "-o", str(out), "--fast", "--claims", "1", "--fmu", str(fmu2)]
    assert main(args) == 0             # a paper statement failing is a finding
    assert main([*args, "--strict"]) == 1
    monkeypatch.setitem(claims_base._REGISTRY, 1, ClaimSpec(1, "fake", _fake("product", False)))
    assert main(args) == 1             # a product check failing is a defect
    assert "[product]" in capsys.readouterr().out


def test_cli_bad_arguments(tmp_path, capsys):
    assert main(["report", "-o", str(tmp_path / "a.html"), "--claims", "99"]) == 2
    assert "no claim [99]" in capsys.readouterr().err
    assert main(["report", "--fmu", str(tmp_path / "missing.fmu")]) == 2
    with pytest.raises(SystemExit) as e:
        main(["report", "--claims", "one"])
    assert e.value.code == 2
    assert not list(tmp_path.iterdir())


def test_cli_help_explains_inputs_outputs_defaults(capsys):
    with pytest.raises(SystemExit):
        main(["report", "--help-full"])
    text = capsys.readouterr().out
    for word in ("report.html", "--fast", "--claims", "--fmu", "--fmi-version", "Exit status",
                 "PASSED"):
        assert word in text


def test_no_shared_paths_in_the_claims_package():
    root = Path(__file__).resolve().parents[1]
    files = [*(root / "harness" / "claims").glob("*.py"), root / "harness" / "report.py",
             root / "harness" / "commands" / "report.py"]
    for f in files:
        assert "shared/" not in f.read_text(encoding="utf-8"), f


def test_report_gains_the_peer_comparison(tmp_path):
    """Issue 5: the report has a section comparing AL/JL/DJL with the peers on X and Y."""
    from harness.claims.base import Settings
    from harness.report import peers_section

    html = peers_section(Settings(fast=True))
    assert "Peers side by side" in html
    for name in ("X", "Y"):
        assert f"Scenario {name}</h3>" in html
    for method in ("DJL", "time-optimal JL", "AL*ZV", "AL*EI", "damped jerk", "Sato III"):
        assert method in html
    assert html.count("data:image/png;base64,") == 2
    assert "raised" not in html


def test_cli_refuses_a_file_that_is_not_a_generator_fmu(tmp_path, capsys):
    from harness.cli import main

    junk = tmp_path / "junk.fmu"
    junk.write_text("x")
    out = tmp_path / "r.html"
    assert main(["report", "--fmu", str(junk), "-o", str(out), "--fast"]) == 2
    assert "cannot read" in capsys.readouterr().err
    assert not out.exists()


def test_report_without_ruckig_warns_and_says_so_in_the_html(tmp_path, fmu2, monkeypatch,
                                                             capsys):
    """ruckig not installed: a warning on the console and a readable note in the HTML (the
    install command from a checkout), no raw exception text; the claims still run."""
    import sys

    import harness.report as report
    from harness.cli import main

    monkeypatch.setitem(sys.modules, "ruckig", None)  # `import ruckig` raises ImportError
    monkeypatch.setattr(report, "run_claims", lambda *a, **k: [])  # the claims: not the point
    out = tmp_path / "r.html"
    assert main(["report", "--fast", "--fmu", str(fmu2), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.startswith("warning: The comparison with the peer methods was left out")
    assert "pip install '.[compare]'" in err
    html = out.read_text(encoding="utf-8")
    assert "<p class='skipped'>The comparison with the peer methods was left out" in html
    assert "pip install &#x27;.[compare]&#x27;" in html or "pip install '.[compare]'" in html
    assert "RuckigMissingError" not in html and "raised" not in html
