"""The harness's imports point down its layers only, with no circle (docs/architecture.md).

Every module of ``harness/`` is read with :mod:`ast` (imports at any depth:
module level, inside functions, under ``TYPE_CHECKING``) and placed in one
layer of :data:`LAYERS`.  The test requires

* every module to be placed (a new module says where it belongs);
* no import of a harness module of a higher layer;
* no circle among the modules (within a layer included);
* every import written inside a function to defer a heavy or optional
  third-party dependency, with a comment on its line that says so.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "harness"

LAYERS: dict[str, tuple[str, ...]] = {
    "basics": (
        "harness", "harness._resources", "harness.errors", "harness.files",
        "harness.executors", "harness.plant", "harness.modemap", "harness.metrics",
        "harness.uncertainty", "harness._engine", "harness.compiled", "harness.scenarios",
        "harness.shaper_designs", "harness.tables", "harness.figures", "harness.lp",
        "harness.programs", "harness.fmu",
        "harness.fmu.*",
    ),
    "inputs": ("harness.tuning_options", "harness.scenario", "harness.machines",
               "harness.part_program"),
    "simulation": ("harness.simulation", "harness.simulation.*"),
    "tuning": ("harness.scoring", "harness.tuning", "harness.tuning.rule",
               "harness.tuning.search", "harness.tuning.tune", "harness.tuning.tables",
               "harness.tuning.remainder", "harness.tuning.shaping", "harness.tuning.graceful",
               "harness.tuning.reference"),
    "studies": ("harness.results", "harness.robustness", "harness.evaluation", "harness.bound",
                "harness.sweeps", "harness.workspace", "harness.online", "harness.report",
                "harness.recommend", "harness.degradation",
                "harness.peers", "harness.peers.*", "harness.claims", "harness.claims.*"),
    "commands": ("harness.commands", "harness.commands.*"),
    "cli": ("harness.cli", "harness.release"),
}
"""The layers, lowest first; a module may import only from its own layer or lower ones."""

DEFERRABLE = ("matplotlib", "control", "scipy", "fmpy", "distributed", "ruckig", "pandas",
              "highspy", "harness._engine")
"""What an import inside a function may load: heavy or optional dependencies only."""


def layer_of(module: str) -> int:
    """Index in :data:`LAYERS` of a module (KeyError if it is in none)."""
    for i, pats in enumerate(LAYERS.values()):
        for pat in pats:
            if module == pat or (pat.endswith(".*") and module.startswith(pat[:-1])):
                return i
    raise KeyError(module)


def module_name(path: Path, root: Path) -> str:
    rel = path.relative_to(root).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def resolve(module: str, is_pkg: bool, node: ast.ImportFrom) -> list[str]:
    """Absolute names a ``from ... import ...`` reaches (the module, or its submodules)."""
    if node.level:
        base = module.split(".") if is_pkg else module.split(".")[:-1]
        base = base[: len(base) - (node.level - 1)]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    return [target] + [f"{target}.{alias.name}" for alias in node.names]


def scan(root: Path = ROOT) -> tuple[dict[str, set[str]], list[tuple[str, int, str, str]]]:
    """Imports between the modules of ``root/harness``, and the imports inside functions."""
    modules = {module_name(p, root): p for p in (root / "harness").rglob("*.py")}
    edges: dict[str, set[str]] = {m: set() for m in modules}
    nested: list[tuple[str, int, str, str]] = []
    for mod, path in modules.items():
        src = path.read_text(encoding="utf-8")
        lines = src.splitlines()
        tree = ast.parse(src)
        is_pkg = path.name == "__init__.py"
        in_func = {id(sub) for fn in ast.walk(tree)
                   if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef))
                   for sub in ast.walk(fn) if isinstance(sub, (ast.Import, ast.ImportFrom))}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = resolve(mod, is_pkg, node)
            else:
                continue
            edges[mod].update(n for n in names if n != mod and (n in modules
                                                                or n == "harness._engine"))
            if id(node) in in_func:
                target = next((n for n in names if n in DEFERRABLE), names[0])
                nested.append((mod, node.lineno, target, lines[node.lineno - 1]))
    return edges, nested


def upward_imports(edges: dict[str, set[str]]) -> list[str]:
    """Each import of a module of a higher layer, in words."""
    names = list(LAYERS)
    return [f"{a} ({names[layer_of(a)]}) imports {b} ({names[layer_of(b)]})"
            for a, targets in sorted(edges.items()) for b in sorted(targets)
            if layer_of(b) > layer_of(a)]


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The circles a depth-first walk of the import graph meets."""
    state: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in sorted(edges.get(m, ())):
            if n not in edges:
                continue
            if state.get(n) == 1:
                found.append(stack[stack.index(n):] + [n])
            elif n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(edges):
        if m not in state:
            visit(m)
    return found


