"""The co-simulation quickstart example runs end to end."""

from __future__ import annotations

import os
import runpy
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_cosim_quickstart(tmp_path, capsys):
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        runpy.run_path(str(EXAMPLES / "cosim_quickstart.py"), run_name="__main__")
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out
    assert "DJL compared with JL" in out
    assert (tmp_path / "djl-fmu-out" / "cosim_quickstart.png").stat().st_size > 10_000
