"""Every ``harness.*`` name the docs and the docstrings give exists (issue 36, item 6).

The names checked are the dotted names ``harness.a[.b...]`` written in

* ``README.md`` and ``docs/*.md`` (prose, tables and code blocks alike), and
* the comments and string literals (docstrings included) of ``harness/**/*.py``,
  read with :mod:`tokenize`, so that code itself is not scanned (it is checked by
  running it).

A name resolves when its longest prefix that is a module imports and every remaining
part is an attribute of what precedes it.  An attribute of a class counts when the class
has it, declares it as a field (a dataclass field or an annotation, possibly without a
class-level value) or assigns it to ``self`` in its source (an attribute set in
``__init__``, such as ``harness.fmu.runner.GeneratorFMU.log``).

Skipped, and only these:

* a name directly after a word character, ``/``, ``.`` or ``-`` (``test_harness.py``,
  ``src/harness.x``: part of another word or a path, not a Python name);
* a name whose last part is ``md``: the Markdown file ``harness.md`` of a link such as
  ``[harness.md](harness.md)``, not a module.

``docs/engine.md``'s Python examples are also run (they once imported a module that no
longer existed), and every relative link of ``README.md`` and ``docs/*.md`` is checked to
reach an existing file and, for ``#anchor``, a heading of that page (GitHub's anchors: the
heading lowercased, its punctuation but ``-`` and ``_`` dropped, spaces made ``-``, a
repeated heading numbered ``-1``, ``-2`` ...): the README's sections moved to docs/ and the
fuzzing log to docs/fuzzing.md (issue 36) with their links kept working.
"""

from __future__ import annotations

import importlib
import inspect
import io
import re
import tokenize
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

NAME = re.compile(r"(?<![\w/.\-])harness(?:\.[A-Za-z_]\w*)+")
"""A dotted name rooted at the package (see the module docstring for what is skipped)."""

_TEXT_TOKENS = {tokenize.COMMENT, tokenize.STRING}
if hasattr(tokenize, "FSTRING_MIDDLE"):  # Python >= 3.12 splits f-strings into tokens
    _TEXT_TOKENS.add(tokenize.FSTRING_MIDDLE)


def _matches(text: str) -> list[re.Match[str]]:
    return [m for m in NAME.finditer(text) if not m.group(0).endswith(".md")]


def _names(text: str) -> list[str]:
    return [m.group(0) for m in _matches(text)]


def names_in_markdown(path: Path) -> list[tuple[int, str]]:
    """``(line, name)`` of every ``harness.*`` name in a Markdown file."""
    return [(i, n) for i, line in enumerate(path.read_text().splitlines(), 1)
            for n in _names(line)]


def names_in_python(path: Path) -> list[tuple[int, str]]:
    """``(line, name)`` of every ``harness.*`` name in a module's comments and strings."""
    found = []
    for tok in tokenize.generate_tokens(io.StringIO(path.read_text()).readline):
        if tok.type in _TEXT_TOKENS:
            found += [(tok.start[0] + tok.string.count("\n", 0, m.start()), m.group(0))
                      for m in _matches(tok.string)]
    return found


def _class_declares(cls: type, name: str) -> bool:
    for k in cls.__mro__:
        if name in getattr(k, "__dataclass_fields__", {}) or name in vars(k).get(
                "__annotations__", {}):
            return True
        try:
            source = inspect.getsource(k)
        except (OSError, TypeError):
            continue
        if re.search(rf"\bself\.{re.escape(name)}\s*(?::[^=\n]+)?=", source):
            return True
    return False


