"""dask.distributed is the optional extra ``[cluster]`` (issue 36, item 7).

Only a Dask cluster (``--scheduler``, ``scheduler=...``) needs it: without it the harness
imports and runs on the local cores, and asking for a scheduler says how to install it.
Its absence is simulated by ``sys.modules["distributed"] = None`` (an import of it, or of
any of its modules, then raises ImportError, as when it is not installed).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HINT = "pip install 'djl-fmu[cluster]'"


def _tomllib():
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib
    return tomllib


def test_distributed_is_the_cluster_extra_and_in_test():
    meta = _tomllib().loads((ROOT / "pyproject.toml").read_text())["project"]

    def named(reqs):
        return [r for r in reqs if r.split(">")[0].split("=")[0].strip() == "distributed"]

    assert not named(meta["dependencies"]), "distributed must not be a hard dependency"
    extras = meta["optional-dependencies"]
    assert named(extras["cluster"]) and named(extras["test"])


@pytest.fixture
def no_distributed(monkeypatch):
    for name in [m for m in sys.modules if m == "distributed" or m.startswith("distributed.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "distributed", None)


def test_a_scheduler_without_distributed_says_how_to_install_it(no_distributed):
    from harness.executors import CLUSTER_INSTALL, ExecutorError, make_executor

    assert CLUSTER_INSTALL == HINT
    with pytest.raises(ExecutorError) as ei:
        with make_executor(scheduler="tcp://127.0.0.1:8786", timeout=1.0):
            pass
    assert HINT in str(ei.value) and "dask.distributed" in str(ei.value)
    # the local cores need nothing more
    with make_executor(workers=1) as ex:
        assert ex.submit(pow, 2, 10).result() == 1024


@pytest.mark.parametrize("command", ["map", "tune"])
def test_the_scheduler_option_without_distributed_is_a_clear_error(no_distributed, command,
                                                                   tmp_path, capsys):
    from harness.cli import main

    status = main([command, "X", "--scheduler", "tcp://127.0.0.1:8786", "--max-moves", "2",
                   "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert status == 2, err
    assert HINT in err and "--scheduler tcp://127.0.0.1:8786" in err
    assert not (tmp_path / "out").exists()  # refused before anything ran or was written


def test_the_harness_imports_and_runs_locally_without_distributed():
    """In a fresh interpreter with dask.distributed hidden: every module that can reach a
    cluster imports, and a sweep runs on the local cores."""
    code = textwrap.dedent("""
        import sys
        sys.modules["distributed"] = None
        import harness.cli, harness.executors, harness.sweeps, harness.workspace
        import harness.tuning.tables, harness.commands.map, harness.commands.tune
        from harness.executors import make_executor
        with make_executor(workers=2) as ex:
            assert ex.submit(pow, 3, 3).result() == 27
        assert sys.modules["distributed"] is None
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr
