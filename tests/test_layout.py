"""The house rules, checked on the source: layers, module size, imports.

Checked with import-linter (the layers contract in pyproject.toml) and with the
standard library's ``ast`` on every module of gtmodel/.
"""

from __future__ import annotations

import ast
import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import REPO

PACKAGE = REPO / "gtmodel"
MODULES = sorted(p for p in PACKAGE.rglob("*.py"))
IDS = [str(p.relative_to(REPO)) for p in MODULES]
#: Heavy optional dependencies that may be imported inside functions.
LAZY_OK = ("matplotlib", "sklearn", "dask", "distributed")
#: Modules that may import gtmodel's own layers inside functions, and why. The ``gtmodel``
#: command must start in a fraction of a second (``gtmodel --help``, ``schema --list``, an
#: input error; issue 24, item 7): each sub-command imports the layers it needs (the whole
#: problem layer pulls in CasADi, SciPy, pandas and matplotlib: 4-6 s) when it runs.
#: (``gtmodel/cli_codegen.py`` holds the routes of ``gtmodel codegen``, ``gtmodel/cli_loop.py`` that of
#: ``gtmodel loop``, ``gtmodel/cli_fmu.py`` those of ``gtmodel export-fmu`` / ``import-fmu``, ``gtmodel/cli_examples.py``
#: that of ``gtmodel examples``, likewise; cli_fmu imports NumPy in its commands too, its parsers are built by ``--help``.)
#: ``gtmodel/__main__.py`` installs the signal handlers before it imports the command (issue 26).
LAZY_GTMODEL_OK = {"gtmodel/cli.py": ("gtmodel.",), "gtmodel/cli_codegen.py": ("gtmodel.",), "gtmodel/cli_loop.py": ("gtmodel.",),
                   "gtmodel/cli_fmu.py": ("gtmodel.", "numpy"), "gtmodel/cli_examples.py": ("gtmodel.",),
                   "gtmodel/__main__.py": ("gtmodel.cli",)}
MAX_LINES = 700


def _subpackage(module: str) -> str:
    parts = module.split(".")
    return ".".join(parts[:2])


def _module_name(path) -> str:
    rel = path.relative_to(REPO).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def test_layers_contract_is_kept():
    exe = shutil.which("lint-imports") or str(Path(sys.executable).parent / "lint-imports")
    proc = subprocess.run([exe], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "0 broken" in proc.stdout


@pytest.mark.parametrize("path", MODULES, ids=IDS)
def test_module_is_not_longer_than_700_lines(path):
    assert len(path.read_text(encoding="utf-8").splitlines()) <= MAX_LINES


@pytest.mark.parametrize("path", MODULES, ids=IDS)
def test_imports_at_module_level_only_except_heavy_optional_ones(path):
    rel = path.relative_to(REPO).as_posix()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    lazy = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for inner in ast.walk(node):
                if isinstance(inner, ast.Import):
                    names = [a.name for a in inner.names]
                elif isinstance(inner, ast.ImportFrom):
                    names = [inner.module or ""]
                else:
                    continue
                lazy += [n for n in names if not n.startswith(LAZY_OK + LAZY_GTMODEL_OK.get(rel, ()))]
    assert not lazy, f"function-level imports of {lazy}"


@pytest.mark.parametrize("path", MODULES, ids=IDS)
def test_no_private_name_imported_from_another_subpackage(path):
    here = _subpackage(_module_name(path))
    tree = ast.parse(path.read_text(encoding="utf-8"))
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("gtmodel."):
            if _subpackage(node.module) == here or node.module.split(".")[1].startswith("_"):
                continue  # own subpackage, or a base module of the whole package
            bad += [f"{node.module}.{a.name}" for a in node.names if a.name.startswith("_")]
            bad += [node.module] if any(p.startswith("_") for p in node.module.split(".")[2:]) else []
    assert not bad, f"private names of other subpackages: {bad}"


def _assertions_inside_loops() -> list[str]:
    """``path:function:line`` of every ``for``/``while`` loop holding an ``assert`` in a test function."""
    found = []
    for p in sorted((REPO / "tests").rglob("*.py")):
        tree = ast.parse(p.read_text(encoding="utf-8"))
        tests = (n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name.startswith("test"))
        found += [
            f"{p.relative_to(REPO)}:{fn.name}:{n.lineno}"
            for fn in tests
            for n in ast.walk(fn)
            if isinstance(n, (ast.For, ast.While)) and any(isinstance(x, ast.Assert) for x in ast.walk(n))
        ]
    return found


def test_no_assertion_inside_a_loop():
    """A loop of asserts stops at the first failure and hides the rest: such cases are
    parametrized, or checked by one assertion that lists every failing element."""
    offenders = _assertions_inside_loops()
    assert not offenders, "assertions inside loops (parametrize, or assert once over a list):\n" + "\n".join(offenders)


TEST_FILES = sorted((REPO / "tests").rglob("*.py"))
#: Calls that give one-shot iterators, which pytest 10 no longer accepts as argvalues.
ITERATOR_CALLS = {"enumerate", "zip", "map", "filter", "iter", "reversed"}


def _one_shot_argvalues(tree) -> list[int]:
    lines = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "parametrize"):
            continue
        values = node.args[1] if len(node.args) > 1 else None
        values = next((k.value for k in node.keywords if k.arg == "argvalues"), values)
        if isinstance(values, ast.GeneratorExp) or (
            isinstance(values, ast.Call)
            and isinstance(values.func, ast.Name)
            and values.func.id in ITERATOR_CALLS
        ):
            lines.append(node.lineno)
    return lines


