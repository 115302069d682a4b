"""Kind ``optimica`` (issue 68, item 1): a problem file naming a ``.mop`` file and its class.

The shipped file solves optimal and verified and gives the objective of ``gtmodel solve
FILE.mop --class NAME`` (the one declaration path of both routes); a sweep reaches it as any
problem file; bad references exit 2 naming the field.
"""

from __future__ import annotations

import json
import os
import tomllib

import pytest

from gtmodel.cli import main
from gtmodel.errors import ProblemError
from gtmodel.exchange.optimica_syntax import CLASS_NAME_RE
from gtmodel.problems.kinds.schemas.optimica import CLASS_PATTERN
from gtmodel.problems.run import load_problem

from ..conftest import PROBLEMS_DIR

SHIPPED = PROBLEMS_DIR / "optimica" / "double_integrator_min_time.toml"
MOP = PROBLEMS_DIR / "optimica" / "double_integrator_min_time.mop"


def _summary(folder):
    return json.loads((folder / "summary.json").read_text(encoding="utf-8"))


def test_shipped_file_solves_verified_and_agrees_with_the_mop_route(tmp_path, capsys):
    assert main(["solve", str(SHIPPED), "--out", str(tmp_path / "kind"), "--no-plots", "--no-report", "-q"]) == 0
    assert main(["solve", str(MOP), "--class", "DoubleIntegrator.MinTime", "--out", str(tmp_path / "mop"), "--no-plots",
                 "--no-report", "-q"]) == 0
    kind, mop = _summary(tmp_path / "kind"), _summary(tmp_path / "mop")
    assert kind["kind"] == mop["kind"] == "optimica"
    assert kind["status"] == "optimal" and kind["verification"]["passed"] is True
    assert kind["objective"] == pytest.approx(mop["objective"], rel=1e-8)
    assert kind["objective"] == pytest.approx(2.0, rel=1e-5)  # T = 2 sqrt(D / a_max)
    assert kind["model"]["class"] == "DoubleIntegrator.MinTime" and kind["model"]["file"].endswith("double_integrator_min_time.mop")
    assert (tmp_path / "kind" / "trajectories.csv").is_file()


def test_the_kinds_tables_reach_the_solve(tmp_path):
    problem = load_problem(SHIPPED, {"collocation.elements": 12}, settings={"solver.max_iter": 77})
    d = problem.declaration
    assert (d.method.elements, d.solver.max_iter, problem.kind) == (12, 77, "optimica")


def test_a_sweep_of_an_optimica_file(tmp_path):
    out = tmp_path / "sweep"
    assert main(["solve", str(SHIPPED), "--sweep", "collocation.elements=20,30", "--out", str(out), "--no-plots", "-q"]) == 0
    cases = [json.loads(p.read_text()) for p in sorted(out.glob("*/summary.json"))]
    assert len(cases) == 2 and all(c["status"] == "optimal" for c in cases)
    assert all(c["objective"] == pytest.approx(2.0, rel=1e-4) for c in cases)


@pytest.mark.parametrize("fixed", [True, False])
def test_state_start_values_fixed_is_the_compiler_option(tmp_path, fixed):
    (tmp_path / "bd.mop").write_text((PROBLEMS_DIR / "optimica" / "bryson_denham.mop").read_text())
    (tmp_path / "p.toml").write_text('kind = "optimica"\n[optimica]\nfile = "bd.mop"\nclass = "BrysonDenham"\n[collocation]\nelements = 60\n'
                                     f"[compiler_options]\nstate_start_values_fixed = {str(fixed).lower()}\n")
    out = tmp_path / "r"
    assert main(["solve", str(tmp_path / "p.toml"), "--out", str(out), "--no-plots", "--no-report", "-q"]) == 0
    objective = _summary(out)["objective"]
    # fixed: Bryson-Denham 4 / (9 l) = 4 (l = 1/9); not fixed: the starts are guesses, a free start needs less energy
    assert objective == pytest.approx(4.0, rel=1e-3) if fixed else objective < 3.9


