"""The reference page and JSON Schemas come from the schemas, and the shipped files obey them.

The JSON Schemas are checked with the independent ``jsonschema`` validator on every
shipped problem file; the committed ``docs/`` copies must equal what the code generates.
"""

from __future__ import annotations

import json
import tomllib

import pytest

jsonschema = pytest.importorskip("jsonschema")

from gtmodel.cli import EXIT_BAD_INPUT, main  # noqa: E402
from gtmodel.problems import KINDS  # noqa: E402
from gtmodel.problems.registry import LOOP_KINDS  # noqa: E402
from gtmodel.problems.docs import json_schema, reference_markdown  # noqa: E402

from ..conftest import PROBLEMS_DIR, REPO  # noqa: E402

SHIPPED = sorted(PROBLEMS_DIR.glob("*.toml"))
DOCS = REPO / "docs"


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_shipped_file_validates_against_its_json_schema(path):
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    jsonschema.validate(data, json_schema(data["kind"]))


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_shipped_file_names_its_schema_for_editors(path):
    first = path.read_text(encoding="utf-8").splitlines()[0]
    kind = tomllib.loads(path.read_text(encoding="utf-8"))["kind"]
    assert first == f"#:schema ../docs/schemas/{kind}.schema.json"
    assert (path.parent / first.split()[1]).is_file()


@pytest.mark.parametrize("kind", list(KINDS))
def test_json_schema_is_a_valid_draft_2020_12_schema(kind):
    jsonschema.Draft202012Validator.check_schema(json_schema(kind))


@pytest.mark.parametrize("kind", list(KINDS))
def test_committed_json_schema_is_current(kind):
    committed = json.loads((DOCS / "schemas" / f"{kind}.schema.json").read_text(encoding="utf-8"))
    assert committed == json_schema(kind), "stale: run `gtmodel schema --docs docs`"


def test_reference_page_is_current():
    committed = (DOCS / "problem_files.md").read_text(encoding="utf-8")
    assert committed == reference_markdown(), "stale: run `gtmodel schema --docs docs`"


def test_reference_page_documents_every_kind():
    text = reference_markdown()
    assert all(f"## {kind}" in text for kind in KINDS)


def test_schema_list_prints_every_kind(capsys):
    assert main(["schema", "--list"]) == 0
    printed = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert printed == [*KINDS, *LOOP_KINDS]  # the problem kinds, then the loop-controller files (issue 45)


def test_schema_out_writes_the_schema(tmp_path, capsys):
    out = tmp_path / "p.json"
    assert main(["schema", "point_to_point", "--out", str(out)]) == 0
    assert json.loads(out.read_text()) == json_schema("point_to_point")


@pytest.mark.parametrize("args, match", [(["schema", "teleport"], "unknown kind 'teleport': expected one of point_to_point"), (["schema"], "give a kind")])
def test_schema_bad_arguments(args, match, capsys):
    assert main(args) == EXIT_BAD_INPUT
    assert match in capsys.readouterr().err
