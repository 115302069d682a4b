"""State bounds and path constraints of the real-time MPC (gtmodel.control.mpc_constraints).

References: the double integrator x'' = u with a position bound, explicit Euler over 4 ms, so
that the horizon problem is a convex QP; it is built again here in NumPy (prediction by the
matrices A, B) and solved by SciPy's SLSQP (a second method). The soft constraints' exact
penalty must give the hard constraints' optimum (IPOPT on both). The closed loop: an MPC
without the bound overshoots it (the reference does), the constrained one holds it.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import Bounds, LinearConstraint, minimize

from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.control.mpc import mpc_controller
from gtmodel.control.mpc_constraints import problem_constraints
from gtmodel.modeling import explicit_ode
from gtmodel.problems.run import load_problem
from gtmodel.trajectory.point_to_point import build_optimization

from ..conftest import REPO
from ..modeling._builders import double_integrator

DT, H, BOUND = 0.004, 20, 0.5
#: A start that can stop before the bound (2 m/s: 4 cm at 50 m/s^2) and one that cannot (5 m/s: 25 cm).
FEASIBLE, INFEASIBLE = np.array([0.4, 2.0]), np.array([0.45, 5.0])


@pytest.fixture(scope="module")
def integrator():
    ode = explicit_ode(double_integrator()[0])
    t = DT * np.arange(101)
    x_ref = np.column_stack([np.minimum(t / 0.2, 1.0), np.where(t < 0.2, 5.0, 0.0)])  # to 1 m: beyond the bound
    kw = dict(horizon=H, Q=[1.0, 0.0], R=[1e-4], u_lb=[-50.0], u_ub=[50.0], method="euler")
    soft = mpc_controller(ode, t, x_ref, np.zeros((101, 1)), x_ub={"x": BOUND}, **kw)
    hard = mpc_controller(ode, t, x_ref, np.zeros((101, 1)), x_ub={"x": BOUND}, hard_constraints=True, **kw)
    free = mpc_controller(ode, t, x_ref, np.zeros((101, 1)), **kw)
    return ode, t, soft, hard, free


def _scipy_first_input(c, k, x0, stages=range(1, H + 1), whole=False, method="SLSQP"):
    """The horizon QP in NumPy, solved by SciPy's SLSQP (or ``method="trust-constr"``): x_{j+1} = A x_j + B u_j, x_j[0] <= BOUND for j in ``stages``
    (the first input, or with ``whole`` all ``H``). The predictions as matrices, ``X = Phi x0 + G u``, so
    that the cost's and constraints' gradients are exact."""
    A, B = np.array([[1.0, DT], [0.0, 1.0]]), np.array([0.0, DT])
    Phi = np.vstack([np.linalg.matrix_power(A, j + 1) for j in range(H)])  # (2H, 2)
    G = np.zeros((2 * H, H))
    for j in range(H):
        for i in range(j + 1):
            G[2 * j:2 * j + 2, i] = np.linalg.matrix_power(A, j - i) @ B
    W = np.kron(np.eye(H), c.Q)
    W[-2:, -2:] = c.Qf
    e0 = Phi @ x0 - c.x_ref[np.minimum(k + 1 + np.arange(H), c.length - 1)].reshape(-1)
    rows = 2 * (np.asarray(stages) - 1)  # the positions x_j[0]
    sc = c.u_ub[0]  # SLSQP on the inputs over their bound

    def cost(v):
        e = e0 + G @ (sc * v)
        return float(e @ W @ e + c.R[0, 0] * sc**2 * v @ v), sc * 2 * (G.T @ (W @ e)) + 2 * c.R[0, 0] * sc**2 * v

    if method == "trust-constr":  # an interior point on the convex QP, its exact Hessian
        r = minimize(cost, np.zeros(H), jac=True, hess=lambda v: 2 * sc**2 * (G.T @ W @ G + c.R[0, 0] * np.eye(H)), method=method,
                     bounds=Bounds(c.u_lb[0] / sc, 1.0), constraints=[LinearConstraint(sc * G[rows], -np.inf, BOUND - (Phi @ x0)[rows])],
                     options={"gtol": 1e-12, "xtol": 1e-14, "maxiter": 5000})
    else:
        r = minimize(cost, np.zeros(H), jac=True, method="SLSQP", bounds=[(c.u_lb[0] / sc, 1.0)] * H,
                     constraints=[{"type": "ineq", "fun": lambda v: BOUND - (Phi @ x0 + G @ (sc * v))[rows],
                                   "jac": lambda v: -sc * G[rows]}],
                     options={"ftol": 1e-15 * max(1.0, cost(np.zeros(H))[0]), "maxiter": 1000})  # ftol is absolute
    assert r.success
    return sc * r.x if whole else sc * r.x[0]


@pytest.mark.parametrize("which", ["soft", "hard"])
@pytest.mark.parametrize("plugin", ["ipopt", "sqpmethod"])
def test_constrained_optimum_agrees_with_scipy(integrator, which, plugin):
    # the bound is active along the horizon; SLSQP's own accuracy limits the agreement to ~1e-5
    _, t, soft, hard, _ = integrator
    c = soft if which == "soft" else hard
    u, _ = c.solve(t[40], FEASIBLE, plugin=plugin, iterations=3)
    ref = _scipy_first_input(c, 40, FEASIBLE)
    assert abs(u[0] - ref) <= 1e-5 * (1 + abs(ref))


def test_soft_penalty_is_exact(integrator):
    # exact penalty: the soft problem's optimum is the hard one's (IPOPT to 1e-10 on both)
    _, t, soft, hard, free = integrator
    u_soft, _ = soft.solve(t[40], FEASIBLE)
    u_hard, _ = hard.solve(t[40], FEASIBLE)
    u_free, _ = free.solve(t[40], FEASIBLE)
    assert abs(u_soft[0] - u_hard[0]) <= 1e-7 * (1 + abs(u_hard[0]))
    assert abs(u_free[0] - u_hard[0]) > 1.0  # and the bound matters here


@pytest.mark.parametrize("which, ok", [("soft", 1.0), ("hard", 0.0)])
def test_infeasible_state_soft_solves_hard_fails(integrator, which, ok):
    # 5 m/s at 5 cm from the bound cannot stop in time: the soft QP still solves, the hard one reports ok = 0
    _, t, soft, hard, _ = integrator
    c = soft if which == "soft" else hard
    u, _, flag = c.function()(t[40], INFEASIBLE, c.u_initial, c.memory_initial)
    assert float(flag) == ok
    assert np.isfinite(float(u))


def _closed_loop(c, ode, t):
    """The MPC's loop-step Function in closed loop with the RK4 plant of the model (no delay)."""
    f = c.function()
    mem = {"w": c.memory_initial}

    def controller(tk, y):
        uk, w_next, ok = f(tk, y, c.u_initial, mem["w"])
        mem["w"] = np.asarray(w_next).ravel()
        return (0 if float(ok) else 6), np.asarray(uk).ravel()

    return run_controller_loop(controller, ode.step(DT, "rk4"), c.x_ref[0], t, c.x_ref, u_lb=c.u_lb, u_ub=c.u_ub, delay=0)


