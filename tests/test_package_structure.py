"""The package layout keeps its promises (DESIGN.md "Layout", issue 16).

Static checks over the source tree with :mod:`ast` (nothing is imported to find imports) and
two import probes in fresh interpreters:

- no module imports another first-party module's underscore name, nor a first-party module
  whose dotted path has an underscore part, wherever the import sits (module level, inside a
  function, under ``TYPE_CHECKING``);
- every module of ``rigtools`` and ``models`` states ``__all__``;
- the stages import downwards only: ``models`` never imports ``rigtools``, ``analysis`` never
  imports ``campaign``, nothing outside ``rigtools.cli`` imports the CLI, ``plots`` holds no
  physics that another stage imports;
- the first-party import graph (counting imports inside functions) has no cycles between
  modules, so a loop cannot be hidden by deferring an import;
- reading the observations table does not load scipy.signal, and the thermal physics does not
  load matplotlib.
"""

from __future__ import annotations

import ast
import functools
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FIRST_PARTY = ("rigtools", "models")
#: Private package names that are data, not code (the schemas shipped inside the wheel).
ALLOWED_PRIVATE_PARTS = {"_data_schemas"}


def _python_files(*tops: str) -> Iterator[Path]:
    for top in tops:
        yield from _files_under(top)


@functools.cache
def _files_under(top: str) -> tuple[Path, ...]:
    return tuple(sorted((ROOT / top).rglob("*.py")))


def module_name(path: Path) -> str:
    """Dotted module name of a file under the project root (``tests`` files keep their path)."""
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def resolve(path: Path, node: ast.ImportFrom) -> str:
    """Absolute module of a ``from ... import`` in ``path`` (relative imports resolved)."""
    if node.level == 0:
        return node.module or ""
    here = module_name(path).split(".")
    if path.name != "__init__.py":
        here = here[:-1]
    base = here[: len(here) - (node.level - 1)] if node.level > 1 else here
    return ".".join([*base, node.module] if node.module else base)


def _local_test_modules() -> set[str]:
    """Helper modules of the test tree imported by bare name (``import mcap_layout``)."""
    return {p.stem for p in _python_files("tests")}


def is_first_party(module: str, local: set[str]) -> bool:
    head = module.split(".")[0]
    return head in FIRST_PARTY or head == "tests" or head in local


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_imports() -> list[str]:
    local = _local_test_modules()
    found = []
    for path in _python_files("rigtools", "models", "tests"):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                mod = resolve(path, node)
                if not is_first_party(mod, local):
                    continue
                where = f"{path.relative_to(ROOT)}:{node.lineno}"
                parts = [p for p in mod.split(".") if p not in ALLOWED_PRIVATE_PARTS]
                if any(_private(p) for p in parts):
                    found.append(f"{where}: from private module {mod}")
                found.extend(
                    f"{where}: from {mod} import {a.name}" for a in node.names if _private(a.name)
                )
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if not is_first_party(a.name, local):
                        continue
                    parts = [p for p in a.name.split(".") if p not in ALLOWED_PRIVATE_PARTS]
                    if any(_private(p) for p in parts):
                        found.append(f"{path.relative_to(ROOT)}:{node.lineno}: import {a.name}")
    return found


def test_no_module_imports_another_modules_private_names() -> None:
    found = private_imports()
    assert not found, f"{len(found)} private import(s):\n" + "\n".join(found)


def test_every_module_states_all() -> None:
    missing = []
    for path in _python_files(*FIRST_PARTY):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = set()
        for node in tree.body:
            targets = []
            if isinstance(node, ast.Assign):
                targets = node.targets
            elif isinstance(node, ast.AnnAssign | ast.AugAssign):
                targets = [node.target]
            names.update(t.id for t in targets if isinstance(t, ast.Name))
        if "__all__" not in names:
            missing.append(str(path.relative_to(ROOT)))
    assert not missing, "modules without __all__:\n" + "\n".join(missing)


