"""The claims report: one self-contained HTML file.

:func:`write_report` runs the registered claims (:mod:`harness.claims`) and
writes, per claim, the paper's statement with its equation / figure numbers,
how both sides were computed, the figures (PNG embedded as base64, or written
beside the HTML), the computed numbers with their tolerances, and PASSED /
FAILED.  Failures are never hidden: a check that fails is shown with its
numbers, a claim whose computation raised is shown with its traceback.

Examples
--------
>>> from harness.report import write_report
>>> summary = write_report("report.html", fast=True)   # doctest: +SKIP
>>> summary.product_ok                                  # doctest: +SKIP
True
"""

from __future__ import annotations

import base64
import datetime as _dt
import functools
import html
import io
import os
import platform
import re
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import __version__
from .claims import ClaimResult, Settings
from .claims.formulas import DERIVATIONS, paper_ref
from .claims.registry import run_claims
from .files import OutputSet
from .peers.compare import compare_scenario
from .peers.ruckig_ref import COMPARE_HINT, ruckig_available
from .scenario import load_scenario
from .uncertainty import span_text

_CSS = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; margin: 2em auto;
       max-width: 1150px; color: #222; line-height: 1.45; }
h1 { font-size: 1.6em; } h2 { margin-top: 2.2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.86em; }
th, td { border: 1px solid #ccc; padding: 3px 7px; text-align: left; vertical-align: top; }
th { background: #f3f3f3; }
td.num { text-align: right; font-family: monospace; white-space: nowrap; }
.PASSED { color: #0a7d28; font-weight: bold; } .FAILED { color: #c0161b; font-weight: bold; }
.REFUTED { color: #9a5b00; font-weight: bold; }
.ERROR { color: #fff; background: #c0161b; font-weight: bold; padding: 0 4px; }
.badge { font-size: 0.75em; padding: 2px 8px; border-radius: 4px; margin-left: 0.6em;
         vertical-align: middle; }
.badge.PASSED { background: #d9f2df; } .badge.FAILED { background: #fbdcdc; }
.badge.REFUTED { background: #fdecc8; }
blockquote { margin: 0.6em 0; padding: 0.4em 1em; background: #f7f7f4;
             border-left: 4px solid #bbb; }
.meta { color: #555; font-size: 0.9em; } .kind { color: #555; font-size: 0.85em; }
img { max-width: 100%; border: 1px solid #eee; margin: 0.5em 0; }
pre { background: #f6f6f6; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
.note { color: #555; font-size: 0.85em; }
.skipped { background: #fff4d6; border-left: 4px solid #e0a800; padding: 0.5em 0.8em; }
"""


@dataclass
class ReportSummary:
    """What :func:`write_report` did.

    Attributes
    ----------
    path : Path
        The HTML file written.
    results : list of ClaimResult
    elapsed : float
        Wall time (s), FMU build included.
    """

    path: Path
    results: list[ClaimResult]
    elapsed: float

    @property
    def all_passed(self) -> bool:
        """Every check of every claim passed."""
        return all(r.passed for r in self.results)

    @property
    def product_ok(self) -> bool:
        """Every *product* check passed and no claim raised."""
        return all(r.product_passed for r in self.results)

    def lines(self) -> list[str]:
        """One summary line per claim."""
        return [r.summary() for r in self.results]


def _e(text: object) -> str:
    return html.escape(str(text))


_SVG_DROP = re.compile(r"<\?xml.*?\?>|<!DOCTYPE.*?>|<metadata>.*?</metadata>|<!--.*?-->"
                       r'|<g id="patch_1">.*?</g>|\s(?:id="(?:figure|patch|text)_\d+")'
                       r'|<style type="text/css">.*?</style>',
                       re.DOTALL)


@functools.lru_cache(maxsize=256)
def math_svg(tex: str) -> str:
    """Render a TeX formula with matplotlib's mathtext as an inline SVG element.

    Works offline (no MathJax, no web font): the glyphs are SVG paths.  The XML
    prologue, the namespace declarations and metadata (which name URLs), the
    comments (which repeat the TeX), the page-wide style and the white background
    are left out; the element sits on the text's baseline.

    Parameters
    ----------
    tex : str
        The formula, without the ``$`` delimiters (mathtext's TeX subset).

    Returns
    -------
    str
        ``<svg ...>...</svg>``.

    Raises
    ------
    ValueError
        If mathtext cannot parse the formula.
    """
    from matplotlib import mathtext  # deferred: matplotlib is heavy to import
    from matplotlib.font_manager import FontProperties  # deferred: matplotlib is heavy

    buf = io.BytesIO()
    depth = mathtext.math_to_image(f"${tex}$", buf, prop=FontProperties(size=11),
                                   format="svg")
    svg = _SVG_DROP.sub("", buf.getvalue().decode("utf-8")).strip()
    style = f'style="vertical-align: -{float(depth or 0.0):.1f}pt" class="math" role="img"'
    # inline in HTML5: no namespace declarations needed, SVG 2 href (no URL in the page)
    svg = re.sub(r'\sxmlns(?::xlink)?="[^"]*"', "", svg).replace("xlink:href=", "href=")
    return svg.replace("<svg ", f"<svg {style} ", 1)


def rich(text: str) -> str:
    """Escape ``text`` for HTML, rendering each ``$...$`` formula as inline SVG (:func:`math_svg`).

    A formula mathtext cannot parse is shown as escaped code, never dropped.
    """
    parts = text.split("$")
    if len(parts) % 2 == 0:  # an unpaired $: plain text
        return _e(text)
    out = []
    for k, part in enumerate(parts):
        if k % 2 == 0:
            out.append(_e(part))
            continue
        try:
            out.append(math_svg(part))
        except ValueError:
            out.append(f"<code>{_e(part)}</code>")
    return "".join(out)


def _figure_png(fig) -> bytes:
    import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    return buf.getvalue()


def _versions() -> str:
    parts = [f"Python {platform.python_version()}"]
    for mod in ("numpy", "scipy", "control", "fmpy", "matplotlib"):
        try:
            m = __import__(mod)
            parts.append(f"{mod} {getattr(m, '__version__', '?')}")
        except ImportError:  # pragma: no cover
            parts.append(f"{mod} missing")

    return f"djl-fmu {__version__}; " + ", ".join(parts)


_BADGE = {"PASSED": "PASSED", "REFUTED": "paper statement refuted (product checks passed)",
          "FAILED": "FAILED: product check", "ERROR": "ERROR: not computed"}
"""The claim's badge: a refuted paper statement is a finding, apart from a failed product
check (a defect)."""


def _claim_section(r: ClaimResult, img_src: Callable[[int, int, bytes], str]) -> str:
    out = [f'<h2 id="claim{r.number}">Claim {r.number}: {_e(r.title)}'
           f'<span class="badge {r.status if r.status != "ERROR" else "FAILED"}">'
           f'{_BADGE[r.status]}</span></h2>']
    n_prod = [c for c in r.checks if c.kind == "product"]
    n_paper = [c for c in r.checks if c.kind == "paper"]
    out.append(f'<p class="meta">Source: {_e(r.source)} &middot; '
               f'product checks {sum(c.passed for c in n_prod)}/{len(n_prod)} passed &middot; '
               f'paper statements {sum(c.passed for c in n_paper)}/{len(n_paper)} confirmed '
               f'&middot; {r.elapsed:.1f} s</p>')
    if r.statement:
        out.append(f"<h3>The paper says</h3><blockquote>{rich(r.statement)}</blockquote>")
    if r.method:
        out.append(f"<h3>How both sides are computed</h3><p>{rich(r.method)}</p>")
    if r.error:
        out.append('<h3 class="FAILED">The computation raised: claim FAILED</h3>'
                   f"<pre>{_e(r.error)}</pre>")
    for i, fig in enumerate(r.figures):
        src = img_src(r.number, i, _figure_png(fig))
        out.append(f'<img src="{src}" alt="claim {r.number}, figure {i + 1}">')
    r.figures.clear()
    if r.checks:
        out.append("<h3>Checks</h3><table><tr><th>check</th><th>kind</th><th>paper side</th>"
                   "<th>product / simulation</th><th>rule</th><th>unit</th><th>verdict</th>"
                   "</tr>")
        for c in r.checks:
            name, kind, exp, meas, rule, unit, verdict = c.row()
            note = f'<div class="note">{_e(c.note)}</div>' if c.note else ""
            out.append(f"<tr><td>{_e(name)}{note}</td><td class='kind'>{_e(kind)}</td>"
                       f"<td class='num'>{_e(exp)}</td><td class='num'>{_e(meas)}</td>"
                       f"<td>{_e(rule)}</td><td>{_e(unit)}</td>"
                       f"<td class='{verdict}'>{verdict}</td></tr>")
        out.append("</table>")
    for t in r.tables:
        out.append(f"<h3>{_e(t.caption)}</h3><table><tr>"
                   + "".join(f"<th>{_e(h)}</th>" for h in t.header) + "</tr>")
        for row in t.formatted():
            out.append("<tr>" + "".join(f"<td class='num'>{_e(c)}</td>" for c in row) + "</tr>")
        out.append("</table>")
    if r.derivations:
        out.append("<h3>Equations re-derived for this claim</h3><ul>"
                   + "".join(f"<li>{rich(d)}</li>" for d in r.derivations) + "</ul>")
    return "\n".join(out)


PEERS_SKIPPED = ("The comparison with the peer methods was left out: it needs the optional "
                 "package ruckig (the time-optimal jerk-limited reference), which is not "
                 f"installed: {COMPARE_HINT}, then run the report again.")
"""The report's note (and the console's warning) when ruckig is missing."""


def peers_section(settings: Settings,
                  img_src: Callable[[int, int, bytes], str] | None = None) -> str:
    """HTML section comparing AL / JL / DJL with the peers on scenarios X and Y.

    Every method goes through the same co-simulation (generator FMU or the peer's exact
    motion, Z axis, plant) and the same metrics as ``djl-fmu compare``, at the same
    settling band and over the same map-error range (time-varying plant, fast engine);
    fast settings use fewer points on the robustness curves and leave out the physical
    limit (its linear programme).  One figure per scenario:
    the stationary-mode curves beside the time-varying map-error curves.
    """
    if not ruckig_available():
        return (f"<h2 id='peers'>Peers side by side</h2>\n<p class='skipped'>{_e(PEERS_SKIPPED)}"
                "</p>")
    errors = np.linspace(-0.4, 0.4, 9 if settings.fast else 41)
    scenarios = [load_scenario(name) for name in ("X", "Y")]
    # the map errors and their worst case: each scenario's uncertainty (+/-2 x map_scale,
    # the worst case over +/-map_scale; the same for X and Y, +/-10 % by default)
    spans = sorted({span_text(sc.uncertainty.map_scale) for sc in scenarios})
    pct = spans[0] if len(spans) == 1 else "map_scale"
    parts = [
        "<h2 id='peers'>Peers side by side: which law ends the motion soonest within the "
        "tolerance?</h2>",
        "<p>AL, JL and DJL from the FMU against the methods users would otherwise pick: "
        "time-optimal jerk-limited (Park et al. 2017, cross-checked with ruckig), Sato &amp; "
        "Shirase 2021's designed jerk times (Condition III), the ZV, ZVD, MZV and EI input "
        "shapers convolved with the AL profile, the ZV, ZVD and EI shapers convolved with the "
        "JL profile (as shapers are used on jerk-limited machines), the damped-jerk law "
        "(Béarée 2014 §4.2), all tuned to the mode at the end of the motion; a time-varying "
        "ZV shaper whose impulses follow the mode along the Z move (after Chang &amp; Park "
        "2005, the reference [12] of Béarée &amp; Olabi 2013), on AL and on JL; and the DJL "
        "with the harness's optimal and robust tuning when available. "
        "Motion time is also given relative to the time-optimal JL with the same limits; "
        "residual (free-oscillation amplitude at the end) in % of AL; settling into the "
        "scenario's band, shared by every method (default: 1 % of AL's residual); "
        f"worst±{pct}%: the largest residual when the whole map f(z) of the time-varying "
        f"plant is off by 1 + e, |e| ≤ {pct} %, every reference planned on the nominal map. "
        "Each table ends with the verdict (who leaves the least residual, who settles "
        "first, who has the smallest worst case). "
        "The figures show the residual against an error on the mode frequency: left on a "
        "stationary mode at the end frequency, right on the time-varying plant (Z moving), "
        "whole map scaled by 1 + e. Same as <code>djl-fmu compare</code>; details in "
        "docs/peers.md.</p>",
    ]
    if img_src is None:
        def img_src(_n: int, _i: int, png: bytes) -> str:
            return "data:image/png;base64," + base64.b64encode(png).decode("ascii")

    import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

    for i, sc in enumerate(scenarios):
        name = sc.name
        try:
            sc = sc.with_fmu(None if settings.fmu is None else Path(settings.fmu),
                             settings.fmi_version)
            # the physical limit (a linear programme, ~30 s a scenario until cached) in
            # the full report only; --fast is the quick look
            map_errors = sc.uncertainty.curve_errors(9 if settings.fast else 41)
            cmp = compare_scenario(sc, errors=errors, map_errors=map_errors,
                                   bound=not settings.fast)
            fig = cmp.plot_robustness()
            png = _figure_png(fig)
            plt.close(fig)
            parts.append(f"<h3>Scenario {_e(name)}</h3>\n<pre>{_e(cmp.table())}</pre>\n"
                         f"<img alt='robustness, scenario {_e(name)}' "
                         f"src='{img_src(0, i, png)}'>")
        except Exception as exc:  # noqa: BLE001 - shown in the report, never hidden
            parts.append(f"<p class='FAILED'>Comparison on scenario {_e(name)} raised: "
                         f"{_e(repr(exc))}</p>")
    return "\n".join(parts)


def render_html(results: Sequence[ClaimResult], *, settings: Settings, elapsed: float,
                command: str | None = None,
                img_src: Callable[[int, int, bytes], str] | None = None,
                extra_sections: Sequence[str] = ()) -> str:
    """Render the report as an HTML string (closes the results' figures).

    ``extra_sections`` are HTML fragments appended after the claims (the peer
    comparison).
    """
    if img_src is None:
        def img_src(_n: int, _i: int, png: bytes) -> str:
            return "data:image/png;base64," + base64.b64encode(png).decode("ascii")

    fmu = (f"user FMU {settings.fmu}" if settings.fmu else
           f"FMU built from this package's sources (FMI {settings.fmi_version}.0)")
    n_ok = sum(r.passed for r in results)
    rows = []
    for r in results:
        prod = [c for c in r.checks if c.kind == "product"]
        pap = [c for c in r.checks if c.kind == "paper"]
        rows.append(
            f"<tr><td><a href='#claim{r.number}'>{r.number}</a></td><td>{_e(r.title)}</td>"
            f"<td>{_e(r.source)}</td><td class='num'>{sum(c.passed for c in prod)}/{len(prod)}"
            f"</td><td class='num'>{sum(c.passed for c in pap)}/{len(pap)}</td>"
            f"<td class='{r.status}'>{r.status}</td><td class='num'>{r.elapsed:.1f} s</td>"
            "</tr>")
    failed = [(r, c) for r in results for c in r.checks if not c.passed]
    failed_html = "".join(f"<li>claim {r.number} ({_e(c.kind)}): {_e(c.describe())}</li>"
                          for r, c in failed)
    errors = "".join(f"<li>claim {r.number}: the computation raised (see its section)</li>"
                     for r in results if r.error)
    body = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        "<title>djl-fmu: verification of the papers' filtering claims</title>",
        f"<style>{_CSS}</style></head><body>",
        "<h1>Bode and impulse analyses verifying the papers' filtering claims</h1>",
        "<p>Each claim of Béarée &amp; Olabi 2013 (<i>Dissociated jerk-limited trajectory "
        "applied to time-varying vibration reduction</i>, RCIM 29(2)) and Béarée 2014 "
        "(<i>État de l'art de la compensation de vibration par la génération de "
        "trajectoire</i>, Assises MUGV) is computed twice: the paper's side (closed forms, "
        "re-derived where the text is garbled) and the product's side (the generator FMU run "
        "through fmpy, the harness's plant, python-control), and compared with the stated "
        "tolerance. <b>product</b> checks test the FMU and the harness against the theory "
        "they implement; <b>paper</b> checks test a quantitative statement of a paper as "
        "written: when one fails, the finding is about the paper and the numbers say by "
        "how much.</p>",
        f"<p class='meta'>Generated {_dt.datetime.now().isoformat(timespec='seconds')} in "
        f"{elapsed:.1f} s &middot; {_e(fmu)} &middot; "
        f"{'fast settings' if settings.fast else 'full settings'} &middot; "
        f"{_e(_versions())}"
        + (f" &middot; command: <code>{_e(command)}</code>" if command else "") + "</p>",
        f"<h2>Summary: {n_ok}/{len(results)} claims passed</h2>",
        "<table><tr><th>claim</th><th>title</th><th>source</th><th>product checks</th>"
        "<th>paper statements</th><th>verdict</th><th>time</th></tr>",
        *rows, "</table>",
    ]
    if failed or errors:
        body.append("<h3>What failed</h3><ul>" + errors + failed_html + "</ul>")
    body.append("<h3>Equations of the papers re-derived (garbled or wrong in the text)</h3><ul>"
                + "".join(f"<li><b>{_e(paper_ref(k))}</b>: {rich(v)}</li>"
                          for k, v in DERIVATIONS.items())
                + "</ul>")
    if extra_sections:
        body.append("<p>Also in this report: <a href='#peers'>peers side by side</a>.</p>")
    for r in results:
        body.append(_claim_section(r, img_src))
    body.extend(extra_sections)
    body.append("</body></html>")
    return "\n".join(body)


def write_report(path: str | os.PathLike = "report.html", *, fast: bool = False,
                 fmi_version: int = 2, fmu: str | os.PathLike | None = None,
                 only: Sequence[int] | None = None, embed: bool = True,
                 progress: bool = False, command: str | None = None,
                 on_result: Callable[[ClaimResult], None] | None = None,
                 peers: bool | None = None) -> ReportSummary:
    """Run the claims and write the HTML report.

    Parameters
    ----------
    path : path-like
        HTML file to write (parent folders are created).  The HTML and its
        figures are written as one set (:class:`harness.files.OutputSet`):
        an error or an interruption leaves the previous report whole.
    fast : bool
        Small grids (as in the test suite).
    fmi_version : {2, 3}
        Which FMU to build and verify when ``fmu`` is not given.
    fmu : path-like, optional
        A generator FMU file to verify instead.
    only : sequence of int, optional
        Claim numbers to run (all by default).
    embed : bool
        Embed the figures as base64 PNG (one self-contained file); otherwise
        write them to ``<stem>_files/`` beside the HTML.
    progress : bool
        tqdm progress bars in the longer sweeps (only on a TTY).
    command : str, optional
        Command line shown in the report.
    on_result : callable, optional
        Called with each claim's result as it completes.
    peers : bool, optional
        Append the comparison with the peer methods (needs ``ruckig``);
        by default when every claim is run.

    Returns
    -------
    ReportSummary
    """
    import matplotlib  # deferred: matplotlib is heavy to import

    matplotlib.use("Agg")
    t0 = time.perf_counter()
    path = Path(path)
    settings = Settings(fast=fast, fmi_version=fmi_version, fmu=fmu, progress=progress)
    results = run_claims(settings, only=only, on_result=on_result)
    img_src = None
    files_dir = path.with_name(path.stem + "_files")
    pngs: dict[str, bytes] = {}
    if not embed:
        def img_src(n: int, i: int, png: bytes) -> str:
            name = f"claim{n}_{i + 1}.png" if n else f"peers_{i + 1}.png"
            pngs[name] = png
            return f"{files_dir.name}/{name}"

    if peers is None:
        peers = only is None
    extra = [peers_section(settings, img_src)] if peers else []
    elapsed = time.perf_counter() - t0

    text = render_html(results, settings=settings, elapsed=elapsed, command=command,
                       img_src=img_src, extra_sections=extra)
    # the HTML and its figures: one set, replacing the previous one whole
    with OutputSet(path.parent) as o:
        o.path(path.name).write_text(text, encoding="utf-8")
        for name, png in pngs.items():
            o.path(f"{files_dir.name}/{name}").write_bytes(png)
        o.commit()
    return ReportSummary(path, results, time.perf_counter() - t0)


def print_failures(summary: ReportSummary, stream=None) -> None:
    """Print every failed check and every claim that raised (to ``stream``, default stdout)."""
    stream = sys.stdout if stream is None else stream
    for r in summary.results:
        for c in r.failed_checks():
            print(f"  claim {r.number} [{c.kind}] {c.describe()}", file=stream)
        if r.error:
            print(f"  claim {r.number}: the computation raised:\n{r.error}", file=stream)
