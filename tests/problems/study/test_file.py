"""Study files: validation (one ProblemError naming the study file and the field) and the
expansion of a design into cases.

Independent reference: the expected cases are written out by hand (itertools semantics:
the last axis varies fastest; numpy.linspace for ranges).
"""

from __future__ import annotations

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, main
from gtmodel.errors import ProblemError
from gtmodel.problems.study.engine import plan_cases, run_study
from gtmodel.problems.study.design import (MAX_CASES, AxisSchema, CaseSchema, DesignSchema, RangeSpec, StudySchema, load_study,
                                         value_text)

from ...conftest import REPO
from .study_fixtures import write_base

AXIS = '[design]\n[[design.axes]]\nfield = "w"\n'

#: (id, study file text after `base`, match). `base = "base.toml"` is prepended unless the text sets base.
BAD_STUDIES = [
    ("toml_syntax", "[design\n", r"invalid TOML"),
    ("missing_base", "NOBASE\n" + AXIS + "values = [1.0]\n", r"missing field 'base'"),
    ("base_not_found", 'base = "nothere.toml"\n' + AXIS + "values = [1.0]\n", r"field 'base': expected an existing problem file"),
    ("unknown_top_field", 'bse = 1\n' + AXIS + "values = [1.0]\n", r"unknown field 'bse'"),
    ("unknown_analysis", 'analysis = "nope"\n' + AXIS + "values = [1.0]\n", r"field 'analysis': expected one of (\w+, )*generic"),
    ("warm_start_not_bool", 'warm_start = "yes"\n' + AXIS + "values = [1.0]\n", r"field 'warm_start': expected true or false"),
    ("missing_design", "", r"missing field 'design'"),
    ("empty_design", "[design]\n", r"field 'design': give exactly one of axes, cases"),
    ("axes_and_cases", AXIS + 'values = [1.0]\n[[design.cases]]\noverrides = { w = 1.0 }\n', r"give exactly one of axes, cases"),
    ("bad_combine", '[design]\ncombine = "cross"\n[[design.axes]]\nfield = "w"\nvalues = [1.0]\n', r"field 'design.combine'"),
    ("axis_two_forms", AXIS + "values = [1.0]\nseeds = 3\n", r"field 'design.axes\[0\]': give exactly one of values, range, seeds, points \(got values, seeds\)"),
    ("axis_no_form", AXIS, r"field 'design.axes\[0\]': give exactly one of .* \(got none\)"),
    ("axis_no_field", '[design]\n[[design.axes]]\nvalues = [1.0]\n', r"missing field 'design.axes\[0\].field'"),
    ("axis_unknown_key", AXIS + "vals = [1.0]\n", r"unknown field 'design.axes\[0\].vals'"),
    ("empty_values", AXIS + "values = []\n", r"field 'design.axes\[0\].values': expected at least one value"),
    ("range_num_zero", AXIS + "range = { start = 0.0, stop = 1.0, num = 0 }\n", r"field 'design.axes\[0\].range.num': expected an integer in 1"),
    ("range_no_stop", AXIS + "range = { start = 0.0, num = 3 }\n", r"missing field 'design.axes\[0\].range.stop'"),
    ("range_nan", AXIS + "range = { start = nan, stop = 1.0, num = 3 }\n", r"field 'design.axes\[0\].range.start': expected a finite number"),
    ("seeds_zero", AXIS + "seeds = 0\n", r"field 'design.axes\[0\].seeds': expected an integer in 1"),
    ("seeds_float", AXIS + "seeds = 2.5\n", r"field 'design.axes\[0\].seeds'"),
    ("first_without_seeds", AXIS + "values = [1.0]\nfirst = 3\n", r"field 'design.axes\[0\].first': only with seeds"),
    ("points_no_z", AXIS + "points = { x = 0.0, y = 1.0 }\n", r"field 'design.axes\[0\].points': expected the coordinates x, y, z"),
    ("points_bad_coordinate", AXIS + 'points = { x = "a", y = 1.0, z = 0.0 }\n', r"field 'design.axes\[0\].points.x': expected a number or a range table"),
    ("zip_unequal", '[design]\ncombine = "zip"\n[[design.axes]]\nfield = "w"\nvalues = [1.0, 2.0]\n'
                    '[[design.axes]]\nfield = "r"\nvalues = [1.0]\n', r"zip needs axes of equal length, got \[2, 1\]"),
    ("two_axes_same_field", AXIS + 'values = [1.0]\n[[design.axes]]\nfield = "w"\nseeds = 2\n', r"the field 'w' has two axes"),
    ("too_many_cases", AXIS + f'seeds = {MAX_CASES}\n[[design.axes]]\nfield = "r"\nvalues = [1.0, 2.0]\n', r"at most 1000000"),
    ("case_unknown_key", '[design]\n[[design.cases]]\noveride = { w = 1.0 }\n', r"unknown field 'design.cases\[0\].overide'"),
]


@pytest.mark.parametrize("case, text, match", BAD_STUDIES, ids=[c[0] for c in BAD_STUDIES])
def test_bad_study_files(tmp_path, case, text, match):
    write_base(tmp_path)
    f = tmp_path / f"{case}.toml"
    f.write_text(text.replace("NOBASE\n", "") if "NOBASE" in text or text.startswith("base =") else f'base = "base.toml"\n{text}')
    with pytest.raises(ProblemError, match=match) as info:
        load_study(f)
    assert str(info.value).startswith(f"{f}: ")  # names the study file first


def _cases(tmp_path, design: str):
    write_base(tmp_path)
    f = tmp_path / "s.toml"
    f.write_text(f'base = "base.toml"\n{design}')
    return load_study(f).cases


