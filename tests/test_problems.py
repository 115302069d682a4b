"""Problem files: the shipped ones load; broken ones give one message naming the field."""

from __future__ import annotations

import pytest

from gtmodel.errors import GtModelError, ProblemError
from gtmodel.problems import load_problem

from .bad_problems import BAD_PROBLEMS, BASE
from .conftest import PROBLEMS_DIR

SHIPPED = sorted(PROBLEMS_DIR.glob("*.toml"))


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_shipped_problems_load(path):
    problem = load_problem(path)
    import tomllib

    assert problem.name == path.stem
    assert problem.kind == tomllib.loads(path.read_text())["kind"]


@pytest.mark.parametrize("case, edit, match", BAD_PROBLEMS, ids=[c[0] for c in BAD_PROBLEMS])
def test_bad_problem_files(tmp_path, case, edit, match):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(BASE.read_text()))
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(f)
    # the first line is the whole message (expression errors add the text and a caret below it)
    first = str(info.value).splitlines()[0]
    assert str(f) in first
    assert isinstance(info.value, (GtModelError, ValueError))


def test_missing_file(tmp_path):
    with pytest.raises(ProblemError, match="cannot read problem file"):
        load_problem(tmp_path / "nope.toml")