def lazy_imports(nested: list[tuple[str, int, str, str]]) -> list[str]:
    """Imports inside functions that defer nothing heavy or optional, or say nothing."""
    return [f"{m}:{line}: {text.strip()}" for m, line, target, text in nested
            if not (target.split(".")[0] in DEFERRABLE or target in DEFERRABLE)
            or "#" not in text]


def test_every_module_has_a_layer():
    edges, _ = scan()
    unplaced = []
    for m in edges:
        try:
            layer_of(m)
        except KeyError:
            unplaced.append(m)
    assert not unplaced, f"modules in no layer of LAYERS (place them): {unplaced}"


def test_no_import_runs_back_up_a_layer():
    problems = upward_imports(scan()[0])
    assert not problems, "\n".join(problems)


def test_no_circle_of_imports():
    found = circles(scan()[0])
    assert not found, "circles: " + "; ".join(" -> ".join(c) for c in found)


def test_imports_inside_functions_only_defer_heavy_dependencies():
    bad = lazy_imports(scan()[1])
    assert not bad, ("imports inside functions that defer nothing heavy, or say nothing:\n"
                     + "\n".join(bad))


def make_tree(root: Path, files: dict[str, str]) -> Path:
    for name, text in {"harness/__init__.py": "", "harness/simulation/__init__.py": "",
                       **files}.items():
        f = root / name
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text)
    return root


def test_the_checks_catch_what_they_are_for(tmp_path):
    """A made-up tree with each defect is caught; a sound one passes."""
    sound = make_tree(tmp_path / "sound", {
        "harness/plant.py": "import numpy\n\ndef f():\n    import matplotlib  # deferred: heavy\n",
        "harness/simulation/master.py": "from ..plant import f\n"})
    edges, nested = scan(sound)
    assert edges["harness.simulation.master"] == {"harness.plant"}
    assert not upward_imports(edges) and not circles(edges) and not lazy_imports(nested)
    up = make_tree(tmp_path / "up", {"harness/plant.py": "from .simulation import master\n",
                                     "harness/simulation/master.py": ""})
    assert upward_imports(scan(up)[0]) == [
        "harness.plant (basics) imports harness.simulation (simulation)",
        "harness.plant (basics) imports harness.simulation.master (simulation)"]
    loop = make_tree(tmp_path / "loop", {"harness/simulation/axis.py": "from . import master\n",
                                         "harness/simulation/master.py": "from . import axis\n"})
    assert circles(scan(loop)[0])
    lazy = make_tree(tmp_path / "lazy", {
        "harness/plant.py": "def f():\n    import json\n\ndef g():\n    import scipy\n"})
    assert [x.split(": ")[1] for x in lazy_imports(scan(lazy)[1])] == ["import json",
                                                                        "import scipy"]


def test_every_command_loads_from_a_checkout_without_the_compiled_engine():
    """CI and users run ``python -m harness.cli`` from a clean checkout, whose ``harness/``
    shadows the installed package and has no built ``_engine``: every module must still
    load (``--help``, ``build``), and a command that needs the engine must say why it
    cannot run instead of printing a traceback."""
    import subprocess
    import sys

    prelude = ("import sys; sys.modules['harness._engine'] = None; "
               "from harness.cli import main; ")
    proc = subprocess.run([sys.executable, "-c", prelude + "sys.exit(main(['--help']))"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "simulate" in proc.stdout and "build" in proc.stdout
    proc = subprocess.run([sys.executable, "-c", prelude + "sys.exit(main(['simulate']))"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert "harness._engine is not importable" in proc.stderr
    assert "pip install" in proc.stderr


def test_every_error_of_the_harness_derives_from_one_base():
    """A script catches every error the harness raises on purpose with one ``except``."""
    import importlib
    import inspect
    import pkgutil

    import harness
    from harness.errors import HarnessError

    defined = []
    for info in pkgutil.walk_packages(harness.__path__, "harness."):
        if info.name == "harness._engine":
            continue
        module = importlib.import_module(info.name)
        defined += [obj for _, obj in inspect.getmembers(module, inspect.isclass)
                    if issubclass(obj, Exception) and obj.__module__ == info.name]
    assert len(defined) >= 8  # the walk found the modules
    strays = sorted(f"{c.__module__}.{c.__qualname__}" for c in defined
                    if not issubclass(c, HarnessError))
    assert not strays, f"errors outside HarnessError: {strays}"
