"""Optimica ``.mop`` files in (issue 68): solved against closed forms, refused with file, line and construct."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.errors import GtModelError, InputError
from gtmodel.exchange.optimica import FREE_FINAL_TIME_MAX, OptimicaError, load_optimica
from gtmodel.exchange.optimica_syntax import MAX_BYTES, MAX_DEPTH, MAX_TOKENS
from gtmodel.modeling import CollocationTranscription
from gtmodel.problems.optimica_run import run_optimica
from gtmodel.problems.run import run_problem

pytest.importorskip("pymoca")

EXAMPLES = Path(__file__).resolve().parents[2] / "problems" / "optimica"

PLANT = """model Plant
  parameter Real a_max = 1;
  Real x(start = 0, fixed = true);
  Real v(start = 0, fixed = true);
  input Real u(min = -a_max, max = a_max);
equation
  der(x) = v;
  der(v) = u;
end Plant;
"""


def _mop(tmp_path: Path, body: str, name: str = "p.mop") -> Path:
    path = tmp_path / name
    path.write_text(PLANT + body, encoding="utf-8")
    return path


def _opt(header: str, body: str = "  extends Plant;\n", constraints: str = "  x(finalTime) = 1;\n") -> str:
    return f"optimization Opt ({header})\n{body}constraint\n{constraints}end Opt;\n"


MIN_TIME = "objective = finalTime, startTime = 0, finalTime(free = true, min = 0.5, max = 10, initialGuess = 3)"


# ---------------------------------------------------------------------------------------------------- solved
@pytest.mark.parametrize(("distance", "a_max"), [(1.0, 1.0), (2.0, 0.5)])
def test_double_integrator_min_time_matches_closed_form(tmp_path, distance, a_max):
    # independent check: the bang-bang closed form T = 2 sqrt(D / a_max) (Bryson and Ho 1975, sec. 7.3)
    path = _mop(tmp_path, _opt(MIN_TIME, f"  extends Plant(a_max = {a_max});\n",
                               f"  x(finalTime) = {distance};\n  v(finalTime) = 0;\n"))
    out = run_optimica(path, "Opt", tmp_path / "out", plots=False)
    assert out.status.value == "optimal" and out.summary["verification"]["passed"]
    assert out.summary["final_time_s"] == pytest.approx(2.0 * np.sqrt(distance / a_max), rel=1e-5)


def test_shipped_double_integrator_through_the_command(tmp_path, capsys):
    # independent check: T = 2 sqrt(1 / 1) = 2 s; the command writes the result folder of any optimal_control problem
    code = main(["solve", str(EXAMPLES / "double_integrator_min_time.mop"), "--class", "DoubleIntegrator.MinTime",
                 "--out", str(tmp_path / "r"), "-q", "--no-plots"])
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert code == 0 and summary["kind"] == "optimica" and summary["status"] == "optimal"
    assert summary["final_time_s"] == pytest.approx(2.0, rel=1e-5)
    assert (tmp_path / "r" / "trajectories.csv").is_file() and (tmp_path / "r" / "report.html").is_file()


@pytest.mark.parametrize(("fixed", "check"), [(True, "equal"), (False, "below")])
def test_bryson_denham_with_state_start_values_fixed(tmp_path, capsys, fixed, check):
    # independent check: the analytic optimum 4 / (9 l) = 4 (Bryson and Ho 1975, sec. 3.11) when the starts are initial
    # conditions (JModelica.org's state_start_values_fixed); without the option the starts are guesses, the start is
    # free, and the relaxed problem's optimum can only be lower
    args = ["solve", str(EXAMPLES / "bryson_denham.mop"), "--class", "BrysonDenham", "--out", str(tmp_path / "r"), "-q",
            "--no-plots", "--no-report"] + (["--state-start-values-fixed"] if fixed else [])
    assert main(args) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["verification"]["passed"]
    if check == "equal":
        assert summary["objective"] == pytest.approx(4.0, rel=1e-5)
    else:
        assert summary["objective"] < 4.0 - 1e-3


def test_free_parameter_constant_thrust(tmp_path):
    # independent check: x(T) = a T^2 / 2 = D gives a = 2 D / T^2 = 2 and objective a^2 = 4 (closed form)
    opt = load_optimica(EXAMPLES / "constant_thrust.mop", "ConstantThrust")
    lo, hi, start = opt.free_parameters["a"]
    assert (lo[0], hi[0], start[0]) == (0.0, 10.0, 1.0)
    out = run_optimica(EXAMPLES / "constant_thrust.mop", "ConstantThrust", tmp_path / "r", plots=False)
    assert out.status.value == "optimal"
    assert out.summary["model_parameters"]["a"] == pytest.approx(2.0, rel=1e-8)
    assert out.summary["objective"] == pytest.approx(4.0, rel=1e-8)


def test_mapping_of_bounds_starts_and_point_constraints(tmp_path):
    # independent check: the declarations read back from the Optimization against the file's literal values
    path = _mop(tmp_path, _opt(MIN_TIME, "  extends Plant(a_max = 2);\n",
                               "  x(finalTime) = 1;\n  0 = v(finalTime);\n  x <= 3;\n  -1 <= v;\n"))
    opt = load_optimica(path, "Opt")
    flat = opt.model.flatten()
    assert (flat.u_lb.tolist(), flat.u_ub.tolist()) == ([-2.0], [2.0])  # input min/max written with a parameter
    assert (opt.free_final_time, opt.final_time_bounds, opt.final_time_guess) == (True, (0.5, 10.0), 3.0)
    path_c = {c.name: (float(c.lb[0]), float(c.ub[0])) for c in opt.path_constraints}
    assert path_c == {"p.mop:15": (-np.inf, 3.0), "p.mop:16": (-1.0, np.inf)}
    starts = sorted(c.name for c in opt.point_constraints if c.at == "start")
    assert starts == ["fixed start of v", "fixed start of x"]  # fixed = true: initial conditions


def test_state_start_values_fixed_fixes_unfixed_starts(tmp_path):
    # independent check: the file's starts are fixed = false; the option alone makes them initial conditions
    path = tmp_path / "free.mop"
    path.write_text(PLANT.replace(", fixed = true", "") + _opt(MIN_TIME), encoding="utf-8")
    assert not [c for c in load_optimica(path, "Opt").point_constraints if c.at == "start"]
    fixed = load_optimica(path, "Opt", state_start_values_fixed=True)
    assert sorted(c.name for c in fixed.point_constraints if c.at == "start") == ["fixed start of v", "fixed start of x"]


# ---------------------------------------------------------------------------------------------------- refused
BAD = [
    # (case, optimization class text or a whole file, class, message)
    ("class not found", _opt(MIN_TIME), "Nope", r"p.mop: optimization class 'Nope' not found \(optimization classes in the file: Opt\)"),
    ("header modifier", _opt("objective = finalTime, static = true"), "Opt", r"p.mop:10: unsupported Optimica class modifier 'static'"),
    ("free start time", _opt("objective = finalTime, startTime(free = true) = 0"), "Opt", r"p.mop:10: unsupported construct: startTime\(\.\.\.\)"),
    ("finalTime attribute", _opt("finalTime(free = true, nominal = 2)"), "Opt", r"p.mop:10: unsupported finalTime attribute 'nominal'"),
    ("strict inequality", _opt(MIN_TIME, constraints="  x < 1;\n"), "Opt", r"p.mop:13: unsupported constraint: write one relation"),
    ("two relations", _opt(MIN_TIME, constraints="  -1 <= x <= 1;\n"), "Opt", r"p.mop:13: unsupported constraint"),
    ("for loop", _opt(MIN_TIME, constraints="  for i in 1:2 loop\n x <= i;\n end for;\n"), "Opt",
     r"p.mop:13: unsupported construct in a constraint section: 'for'"),
    ("if expression", _opt(MIN_TIME, constraints="  x <= if v > 0 then 1 else 2;\n"), "Opt",
     r"p.mop:13: unsupported construct in a constraint section: 'if'"),
    ("unknown function", _opt(MIN_TIME, constraints="  foo(x) <= 1;\n"), "Opt", r"p.mop:13: unsupported function 'foo'"),
    ("unknown name", _opt(MIN_TIME, constraints="  y <= 1;\n"), "Opt", r"p.mop:13: unknown name 'y'"),
    ("free on a state", _opt(MIN_TIME, "  extends Plant(x(free = true));\n"), "Opt",
     r"p.mop:11: unsupported construct: free = true on 'x', which is not a parameter"),
    ("untimed objective", _opt("objective = x, finalTime = 2"), "Opt", r"p.mop:10: objective: a model variable without a time"),
    ("timed and untimed", _opt(MIN_TIME, constraints="  x(finalTime) <= v;\n"), "Opt",
     r"p.mop:13: unsupported constraint: timed variables .* and variables at every time"),
    ("interior time, free tf", _opt(MIN_TIME, constraints="  x(1.5) = 1;\n"), "Opt", r"p.mop:13: timed variable at t = 1.5 s: with a free final time"),
    ("timed integrand", _opt("objectiveIntegrand = x(finalTime), finalTime = 2"), "Opt", r"p.mop:10: a timed variable x\(\.\.\.\) is not allowed here"),
    ("der of a non-state", _opt(MIN_TIME, constraints="  der(u) <= 1;\n"), "Opt", r"p.mop:13: der\(u\): 'u' is not a state"),
    ("matrix product", _opt(MIN_TIME, "  extends Plant;\n  Real w[2];\nequation\n  w[1] = x;\n  w[2] = v;\n", "  w * w <= 1;\n"), "Opt",
     r"p.mop:17: unsupported construct: '\*' of two arrays"),
    ("constraint in a model", "model M\n  Real y;\nequation\n  der(y) = 1;\nconstraint\n  y <= 1;\nend M;\n" + _opt(MIN_TIME), "Opt",
     r"p.mop:14: unsupported construct: a constraint section in model M"),
    ("free in a model", PLANT.replace("parameter Real a_max = 1", "parameter Real k(free = true) = 1").replace("model Plant", "model Q")
     .replace("end Plant", "end Q") + _opt(MIN_TIME), "Opt", r"p.mop:11: unsupported construct: Optimica attribute 'free' in model Q"),
    ("when clause", "model W\n  Real y;\nequation\n  der(y) = 1;\n  when y > 1 then\n  end when;\nend W;\n" + _opt(MIN_TIME), "Opt",
     r"p.mop:14: unsupported Modelica construct: when-clause"),
    ("Modelica syntax", _opt(MIN_TIME, "  extends Plant;\n  Real y\n"), "Opt", r"p.mop:\d+: Modelica syntax error"),
    ("no end", "optimization Opt (objective = finalTime)\n  extends Plant;\n", "Opt", r"p.mop:10: class 'Opt' has no 'end Opt;'"),
    ("quoted identifier", _opt(MIN_TIME, "  extends Plant;\n  Real 'x; system(\"rm\")';\n"), "Opt", r"p.mop:12: unsupported construct: quoted identifier"),
    ("non-ASCII name", _opt(MIN_TIME, "  extends Plant;\n  Real \u00e9;\n"), "Opt", r"p.mop:12: character '\u00e9' is not Modelica syntax"),
    ("class name with a path", _opt(MIN_TIME), "../../etc/Opt", r"class name '\.\./\.\./etc/Opt' is not a dotted Modelica name"),
]


@pytest.mark.parametrize(("case", "text", "cls", "match"), BAD, ids=[b[0] for b in BAD])
def test_unsupported_constructs_are_refused_with_file_line_and_construct(tmp_path, case, text, cls, match):
    # independent check: the line numbers are those of the file as written (PLANT is lines 1-9, the class from line 10)
    path = _mop(tmp_path, text)
    with pytest.raises(OptimicaError, match=match):
        load_optimica(path, cls)


def test_missing_file(tmp_path):
    # independent check: nothing on disk
    with pytest.raises(InputError, match=r"nothing.mop: no such Optimica file"):
        load_optimica(tmp_path / "nothing.mop", "Opt")


@pytest.mark.parametrize(
    ("case", "make", "match"),
    [
        ("huge file", lambda: PLANT + "// " + "x" * MAX_BYTES + "\n" + _opt(MIN_TIME), r"file too large"),
        ("deep brackets", lambda: PLANT + _opt(MIN_TIME, constraints="  x <= " + "(" * 5000 + "1" + ")" * 5000 + ";\n"),
         rf"p.mop:13: nesting deeper than {MAX_DEPTH} levels"),
        ("deep classes", lambda: "".join(f"package P{i}\n" for i in range(200)) + "".join(f"end P{i};\n" for i in reversed(range(200))),
         rf"classes nested deeper than {MAX_DEPTH} levels"),
        ("long name", lambda: PLANT + _opt(MIN_TIME, "  extends Plant;\n  Real " + "a" * 5000 + ";\n"), r"p.mop:12: name too long"),
        ("many tokens", lambda: PLANT + _opt(MIN_TIME, constraints="  x <= " + "1+" * (MAX_TOKENS // 2) + "1;\n"),
         rf"p.mop:13: file too large \(more than {MAX_TOKENS} tokens\)"),
    ],
)
def test_hostile_input_is_refused_before_any_work(tmp_path, case, make, match):
    # independent check: each limit is the module's documented constant; the refusal is an InputError, never a crash
    path = tmp_path / "p.mop"
    path.write_text(make(), encoding="utf-8")
    with pytest.raises(OptimicaError, match=match):
        load_optimica(path, "Opt")


def test_hostile_class_name_on_the_command_line_writes_nothing(tmp_path, capsys, monkeypatch):
    # independent check: the file system after the run; a class name is never a path
    monkeypatch.chdir(tmp_path)
    path = _mop(tmp_path, _opt(MIN_TIME))
    assert main(["solve", str(path), "--class", "../../evil"]) == 2
    assert "not a dotted Modelica class name" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.mop"]


def test_command_refuses_a_mop_without_class_and_a_bad_file_exits_2(tmp_path, capsys):
    # independent check: the exit code table (invalid input: 2) and the message on stderr
    path = _mop(tmp_path, _opt(MIN_TIME, constraints="  y <= 1;\n"))
    assert main(["solve", str(path), "--out", str(tmp_path / "a")]) == 2
    assert "needs --class" in capsys.readouterr().err
    assert main(["solve", str(path), "--class", "Opt", "--out", str(tmp_path / "b"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "p.mop:13: unknown name 'y'" in err
    assert json.loads((tmp_path / "b" / "summary.json").read_text())["status"] == "invalid_input"


def test_optimica_error_is_a_gtmodel_error():
    # independent check: the project's exception hierarchy (gtmodel.errors)
    assert issubclass(OptimicaError, InputError) and issubclass(OptimicaError, GtModelError)


def test_model_from_a_mo_file_beside_and_open_final_time_bounds(tmp_path):
    # independent check: T = 2 sqrt(D / a_max) = 2 s; the free final time without min/max gets the documented defaults
    (tmp_path / "plants.mo").write_text("package Plants\n" + PLANT.replace("model Plant", "model DI").replace("end Plant", "end DI")
                                        + "end Plants;\n", encoding="utf-8")
    path = tmp_path / "opt.mop"
    path.write_text("optimization MinTime (objective = finalTime, finalTime(free = true, initialGuess = 3))\n"
                    "  extends Plants.DI;\nconstraint\n  x(finalTime) = 1;\n  v(finalTime) = 0;\nend MinTime;\n", encoding="utf-8")
    opt = load_optimica(path, "MinTime")
    assert opt.final_time_bounds == (1e-6, FREE_FINAL_TIME_MAX)
    out = run_optimica(path, "MinTime", tmp_path / "r", plots=False)
    assert out.status.value == "optimal" and out.summary["final_time_s"] == pytest.approx(2.0, rel=1e-5)


def test_array_variables_in_constraints(tmp_path):
    # independent check: two independent double integrators with |tau_i| <= 1 reach q = (1, 1/4) at rest; the slower
    # axis sets the time, T = 2 sqrt(1 / 1) = 2 s (closed form), with the other axis's element constraint q[2](finalTime)
    text = ("model Axes\n  Real q[2](each start = 0, each fixed = true);\n  Real w[2](each start = 0, each fixed = true);\n"
            "  input Real tau[2];\nequation\n  der(q) = w;\n  der(w) = tau;\nend Axes;\n"
            "optimization Opt (objective = finalTime, finalTime(free = true, min = 0.5, max = 10, initialGuess = 3))\n"
            "  extends Axes;\nconstraint\n  tau <= 1;\n  tau >= -1;\n  q[1](finalTime) = 1;\n  q[2](finalTime) = 0.25;\n"
            "  w(finalTime) = 0;\nend Opt;\n")
    path = tmp_path / "axes.mop"
    path.write_text(text, encoding="utf-8")
    opt = load_optimica(path, "Opt")
    assert [int(c.expr.numel()) for c in opt.path_constraints] == [2, 2]
    out = run_optimica(path, "Opt", tmp_path / "r", plots=False)
    assert out.status.value == "optimal" and out.summary["final_time_s"] == pytest.approx(2.0, rel=1e-5)


def test_fixed_start_contradicted_by_a_start_constraint_is_refused(tmp_path):
    # independent check: the file's own values (x starts fixed at 0, the constraint says 0.5); the run names the constraint
    path = _mop(tmp_path, _opt(MIN_TIME, constraints="  x(startTime) = 0.5;\n  x(finalTime) = 1;\n"))
    out = run_optimica(path, "Opt", tmp_path / "r", plots=False)
    assert out.status.value == "invalid_input"
    assert "fixed start x = 0 contradicts the problem's start constraint 'p.mop:13'" in out.summary["message"]


def test_bryson_denham_agrees_with_the_native_problem_file_on_the_same_mesh(tmp_path):
    # independent check: problems/benchmarks/bryson_denham.toml (the optimal_control kind, its Python model) on the same
    # 60 Radau elements of 3 points; the two declarations of one problem give one optimum
    native = run_problem(EXAMPLES.parent / "benchmarks" / "bryson_denham.toml", tmp_path / "native", plots=False)
    opt = load_optimica(EXAMPLES / "bryson_denham.mop", "BrysonDenham", state_start_values_fixed=True)
    mop = CollocationTranscription(opt, elements=60, points=3, scheme="radau").solve()
    assert native.summary["status"] == "optimal" and mop.status == "optimal"
    assert mop.objective == pytest.approx(native.summary["objective"], rel=1e-7)


def test_several_optimization_classes_in_one_file(tmp_path):
    # independent check: each class read alone gives its own declarations (the file's literal values); the other class,
    # with its Optimica attributes and constraint section, is left out rather than refused
    second = _opt(MIN_TIME).replace("Opt", "Other").replace("  x(finalTime) = 1;\n", "  x(finalTime) = 2;\n  v <= 3;\n")
    path = _mop(tmp_path, _opt(MIN_TIME) + second)
    first, other = load_optimica(path, "Opt"), load_optimica(path, "Other")
    assert (len(first.path_constraints), len(other.path_constraints)) == (0, 1)
    assert [float(c.lb[0]) for c in other.declared_point_constraints] == [2.0]


def test_connected_components_from_a_mo_beside_the_file(tmp_path):
    # independent check: the closed form of minimum-dissipation charging, R C^2 U^2 / T = 0.5 J (constant current);
    # the folder also holds broken .mo files (syntax_error.mo), which declare no class the .mop uses and are not read
    data = Path(__file__).parent / "data"
    out = run_optimica(data / "rc_charge.mop", "Charge", tmp_path / "r", plots=False)
    assert out.status.value == "optimal" and out.summary["verification"]["passed"]
    assert out.summary["objective"] == pytest.approx(0.5, rel=1e-8)


@pytest.mark.parametrize(("start", "final", "at", "target"), [(0.0, 1.0, "finalTime", 1.0), (1.0, 2.0, "1.5", 0.25)])
def test_free_parameter_with_interior_time_and_start_time(tmp_path, start, final, at, target):
    # independent check: x(t) = a (t - t0)^2 / 2, so x(t1) = target gives a = 2 target / (t1 - t0)^2 = 2 (closed form)
    text = (EXAMPLES / "constant_thrust.mop").read_text().replace("startTime = 0, finalTime = 1",
                                                                   f"startTime = {start}, finalTime = {final}")
    text = text.replace("x(finalTime) = 1;", f"x({at}) = {target};")
    path = tmp_path / "thrust.mop"
    path.write_text(text, encoding="utf-8")
    out = run_optimica(path, "ConstantThrust", tmp_path / "r", plots=False)
    assert out.status.value == "optimal"
    assert out.summary["model_parameters"]["a"] == pytest.approx(2.0, rel=1e-7)


def test_initial_guess_attributes_of_variables(tmp_path):
    # independent check: the guesses read back against the file's literal values, top-level and inside a component
    text = ("optimization Opt (objective = finalTime, finalTime(free = true, min = 0.5, max = 10, initialGuess = 2.5))\n"
            "  Plant p(x(initialGuess = 0.25));\n  input Real w(initialGuess = 0.5);\nequation\n  p.u = w;\n"
            "constraint\n  p.x(finalTime) = 1;\nend Opt;\n")
    opt = load_optimica(_mop(tmp_path, text), "Opt")
    guesses = {k: np.ravel(v).tolist() for k, v in opt.initial_guesses.items()}
    assert guesses == {"p.x": [0.25], "w": [0.5]} and opt.final_time_guess == 2.5
