"""The documentation stays true: every code block of README.md and docs/*.md runs, the site builds.

Each page's fenced blocks run in order, in one namespace, in a temporary working folder
in which ``problems/``, ``studies/`` and ``models/`` are those of the repository:

- ```` ```python ````: executed;
- ```` ```bash ```` / ```` ```console ````: every command (a ``$ `` line of a console block)
  must be a ``gtmodel ...`` command and is run by :func:`gtmodel.cli.main` in this process;
  it must exit 0 (``exit=N`` in the info string: N);
- a word ``file=NAME`` in the info string (```` ```toml file=p.toml ````): the block is a
  file that later blocks use, written to the folder, not executed;
- ``norun``: shown, not run (installs, clusters, ``make``, benchmarks); a bash block with a
  command other than ``gtmodel`` must say so;
- ``slow``: run only by the slow run (``python -m pytest -m slow``), which runs the whole
  page; the default run leaves these blocks out.

Blocks of other languages (``text``, ``toml`` without a file name, ``c``) are shown only.
The site test builds the HTML documentation with ``sphinx -W`` (every warning an error).
"""

from __future__ import annotations

import importlib
import importlib.util
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from .conftest import REPO

DOCS = REPO / "docs"
PAGES = [REPO / "README.md", *sorted(DOCS.glob("*.md"))]
#: Pages whose blocks all run only in the slow run, with the reason.
SLOW_PAGES = {"modeling.md": "the modelling tutorial solves several optimal control problems (about a minute)"}
#: Repository folders the blocks refer to by relative path.
LINKED = ("problems", "studies", "models", "codegen", "tests")  # tests: the users' model fixtures some pages run
FENCE = re.compile(r"^```([^\n`]*)\n(.*?)^```\s*$", re.S | re.M)
KNOWN_FLAGS = {"norun", "slow"}


@dataclass(frozen=True)
class Block:
    """One fenced code block: language, source, info-string words, 1-based line."""

    lang: str
    source: str
    file: str | None
    flags: frozenset[str]
    exit_code: int
    line: int


def blocks(text: str) -> list[Block]:
    """Every fenced block of a Markdown text, in order.

    Raises
    ------
    ValueError
        An unknown word in an info string (a typo must not silently skip a block).
    """
    out = []
    for m in FENCE.finditer(text):
        info = m.group(1).split()
        lang = info[0] if info else ""
        name, flags, code = None, set(), 0
        for word in info[1:] if not lang.startswith("{") else []:  # "{toctree}": a MyST directive
            if word.startswith("file="):
                name = word.split("=", 1)[1]
            elif word.startswith("exit="):
                code = int(word.split("=", 1)[1])
            elif word in KNOWN_FLAGS:
                flags.add(word)
            else:
                raise ValueError(f"line {text.count(chr(10), 0, m.start()) + 1}: unknown word {word!r} in the info string {m.group(1)!r}")
        out.append(Block(lang, m.group(2), name, frozenset(flags), code, text.count("\n", 0, m.start()) + 1))
    return out


def commands(block: Block) -> list[list[str]]:
    """The commands of a bash or console block, split like a shell (comments dropped)."""
    logical: list[str] = []  # one entry per command, continuation lines ("\\" at the end) joined
    continued = False
    for ln in block.source.splitlines():
        if continued:
            logical[-1] += " " + ln
        elif block.lang != "console" or ln.startswith("$ "):
            logical.append(ln[2:] if block.lang == "console" else ln)
        else:
            continue  # the output of a console command
        continued = logical[-1].endswith("\\")
        if continued:
            logical[-1] = logical[-1][:-1]
    return [words for ln in logical if (words := shlex.split(ln, comments=True))]


def _params():
    out = []
    for page in PAGES:
        found = blocks(page.read_text(encoding="utf-8"))
        rel = page.relative_to(REPO).as_posix()
        if page.name in SLOW_PAGES and page.parent == DOCS:
            out.append(pytest.param(page, True, id=f"{rel}[all]", marks=pytest.mark.slow))
            continue
        out.append(pytest.param(page, False, id=rel))
        if any("slow" in b.flags for b in found):
            out.append(pytest.param(page, True, id=f"{rel}[all]", marks=pytest.mark.slow))
    return out