@pytest.mark.parametrize("which", ["free", "soft"])
def test_closed_loop_holds_the_bound(integrator, which):
    # the reference runs to 1 m; the unconstrained MPC follows it past 0.5 m, the soft-constrained one
    # stays below 0.5 m (to 1e-3 m: the slack of the linearised real-time iteration)
    ode, t, soft, _, free = integrator
    run = _closed_loop(soft if which == "soft" else free, ode, t)
    peak = float(np.max(run.x[:, 0]))
    if which == "free":
        assert peak > BOUND + 0.1
    else:
        assert peak <= BOUND + 1e-3
        assert run.status_counts == {"0": t.size}


@pytest.mark.parametrize("table, match", [({"y": 1.0}, r"state_ub\.y: expected a state of the model \(x, v\)"),
                                          ({"x": float("nan")}, r"state_ub\.x: expected a number")])
def test_bad_bound_tables_are_refused(integrator, table, match):
    ode, t, soft, _, _ = integrator
    with pytest.raises(InputError, match=match):
        mpc_controller(ode, t, soft.x_ref, soft.u_ref, x_ub=table)


def test_problem_constraints_of_an_optimal_control_file():
    # the [bounds] of a state as the file states them (here through an override of the file)
    loaded = load_problem(REPO / "problems" / "dc_motor_move.toml", {"bounds": {"src.v": [-24.0, 24.0], "rotor.w": [-90.0, 80.0]}})
    x_lb, x_ub, path, *_ = problem_constraints(loaded.declaration.optimization, ["ind.i", "emf.phi", "rotor.w"], ["src.v"])
    assert (x_lb.tolist(), x_ub.tolist()) == ([-np.inf, -np.inf, -90.0], [np.inf, np.inf, 80.0])
    assert path is None


