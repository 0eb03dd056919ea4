"""Issue #10 item 9: every command's outputs replace the previous set whole, or not at all.

An interruption (Ctrl-C, SIGTERM, an exception) while the files are written or while they
are swapped in leaves the previous files byte for byte and no staging folder; a process
killed during the swap (SIGKILL) is rolled back by the next run; a successful run replaces
every file of its set.  See harness.files.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest

from harness import files
from harness.cli import main
from harness.files import TMP_PREFIX, OutputSet, recover_stale

from _scenarios import SMALL_AXIS

NAMES = ("a.csv", "b.png", "sub/c.txt", "summary.txt")


def _snapshot(d: Path) -> dict[str, bytes]:
    """Every file under ``d`` (relative POSIX name -> bytes), staging folders included."""
    return {p.relative_to(d).as_posix(): p.read_bytes() for p in sorted(d.rglob("*"))
            if p.is_file() or p.is_symlink()}


def _no_staging(d: Path) -> None:
    assert not [p for p in d.rglob("*") if p.name.startswith(TMP_PREFIX)]


def _seed(out: Path, names: tuple[str, ...] | list[str]) -> dict[str, bytes]:
    """A previous set (``old <name>``) and a file of the user's, ``notes.txt``."""
    for n in names:
        p = out / n
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(f"old {n}\n".encode())
    (out / "notes.txt").write_text("the user's own file\n")
    return _snapshot(out)


def _write_new(o: OutputSet, names: tuple[str, ...] = NAMES) -> None:
    for n in names:
        o.path(n).write_bytes(f"new {n}\n".encode())


def _interrupt_path(monkeypatch: pytest.MonkeyPatch, n: int,
                    exc: type[BaseException] = KeyboardInterrupt) -> None:
    """Raise ``exc`` when the n-th output file is about to be written (1-based)."""
    orig = OutputSet.path
    calls: list[str] = []

    def path(self: OutputSet, name: str) -> Path:
        calls.append(name)
        if len(calls) == n:
            raise exc("interrupted while writing")
        return orig(self, name)

    monkeypatch.setattr(OutputSet, "path", path)


def _interrupt_swap(monkeypatch: pytest.MonkeyPatch, n: int, after: bool = False,
                    exc: type[BaseException] = KeyboardInterrupt) -> None:
    """Raise ``exc`` at the n-th file of the swap: before it is swapped, or just after."""
    orig = files._swap_one
    calls: list[str] = []

    def swap(base: Path, tmp: Path, name: str, created: list[Path]) -> None:
        calls.append(name)
        if len(calls) == n and not after:
            raise exc("interrupted before a swap")
        orig(base, tmp, name, created)
        if len(calls) == n and after:
            raise exc("interrupted after a swap")

    monkeypatch.setattr(files, "_swap_one", swap)


# ------------------------------------------------------------------ the mechanism

def test_a_successful_set_replaces_every_file_and_leaves_the_rest(tmp_path):
    out = tmp_path / "out"
    _seed(out, NAMES[:2])  # a.csv and b.png exist, sub/c.txt and summary.txt are new
    (out / "other.csv").write_text("a file of an earlier run, not in this set\n")
    with OutputSet(out) as o:
        _write_new(o)
        written = o.commit()
    assert written == [out / n for n in NAMES]
    snap = _snapshot(out)
    assert {n: snap[n] for n in NAMES} == {n: f"new {n}\n".encode() for n in NAMES}
    assert snap["notes.txt"] == b"the user's own file\n"
    assert snap["other.csv"].startswith(b"a file")
    _no_staging(out)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
@pytest.mark.parametrize("exc", [KeyboardInterrupt, OSError, RuntimeError])
def test_interrupted_while_writing_leaves_the_previous_set(tmp_path, monkeypatch, n, exc):
    out = tmp_path / "out"
    before = _seed(out, NAMES)
    _interrupt_path(monkeypatch, n, exc)
    with pytest.raises(exc), OutputSet(out) as o:
        _write_new(o)
        o.commit()
    assert _snapshot(out) == before
    _no_staging(out)


