"""``gtmodel codegen`` of a model that came from Modelica source (issue 68: "codegen generates and checks the C of a
model that came from a .mo file").

Two routes: ``gtmodel codegen model FILE.mo:CLASS`` (and ``FILE.mop:Pkg.Opt``, the model of an
Optimica class) generates, compiles and checks the model's C against Python; and ``gtmodel
codegen tracking RESULT_DIR`` builds the tracking controller of an ``optimica`` problem's
result folder and checks it in closed loop. Each compiles C (a few seconds each; the drive written
with the MSL's class paths about 12 s, marked slow).
"""

from __future__ import annotations

import json
import re

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main
from gtmodel.codegen.build import find_compiler
from gtmodel.errors import ModelError
from gtmodel.problems.user_model import load_user_model

from ..conftest import PROBLEMS_DIR, REPO

RC = REPO / "tests" / "exchange" / "data" / "rc_circuit.mo"
MSL_DRIVE = PROBLEMS_DIR / "optimica" / "msl_drive_min_time.mop"
OPTIMICA = PROBLEMS_DIR / "optimica"

#: A DC motor driving an inertia through a gear, in plain Modelica (its input the voltage).
DRIVE = """
model Drive "a DC motor (R, L, k) behind a gear (ratio) on an inertia"
  parameter Real R = 1.0 "armature resistance [Ohm]";
  parameter Real L = 0.01 "armature inductance [H]";
  parameter Real k = 0.05 "torque constant [N.m/A]";
  parameter Real J = 0.002 "inertia at the load [kg.m2]";
  parameter Real ratio = 10 "gear ratio";
  input Real v(min = -24, max = 24) "voltage [V]";
  Real i(start = 0, fixed = true) "current [A]";
  Real phi(start = 0, fixed = true) "load angle [rad]";
  Real w(start = 0, fixed = true) "load speed [rad/s]";
equation
  L * der(i) = v - R * i - k * ratio * w;
  der(phi) = w;
  J * der(w) = ratio * k * i;
end Drive;
"""

needs_cc = pytest.mark.skipif(find_compiler() is None, reason="no C compiler")


@needs_cc
@pytest.mark.parametrize("source, cls", [
    ("drive.mo", "Drive"), ("rc", "Circuit.RC"), ("mop", "DoubleIntegrator.MinTime"),
    pytest.param("msl", "MinTime", marks=pytest.mark.slow),
], ids=["drive_mo", "connected_mo", "optimica_mop", "msl_drive_mop"])
def test_codegen_model_of_modelica_source_generates_and_checks(tmp_path, capsys, source, cls):
    if source == "drive.mo":
        path = tmp_path / "drive.mo"
        path.write_text(DRIVE)
    else:  # msl: a drive written with the MSL's class paths, higher index as written (reduced before the C)
        path = {"rc": RC, "mop": OPTIMICA / "double_integrator_min_time.mop", "msl": MSL_DRIVE}[source]
    out = tmp_path / "c"
    assert main(["codegen", "model", f"{path}:{cls}", "--out", str(out), "--check", "-n", "200", "-q"]) == EXIT_OK
    printed = capsys.readouterr().out
    assert "PASSED" in printed and "step_rk4 over 250 periods vs simulate()" in printed
    assert sorted(p.suffix for p in out.glob("gt_*")) == [".c", ".c", ".h", ".h"]


@needs_cc
def test_tracking_controller_of_an_optimica_result_is_checked_in_closed_loop(tmp_path, capsys):
    result = tmp_path / "r"
    assert main(["solve", str(OPTIMICA / "double_integrator_min_time.toml"), "--out", str(result), "--no-plots", "--no-report",
                 "-q"]) == EXIT_OK
    assert main(["codegen", "tracking", str(result), "--out", str(tmp_path / "c"), "--check", "-n", "100", "-q"]) == EXIT_OK
    printed = capsys.readouterr().out
    assert "closed-loop check: PASSED" in printed and re.search(r"u in \[-1, 1\]: \S+ at t = \S+ s, limit -?1, [-+]\S+ % \(held\)", printed)
    summary = json.loads((tmp_path / "c" / "summary.json").read_text())  # the same figures for machines
    loop = summary["parts"][-1]
    assert summary["status"] == "converged" and loop["bounds"][0]["name"] == "u" and loop["bounds"][0]["held"]


def test_model_of_a_mop_file_is_its_optimization_class(tmp_path):
    model = load_user_model(OPTIMICA / "double_integrator_min_time.mop", "DoubleIntegrator.MinTime")
    assert list(model.variables("state")) == ["x", "v"] and list(model.variables("input")) == ["u"]


@pytest.mark.parametrize("text, cls, match", [
    (DRIVE, "Motor", r"drive\.mo"),
    ("model Drive\n  Real x;\nequation\n  der(x) = ;\nend Drive;\n", "Drive", r"drive\.mo:4"),
], ids=["class_not_found", "syntax_error"])
def test_bad_modelica_model_is_refused_naming_the_file(tmp_path, capsys, text, cls, match):
    path = tmp_path / "drive.mo"
    path.write_text(text)
    with pytest.raises(ModelError, match=match):
        load_user_model(path, cls)
    assert main(["codegen", "model", f"{path}:{cls}", "--out", str(tmp_path / "c")]) == EXIT_BAD_INPUT
    assert str(path) in capsys.readouterr().err


@needs_cc
def test_tracking_controller_file_with_an_optimica_reference_problem(tmp_path, capsys):
    # a loop file's [reference] problem may be an optimica problem file, its model the .mop's class
    (tmp_path / "di.mop").write_text((OPTIMICA / "double_integrator_min_time.mop").read_text())
    (tmp_path / "p.toml").write_text('kind = "optimica"\n[optimica]\nfile = "di.mop"\nclass = "DoubleIntegrator.MinTime"\n')
    (tmp_path / "tc.toml").write_text('name = "di_tracking"\n[controller]\nmodel = "di.mop:DoubleIntegrator.MinTime"\nperiod = 0.004\n'
                                      '[reference]\nproblem = "p.toml"\nsettle_time = 0.2\n[check]\nparameter_factor = 1.0\n')
    assert main(["codegen", "tracking", str(tmp_path / "tc.toml"), "--out", str(tmp_path / "c"), "--check", "-n", "100", "-q"]) == EXIT_OK
    assert "closed-loop check: PASSED" in capsys.readouterr().out
    assert (tmp_path / "c" / "gt_di_tracking.c").is_file()
