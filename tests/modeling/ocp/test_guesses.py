"""Initial guesses from a simulation and from a table.

References: the double integrator under ``u = 2 - 4 t`` from rest has ``v = 2 t - 2 t^2``,
``x = t^2 - 2 t^3 / 3`` (integrated by hand); a table's columns are interpolated linearly
(numpy.interp). A table of another model is refused naming its columns.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling import CollocationTranscription, Optimization
from gtmodel.modeling.ocp.guesses import guess_by_simulation, guess_from_table, guess_values

from .._builders import double_integrator


def _opt():
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=1.0)
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.add_point_constraint(v, at="start", lb=0.0, ub=0.0)
    return opt


def _at(opt, name, t):
    return guess_values(opt.initial_guesses[name], 1, name, np.zeros(1), np.array([t]))[0, 0]


def test_guess_by_simulation_follows_the_closed_form():
    opt = _opt()
    guess_by_simulation(opt, {"u": lambda t: 2.0 - 4.0 * t}, samples=401)
    # the input is held constant on the grid (step 1/400 s, slope -4): v differs by at
    # most 4 t (1/400) / 2 = t / 200 from the smooth closed form
    t = np.array([0.25, 0.5, 0.9])
    v = np.array([_at(opt, "v", s) for s in t])
    x = np.array([_at(opt, "x", s) for s in t])
    u = np.array([_at(opt, "u", s) for s in t])
    np.testing.assert_array_less(np.abs(v - (2 * t - 2 * t**2)), 6e-3 * t)
    np.testing.assert_array_less(np.abs(x - (t**2 - 2 * t**3 / 3)), 6e-3 * t**2)
    np.testing.assert_allclose(u, 2.0 - 4.0 * t, atol=2e-2)  # held on the grid

def test_guess_from_table_interpolates_and_is_used_by_the_transcription():
    opt = _opt()
    opt.set_objective(lagrange=opt.model.variables("input")["u"] ** 2)
    done = guess_from_table(opt, ["t", "x", "kinetic"], [[0.0, 0.0, 0.0], [1.0, 2.0, 0.0]], ignore=["kinetic"])
    assert done == ["x"] and _at(opt, "x", 0.25) == pytest.approx(0.5)
    tr = CollocationTranscription(opt, elements=4)
    w0 = tr._initial_w(opt.initial_guesses, 1.0, tr.dae.parameter_vector({}))
    first_x = w0[tr.nlp.offsets[("x", 1, 0)]]  # the state at the start of element 1 (t = 0.25)
    assert first_x == pytest.approx(0.5)


BAD = [
    (["time", "x"], [[0.0, 1.0]], r"no time column 't'"),
    (["t", "theta", "x"], [[0.0, 1.0, 1.0], [1.0, 1.0, 2.0]], r"columns theta name no state, input or algebraic variable of model 'double_integrator' \(a table of another problem\?\)"),
    (["t", "x"], [[0.0, 1.0], [0.0, 2.0]], r"must increase strictly"),
]


@pytest.mark.parametrize("columns, data, match", BAD, ids=["no_time", "another_model", "times_repeat"])
def test_bad_tables(columns, data, match):
    with pytest.raises(InputError, match=match):
        guess_from_table(_opt(), columns, data)


def test_simulation_with_an_unknown_input():
    with pytest.raises(InputError, match=r"'F' is not an input of model 'double_integrator' \(inputs: u\)"):
        guess_by_simulation(_opt(), {"F": 1.0})


def test_a_coarse_result_is_sampled_once_for_the_fine_mesh(monkeypatch):
    """A coarse solution guesses the fine mesh with one evaluation of its polynomials for every
    variable and point (was one per variable and point); the values are those of
    OptimizationResult.sample, the second method, at each of the fine mesh's times."""
    from gtmodel.modeling.ocp.guesses import ResultGuess
    from gtmodel.modeling.ocp.result import CollocationData

    from .._builders import min_energy_problem

    opt = min_energy_problem()
    coarse = CollocationTranscription(opt, elements=4).solve()
    fine = CollocationTranscription(opt, elements=12)
    calls = []
    evaluate = CollocationData.evaluate
    monkeypatch.setattr(CollocationData, "evaluate", lambda self, t: (self is coarse.collocation and calls.append(np.size(t))) or evaluate(self, t))
    fine.solve(initial_guess=coarse)
    assert calls == [len(fine.nlp.blocks)]  # one point set: the time of every block of the NLP vector
    t = np.linspace(0.0, 1.0, 7)
    sampled = ResultGuess(coarse, 0.0, 1.0).values(t)
    by_point = coarse.sample(t)
    np.testing.assert_allclose(sampled["x"][:, 0], by_point["states"]["x"], rtol=0, atol=1e-14)
    np.testing.assert_allclose(sampled["u"][:, 0], by_point["inputs"]["u"], rtol=0, atol=1e-14)


def test_a_result_guess_is_stretched_onto_another_final_time():
    """A result of horizon 1 s guessing a 2 s horizon: the value at 2 t is the result's at t (linear map)."""
    from gtmodel.modeling.ocp.guesses import ResultGuess

    from .._builders import min_energy_problem

    coarse = CollocationTranscription(min_energy_problem(), elements=4).solve()
    t = np.array([0.0, 0.3, 1.0])
    np.testing.assert_allclose(ResultGuess(coarse, 0.0, 2.0).values(2 * t)["x"][:, 0], coarse.sample(t)["states"]["x"], atol=1e-14)
