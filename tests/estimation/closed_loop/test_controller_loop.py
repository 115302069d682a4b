"""The closed-loop check harness (estimation.closed_loop.controller_loop) on an integrator plant.

References: closed forms of ``x_{k+1} = x_k + u_k`` under a constant or a state feedback law
(the one-sample delay, the step disturbance), the counts of out-of-bound inputs and statuses
by construction, and the parameter set's own values for the mismatched robot.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.controller_loop import mismatched_robot, run_controller_loop
from gtmodel.robots import load_parameters

x, u, p = ca.SX.sym("x"), ca.SX.sym("u"), ca.SX.sym("p", 0)
INTEGRATOR = ca.Function("step", [x, u, p], [x + u])
T = np.arange(6.0)


@pytest.mark.parametrize("delay, expected", [(0, [0, 1, 2, 3, 4, 5]), (1, [0, 1, 2, 3, 4, 5]), (2, [0, 1, 2, 3, 4, 5])])
def test_constant_input_with_delay_integrates(delay, expected):
    # u = 1 from the first call on (u_before defaults to it): x_k = k whatever the delay
    r = run_controller_loop(lambda t, y: (0, [1.0]), INTEGRATOR, [0.0], T, np.zeros((6, 1)), [-2.0], [2.0], delay=delay)
    np.testing.assert_array_equal(r.x[:, 0], expected)


def test_one_sample_delay_acts_one_period_late():
    # u_k = 1 - x_k seen at once would reach 1 after one step; delayed, u_0 = u_before = 0 first
    r = run_controller_loop(lambda t, y: (0, [1.0 - y[0]]), INTEGRATOR, [0.0], T, np.ones((6, 1)), [-5.0], [5.0],
                            delay=1, u_before=[0.0])
    np.testing.assert_allclose(r.u[:3, 0], [0.0, 1.0, 1.0])  # applied: before, u_0 = 1 (x_0 = 0), u_1 = 1 (x_1 = 0)
    np.testing.assert_allclose(r.x[:4, 0], [0.0, 0.0, 1.0, 2.0])


def test_disturbance_bounds_and_statuses_are_counted():
    r = run_controller_loop(lambda t, y: (6 if t >= 4 else 0, [3.0 if t == 2 else 0.0]), INTEGRATOR, [0.0], T, np.zeros((6, 1)),
                            [-1.0], [1.0], delay=0, disturbance=[0.5], disturbance_time=3.0, status_names={0: "GT_OK", 6: "GT_NOT_CONVERGED"})
    np.testing.assert_allclose(r.x[:, 0], [0, 0, 0, 3, 3.5, 4.0])
    assert r.bound_violations == 1
    assert r.status_counts == {"GT_OK": 4, "GT_NOT_CONVERGED": 2}
    assert r.max_error == 4.0 and r.rms_error == pytest.approx(np.sqrt(np.mean(np.array([0, 0, 0, 3, 3.5, 4.0]) ** 2)))


@pytest.mark.parametrize("names, shown", [(None, "(states 0)"), (["cart.s"], "(states cart.s)")])
def test_the_summary_names_the_error_states(names, shown):
    r = run_controller_loop(lambda t, y: (0, [0.0]), INTEGRATOR, [0.0], T, np.zeros((6, 1)), [-1.0], [1.0], state_names=names)
    assert r.summary_lines()[0] == f"tracking error: RMS 0, max 0 {shown}"


def test_mismatched_robot_scales_masses_and_friction():
    base = load_parameters("L1")
    m = mismatched_robot(base, 1.1, 0.9)
    assert m.dynamics.m_p == pytest.approx(1.1 * base.dynamics.m_p)
    np.testing.assert_allclose(m.dynamics.m_c, 1.1 * np.asarray(base.dynamics.m_c))
    np.testing.assert_allclose(m.dynamics.f_c, 0.9 * np.asarray(base.dynamics.f_c))
    np.testing.assert_array_equal(m.kinematics.L, base.kinematics.L)


@pytest.mark.parametrize("kwargs, match", [({"delay": -1}, "delay"), ({"x_ref": np.zeros((5, 1))}, "x_ref")])
def test_bad_arguments(kwargs, match):
    args = dict(x_ref=np.zeros((6, 1)), delay=1)
    args.update(kwargs)
    with pytest.raises(InputError, match=match):
        run_controller_loop(lambda t, y: (0, [0.0]), INTEGRATOR, [0.0], T, args["x_ref"], [-1.0], [1.0], delay=args["delay"])


# x_{k+1} = 10 x_k + u_k: an unstable plant step (as an explicit step on a stiff model); the closed form x_k = 10^k x_0
GROWING = ca.Function("step", [x, u, p], [10.0 * x + u])


@pytest.mark.parametrize("plant, steps, diverged", [(INTEGRATOR, 6, False), (GROWING, 6, False), (GROWING, 8, True)],
                         ids=["bounded", "10^5 x_0: not yet", "10^7 x_0: diverged"])
def test_a_runaway_plant_is_flagged(plant, steps, diverged):
    # DIVERGED = 1e6 times 1 + max |x_ref| (here 1): 10^5 stays under it, 10^7 is beyond
    r = run_controller_loop(lambda t, y: (0, [0.0]), plant, [1.0], np.arange(float(steps)), np.ones((steps, 1)), [-1.0], [1.0], delay=0)
    assert r.diverged is diverged


def test_a_non_finite_plant_state_is_flagged():
    nan_step = ca.Function("step", [x, u, p], [x / (x - 1.0) + u])  # 1 / 0 at x = 1
    r = run_controller_loop(lambda t, y: (0, [0.0]), nan_step, [1.0], T, np.ones((6, 1)), [-1.0], [1.0], delay=0)
    assert r.diverged


def test_the_plant_s_states_inside_each_period_are_recorded():
    # interior(x, u, p): the integrator's states at the period's quarter points, x + u j / 4 (j = 1, 2, 3), by hand
    quarters = ca.Function("interior", [x, u, p], [ca.horzcat(*[x + u * j / 4 for j in (1, 2, 3)])])
    r = run_controller_loop(lambda t, y: (0, [1.0]), INTEGRATOR, [0.0], T, np.zeros((6, 1)), [-2.0], [2.0], delay=0, interior=quarters)
    assert r.x_interior.shape == (6, 3, 1)
    np.testing.assert_allclose(r.x_interior[:, :, 0], np.arange(6.0)[:, None] + [0.25, 0.5, 0.75])
    assert run_controller_loop(lambda t, y: (0, [1.0]), INTEGRATOR, [0.0], T, np.zeros((6, 1)), [-2.0], [2.0]).x_interior is None