def test_problem_constraints_of_the_robot():
    # point_to_point's cart travel (|q_i| <= 1 m for L1) and spherical-joint limits, over T, T_dot
    loaded = load_problem(REPO / "problems" / "l1_time_optimal.toml")
    names = [f"T[{i}]" for i in range(3)] + [f"T_dot[{i}]" for i in range(3)]
    _, _, path, lb, ub, labels = problem_constraints(build_optimization(loaded.declaration)[0], names, ["tau[0]", "tau[1]", "tau[2]"])
    assert labels[:3] == ["cart_travel[0]", "cart_travel[1]", "cart_travel[2]"] and labels[3].startswith("joint_angle")
    assert (lb[:3].tolist(), ub[:3].tolist()) == ([-1.0] * 3, [1.0] * 3)
    h = np.asarray(path([-0.2, 2.75, -0.4, 0, 0, 0], [0, 0, 0])).ravel()
    assert np.all(h[:3] > -1.0) and np.all(h[:3] < 1.0) and np.all(h[3:] >= lb[3:])  # the start pose is inside


MULTIPLE_SHOOTING = ["fatrop", "hpipm"]


@pytest.fixture(scope="module")
def multiple_shooting(integrator):
    ode, t, soft, *_ = integrator
    kw = dict(horizon=H, Q=[1.0, 0.0], R=[1e-4], u_lb=[-50.0], u_ub=[50.0], method="euler")
    return {(solver, hard): mpc_controller(ode, t, soft.x_ref, soft.u_ref, x_ub={"x": BOUND}, hard_constraints=hard, solver=solver,
                                           constraint_backoff=False, **kw)  # the rows as declared (no aim inside): SLSQP's problem
            for solver in MULTIPLE_SHOOTING for hard in (False, True)}


@pytest.mark.parametrize("hard", [False, True], ids=["soft", "hard"])
@pytest.mark.parametrize("solver", MULTIPLE_SHOOTING)
def test_multiple_shooting_step_agrees_with_scipy(integrator, multiple_shooting, solver, hard):
    # the multiple-shooting NLP by fatrop (interior point to 1e-8), or hpipm's one real-time iteration (its QP is
    # the horizon problem itself here: linear dynamics, quadratic cost; the soft rows a slack per side and stage),
    # in the loop-step Function against SLSQP
    _, t, soft, *_ = integrator
    c = multiple_shooting[solver, hard]
    u, _, ok = c.function()(t[40], FEASIBLE, c.u_initial, c.memory_initial)
    ref = _scipy_first_input(soft, 40, FEASIBLE)
    # HPIPM's speed_abs mode stops on the complementarity alone (1e-8): on the hard rows, whose multipliers are large,
    # its first input is 1.2e-5 off SLSQP's (the second iteration gets 1e-9)
    tol = 2e-5 if (solver, hard) == ("hpipm", True) else 1e-5
    assert float(ok) == 1.0
    assert abs(float(u) - ref) <= tol * (1 + abs(ref))