def test_a_partial_file_never_reaches_the_folder(tmp_path):
    out = tmp_path / "out"
    before = _seed(out, NAMES)
    with pytest.raises(KeyboardInterrupt), OutputSet(out) as o:
        with o.path("a.csv").open("wb") as f:
            f.write(b"half a fi")
            raise KeyboardInterrupt
    assert _snapshot(out) == before
    _no_staging(out)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
@pytest.mark.parametrize("after", [False, True], ids=["before", "after"])
@pytest.mark.parametrize("exc", [KeyboardInterrupt, OSError])
def test_interrupted_during_the_swap_restores_the_previous_set(tmp_path, monkeypatch, n,
                                                               after, exc):
    out = tmp_path / "out"
    before = _seed(out, NAMES[:2])  # sub/c.txt and summary.txt did not exist: removed again
    _interrupt_swap(monkeypatch, n, after, exc)
    with pytest.raises(exc), OutputSet(out) as o:
        _write_new(o)
        o.commit()
    assert _snapshot(out) == before
    assert not (out / "sub").exists()  # the folder the swap made is removed too
    _no_staging(out)


def test_a_new_folder_is_removed_when_nothing_was_committed(tmp_path, monkeypatch):
    out = tmp_path / "a" / "b" / "out"
    _interrupt_path(monkeypatch, 2)
    with pytest.raises(KeyboardInterrupt), OutputSet(out) as o:
        _write_new(o)
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def python_sigint() -> Iterator[None]:
    """Python's own SIGINT handler (KeyboardInterrupt) for one test, then the inherited one.

    A suite started in the background (``nohup pytest``, ``pytest &`` from a script) inherits
    SIGINT ignored: a test that sends itself SIGINT and expects KeyboardInterrupt installs
    the handler it relies on.
    """
    prev = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, prev)


def test_signals_during_the_swap_are_delivered_after_it(tmp_path, monkeypatch, python_sigint):
    """Ctrl-C in the middle of the swap waits for its end: the new set is whole, then the
    KeyboardInterrupt comes."""
    out = tmp_path / "out"
    _seed(out, NAMES)
    orig = files._swap_one

    def swap(*a: object) -> None:
        os.kill(os.getpid(), signal.SIGINT)
        orig(*a)  # type: ignore[arg-type]

    monkeypatch.setattr(files, "_swap_one", swap)
    with pytest.raises(KeyboardInterrupt), OutputSet(out) as o:
        _write_new(o)
        o.commit()
    snap = _snapshot(out)
    assert {n: snap[n] for n in NAMES} == {n: f"new {n}\n".encode() for n in NAMES}
    _no_staging(out)


def test_names_stay_inside_the_folder(tmp_path):
    with OutputSet(tmp_path) as o:
        for bad in ("../x.csv", "/etc/x", "", "a/../../x", TMP_PREFIX + "x/y"):
            with pytest.raises(ValueError):
                o.path(bad)
    _no_staging(tmp_path)


def test_an_unwritten_file_or_a_folder_in_the_way_fails_before_the_swap(tmp_path):
    out = tmp_path / "out"
    before = _seed(out, NAMES)
    with pytest.raises(FileNotFoundError, match="was not written"), OutputSet(out) as o:
        o.path("a.csv").write_text("x")
        o.path("never.csv")
        o.commit()
    (out / "dir.csv").mkdir()
    with pytest.raises(IsADirectoryError), OutputSet(out) as o:
        o.path("a.csv").write_text("x")
        o.path("dir.csv").write_text("x")
        o.commit()
    (out / "dir.csv").rmdir()
    assert _snapshot(out) == before
    _no_staging(out)


_KILLED_DURING_SWAP = """
import os, signal, sys
from harness import files
orig, n = files._swap_one, [0]
def swap(*a):
    n[0] += 1
    if n[0] == 3:
        os.kill(os.getpid(), signal.SIGKILL)
    orig(*a)
files._swap_one = swap
with files.OutputSet(sys.argv[1]) as o:
    for name in ("a.csv", "b.png", "sub/c.txt", "summary.txt"):
        o.path(name).write_bytes(("new " + name + "\\n").encode())
    o.commit()
"""