def test_the_fence_parser_reads_info_strings():
    # reference: a hand-written page with one block of each kind
    text = "x\n```python\na = 1\n```\n```toml file=p.toml\nk = 1\n```\n```bash norun\npip install .\n```\n```bash slow exit=2\ngtmodel solve x\n```\n"
    found = blocks(text)
    assert [(b.lang, b.file, sorted(b.flags), b.exit_code, b.line) for b in found] == [
        ("python", None, [], 0, 2),
        ("toml", "p.toml", [], 0, 5),
        ("bash", None, ["norun"], 0, 8),
        ("bash", None, ["slow"], 2, 11),
    ]
    with pytest.raises(ValueError, match="unknown word 'nrun'"):
        blocks("```bash nrun\nx\n```\n")
    console = Block("console", "$ gtmodel schema --list \\\n  --x\npoint_to_point\n", None, frozenset(), 0, 1)
    assert commands(console) == [["gtmodel", "schema", "--list", "--x"]]


@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(REPO).as_posix() for p in PAGES])
def test_every_shell_block_runs_gtmodel_or_says_norun(page):
    others = [
        f"{page.name}, line {b.line}: {' '.join(words)!r}"
        for b in blocks(page.read_text(encoding="utf-8"))
        if b.lang in ("bash", "console", "sh", "shell") and "norun" not in b.flags
        for words in commands(b)
        if words[0] != "gtmodel"
    ]
    assert others == [], "not gtmodel commands: mark their blocks `norun`"


def _run(b: Block, page: Path, folder: Path, namespace: dict, main) -> None:
    """Run one block of ``page`` in ``folder`` (the working folder); a failing command stops the page."""
    if b.file is not None:
        (folder / b.file).write_text(b.source, encoding="utf-8")
        importlib.invalidate_caches()  # the import system's listing of "." may be another test's folder
    elif b.lang == "python":
        exec(compile(b.source, f"{page.name}[line {b.line}]", "exec"), namespace)  # noqa: S102 - our own docs
    elif b.lang in ("bash", "console", "sh", "shell"):
        for words in commands(b):
            code = main(words[1:])
            if code != b.exit_code:  # later blocks read what this one writes: stop here
                pytest.fail(f"{page.name}, block at line {b.line}: {' '.join(words)} exited {code}, expected {b.exit_code}")


@pytest.mark.parametrize(("page", "everything"), _params())
def test_the_code_blocks_of_the_page_run(page, everything, tmp_path, monkeypatch):
    from gtmodel.cli import main

    for name in LINKED:
        (tmp_path / name).symlink_to(REPO / name, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setattr("sys.path", list(sys.path))  # pages put "." on sys.path for their own files
    before = set(sys.modules)
    namespace: dict = {"__name__": f"doc_{page.stem}"}
    try:
        for b in blocks(page.read_text(encoding="utf-8")):
            if "norun" not in b.flags and ("slow" not in b.flags or everything):
                _run(b, page, tmp_path, namespace, main)
    finally:
        for name in set(sys.modules) - before:  # the pages' own modules (two_mass, cart_with_load)
            module_file = getattr(sys.modules[name], "__file__", None) or ""
            if module_file.startswith(str(tmp_path)):
                del sys.modules[name]


def test_every_page_is_on_the_site():
    # the site's index lists every page of docs/ (Sphinx -W would fail on an orphan, but only in the slow run)
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"^([\w/]+)$", index, flags=re.M))
    pages = {p.stem for p in DOCS.glob("*.md")} - {"index"}
    assert pages <= listed, f"not in a toctree of docs/index.md: {sorted(pages - listed)}"


DOCS_EXTRA = ("sphinx", "myst_parser", "numpydoc")


@pytest.mark.slow
def test_the_site_builds_without_warnings(tmp_path):
    # about 35 s of CPU (autodoc imports every package and renders every docstring)
    missing = [m for m in DOCS_EXTRA if importlib.util.find_spec(m) is None]
    if missing:
        pytest.skip(f"the docs extra is not installed (no {', '.join(missing)}): pip install '.[docs]'")
    run = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(tmp_path / "doctrees"), str(DOCS), str(tmp_path / "html")],
        capture_output=True, text=True, cwd=REPO, timeout=900,
    )
    assert run.returncode == 0, f"sphinx -W failed:\n{run.stderr[-5000:]}"
    api = (tmp_path / "html" / "api" / "modeling.html").read_text(encoding="utf-8")
    assert "gtmodel.modeling.Optimization" in api  # the reference holds the package-level names
    assert (tmp_path / "html" / "own_data.html").is_file()
