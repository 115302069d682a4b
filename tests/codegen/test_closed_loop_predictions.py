"""Where a state went beyond its bound, what the controller's own model predicted there
(gtmodel.codegen.check.loop_causes.excess_predictions, named in the check's failure).

Reference: a scalar first-order model ``x+ = a x + b u`` whose prediction over ``n`` periods with a
held input is the closed form ``a^n x + b u (1 - a^n) / (1 - a)``; the plant's run is written out by
hand (the same law with a larger gain ``b``: a model error; or the same ``b``: an excess the
controller chose).
"""

from __future__ import annotations

from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from gtmodel.codegen.check.closed_loop import LoopCheck
from gtmodel.codegen.check.loop_causes import excess_predictions
from gtmodel.control.bounds import bound_report
from gtmodel.estimation.closed_loop.controller_loop import LoopSummary

A, B_MODEL, U_MAX, X_MAX, DT = 0.9, 0.1, 10.0, 6.0, 0.004


def model_step() -> ca.Function:
    x, u = ca.SX.sym("x"), ca.SX.sym("u")
    return ca.Function("F", [x, u], [A * x + B_MODEL * u])


def run_of(b_plant: float, n: int = 12, u: float = U_MAX) -> LoopSummary:
    """The plant ``x+ = A x + b_plant u`` from rest under the input held at ``u`` (at its bound ``U_MAX``)."""
    x = np.zeros(n)
    for k in range(1, n):
        x[k] = A * x[k - 1] + b_plant * u
    t = DT * np.arange(n)
    return LoopSummary(t=t, x=x[:, None], x_ref=np.zeros((n, 1)), u=np.full((n, 1), u), status=np.zeros(n, dtype=int),
                       step_s=np.zeros(n), error_states=(0,), u_lb=np.array([-U_MAX]), u_ub=np.array([U_MAX]))


def setup_of(controller, delay: int = 1) -> SimpleNamespace:
    return SimpleNamespace(controller=controller, names=(["x"], ["v"], []), loop={"delay": delay})


def bounds_of(run: LoopSummary):
    return bound_report({"x": run.x[:, 0], "v": run.u[:, 0]}, {"x": -X_MAX, "v": -U_MAX}, {"x": X_MAX, "v": U_MAX}, times=run.t)


def closed_form(x0: float, n: int, u: float = U_MAX) -> float:
    return A ** n * x0 + B_MODEL * u * (1 - A ** n) / (1 - A)


@pytest.mark.parametrize("delay", [0, 1, 2])
def test_a_plant_stronger_than_the_model_is_named_the_models_error(delay):
    run = run_of(b_plant=0.15)  # reaches 0.15 * 10 / 0.1 = 15 at rest; the model only 10, both beyond 6
    mpc = SimpleNamespace(step=model_step())
    (p,) = excess_predictions(setup_of(mpc, delay), run, bounds_of(run), label="MPC")
    k = int(np.argmax(run.x[:, 0]))  # the largest excess: the last sample of the rising run
    assert p["time"] == pytest.approx(run.t[k]) and p["periods"] == 1 + delay
    assert p["predicted"] == pytest.approx(closed_form(run.x[k - 1 - delay, 0], 1 + delay), rel=1e-12)
    assert p["error"] == pytest.approx(run.x[k, 0] - p["predicted"], rel=1e-12)
    assert p["error_relative"] == pytest.approx(p["error"] / X_MAX, rel=1e-12)
    assert p["inputs_at_bounds"] == {"v": U_MAX}


def test_the_prediction_held_means_a_model_error_and_beyond_means_the_controllers_choice():
    # a bound the model keeps (from a plant state below it, one period) but the plant crosses
    n = 3
    x = np.array([0.0, 5.5, 0.0])
    x[2] = A * x[1] + 0.15 * U_MAX  # 6.45 > 6; the model: 0.9 * 5.5 + 1 = 5.95 (held) - with delay 0, one period
    t = DT * np.arange(n)
    run = LoopSummary(t=t, x=x[:, None], x_ref=np.zeros((n, 1)), u=np.full((n, 1), U_MAX), status=np.zeros(n, dtype=int),
                      step_s=np.zeros(n), error_states=(0,), u_lb=np.array([-U_MAX]), u_ub=np.array([U_MAX]))
    (held,) = excess_predictions(setup_of(SimpleNamespace(step=model_step()), 0), run, bounds_of(run), label="MPC")
    assert held["predicted"] == pytest.approx(A * 5.5 + B_MODEL * U_MAX) and held["predicted_percent"] < 0
    chose = run_of(b_plant=B_MODEL)  # the plant is the model: the prediction is the plant's value
    (p,) = excess_predictions(setup_of(SimpleNamespace(step=model_step()), 1), chose, bounds_of(chose), label="MPC")
    assert p["error"] == pytest.approx(0.0, abs=1e-12) and p["predicted_percent"] > 1
    check_held = LoopCheck(closed=run, feedforward=run, bounds=bounds_of(run), predictions=[held], label="MPC", memory_bytes=0, work_bytes=0)
    check_chose = LoopCheck(closed=chose, feedforward=chose, bounds=bounds_of(chose), predictions=[p], label="MPC", memory_bytes=0, work_bytes=0)
    failures = {"held": " ".join(check_held.failures()), "chose": " ".join(check_chose.failures())}
    assert "predicted 5.95 (-0.833 % of the bound beyond it" in failures["held"]
    assert "the excess is the model's error on this plant" in failures["held"]
    assert "not the model's error, the step did not hold the bound" in failures["chose"] and "the inputs at their bounds then: v 10" in failures["chose"]
    assert "where a bound was exceeded, the MPC's model:" in "\n".join(check_held.summary_lines())
    assert check_held.to_dict()["predictions"] == [held]