_KILLED_WHILE_WRITING = """
import os, signal, sys
from harness import files
with files.OutputSet(sys.argv[1]) as o:
    o.path("a.csv").write_bytes(b"new")
    os.kill(os.getpid(), signal.SIGKILL)
"""


def _run_killed(code: str, out: Path) -> None:
    proc = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True,
                          cwd=Path(__file__).parents[1], timeout=120)
    assert proc.returncode == -signal.SIGKILL, proc.stderr


def test_killed_during_the_swap_is_rolled_back_by_the_next_run(tmp_path):
    out = tmp_path / "out"
    before = _seed(out, NAMES[:2])
    _run_killed(_KILLED_DURING_SWAP, out)
    # a mix was left (a.csv and b.png new) with the journal and the backups
    stale = list(out.glob(TMP_PREFIX + "*"))
    assert len(stale) == 1 and (stale[0] / files.JOURNAL).is_file()
    assert (out / "a.csv").read_bytes() == b"new a.csv\n"
    # the next set opened there rolls it back, then does its own work
    with OutputSet(out) as o:
        assert list(out.glob(TMP_PREFIX + "*")) == [o.tmp]
        assert {k: v for k, v in _snapshot(out).items()
                if not k.startswith(TMP_PREFIX)} == before
    assert _snapshot(out) == before
    _no_staging(out)


def test_killed_while_writing_leaves_the_set_and_the_next_run_removes_its_folder(tmp_path):
    out = tmp_path / "out"
    before = _seed(out, NAMES)
    _run_killed(_KILLED_WHILE_WRITING, out)
    assert len(list(out.glob(TMP_PREFIX + "*"))) == 1
    assert {k: v for k, v in _snapshot(out).items() if not k.startswith(TMP_PREFIX)} == before
    recover_stale(out)
    assert _snapshot(out) == before
    _no_staging(out)


def test_a_live_staging_folder_is_left_alone(tmp_path):
    out = tmp_path / "out"
    with OutputSet(out) as o1:
        o1.path("a.csv").write_text("1")
        with OutputSet(out) as o2:  # its opening looks for stale folders: o1's is alive
            assert o1.tmp is not None and o1.tmp.is_dir()
            o2.path("b.csv").write_text("2")
            o2.commit()
        o1.commit()
    assert _snapshot(out) == {"a.csv": b"1", "b.csv": b"2"}


# ------------------------------------------------------------------ SIGTERM

def test_sigterm_stops_a_command_and_cleans_up(tmp_path, capsys):
    """SIGTERM while the outputs are written: exit 143, the previous set, no staging."""
    from harness.commands._common import interruptible, write_outputs

    out = tmp_path / "out"
    before = _seed(out, ["x.csv", "summary.txt"])

    def run(_args: object) -> int:
        def write(o: OutputSet) -> None:
            o.path("x.csv").write_text("new")
            os.kill(os.getpid(), signal.SIGTERM)
            raise AssertionError("SIGTERM did not stop the command")  # pragma: no cover

        write_outputs(out, write, "summary")
        return 0

    handler = signal.getsignal(signal.SIGTERM)
    from harness.commands._common import CommandError

    with pytest.raises(CommandError) as ei:
        interruptible(run)(None)
    assert ei.value.status == 143
    assert signal.getsignal(signal.SIGTERM) == handler
    assert _snapshot(out) == before
    _no_staging(out)