@cache
def resolves(name: str) -> bool:
    """True when ``name`` is an importable module followed by existing attributes."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        module_name = ".".join(parts[:i])
        try:
            obj = importlib.import_module(module_name)
            break
        except ModuleNotFoundError as e:
            if e.name is None or not module_name.startswith(e.name):
                raise  # the module exists but an import inside it failed: a real error
    for part in parts[i:]:
        if hasattr(obj, part):
            obj = getattr(obj, part)
        elif inspect.isclass(obj) and _class_declares(obj, part):
            obj = None  # an instance attribute: nothing further to look into
        else:
            return False
    return True


def _sources() -> list[tuple[Path, list[tuple[int, str]]]]:
    docs = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    code = sorted((ROOT / "harness").rglob("*.py"))
    return ([(p, names_in_markdown(p)) for p in docs]
            + [(p, names_in_python(p)) for p in code])


def test_the_scan_finds_names_and_refuses_stale_ones(tmp_path):
    # what a stale reference looked like before issue 36, and what replaced it
    for stale in ("harness.cosim", "harness.cosim.Session", "harness.planner.MoveSamples",
                  "harness.engine.FastAxis", "harness.simulation.master.MotionAxis",
                  "harness.tuning.TuningResult", "harness.simulation.session.Session.tune"):
        assert not resolves(stale), stale
    for current in ("harness.simulation.session.Session", "harness.simulation.axis.MoveSamples",
                    "harness.simulation.fast_axis.FastAxis", "harness.peers.motion_axis.MotionAxis",
                    "harness.tuning.rule.TuningResult", "harness.fmu.runner.GeneratorFMU.log",
                    "harness.simulation.session.Session.map_error_residuals", "harness._engine"):
        assert resolves(current), current
    text = ("see `harness.cosim.Session` and [harness.md](harness.md#x); "
            "tests/test_harness.py; :func:`harness.evaluation.run_case`.")
    assert _names(text) == ["harness.cosim.Session", "harness.evaluation.run_case"]
    tokens = '"""Doc.\n\nUses :class:`harness.planner.MoveSamples`."""\nx = 1  # harness.engine\n'
    path = tmp_path / "module.py"
    path.write_text(tokens)
    assert names_in_python(path) == [(3, "harness.planner.MoveSamples"), (4, "harness.engine")]


def test_every_harness_name_in_the_docs_and_docstrings_exists():
    sources = _sources()
    assert sum(len(found) for _, found in sources) > 300  # the scan sees the references
    stale = [f"{p.relative_to(ROOT)}:{line}: {name}"
             for p, found in sources for line, name in found if not resolves(name)]
    assert not stale, "names that do not import (write the current module):\n" + "\n".join(stale)


@pytest.mark.parametrize("block", range(2))
def test_engine_doc_examples_run(block, tmp_path, monkeypatch):
    text = (ROOT / "docs" / "engine.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 2, "docs/engine.md: update this test's count of examples"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(blocks[block], f"docs/engine.md, example {block + 1}", "exec"), namespace)
    if block == 0:
        assert namespace["T"] == pytest.approx(0.991) and namespace["rows"].shape == (7, 1200)
        assert namespace["rows"][0, -1] == pytest.approx(0.4, abs=1e-12)
    else:
        run = namespace["run"]
        assert run["x"][-1] == pytest.approx(0.6, abs=1e-12) and run["queue_length"].max() == 1


def _slug(heading: str) -> str:
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _outside_code(path: Path) -> list[tuple[int, str]]:
    lines, fence = [], False
    for i, line in enumerate(path.read_text().splitlines(), 1):
        if line.startswith("```"):
            fence = not fence
        elif not fence:
            lines.append((i, line))
    return lines


@cache
def _anchors(path: Path) -> frozenset[str]:
    seen: dict[str, int] = {}
    out = set()
    for _, line in _outside_code(path):
        m = re.match(r"#{1,6} (.*)", line)
        if m:
            s = _slug(m.group(1))
            n = seen.get(s, 0)
            out.add(s if n == 0 else f"{s}-{n}")
            seen[s] = n + 1
    return frozenset(out)


def test_slugs_are_githubs():
    assert _slug("Replayed tables (profile = 4)") == "replayed-tables-profile--4"
    assert _slug("Two engines (`--engine`)") == "two-engines---engine"
    assert _slug("Fuzz harnesses (`tests/fuzz/`)") == "fuzz-harnesses-testsfuzz"
    assert _slug("DJL tuned to win — and what it costs") == "djl-tuned-to-win--and-what-it-costs"


def test_every_relative_link_of_the_docs_resolves():
    bad = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for line_no, line in _outside_code(page):
            for m in re.finditer(r"\]\(([^)\s]+)\)", line):
                target = m.group(1)
                if re.match(r"[a-z][a-z0-9+.-]*:", target):
                    continue  # https:, mailto: ...
                file, _, anchor = target.partition("#")
                path = (page.parent / file).resolve() if file else page
                where = f"{page.relative_to(ROOT)}:{line_no}: {target}"
                if not path.exists():
                    bad.append(f"{where} (no such file)")
                elif anchor and path.suffix == ".md" and anchor not in _anchors(path):
                    bad.append(f"{where} (no such heading)")
    assert not bad, "links that lead nowhere:\n" + "\n".join(bad)
