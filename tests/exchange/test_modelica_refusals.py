"""What pymoca 0.12 reads as something else without a word is refused (gtmodel.exchange.modelica_checks).

Each refused source was tried on pymoca 0.12 first (the module docstring of
gtmodel.exchange.modelica_checks says what pymoca did with it); the error names the file, the
line and the construct. The look-alikes pymoca translates correctly still load, checked against
their closed-form solutions or the parameter values the Modelica semantics give.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.exchange.modelica import load_modelica

pytest.importorskip("pymoca")

_DECAY = """
  Real x(start = 1);
equation
  der(x) = -x;
"""

_R = """model R
  parameter Real k = 1;
  Real z(start = 1);
equation
  der(z) = -k * z;
end R;
"""

_AB = _R.replace("model R", "model A").replace("end R", "end A") + """model B
  parameter Real c = 5;
  Real y(start = 2);
equation
  der(y) = -c * y;
end B;
"""

#: (id, source, line, construct): what pymoca 0.12 misreads, refused at that line.
BAD = [
    ("short_input_connector", "connector RealIn = input Real;\nmodel M\n  RealIn u;" + _DECAY + "end M;\n",
     1, "short class with a prefix"),
    ("short_output_connector", "model M\n  connector RealOut = output Real;\n  RealOut y;" + _DECAY + "  y = x;\nend M;\n",
     2, "short class with a prefix"),
    ("short_parameter_type", "type Gain = parameter Real;\nmodel M\n  Gain k = 2;" + _DECAY + "end M;\n",
     1, "short class with a prefix"),
    ("short_flow_connector", "connector FlowC = flow Real;\nmodel M\n  FlowC f;" + _DECAY + "  f = x;\nend M;\n",
     1, "short class with a prefix"),
    ("short_array_type", "type Vec = Real[3];\nmodel M\n  Vec v(each start = 1);\nequation\n  der(v) = -v;\nend M;\n",
     1, "short class with array dimensions"),
    ("conditional_real_false", "model M\n  Real w if false;" + _DECAY + "end M;\n", 2, "conditional component"),
    ("conditional_component", _R + "model M\n  parameter Boolean useR = false;\n  R r(k = 3) if useR;" + _DECAY + "end M;\n",
     9, "conditional component"),
    ("conditional_after_if_expression", _R + "model M\n  parameter Boolean a = true;\n\n  R r(k = if a then 1 else 2)\n"
     "    if a annotation(Dialog(group = \"x\"));" + _DECAY + "end M;\n", 11, "conditional component"),
    ("final_declaration_overridden", _R.replace("  parameter Real k", "  final parameter Real k") + "model M\n  R r(k = 3);\nend M;\n",
     2, "final outside the loaded class"),
    ("final_modification_in_extends", _R + "model R2\n  extends R(final k = 2);\nend R2;\nmodel M\n  R2 r(k = 3);\nend M;\n",
     8, "final outside the loaded class"),
    ("final_modification_nested", _R + "model W\n  R r(final k = 2);\nend W;\nmodel M\n  W w(r(k = 3));\nend M;\n",
     8, "final outside the loaded class"),
    ("component_redeclare", _AB + "model Holder\n  replaceable A a;\nend Holder;\nmodel M\n  Holder h(redeclare B a);\nend M;\n",
     17, "component redeclare"),
    ("outer_parameter", "model Sub\n  outer parameter Real g;\n  Real z(start = 1);\nequation\n  der(z) = -g * z;\nend Sub;\n"
     "model M\n  inner parameter Real g = 4;\n  Sub s;\nend M;\n", 2, "outer element"),
    ("enumeration", "model M\n  type Mode = enumeration(slow, fast);\n  parameter Mode mode = Mode.fast;" + _DECAY + "end M;\n",
     2, "enumeration type"),
    ("boolean_variable", "model M\n  Real x(start = 1);\n  Boolean on;\nequation\n  on = time > 0.5;\n"
     "  der(x) = if on then -3 * x else -x;\nend M;\n", 3, "Boolean or Integer variable"),
    ("integer_output", "model M\n  Real x(start = 1);\n  output Integer n;\nequation\n  n = 3;\n  der(x) = -x;\nend M;\n",
     3, "Boolean or Integer variable"),
    ("reduction_sum", "model M\n  Real x[3](each start = 1);\n  Real s;\nequation\n  der(x) = -x;\n"
     "  s = sum(x[i]^2 for i in 1:3);\nend M;\n", 6, "reduction expression"),
    ("reduction_without_iterator", "model M\n  Real x(start = 1);\n  Real s;\nequation\n  der(x) = -x;\n"
     "  s = sum(1.0 for i in 1:3);\nend M;\n", 6, "reduction expression"),  # pymoca: s = 1.0, not 3.0
    ("reduction_in_for_equation", "model M\n  Real x[2](each start = 1);\n  Real y[2];\nequation\n  der(x) = -x;\n"
     "  for i in 1:2 loop\n    y[i] = max(\n      x[j] for j in 1:2);\n  end for;\nend M;\n", 8, "reduction expression"),
    ("array_comprehension_binding", "model M\n  parameter Real w[3] = {2 * k for k in 1:3};" + _DECAY + "end M;\n",
     2, "reduction expression"),
]


@pytest.mark.parametrize(("source", "line", "construct"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_misread_construct_is_refused_with_file_line_and_construct(tmp_path, source, line, construct):
    path = tmp_path / "bad.mo"
    path.write_text(source, encoding="utf-8")
    with pytest.raises(InputError, match=rf"bad\.mo:{line}: unsupported Modelica construct: {construct} \(pymoca 0\.12 .*; instead, "):
        load_modelica(path)


_CONNECTOR = "connector Pin\n  Real v;\n  flow Real i;\nend Pin;\nconnector PositivePin = Pin;\n"
_MSL_FINAL = """model M
  Modelica.Mechanics.Rotational.Components.Inertia inertia(final J = 2, w(start = 1), phi(start = 0));
  Modelica.Mechanics.Rotational.Sources.Torque torque;