@functools.cache
def import_graph() -> dict[str, set[str]]:
    """First-party module -> first-party modules it imports (anywhere in the file).

    ``from pkg import name`` counts as an import of ``pkg.name`` when that is a module and of
    ``pkg`` otherwise; package ``__init__`` modules are left out of the graph (they re-export
    their children, and an edge through them is not a loop between ideas).
    """
    files = {module_name(p): p for p in _python_files(*FIRST_PARTY)}
    packages = {m for m, p in files.items() if p.name == "__init__.py"}
    graph: dict[str, set[str]] = {}
    for mod, path in files.items():
        if mod in packages:
            continue
        edges: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[str] = []
            if isinstance(node, ast.ImportFrom):
                base = resolve(path, node)
                for a in node.names:
                    sub = f"{base}.{a.name}"
                    targets.append(sub if sub in files else base)
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            edges.update(t for t in targets if t in files and t not in packages and t != mod)
        graph[mod] = edges
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(max(10_000, sys.getrecursionlimit()))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles_between_modules() -> None:
    found = cycles(import_graph())
    assert not found, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in found)


def test_cycle_finder_finds_a_cycle() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


@pytest.mark.parametrize(
    ("importer", "imported"),
    [
        ("models", "rigtools"),
        ("rigtools.analysis", "rigtools.campaign"),
        ("rigtools.analysis", "rigtools.cli"),
        ("rigtools.ingest", "rigtools.analysis"),
        ("rigtools.ingest", "rigtools.campaign"),
        ("rigtools.plots", "rigtools.campaign"),
        ("rigtools.plots", "rigtools.cli"),
        ("rigtools.campaign", "rigtools.cli"),
        ("rigtools.campaign", "rigtools.calibration"),
        ("rigtools.analysis", "rigtools.calibration"),
        ("rigtools.ingest", "rigtools.calibration"),
        ("rigtools.calibration", "rigtools.cli"),
        ("rigtools.calibration", "rigtools.pipeline"),
        ("rigtools.calibration", "rigtools.report"),
        ("rigtools.campaign", "rigtools.pipeline"),
        ("rigtools.report", "rigtools.pipeline"),
        ("rigtools.report", "rigtools.cli"),
        ("rigtools.pipeline", "rigtools.cli"),
        ("rigtools.demo", "rigtools.cli"),
    ],
)
def test_stages_import_downwards(importer: str, imported: str) -> None:
    bad = sorted(
        f"{m} imports {t}"
        for m, ts in import_graph().items()
        if m == importer or m.startswith(importer + ".")
        for t in ts
        if t == imported or t.startswith(imported + ".")
    )
    assert not bad, "\n".join(bad)


def test_nothing_outside_plots_imports_drawing_helpers_for_physics() -> None:
    """``plots`` only draws: nothing imports it but the CLI, demo, report and the pipeline.

    (The pipeline's calibrate stage writes the calibration's figures beside its summary.)
    """
    allowed = ("rigtools.plots", "rigtools.cli", "rigtools.demo", "rigtools.report",
               "rigtools.pipeline")
    bad = sorted(
        f"{m} imports {t}"
        for m, ts in import_graph().items()
        if not m.startswith(allowed)
        for t in ts
        if t.startswith("rigtools.plots")
    )
    assert not bad, "\n".join(bad)


def _loaded_after(statement: str) -> set[str]:
    code = f"import sys\n{statement}\nprint('\\n'.join(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    return set(out.stdout.split())


def test_reading_observations_does_not_load_signal_processing() -> None:
    loaded = _loaded_after("import rigtools.campaign.observation_files")
    assert "scipy.signal" not in loaded


def test_thermal_physics_does_not_load_matplotlib() -> None:
    loaded = _loaded_after("import models.thermal")
    assert not any(m == "matplotlib" or m.startswith("matplotlib.") for m in loaded)
