"""The generator examples run and draw what they claim."""

from __future__ import annotations

import runpy
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_paper_generator_figures(tmp_path):
    mod = runpy.run_path(str(EXAMPLES / "paper_generator_figures.py"), run_name="example")
    written = mod["main"](tmp_path)
    assert len(written) == 4
    assert all(p.stat().st_size > 10_000 for p in written)