def test_sigterm_to_the_cli_process(tmp_path):
    """A real ``djl-fmu`` process terminated while writing: exit 143, nothing left over."""
    out = tmp_path / "out"
    before = _seed(out, ["s.csv", "summary.txt"])
    code = textwrap.dedent("""
        import os, signal, sys
        from harness import files
        from harness.cli import main
        orig = files.OutputSet.path
        def path(self, name):
            if name == "summary.txt":
                os.kill(os.getpid(), signal.SIGTERM)
            return orig(self, name)
        files.OutputSet.path = path
        sys.exit(main(sys.argv[1:]))
    """)
    scen = tmp_path / "s.toml"
    scen.write_text('name = "s"\n' + SMALL_AXIS)
    proc = subprocess.run([sys.executable, "-c", code, "simulate", str(scen), "-o", str(out),
                           "--no-plot", "-q"], capture_output=True, text=True,
                          cwd=tmp_path, timeout=600)  # the installed package, not the sources
    assert proc.returncode == 143, proc.stderr
    assert "terminated" in proc.stderr and "Traceback" not in proc.stderr
    assert _snapshot(out) == before
    _no_staging(out)


# ------------------------------------------------------------------ every command

def _fast_engine() -> bool:
    try:
        from harness import _engine  # noqa: F401
    except ImportError:
        return False
    return True


def _ruckig() -> bool:
    from harness.peers.ruckig_ref import ruckig_available

    return ruckig_available()


needs_fast = pytest.mark.skipif(not _fast_engine(), reason="needs the compiled engine")


def _commands(tmp_path: Path) -> dict[str, tuple[list[str], Path, list[str]]]:
    """argv, output folder, the files of the set (names relative to the folder)."""
    scen = tmp_path / "s.toml"
    scen.write_text('name = "s"\n' + SMALL_AXIS
                    + "\n[map]\nz0 = [0.0]\nz_distance = [0.3]\ndistance = [0.2, 0.3]\n"
                    "v_max = [2.0]\n")
    o = tmp_path / "out"
    return {
        "simulate": (["simulate", str(scen), "-o", str(o), "-q"], o,
                     ["s.csv", "s-signals.csv", "s-robustness.csv", "s-degradation.csv",
                      "s.png", "s-robustness.png", "s-degradation.png", "summary.txt"]),
        "map": (["map", str(scen), "-o", str(o), "-q", "--workers", "1", "--engine", "fmu"],
                o, ["s-map.csv", "s-map.png", "s-map-DJL-residual.png",
                    "s-map-JL-residual.png", "s-map-djl-vs-jl-settling.png", "summary.txt"]),
        "tune": (["tune", str(scen), "--single", "--tuning", "paper", "-o", str(o), "-q"], o,
                 ["s-jerk-times.csv", "summary.txt"]),
        "compare": (["compare", "X", "--peers", "AL*ZV", "--no-tuned-djl", "--timeopt", "0",
                     "--no-stationary", "--no-bound", "-o", str(o), "-q"], o,
                    ["X.csv", "X-map-error.csv", "X-robustness.csv", "X-degradation.csv",
                     "X-map-error.png", "X-robustness.png", "X-degradation.png", "X-runs.png",
                     "summary.txt"]),
        "report": (["report", "--fast", "--claims", "1", "--figures-beside", "-o",
                    str(o / "r.html")], o, ["r.html", "r_files/claim1_1.png"]),
        "demo": (["demo", "--out", str(o)], o,
                 ["JerkLimitedTrajectory-fmi2.fmu", "JerkLimitedTrajectory-fmi3.fmu",
                  "demo_djl.png"]),
        "build": (["build", "--fmi-version", "3", "--no-validate", "-o",
                   str(o / "g.fmu")], o, ["g.fmu"]),
    }


@pytest.mark.parametrize("command", [
    "simulate", "map",
    pytest.param("tune", marks=needs_fast),
    pytest.param("compare", marks=[needs_fast, pytest.mark.skipif(
        not _ruckig(), reason="needs ruckig")]),
    "report", "demo", "build"])
def test_every_command_writes_its_set_whole(tmp_path, monkeypatch, capsys, command):
    argv, out, names = _commands(tmp_path)[command]
    before = _seed(out, names)
    # interrupted at the last file written, then in the middle of the swap
    stops = [("write", len(names))] + ([("swap", 2)] if len(names) > 1 else [("swap", 1)])
    for where, n in stops:
        with monkeypatch.context() as m:
            if where == "write":
                _interrupt_path(m, n)
            else:
                _interrupt_swap(m, n, after=True)
            assert main(argv) == 130, (where, n, capsys.readouterr().err)
        assert _snapshot(out) == before, (where, n)
        _no_staging(out)
    # a successful run replaces every file of the set, and only those
    assert main(argv) == 0, capsys.readouterr().err
    after = _snapshot(out)
    assert sorted(after) == sorted(before)
    assert after["notes.txt"] == before["notes.txt"]
    assert all(after[n] != before[n] for n in names)
    _no_staging(out)