@pytest.mark.parametrize("case", ["no_prediction_function", "excess_before_the_delay", "bound_held", "other_states"])
def test_nothing_is_predicted_where_nothing_can_be(case):
    early = case == "excess_before_the_delay"  # beyond at the second sample, before the input decided then acts
    run = run_of(b_plant=0.7 if early else 0.15, n=2 if early else 12, u=U_MAX if case != "bound_held" else 1.0)
    controller = SimpleNamespace(predict=None) if case == "no_prediction_function" else SimpleNamespace(step=model_step())
    setup = setup_of(controller, 1)
    if case == "other_states":  # a plant in the tool's coordinates (a robot): not the model's states
        setup.loop = {"delay": 1, "output": lambda x: x}
    assert excess_predictions(setup, run, bounds_of(run)) == []


def test_the_tracking_laws_predict_is_used():
    run = run_of(b_plant=0.15)
    (p,) = excess_predictions(setup_of(SimpleNamespace(predict=model_step()), 1), run, bounds_of(run), label="tracking")
    assert p["controller"] == "tracking" and p["periods"] == 2


def test_an_excess_the_noise_carried_is_named_so():
    """The plant is the model (no model error) and beyond its bound; from the state the controller measured (1.0
    below the true one at the prediction's start, by hand) its model keeps the bound: the noise's, not the step's."""
    run = run_of(b_plant=B_MODEL, n=12, u=U_MAX)  # rises to 6.86 at the last sample: beyond 6
    k = run.t.size - 1
    run.y = run.x.copy()
    run.y[k - 2, 0] -= 1.0  # what the controller measured two periods before the worst sample
    (p,) = excess_predictions(setup_of(SimpleNamespace(step=model_step()), 1), run, bounds_of(run), label="MPC")
    assert p["error"] == pytest.approx(0.0, abs=1e-12) and p["predicted_percent"] > 1
    assert p["predicted_from_measured"] == pytest.approx(closed_form(run.x[k - 2, 0] - 1.0, 2), rel=1e-12)
    assert p["measured_percent"] < 1
    check = LoopCheck(closed=run, feedforward=run, bounds=bounds_of(run), predictions=[p], label="MPC", memory_bytes=0, work_bytes=0)
    assert "the measurement's noise carried the step beyond it" in " ".join(check.failures())


def test_an_excess_the_filters_estimate_carried_is_named_so():
    """The plant is the model; the measurement filter's estimate two periods before the worst sample 1.0 below the
    plant's state (10 times its noise, by hand): from it the model keeps the bound; the text names both shares."""
    run = run_of(b_plant=B_MODEL, n=12, u=U_MAX)
    k = run.t.size - 1
    x_hat = run.x.copy()
    x_hat[k - 2, 0] -= 1.0
    mpc = SimpleNamespace(step=model_step(), state_filter=SimpleNamespace(sigma=np.array([0.1])))
    (p,) = excess_predictions(setup_of(mpc, 1), run, bounds_of(run), label="MPC", x_hat=x_hat)
    assert p["predicted_from_estimate"] == pytest.approx(closed_form(run.x[k - 2, 0] - 1.0, 2), rel=1e-12)
    assert p["estimate_percent"] < 1 and p["estimate_worst"] == {"name": "x", "estimate": pytest.approx(x_hat[k - 2, 0]),
                                                                 "value": pytest.approx(run.x[k - 2, 0]), "sigmas": pytest.approx(10.0)}
    check = LoopCheck(closed=run, feedforward=run, bounds=bounds_of(run), predictions=[p], label="MPC", memory_bytes=0, work_bytes=0)
    text = " ".join(check.failures())
    assert "from the state its measurement filter estimated its model predicted" in text
    assert f"the estimate's share {p['predicted'] - p['predicted_from_estimate']:+.4g}, the model's error's +0" in text


def test_the_loop_records_what_the_controller_measured():
    """run_controller_loop's ``y``: the plant's state plus the noise drawn from its seed (NumPy's generator, by hand)."""
    from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop

    x, u, p = ca.SX.sym("x"), ca.SX.sym("u"), ca.SX.sym("p", 0)
    plant = ca.Function("plant", [x, u, p], [A * x + B_MODEL * u, 1])
    t = DT * np.arange(5)
    run = run_controller_loop(lambda tk, y: (0, np.array([1.0])), plant, np.array([0.5]), t, np.zeros((5, 1)),
                              u_lb=np.array([-U_MAX]), u_ub=np.array([U_MAX]), noise_std=0.1, seed=3, delay=0)
    noise = 0.1 * np.random.default_rng(3).standard_normal((5, 1))
    np.testing.assert_allclose(run.y, run.x + noise, rtol=0, atol=1e-15)
