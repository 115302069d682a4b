"""Tests of the restricted expression language of problem files.

References: every good expression is compared numerically with the same expression built
directly in CasADi; the end-to-end problems have closed-form optima (double integrator,
rest to rest over distance 1: minimum time with |u| <= 1 is tf = 2; minimum energy in
1 s is integral u^2 = 12).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import ProblemError
from gtmodel.modeling import (
    CollocationTranscription,
    Optimization,
    apply_to,
    optimization_names,
    parse_constraint,
    parse_expression,
    parse_objective,
)

from .._builders import double_integrator

EVAL_TOL = 1e-12  # parsed vs directly built expression, same operations in double precision
MIN_TIME_TOL = 1e-5  # min-time tf: bang-bang with active bounds, IPOPT tol 1e-8 (as test_collocation)
COST_TOL = 1e-6  # min-energy cost: the cubic solution is exactly representable (d = 3)

X, Y, Z = ca.SX.sym("x"), ca.SX.sym("y"), ca.SX.sym("z")
TF = ca.SX.sym("final_time")
VEC = ca.SX.sym("T", 3)
SYMS = ca.vertcat(X, Y, Z, TF)
W = 0.25
NAMES = {"x": X, "y": Y, "z": Z, "w": W, "final_time": TF, "start_time": 0.0, "T": VEC}
RNG_POINTS = np.random.default_rng(7).uniform(0.1, 0.9, size=(5, 4))  # x, y, z, tf in (0.1, 0.9)


def _same(parsed: ca.SX, direct: ca.SX) -> None:
    f = ca.Function("f", [SYMS], [parsed, ca.SX(direct)])
    for pt in RNG_POINTS:
        a, b = (float(v) for v in f(pt))
        assert a == pytest.approx(b, abs=EVAL_TOL, rel=EVAL_TOL)


GOOD_EXPRESSIONS = [
    ("x + y * z", X + Y * Z),
    ("x - y / z", X - Y / Z),
    ("x^2 + y^2", X**2 + Y**2),  # ^ binds tighter than +
    ("x**2 + y**2", X**2 + Y**2),
    ("-x^2", -(X**2)),
    ("2^-1 * x", 0.5 * X),
    ("x^y^z", X ** (Y**Z)),  # right associative
    ("+x - -y", X + Y),
    ("(x + y) * (x - y)", (X + Y) * (X - Y)),
    ("abs(x - y)", ca.fabs(X - Y)),
    ("sqrt(x) + exp(y) + log(z)", ca.sqrt(X) + ca.exp(Y) + ca.log(Z)),
    ("sin(x) * cos(y) + tan(z) + tanh(x)", ca.sin(X) * ca.cos(Y) + ca.tan(Z) + ca.tanh(X)),
    ("asin(x) + acos(y) + atan(z)", ca.asin(X) + ca.acos(Y) + ca.atan(Z)),
    ("atan2(y, x)", ca.atan2(Y, X)),
    ("min(x, y) + max(x, y, z)", ca.fmin(X, Y) + ca.fmax(ca.fmax(X, Y), Z)),
    ("w * x + 1e-3", W * X + 1e-3),
    ("2 * pi * final_time", 2 * np.pi * TF),
    ("start_time + x", X),
    ("  x\n + y", X + Y),  # leading blanks and newlines are spaces
]


@pytest.mark.parametrize("text,direct", GOOD_EXPRESSIONS, ids=[g[0] for g in GOOD_EXPRESSIONS])
def test_good_expression_matches_casadi(text, direct):
    _same(parse_expression(text, NAMES), direct)


GOOD_OBJECTIVES = [
    # text, mayer, lagrange
    ("final_time", TF, 0),
    ("integral(x^2)", 0, X**2),
    ("final_time + w * integral(x^2 + y^2)", TF, W * (X**2 + Y**2)),
    ("integral(x) * w + integral(y) - integral(z) / 2", 0, W * X + Y - Z / 2),
    ("x(final_time)^2 - 2 * (final_time + integral(y))", X**2 - 2 * TF, -2 * Y),
    ("-integral(x) / final_time", 0, -X / TF),
    ("exp(w) * (1 + integral(z))", np.exp(W), np.exp(W) * Z),
]


@pytest.mark.parametrize("text,mayer,lagrange", GOOD_OBJECTIVES, ids=[g[0] for g in GOOD_OBJECTIVES])
def test_objective_splits_into_mayer_and_lagrange(text, mayer, lagrange):
    obj = parse_objective(text, NAMES)
    _same(obj.mayer, mayer)
    _same(obj.lagrange, lagrange)


GOOD_CONSTRAINTS = [
    # text, expr, lb, ub, at
    ("abs(x) <= 1.0", ca.fabs(X), -np.inf, 1.0, None),
    ("1.0 >= abs(x)", ca.fabs(X), -np.inf, 1.0, None),
    ("x >= w", X, W, np.inf, None),
    ("-0.5 <= y <= 0.5", Y, -0.5, 0.5, None),
    ("0.5 >= y >= -2 * w", Y, -0.5, 0.5, None),
    ("x <= y", X - Y, -np.inf, 0.0, None),
    ("x >= y + z", Y + Z - X, -np.inf, 0.0, None),
    ("x == y", X - Y, 0.0, 0.0, None),
    ("x(final_time) == 0.3", X, 0.3, 0.3, "final"),
    ("0.3 == x(final_time) + y(final_time)", X + Y, 0.3, 0.3, "final"),
    ("x(start_time) <= final_time", X - TF, -np.inf, 0.0, "start"),
    ("final_time <= 3", TF, -np.inf, 3.0, None),
]


@pytest.mark.parametrize("text,expr,lb,ub,at", GOOD_CONSTRAINTS, ids=[g[0] for g in GOOD_CONSTRAINTS])
def test_constraint_forms(text, expr, lb, ub, at):
    c = parse_constraint(text, NAMES, key="constraints[0]")
    _same(c.expr, expr)
    assert (c.lb, c.ub, c.at, c.text, c.name) == (lb, ub, at, text, "constraints[0]")


BAD = [
    # function, text, expected message (regex)
    ("expr", "tua1 + x", r"field 'k': undefined name at column 1: 'tua1'"),
    ("expr", "x + yy", r"undefined name at column 5: 'yy'; did you mean 'y'"),
    ("expr", "x +* 2", r"syntax error \(invalid syntax\) at column 4: '\*'"),
    ("expr", "x + (y", r"syntax error \('\(' was never closed\) at column 5: '\('"),
    ("expr", "x +", r"unexpected end of expression\) at column 4"),
    ("expr", "x = 1", r"at column 3: '='; use == for equality"),
    ("expr", "__import__('os')", r"undefined function at column 1: '__import__'"),
    ("expr", "eval('1')", r"undefined function at column 1: 'eval'"),
    ("expr", "exec(x)", r"undefined function at column 1: 'exec'"),
    ("expr", "x.__class__", r"attribute access is not allowed at column 1: 'x.__class__'"),
    ("expr", "ca.sin(x)", r"only named functions can be called at column 1: 'ca.sin'"),
    ("expr", "x + 'a'", r"string constants are not allowed at column 5: ''a''"),
    ("expr", "T[0]", r"indexing is not allowed.* at column 1: 'T\[0\]'"),
    ("expr", "x and y", r"boolean operators are not allowed"),
    ("expr", "lambda: x", r"lambda is not allowed at column 1"),
    ("expr", "[x for x in y]", r"listcomp is not allowed"),
    ("expr", "x if y else z", r"conditional expressions are not allowed"),
    ("expr", "x % 2", r"operator is not allowed \(use \+ - \* / \^\) at column 3: '%'"),
    ("expr", "~x", r"unary operator is not allowed"),
    ("expr", "True + x", r"constant of type bool is not allowed"),
    ("expr", "1j * x", r"constant of type complex is not allowed"),
    ("expr", "x / (1 - 1)", r"division by zero at column 5: '\(1 - 1\)'|division by zero at column 6"),
    ("expr", "max(x)", r"max\(\) takes at least 2 arguments, got 1"),
    ("expr", "sin(x, y)", r"sin\(\) takes 1 argument, got 2"),
    ("expr", "max(x, y=1)", r"keyword arguments are not allowed"),
    ("expr", "T + 1", r"'T' has 3 elements, only scalars are allowed at column 1: 'T'"),
    ("expr", "", r"field 'k': empty expression"),
    ("expr", "   ", r"empty expression"),
    ("expr", "x <= 1", r"comparisons are only allowed in constraints"),
    ("expr", "x(final_time)", r"time-point evaluation is not allowed in this expression"),
    ("expr", "integral(x)", r"integral\(\) is only allowed in the objective"),
    ("con", "x < 1", r"strict comparison '<' is not allowed, use <= / >= at column 3: '<'"),
    ("con", "(x) > 1", r"strict comparison '>' is not allowed, use <= / >= at column 5: '>'"),
    ("con", "x != 1", r"comparison '!=' is not allowed"),
    ("con", "x + 1", r"a constraint needs a comparison <=, >= or =="),
    ("con", "0 <= x <= 1 and y <= 2", r"boolean operators are not allowed; write one constraint per condition"),
    ("con", "0 <= x >= 1", r"double comparison must be lo <= e <= hi"),
    ("con", "y <= x <= 1", r"outer parts of a double comparison must be numbers at column 1: 'y'"),
    ("con", "0 <= x <= 1 <= 2", r"at most two comparisons"),
    ("con", "1 <= x <= 0", r"lower bound 1 exceeds upper bound 0"),
    ("con", "w <= 1", r"the constraint contains no variables"),
    ("con", "x(start_time) == x(final_time)", r"mixes start_time and final_time .* at column 18"),
    ("con", "x(final_time) + y == 0", r"'y' is not evaluated at a time point .* at column 17: 'y'"),
    ("con", "x(1.0) == 0", r"only be evaluated at final_time or start_time"),
    ("con", "w(final_time) <= x", r"'w' does not vary in time"),
    ("con", "integral(x) <= 1", r"integral\(\) is only allowed in the objective"),
    ("obj", "sin(integral(x))", r"integral\(\) inside sin\(\) is not allowed at column 5: 'integral'"),
    ("obj", "integral(x)^2", r"integral\(\) must be a term of the objective"),
    ("obj", "integral(x) * integral(y)", r"product or ratio of integral\(\) terms"),
    ("obj", "1 / integral(x)", r"integral\(\) in a denominator"),
    ("obj", "x * integral(y)", r"factor of integral\(\) must be constant in time .* column 1: 'x'"),
    ("obj", "x(final_time) * integral(y)", r"time-point evaluation is not allowed in a factor"),
    ("obj", "integral(integral(x))", r"nested integral\(\)"),
    ("obj", "integral(x(final_time))", r"time-point evaluation is not allowed inside integral\(\)"),
    ("obj", "final_time + x", r"'x' varies in time and is outside integral\(\) at column 14: 'x'; write x\(final_time\)"),
    ("obj", "x(start_time)", r"at final_time only"),
    ("obj", "final_time <= 1", r"not a comparison"),
]
_FNS = {"expr": parse_expression, "con": parse_constraint, "obj": parse_objective}


@pytest.mark.parametrize("fn,text,match", BAD, ids=[f"{b[0]}:{b[1]}" for b in BAD])
def test_bad_input_raises_problem_error(fn, text, match):
    with pytest.raises(ProblemError, match=match) as info:
        _FNS[fn](text, NAMES, origin="problems/p.toml", key="k")
    assert str(info.value).startswith("problems/p.toml: field 'k': ")


def test_error_message_format_and_caret():
    with pytest.raises(ProblemError) as info:
        parse_constraint("abs(qd1) <= 1 and x", NAMES, origin="a.toml", key="constraints[2]")
    msg = str(info.value)
    first, text_line, caret_line = msg.splitlines()
    assert first.startswith("a.toml: field 'constraints[2]': ")
    assert text_line.strip() == "abs(qd1) <= 1 and x"
    assert caret_line.index("^") == text_line.index("abs")


def test_close_matches_are_listed():
    names = {"tau1": X, "tau2": Y, "tau3": Z}
    with pytest.raises(ProblemError, match=r"undefined name at column 10: 'tau'; did you mean 'tau1', 'tau2', 'tau3'"):
        parse_objective("integral(tau^2)", names)


def test_caret_power_columns_map_to_the_original_text():
    # "^" is rewritten to "**" internally; the column must still refer to the user's text
    with pytest.raises(ProblemError, match=r"at column 13: 'q'"):
        parse_expression("x^2 + y^2 + q", NAMES)


def test_symbolic_parameter_is_static_only_when_declared():
    p = ca.SX.sym("p")
    names = dict(NAMES, p=p)
    with pytest.raises(ProblemError, match="factor of integral"):
        parse_objective("p * integral(x)", names)
    obj = parse_objective("p * integral(x) + p", names, static=["p"])
    assert ca.is_equal(ca.simplify(obj.lagrange - p * X), ca.SX(0))
    assert ca.is_equal(obj.mayer, p)


def _min_time_problem():
    m, x, v, u = double_integrator()
    opt = Optimization(m, free_final_time=True, final_time_bounds=(0.5, 5.0), final_time_guess=1.0)
    return opt


REST_TO_REST = ["x(start_time) == 0", "v(start_time) == 0", "x(final_time) == d", "0 == v(final_time)"]


def test_end_to_end_min_time_from_strings():
    # reference: min tf with |u| <= 1, rest to rest over 1  =>  tf = 2 (u = +1 then -1)
    opt = _min_time_problem()
    obj, cons = apply_to(
        opt,
        objective="final_time + w * integral(u^2)",
        constraints=[*REST_TO_REST, "-1 <= u <= 1", "abs(v) <= 10"],
        parameters={"w": 0.0, "d": 1.0},
        origin="problems/di.toml",
        prefix="optimization.",
    )
    assert [c.at for c in cons] == ["start", "start", "final", "final", None, None]
    assert len(opt.point_constraints) == 4 and len(opt.path_constraints) == 2
    assert opt.path_constraints[0].name == "optimization.constraints[4]"
    res = CollocationTranscription(opt, elements=40, points=3).solve()
    assert res.status == "optimal"
    assert res.final_time == pytest.approx(2.0, abs=MIN_TIME_TOL)
    assert res.states["x"][-1] == pytest.approx(1.0, abs=1e-8)


def test_end_to_end_min_energy_from_strings():
    # reference: min int_0^1 u^2 dt, rest to rest over 1 => cost 12
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=1.0)
    apply_to(opt, objective="integral(u^2)", constraints=REST_TO_REST, parameters={"d": 1.0})
    res = CollocationTranscription(opt, elements=10, points=3).solve()
    assert res.status == "optimal"
    assert res.objective == pytest.approx(12.0, abs=COST_TOL)


def test_apply_to_errors_name_file_and_field():
    opt = _min_time_problem()
    with pytest.raises(ProblemError, match=r"^di\.toml: field 'optimization\.constraints\[1\]': undefined name"):
        apply_to(opt, constraints=["x(start_time) == 0", "vv(start_time) == 0"], origin="di.toml",
                 prefix="optimization.")
    foreign = ca.SX.sym("foreign")
    with pytest.raises(ProblemError, match=r"field 'objective': .*unknown symbol"):
        apply_to(opt, objective="integral(q)", names={"q": foreign}, origin="di.toml")


def test_optimization_names_table():
    opt = _min_time_problem()
    names = optimization_names(opt, parameters={"w": 2.0})
    assert {"x", "v", "u", "kinetic", "time", "final_time", "start_time", "w"} <= set(names)
    assert ca.is_equal(names["final_time"], opt.final_time)
    with pytest.raises(ProblemError, match="clashes"):
        optimization_names(opt, parameters={"x": 1.0})
    with pytest.raises(ProblemError, match="finite number"):
        optimization_names(opt, parameters={"w": "a"})
    # output 'kinetic' is a time-varying name: allowed in integral(), not bare in the Mayer term
    obj, _ = apply_to(opt, objective="integral(kinetic) + kinetic(final_time)")
    assert not obj.lagrange.is_constant() and not obj.mayer.is_constant()


def test_optimization_names_elements():
    m, x, v, u = double_integrator()
    vec = m.input("f", 2)
    m.equation(m.der(m.state("s")), vec[0] + vec[1])
    opt = Optimization(m)
    names = optimization_names(opt, elements={"f": ["f1", "f2"]})
    assert ca.is_equal(names["f2"], vec[1])
    c = parse_constraint("f1 + f2 <= 1", names)
    assert ca.is_equal(ca.simplify(c.expr - vec[0] - vec[1]), ca.SX(0))
    with pytest.raises(ProblemError, match="2 elements, only scalars"):
        parse_expression("f + 1", names)
    with pytest.raises(ProblemError, match="1 names for 2 elements"):
        optimization_names(opt, elements={"f": ["f1"]})
    with pytest.raises(ProblemError, match="is not a new identifier"):
        optimization_names(opt, elements={"f": ["x", "f2"]})


def test_documented_example_parses():
    # docs/problem_language.md: the complete example, on a table of the documented L1 names
    import tomllib
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[3] / "docs" / "problem_language.md").read_text()
    block = doc.split("## Complete example", 1)[1].split("```toml\n", 1)[1].split("```", 1)[0]
    data = tomllib.loads(block)
    scalars = "x y z xd yd zd q1 q2 q3 qd1 qd2 qd3 tau1 tau2 tau3 time final_time".split()
    names = {n: ca.SX.sym(n) for n in scalars} | {"start_time": 0.0} | data["parameters"]
    obj = parse_objective(data["optimization"]["objective"], names)
    assert ca.is_equal(obj.mayer, names["final_time"])
    cons = [parse_constraint(t, names) for t in data["optimization"]["constraints"]]
    assert [c.at for c in cons] == [None] * 5 + ["final"]
    assert (cons[4].lb, cons[4].ub) == (-0.5, 0.5)
    assert data["optimization"]["final_time"]["free"] is True


def test_time_points_and_integrals_need_the_callbacks_of_an_optimization():
    # without (timed, integral) callbacks (e.g. the robot kinds) a constraint keeps to one of
    # start_time/final_time and no integral(); with them (apply_to) it becomes "timed"

    names = {"x": ca.SX.sym("x"), "final_time": ca.SX.sym("final_time"), "start_time": 0.0}
    with pytest.raises(ProblemError, match=r"a variable can only be evaluated at final_time or start_time"):
        parse_constraint("x(0.5) == 1", names, static=["final_time", "start_time"])
    seen = []
    specials = (lambda e, t: seen.append(t) or ca.SX.sym("xt"), lambda e: ca.SX.sym("I"))
    c = parse_constraint("x(0.5) + integral(x^2) <= x(final_time)", names, static=["final_time", "start_time"], specials=specials)
    assert c.at == "timed" and c.ub == 0.0 and len(seen) == 2 and seen[1] == "final"
    assert float(ca.DM(ca.evalf(seen[0]))) == 0.5


@pytest.mark.parametrize("name, known, expected", [
    ("link.omega", ["link.w", "link.phi", "motor.w"], ["link.w"]),  # the MSL's name on the same path first
    ("link.omega", ["link.phi", "motor.w"], []),  # no link.w: nothing close
    ("tua1", ["tau1", "tau2", "x"], ["tau1"]),  # difflib (ratio 0.75; tau2 0.5 is below its cutoff 0.6)
    ("theta", ["phi", "theta_dot"], ["phi", "theta_dot"]),
])
def test_close_names_put_the_msl_name_first(name, known, expected):
    from gtmodel.modeling.ocp.suggestions import close_names

    assert close_names(name, known) == expected