@pytest.mark.skipif(sys.platform == "win32", reason="process groups and SIGTERM are POSIX")
def test_sigterm_to_a_pooled_map_exits_quietly(tmp_path):
    """SIGTERM to the whole process group of a map on a process pool (what a job runner or
    `timeout` sends): the one line "terminated", exit 143, no traceback from the pool."""
    import subprocess
    import time

    out = tmp_path / "map"
    proc = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "map", "X", "--workers", "2", "--max-moves",
         "3000", "-o", str(out)],
        cwd=tmp_path, stdout=subprocess.PIPE,  # outside the checkout: the installed package
        stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        # wait for the two workers, then let them take tasks
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            kids = [p for p in Path("/proc").iterdir() if p.name.isdigit()
                    and _ppid(p) == proc.pid]
            if len(kids) >= 2 or proc.poll() is not None:
                break
            time.sleep(0.2)
        time.sleep(3.0)
        assert proc.poll() is None, proc.communicate()
        os.killpg(proc.pid, signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:  # pragma: no cover
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 143, stderr
    # the progress lines of the moves done (none says "done"), then the one line
    *progress, last = stderr.splitlines()
    assert last == "djl-fmu map: terminated (SIGTERM)", stderr
    assert all(x.startswith("map X: ") and "done" not in x for x in progress), stderr
    assert "Traceback" not in stdout + stderr
    assert not out.exists() or not any(out.iterdir())


def _ppid(proc_dir: Path) -> int | None:
    try:
        stat = (proc_dir / "stat").read_text()
    except OSError:
        return None
    return int(stat.rsplit(")", 1)[1].split()[1])


# ------------------------------------------------------ figures not drawn twice (issue 18)


def _figure(y, title="t"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0.0, 1.0, 2.0], y, label="a")
    ax.legend()
    ax.set_title(title)
    return fig


def test_a_figure_drawn_before_is_copied_from_the_cache(tmp_path, monkeypatch):
    cache = tmp_path / "figures"
    first = files.save_figure(_figure([0.0, 1.0, 0.5]), tmp_path / "a.png", cache=cache,
                              salt="code")
    assert len(list(cache.glob("*.png"))) == 1
    fig = _figure([0.0, 1.0, 0.5])

    def no_render(*a, **k):
        raise AssertionError("rendered again")

    monkeypatch.setattr(fig, "savefig", no_render)
    again = files.save_figure(fig, tmp_path / "b.png", cache=cache, salt="code")
    assert again.read_bytes() == first.read_bytes()
    # what the figure draws, or the code that drew it, changes its key
    base = files.figure_digest(_figure([0.0, 1.0, 0.5]), 110, "code")
    assert files.figure_digest(_figure([0.0, 1.0, 0.5]), 110, "code") == base
    for other in (files.figure_digest(_figure([0.0, 1.0, 0.51]), 110, "code"),
                  files.figure_digest(_figure([0.0, 1.0, 0.5], "u"), 110, "code"),
                  files.figure_digest(_figure([0.0, 1.0, 0.5]), 100, "code"),
                  files.figure_digest(_figure([0.0, 1.0, 0.5]), 110, "other code")):
        assert other != base
    import matplotlib.pyplot as plt

    plt.close("all")


def test_the_figure_cache_keeps_the_most_recent(tmp_path, monkeypatch):
    monkeypatch.setattr(files, "FIGURE_CACHE_SIZE", 3)
    cache = tmp_path / "figures"
    for i in range(5):
        files.save_figure(_figure([0.0, 1.0, float(i)]), tmp_path / f"{i}.png", cache=cache)
    assert len(list(cache.glob("*.png"))) == 3