@pytest.mark.parametrize("path", TEST_FILES, ids=[str(p.relative_to(REPO)) for p in TEST_FILES])
def test_parametrize_gets_a_collection_not_a_one_shot_iterator(path):
    """pytest 10 removes iterators (enumerate, zip, generators) as parametrize values."""
    assert _one_shot_argvalues(ast.parse(path.read_text(encoding="utf-8"))) == []


def test_one_shot_argvalues_are_found():
    """The check above can fail: it finds enumerate(...) and a generator expression."""
    source = (
        "@pytest.mark.parametrize('i, n', enumerate((1, 2)))\ndef t(i, n): pass\n"
        "@pytest.mark.parametrize('x', (x for x in 'ab'))\ndef u(x): pass\n"
        "@pytest.mark.parametrize('x', [1, 2])\ndef v(x): pass\n"
    )
    assert _one_shot_argvalues(ast.parse(source)) == [1, 3]


def _make_layout():
    spec = importlib.util.spec_from_file_location("make_layout", REPO / "docs" / "make_layout.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_layout_page_lists_every_module_with_its_docstring():
    """docs/layout.md's module table is what docs/make_layout.py builds from the code now."""
    make_layout = _make_layout()
    text = make_layout.LAYOUT.read_text(encoding="utf-8")
    assert make_layout.updated(text) == text, "docs/layout.md is out of date: run python docs/make_layout.py"


def test_layout_table_names_a_new_module(tmp_path):
    """The check above can fail: a table without one module differs from the built one."""
    make_layout = _make_layout()
    table = make_layout.module_table()
    assert "`gtmodel/defaults.py`" in table
    stale = table.replace(next(ln for ln in table.splitlines() if "`gtmodel/defaults.py`" in ln) + "\n", "")
    assert make_layout.updated(stale) != stale


def _cycles(graph) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan), i.e. import cycles."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.find_modules_directly_imported_by(v):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for module in sorted(graph.modules):
        if module not in index:
            visit(module)
    return found


def test_no_import_cycle_between_modules():
    """Every import of gtmodel/ (TYPE_CHECKING ones too), as import-linter's grimp builds the graph."""
    grimp = pytest.importorskip("grimp")
    assert _cycles(grimp.build_graph("gtmodel")) == []


def test_a_cycle_is_found():
    """The check above can fail: a two-module cycle is one component."""

    class Graph:
        modules = {"a", "b", "c"}
        edges = {"a": {"b"}, "b": {"a"}, "c": {"a"}}

        def find_modules_directly_imported_by(self, m):
            return self.edges[m]

    assert _cycles(Graph()) == [["a", "b"]]
