"""``gtmodel examples DIR`` (issue 67, item 6): the shipped problems, models, studies and loop files copied out.

Compared byte for byte with the checkout's trees: CI installs the wheel (``pip install .``),
so there the copy comes from the wheel's ``gtmodel/_examples/`` (``setup.py``) and a file the
wheel lacks fails here; an editable install copies from its checkout.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
import zipfile

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main
from gtmodel.cli_examples import EXAMPLES

from .conftest import REPO

SKIP = {"__pycache__", ".ipynb_checkpoints", "results"}


def _files(root) -> list[str]:
    return sorted(p.relative_to(root).as_posix() for tree in EXAMPLES if (root / tree).is_dir() for p in (root / tree).rglob("*")
                  if p.is_file() and p.suffix != ".pyc" and not SKIP & set(p.relative_to(root).parts))


def test_examples_copies_every_shipped_file_and_says_how_to_run_one(tmp_path, capsys):
    out = tmp_path / "examples"
    assert main(["examples", str(out)]) == EXIT_OK
    text = capsys.readouterr().out
    expected = _files(REPO)
    assert _files(out) == expected and len(expected) > 60
    assert [f for f in expected if (out / f).read_bytes() != (REPO / f).read_bytes()] == []
    assert f"copied {len(expected)} files into {out}/" in text
    assert f"run one:     cd {out} && gtmodel solve problems/l1_time_optimal.toml" in text
    assert [p.name for p in tmp_path.iterdir()] == ["examples"]  # the staging folder is gone


def test_a_copied_problem_finds_its_model_beside_it(tmp_path):
    """The problem files name their models relative to themselves (``../models/dc_motor.py``): the copy keeps them working."""
    from gtmodel.problems.run import load_problem

    assert main(["examples", str(tmp_path / "ex")]) == EXIT_OK
    problem = load_problem(tmp_path / "ex" / "problems" / "dc_motor_move.toml")
    assert problem.name == "dc_motor_move"


def test_an_empty_folder_is_taken(tmp_path, capsys):
    (tmp_path / "ex").mkdir()
    assert main(["examples", str(tmp_path / "ex")]) == EXIT_OK
    assert (tmp_path / "ex" / "problems" / "l1_time_optimal.toml").is_file() and "copied" in capsys.readouterr().out


REFUSED = {
    "a folder with a file": ("mine.txt", "the folder is not empty; give a new or empty folder for the examples (nothing was copied)"),
    "a folder with a folder": ("problems/mine.toml", "the folder is not empty"),
    "a file": (None, "exists and is not a folder; give a new or empty folder"),
}


@pytest.mark.parametrize(("inside", "match"), list(REFUSED.values()), ids=list(REFUSED))
def test_a_folder_in_use_is_refused_naming_it_and_left_as_it_was(tmp_path, capsys, inside, match):
    target = tmp_path / "ex"
    if inside is None:
        target.write_text("a user's file\n")
    else:
        (target / inside).parent.mkdir(parents=True, exist_ok=True)
        (target / inside).write_text("a user's file\n")
    before = {p.relative_to(tmp_path).as_posix(): p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    code = main(["examples", str(target)])
    err = capsys.readouterr().err
    after = {p.relative_to(tmp_path).as_posix(): p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert (code, f"gtmodel: error: {target}: {match}" in err, after == before) == (EXIT_BAD_INPUT, True, True), err


def test_the_build_hook_and_the_sdist_ship_the_trees_the_command_copies():
    """setup.py copies EXAMPLES into the wheel, MANIFEST.in grafts them into the sdist: the same names as cli_examples'."""
    tree = ast.parse((REPO / "setup.py").read_text(encoding="utf-8"))
    shipped = next(ast.literal_eval(node.value) for node in tree.body if isinstance(node, ast.Assign)
                   and any(getattr(t, "id", None) == "EXAMPLES" for t in node.targets))
    grafted = re.findall(r"^graft (\S+)$", (REPO / "MANIFEST.in").read_text(encoding="utf-8"), flags=re.M)
    assert tuple(shipped) == EXAMPLES and sorted(grafted) == sorted(EXAMPLES)


@pytest.mark.slow  # builds the wheel (pip, about 10 s; its build requirements from the index)
def test_the_wheel_carries_the_examples(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", str(REPO), "--no-deps", "-q", "-w", str(tmp_path)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    with zipfile.ZipFile(next(tmp_path.glob("gtmodel-*.whl"))) as wheel:
        names = {n.removeprefix("gtmodel/_examples/") for n in wheel.namelist() if n.startswith("gtmodel/_examples/")}
    assert sorted(names) == _files(REPO)