def test_class_pattern_is_the_readers():
    assert CLASS_PATTERN == CLASS_NAME_RE.pattern


def _write(tmp_path, file='"m.mop"', cls='"DoubleIntegrator.MinTime"', extra=""):
    (tmp_path / "m.mop").write_text(MOP.read_text())
    (tmp_path / "notes.txt").write_text("not Modelica\n")
    (tmp_path / "sub").mkdir(exist_ok=True)
    path = tmp_path / "sub" / "p.toml" if extra == "in_sub" else tmp_path / "p.toml"
    path.write_text(f'kind = "optimica"\n[optimica]\nfile = {file}\nclass = {cls}\n' + ("" if extra == "in_sub" else extra))
    return path


@pytest.mark.parametrize("file, cls, extra, match", [
    ('"missing.mop"', None, "", r"field 'optimica.file': expected an existing \.mop file inside the problem file's folder"),
    (None, '"DoubleIntegrator.NoSuch"', "", r"field 'optimica.class': .*optimization class 'DoubleIntegrator.NoSuch' .*MinTime"),
    (None, '"Pkg..Opt"', "", r"field 'optimica.class'"),
    (None, '"../../evil"', "", r"field 'optimica.class'"),
    ('"../m.mop"', None, "in_sub", r"field 'optimica.file': expected a \.mop file inside the problem file's folder"),
    ('"/etc/passwd"', None, "", r"field 'optimica.file': expected a \.mop file inside the problem file's folder"),
    ('"link.mop"', None, "", r"field 'optimica.file': expected a \.mop file inside the problem file's folder .*symbolic links"),
    ('"notes.txt"', None, "", r"field 'optimica.file': expected a Modelica/Optimica source file \(\.mop, \.mo\)"),
    ('"sub"', None, "", r"field 'optimica.file': expected a regular \.mop file"),
    (None, None, "[compiler_options]\nstate_start_values_fixed = 1\n", r"compiler_options.state_start_values_fixed"),
    (None, None, "[compiler_options]\ngenerate_ode = true\n", r"compiler_options.generate_ode"),
    (None, None, '[continuation]\nstart_factor = 10.0\nstep = 100.0\n', r"field 'continuation.step'"),
    (None, None, '[transcription]\nmethod = "multiple_shooting"\nrefine = true\n', r"field 'transcription.refine'"),
], ids=["missing_file", "class_not_found", "class_not_dotted", "class_a_path", "dotdot_escape", "absolute_elsewhere",
        "symlink_out", "not_modelica", "a_folder", "option_not_bool", "unknown_option", "bad_setting", "shooting_refined"])
def test_bad_inputs_name_the_field_and_exit_2(tmp_path, capsys, file, cls, extra, match):
    kw = {k: v for k, v in (("file", file), ("cls", cls)) if v is not None}
    path = _write(tmp_path, extra=extra, **kw)
    outside = tmp_path.parent / f"{tmp_path.name}_outside.mop"
    outside.write_text(MOP.read_text())
    os.symlink(outside, tmp_path / "link.mop")
    with pytest.raises(ProblemError, match=match):
        load_problem(path)
    out = tmp_path / "out"
    assert main(["solve", str(path), "--out", str(out), "--no-plots", "-q"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "gtmodel: error" in err
    summary = _summary(out) if (out / "summary.json").is_file() else {"status": "invalid_input"}
    assert summary["status"] == "invalid_input"


def test_shipped_file_validates_and_names_its_schema():
    jsonschema = pytest.importorskip("jsonschema")
    from gtmodel.problems.docs import json_schema

    text = SHIPPED.read_text(encoding="utf-8")
    jsonschema.validate(tomllib.loads(text), json_schema("optimica"))
    assert text.splitlines()[0] == "#:schema ../../docs/schemas/optimica.schema.json"
    assert (SHIPPED.parent / text.splitlines()[0].split()[1]).is_file()