equation
  connect(torque.flange, inertia.flange_a);
  torque.tau = -inertia.w;
end M;
"""

#: (id, source, parameters {name: value}, state, rate a of state(t) = c + (s0 - c) exp(-a t), its start s0, its limit c):
#: forms pymoca 0.12 translates correctly, with the values the Modelica semantics give.
GOOD = [
    ("short_type_with_unit", 'type Voltage = Real(unit = "V", min = 0);\nmodel M\n  parameter Voltage V0 = 3;\n'
     "  Voltage v(start = 2);\nequation\n  der(v) = -v + V0;\nend M;\n", {"V0": 3.0}, "v", 1.0, 2.0, 3.0),
    ("short_type_in_class", 'model M\n  type Gain = Real(unit = "1");\n  parameter Gain k = 2;\n  Real x(start = 1);\n'
     "equation\n  der(x) = -k * x;\nend M;\n", {"k": 2.0}, "x", 2.0, 1.0, 0.0),
    ("short_type_of_short_type", 'type Voltage = Real(unit = "V", start = 7);\ntype V2 = Voltage(min = 1);\n'
     "model M\n  V2 v;\nequation\n  der(v) = -v;\nend M;\n", {}, "v", 1.0, 7.0, 0.0),
    ("short_connector_alias", _CONNECTOR + "model M\n  PositivePin p;\n  Real x(start = 1);\nequation\n  p.v = x;\n"
     "  der(x) = -x;\nend M;\n", {}, "x", 1.0, 1.0, 0.0),
    ("short_model_with_modification", _R + "model M = R(k = 5);\n", {"k": 5.0}, "z", 5.0, 1.0, 0.0),
    ("final_parameter_in_loaded_class", "model M\n  final parameter Real k = 2;\n  Real x(start = 1);\nequation\n"
     "  der(x) = -k * x;\nend M;\n", {"k": 2.0}, "x", 2.0, 1.0, 0.0),
    ("final_modification_in_loaded_class", _R + "model M\n  R r(final k = 2);\nend M;\n", {"r.k": 2.0}, "r.z", 2.0, 1.0, 0.0),
    ("final_on_msl_component", _MSL_FINAL, {"inertia.J": 2.0}, "inertia.w", 0.5, 1.0, 0.0),
    ("class_redeclare", _AB.replace("parameter Real c = 5", "parameter Real k = 5").replace("c * y", "k * y")
     + "model Holder\n  replaceable model C = A;\n  C a;\nend Holder;\nmodel M\n  Holder h(redeclare model C = B);\nend M;\n",
     {"h.a.k": 5.0}, "h.a.y", 5.0, 2.0, 0.0),
    ("replaceable_without_redeclare", _R + "model Holder\n  replaceable R a constrainedby R;\nend Holder;\n"
     "model M\n  Holder h(a(k = 4));\nend M;\n", {"h.a.k": 4.0}, "h.a.z", 4.0, 1.0, 0.0),
    ("boolean_parameter_if_equation", 'model M\n  parameter Boolean fast = true "if useX then; final outer";\n'
     "  Real x(start = 1); // Real y if false;\nequation\n  if fast then\n    der(x) = -3 * x;\n  else\n    der(x) = -x;\n"
     "  end if;\nend M;\n", {"fast": 1.0}, "x", 3.0, 1.0, 0.0),
    ("integer_parameter_protected", "model M\n  parameter Integer n = 3;\nprotected\n  Real x(start = 1);\nequation\n"
     "  der(x) = -n * x;\nend M;\n", {"n": 3.0}, "x", 3.0, 1.0, 0.0),
    ("integer_in_function", "function pw\n  input Real x;\n  input Integer n;\n  output Real y;\nprotected\n  Integer m;\n"
     "algorithm\n  m := n;\n  y := x ^ m;\nend pw;\nmodel M\n  Real x(start = 1);\nequation\n  der(x) = -pw(x, 1);\nend M;\n",
     {}, "x", 1.0, 1.0, 0.0),
    ("inner_alone_each_on_array", "model M\n  inner parameter Real g = 4;\n  Real x[2](each start = 1);\nequation\n"
     "  der(x) = -g * x;\nend M;\n", {"g": 4.0}, "x", 4.0, 1.0, 0.0),
    ("for_equation_and_array_sum", "model M\n  parameter Real w[2] = {1, 2};\n  Real x[2](each start = 1);\nequation\n"
     "  for i in 1:2 loop\n    der(x[i]) = -sum(w.^2) * x[i];\n  end for;\nend M;\n", {}, "x", 5.0, 1.0, 0.0),
]


@pytest.mark.parametrize(("source", "params", "state", "rate", "s0", "limit"), [g[1:] for g in GOOD], ids=[g[0] for g in GOOD])
def test_correctly_translated_form_loads_with_the_right_values(tmp_path, source, params, state, rate, s0, limit):
    path = tmp_path / "good.mo"
    path.write_text(source, encoding="utf-8")
    model = load_modelica(path)
    dae = model.flatten()
    got = dict(zip(dae.p_names, dae.p_value.tolist()))
    assert {name: got.get(name) for name in params} == params
    t = np.linspace(0.0, 1.0, 6)
    sim = model.simulate(t, rtol=1e-10, atol=1e-12)
    got_state = np.asarray(sim.x[state], dtype=float).reshape(len(t), -1)  # an array state: every element
    np.testing.assert_allclose(got_state, (limit + (s0 - limit) * np.exp(-rate * t))[:, None] + 0 * got_state, atol=1e-7)


def test_short_type_keeps_unit_bound_and_start(tmp_path):
    path = tmp_path / "good.mo"
    path.write_text(GOOD[2][1], encoding="utf-8")  # type V2 = Voltage(min = 1) of type Voltage = Real(unit = "V", start = 7)
    model = load_modelica(path)
    dae = model.flatten()
    assert dae.x_start.tolist() == [7.0] and np.asarray(dae.x_lb, dtype=float).tolist() == [1.0] and model.units["v"] == "V"