def test_product_last_axis_fastest_with_labels_and_columns(tmp_path):
    cases = _cases(tmp_path, '[design]\n[[design.axes]]\nfield = "limits.force"\nvalues = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]\n'
                             '[[design.axes]]\nfield = "method.grid"\nrange = { start = 10, stop = 20, num = 3, integer = true }\n')
    assert [c.overrides for c in cases] == [
        {"limits.force": f, "method.grid": g} for f in ([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]) for g in (10, 15, 20)]
    assert cases[1].label == "limits.force=[1.0,2.0,3.0],method.grid=15"
    assert cases[1].design == {"limits.force": "[1.0,2.0,3.0]", "method.grid": 15}  # vectors as TOML text
    assert [c.chain for c in cases[:4]] == ["limits.force=[1.0,2.0,3.0]"] * 3 + ["limits.force=[4.0,5.0,6.0]"]


def test_zip_pairs_the_axes(tmp_path):
    cases = _cases(tmp_path, '[design]\ncombine = "zip"\n[[design.axes]]\nfield = "w"\nvalues = [0.0, 0.5]\n'
                             '[[design.axes]]\nfield = "r"\nseeds = 2\nfirst = 7\n')
    assert [c.overrides for c in cases] == [{"w": 0.0, "r": 7}, {"w": 0.5, "r": 8}]
    assert {c.chain for c in cases} == {""}  # zip: one chain


def test_points_grid_gives_three_columns(tmp_path):
    cases = _cases(tmp_path, '[design]\n[[design.axes]]\nfield = "motion.end"\n'
                             'points = { x = { start = -0.1, stop = 0.1, num = 3 }, y = { start = 2.8, stop = 3.0, num = 2 }, z = -0.6 }\n')
    assert len(cases) == 6
    assert cases[1].overrides == {"motion.end": [-0.1, 3.0, -0.6]}  # numpy.linspace(2.8, 3.0, 2)[1]
    assert cases[1].design == {"motion.end.x": -0.1, "motion.end.y": 3.0, "motion.end.z": -0.6}
    assert cases[1].label == "motion.end=[-0.1,3,-0.6]"


def test_seeds_and_ranges(tmp_path):
    cases = _cases(tmp_path, '[design]\n[[design.axes]]\nfield = "w"\nrange = { start = 0.0, stop = 0.01, num = 3 }\n'
                             '[[design.axes]]\nfield = "r"\nseeds = 2\n')
    assert [c.overrides["w"] for c in cases] == [0.0, 0.0, 0.005, 0.005, 0.01, 0.01]
    assert [c.overrides["r"] for c in cases] == [0, 1] * 3
    assert all(type(c.overrides["r"]) is int and type(c.overrides["w"]) is float for c in cases)


def test_explicit_cases(tmp_path):
    cases = _cases(tmp_path, '[design]\n[[design.cases]]\nlabel = "fast"\noverrides = { "limits.force" = [500.0, 500.0, 500.0], w = 0.001 }\n'
                             '[[design.cases]]\noverrides = { w = 0.01 }\n')
    assert [c.label for c in cases] == ["fast", "case1"]
    assert cases[0].design == {"limits.force": "[500.0,500.0,500.0]", "w": 0.001}


@pytest.mark.parametrize("value, text", [(0.001, "0.001"), (3, "3"), (True, "true"), ("L1", '"L1"'), ([1.0, [2, 3]], "[1.0,[2,3]]")])
def test_value_text(value, text):
    assert value_text(value) == text


def test_unknown_field_of_the_base_fails_before_anything_runs(tmp_path):
    f = tmp_path / "s.toml"
    base = write_base(tmp_path)
    f.write_text('base = "base.toml"\n[design]\n[[design.axes]]\nfield = "limits.forse"\nvalues = [1.0]\n')
    with pytest.raises(ProblemError, match=r"cannot sweep 'limits.forse'") as info:
        run_study(f, tmp_path / "out", workers=1)
    # the study file first (its design is at fault), then the base file and its missing field
    assert str(info.value).startswith(f"{f}: field 'design' (case 'limits.forse=1.0'): {base}:")
    assert not (tmp_path / "out").exists()


def test_unknown_field_exits_2_from_the_command(tmp_path, capsys):
    write_base(tmp_path)
    f = tmp_path / "s.toml"
    f.write_text('base = "base.toml"\n[design]\n[[design.axes]]\nfield = "nothing"\nvalues = [1.0]\n')
    assert main(["study", str(f), "--out", str(tmp_path / "out"), "--workers", "1", "-q"]) == EXIT_BAD_INPUT
    assert "cannot sweep 'nothing'" in capsys.readouterr().err


def test_two_cases_of_the_same_problem_are_refused(tmp_path):
    write_base(tmp_path)
    f = tmp_path / "s.toml"
    f.write_text('base = "base.toml"\n[design]\n[[design.cases]]\nlabel = "a"\noverrides = { "method.grid" = 40 }\n'
                 '[[design.cases]]\nlabel = "b"\noverrides = { "method.grid" = 40 }\n')
    with pytest.raises(ProblemError, match=r"the cases 'a' and 'b' are the same problem"):
        plan_cases(load_study(f), tmp_path / "out")


@pytest.mark.parametrize("schema", [StudySchema, DesignSchema, AxisSchema, RangeSpec, CaseSchema], ids=lambda s: s.__name__)
def test_every_field_is_documented(schema):
    page = (REPO / "docs" / "study_files.md").read_text()
    missing = [name for name in schema.model_fields if f"`{name}`" not in page and f"`design.{name}`" not in page
               and f"{name} =" not in page and f"{name}," not in page]
    assert not missing, f"docs/study_files.md does not name {missing}"