@pytest.mark.parametrize("solver", MULTIPLE_SHOOTING)
def test_multiple_shooting_hard_infeasible_fails_soft_solves(multiple_shooting, solver):
    # the safe-input contract: an infeasible hard problem gives ok = 0 (its result violates the rows)
    flags = [float(c.function()(0.16, INFEASIBLE, c.u_initial, c.memory_initial)[2]) for c in (multiple_shooting[solver, False], multiple_shooting[solver, True])]
    assert flags == [1.0, 0.0]


@pytest.mark.parametrize("solver", MULTIPLE_SHOOTING)
def test_multiple_shooting_refuses_input_dependent_constraints(integrator, solver):
    import casadi as ca

    ode, t, soft, *_ = integrator
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u")
    path = ca.Function("h", [x, u], [x[1] + 0.01 * u])
    with pytest.raises(InputError, match=f"solver: {solver} takes state and path constraints of the states only"):
        mpc_controller(ode, t, soft.x_ref, soft.u_ref, path=path, path_ub=[1.0], solver=solver)


def test_hpipm_closed_loop_holds_the_bound(integrator, multiple_shooting):
    # the soft rows of the hpipm step in the loop (a second QP solver for test_closed_loop_holds_the_bound's bound)
    ode, t, *_ = integrator
    run = _closed_loop(multiple_shooting["hpipm", False], ode, t)
    assert float(np.max(run.x[:, 0])) <= BOUND + 1e-3
    assert run.status_counts == {"0": t.size}


@pytest.mark.parametrize("solver", ["sqpmethod", "fatrop", "hpipm"])
def test_constraint_every_kth_state_agrees_with_scipy(integrator, solver):
    # a reference that rises above the bound and falls back within the horizon; rows on x_7, x_14 and
    # x_20 only: SLSQP on the same thinned QP (a second method), whose optimum is not the one
    # constrained on every state (x_1..x_6 may cross the bound)
    ode, t, *_ = integrator
    x_ref = np.column_stack([0.45 + 0.1 * np.sin(2 * np.pi * t / 0.08), 0.1 * 2 * np.pi / 0.08 * np.cos(2 * np.pi * t / 0.08)])
    kw = dict(x_ub={"x": BOUND}, horizon=H, Q=[1e4, 0.0], R=[1e-6], u_lb=[-5e3], u_ub=[5e3], method="euler", hard_constraints=True)
    c = mpc_controller(ode, t, x_ref, np.zeros((t.size, 1)), solver=solver, constraint_every=7, **kw)
    every = mpc_controller(ode, t, x_ref, np.zeros((t.size, 1)), **kw)
    assert c.constraints.stages(H) == [7, 14, 20]
    x0 = x_ref[0]
    _, w = c.solve(t[0], x0, plugin=solver, iterations=3)
    ref = _scipy_first_input(c, 0, x0, stages=[7, 14, 20], whole=True, method="trust-constr")
    assert np.max(np.abs(w - ref)) <= 1e-4 * (1 + np.max(np.abs(ref)))
    assert np.max(np.abs(ref - _scipy_first_input(every, 0, x0, whole=True, method="trust-constr"))) > 1.0  # N: not the everywhere-constrained optimum


def test_constraint_rows_count_the_constrained_states(integrator):
    ode, t, soft, *_ = integrator
    c = mpc_controller(ode, t, soft.x_ref, soft.u_ref, x_ub={"x": BOUND}, horizon=H, constraint_every=7)
    assert (c.constraint_rows, soft.constraint_rows, c.bounds()["lbg"].size) == (3, H, 1 + 3)


@pytest.mark.parametrize("every", [0, -1, 1.5, True])
def test_bad_constraint_every_is_refused(integrator, every):
    ode, t, soft, *_ = integrator
    with pytest.raises(InputError, match="constraint_every: expected an integer >= 1"):
        mpc_controller(ode, t, soft.x_ref, soft.u_ref, x_ub={"x": BOUND}, constraint_every=every)
