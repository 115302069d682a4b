"""Modelica source import through pymoca, checked against closed-form solutions and SciPy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.errors import InputError
from gtmodel.exchange.modelica import load_modelica

pytest.importorskip("pymoca")

DATA = Path(__file__).parent / "data"


def test_oscillator_parameters_start_values_and_solution():
    model = load_modelica(DATA / "oscillator.mo")
    assert model.name == "Oscillator" and model.source == DATA / "oscillator.mo"
    assert model.exchange_metadata["k"] == ("N/m", "stiffness") and model.units["x"] == "m"
    dae = model.flatten()
    assert list(dae.p_names) == ["m", "k", "c"] and dae.p_value.tolist() == [1.0, 4.0, 0.0]
    assert dae.x_start.tolist() == [1.0, 0.0]
    t = np.linspace(0.0, 2.0, 11)
    sim = model.simulate(t, u=0.0, p={"k": 9.0}, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sim.x["x"], np.cos(3.0 * t), atol=1e-8)  # x'' = -9 x, x(0) = 1
    np.testing.assert_allclose(sim.outputs["energy_out"], 4.5, rtol=1e-7)  # conserved: k x0^2 / 2


def test_connected_rc_circuit_decays_with_rc():
    model = load_modelica(DATA / "rc_circuit.mo")  # the last model of the package: Circuit.RC
    assert model.name == "RC"
    t = np.linspace(0.0, 0.3, 7)
    sim = model.simulate(t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(sim.x["c.u"], np.exp(-t / (100.0 * 1e-3)), atol=1e-8)


def test_van_der_pol_with_initial_equation_matches_scipy():
    model = load_modelica(DATA / "van_der_pol.mo", "VanDerPol")
    assert "lambda_" in model.flatten().p_names  # a Python keyword, renamed
    t = np.linspace(0.0, 5.0, 11)
    sim = model.simulate(t, rtol=1e-10, atol=1e-12)
    ref = solve_ivp(lambda _, s: [s[1], -s[0] + (1 - s[0] ** 2) * s[1]], (0, 5), [2.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sim.x["x"], ref.y[0], atol=1e-6)


def test_arrays_for_equations_extends_if_expressions_and_functions():
    # references: x' = -min(x, 0.5) from 1 reaches 0.5 at t = 1; x' = -x^2 gives 1 / (1 + t)
    chain = load_modelica(DATA / "chain_arrays.mo")
    assert chain.flatten().x_names == ["x[0]", "x[1]", "x[2]", "v[0]", "v[1]", "v[2]"]  # Modelica x[1] is x[0]
    t = np.linspace(0.0, 2.0, 11)
    sat = load_modelica(DATA / "saturated_extends.mo", "Saturated").simulate(t, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(sat.x["x"], np.where(t <= 1.0, 1.0 - 0.5 * t, 0.5 * np.exp(-(t - 1.0))), atol=1e-7)
    fun = load_modelica(DATA / "top_level_function.mo", "WithFunction").simulate(t, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(fun.x["x"], 1.0 / (1.0 + t), atol=1e-8)


@pytest.mark.parametrize(
    ("file", "cls", "match"),
    [
        ("syntax_error.mo", None, r"syntax_error.mo:5: Modelica syntax error: missing ';' at 'end'"),
        ("bouncing_ball_when.mo", None, r"bouncing_ball_when.mo:7: unsupported Modelica construct: when-clause"),
        ("algorithm_section.mo", None, r"algorithm_section.mo:4: unsupported Modelica construct: algorithm section"),
        ("assert_clause.mo", None, r"assert_clause.mo:6: unsupported Modelica construct: assert\(\)"),
        ("missing.mo", None, r"missing.mo: no such Modelica file"),
        ("oscillator.mo", "NoSuchModel", r"oscillator.mo: pymoca cannot translate class 'NoSuchModel'"),
        ("nested_function.mo", None, r"nested_function.mo: pymoca cannot translate class 'WithFunction': a function declared inside"),
    ],
)
def test_bad_modelica_names_file_line_and_construct(file, cls, match):
    with pytest.raises(InputError, match=match):
        load_modelica(DATA / file, cls)


FOR_LOOP_MO = """model ForLoop
  parameter Real a = 0.5;
  Real z(start = 1, fixed = true);
  Real x[3](start = {1, 2, 3}, each fixed = true);
  Real y[3];
equation
  der(z) = -z;
  for i in 1:3 loop
    der(x[i]) = -a*x[i];
    y[i] = 2*x[i];
  end for;
end ForLoop;
"""


@pytest.mark.parametrize("scalar_first", [True, False])
def test_for_loop_of_several_equations_loads_and_simulates(tmp_path, scalar_first):
    # pymoca gives the loop as one 3 x 2 matrix of residuals; stacked with the scalar equation it needs a column each
    text = FOR_LOOP_MO if scalar_first else FOR_LOOP_MO.replace("  der(z) = -z;\n", "").replace("end for;\n", "end for;\n  der(z) = -z;\n")
    (tmp_path / "for_loop.mo").write_text(text)
    model = load_modelica(tmp_path / "for_loop.mo")
    t = np.linspace(0.0, 2.0, 9)
    sim = model.simulate(t, rtol=1e-11, atol=1e-12)
    closed = np.exp(-0.5 * t)[:, None] * np.array([1.0, 2.0, 3.0])  # x_i' = -a x_i, x_i(0) = i
    np.testing.assert_allclose(sim.x["x"], closed, atol=1e-8)
    np.testing.assert_allclose(sim.z["y"], 2.0 * closed, atol=1e-8)
    np.testing.assert_allclose(sim.x["z"], np.exp(-t), atol=1e-8)
