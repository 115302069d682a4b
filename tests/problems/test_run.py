"""Problem files: the shipped ones load; broken ones give one message naming the field."""

from __future__ import annotations

import tomllib

import pytest

from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem

from ..bad_problems import BAD_PROBLEMS, BASE
from ..conftest import PROBLEMS_DIR

SHIPPED = sorted(PROBLEMS_DIR.glob("*.toml"))


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_shipped_problems_load(path):
    problem = load_problem(path)
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
    assert first.startswith(f"{f}: ")
    assert "field '" in first or "invalid TOML" in first


def test_missing_file(tmp_path):
    with pytest.raises(ProblemError, match="cannot read problem file"):
        load_problem(tmp_path / "nope.toml")


@pytest.mark.parametrize(
    "content, match",
    [
        (b"\xff\xfe name = 1", "not UTF-8 text"),
        (b"", "missing field 'kind'"),
        (b'kind = 3', "field 'kind': expected one of point_to_point"),
        (b"kind = [1]", "field 'kind': expected one of point_to_point"),
    ],
    ids=["not_utf8", "empty", "kind_not_a_string", "kind_a_list"],
)
def test_unreadable_problem_files(tmp_path, content, match):
    f = tmp_path / "x.toml"
    f.write_bytes(content)
    with pytest.raises(ProblemError, match=match):
        load_problem(f)
