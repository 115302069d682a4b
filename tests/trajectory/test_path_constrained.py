"""Path-constrained time-optimal motion: reachability solver, IPOPT cross-check, collocation.

Independent references, named in each test: the analytic trapezoidal profile, the IPOPT
transcription of the same gridded problem (:meth:`PathConstrainedProblem.solve_nlp`), the
inverse dynamics of :class:`GantryTau3Dynamics` evaluated directly, finite differences of
the inverse kinematics, dense numerical quadrature, and the collocation (projection)
method of Dressler (2012), ch. 3.5.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError, SolverError, UnreachablePoseError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.trajectory.path import Polyline, SplinePath, StraightLine
from gtmodel.trajectory.path_constrained import (
    PathConstrainedProblem,
    PathConstraints,
    solve_path_collocation,
    solve_path_convex,
    uniform_grid,
)
from gtmodel.trajectory.path_constrained.reachability import _interval, _intervals

# analytic trapezoid: the gridded optimum converges to T* = 1 s like ds^2
TRAPEZOID_TOL = {100: 1e-4, 500: 5e-6}
LIMIT_REL_TOL = 1e-9  # sampled |velocity|, |acceleration| vs limit (rounding only)
NLP_REL_TOL = 1e-6  # reachability vs IPOPT on the same grid (IPOPT tol 1e-10)
DYNAMICS_REL_TOL = 1e-9  # coefficient form vs direct inverse dynamics (same model, rounding)
FD_STEP = 1e-6
FD_TOL = 1e-6  # central differences of q(s): truncation ~ h^2 q''' plus rounding ~ eps/h
ENERGY_QUAD_TOL = 1e-4  # Gauss-Legendre energy vs dense trapezoidal rule
AT_BOUND = 0.99  # a force counts as "at its bound" above 99 % of the limit
# collocation: the degree-2 input polynomial through bang-bang values overshoots between the
# collocation points (observed 11 % near the end of the L1 motion at 50 elements; cf.
# point_to_point's documented 28 %); the bounds themselves hold at the collocation points
COLLOCATION_OVERSHOOT = 0.15

L1_START = np.array([-0.2, 2.75, -0.4])
L1_END = np.array([0.2, 3.0, -0.6])
L1_FORCE = 450.0


# ----------------------------------------------------------------------------- kinematic limits
@pytest.fixture(scope="module")
def trapezoid_problem():
    line = StraightLine([0.0, 0.0, 0.0], [0.8, 0.3, -0.2])
    return PathConstrainedProblem(line, PathConstraints(tcp_velocity_limit=1.0, tcp_acceleration_limit=5.0))


@pytest.mark.parametrize("points", sorted(TRAPEZOID_TOL))
def test_trapezoid_duration_and_limits(trapezoid_problem, points):
    """Reference: the analytic trapezoid. The x axis binds (0.8 m at 1 m/s, 5 m/s^2):
    T* = D / v + v / a = 0.8 + 0.2 = 1.000 s."""
    sol = trapezoid_problem.solve(points)
    assert sol.status == "optimal", sol.message
    T_star = 0.8 / 1.0 + 1.0 / 5.0
    assert abs(sol.final_time - T_star) <= TRAPEZOID_TOL[points]
    assert sol.final_time >= T_star - 1e-12  # constant coefficients: the gridded profile is feasible, cannot beat T*
    tr = sol.trajectory()
    assert np.all(np.abs(tr["T_dot"]) <= 1.0 * (1 + LIMIT_REL_TOL))
    assert np.all(np.abs(tr["T_ddot"]) <= 5.0 * (1 + LIMIT_REL_TOL))
    assert np.max(np.abs(tr["T_dot"][:, 0])) == pytest.approx(1.0, rel=1e-9)
    np.testing.assert_allclose(tr["T"][[0, -1]], [[0, 0, 0], [0.8, 0.3, -0.2]], atol=1e-12)
    np.testing.assert_allclose(np.diff(tr["t"][:-1]), 0.004, rtol=1e-9)
    assert tr["t"][-1] == pytest.approx(sol.final_time, rel=1e-15)


def test_trapezoid_reachability_equals_ipopt(trapezoid_problem):
    """Reference: IPOPT on the same gridded problem (independent guess)."""
    gp = trapezoid_problem.gridded(100)
    a = trapezoid_problem.solve(gp)
    b = trapezoid_problem.solve_nlp(gp)
    assert b.status == "optimal", b.message
    assert abs(a.final_time - b.final_time) <= NLP_REL_TOL * b.final_time


@pytest.mark.parametrize("points", [100, 500])
def test_tight_ipopt_lands_on_the_gridded_optimum(points):
    """Reference: IPOPT (an interior-point method on the same grid) with tol 1e-14 and
    unrelaxed bounds; the reachability optimum is exact, so the two agree to 1e-12
    relative (1e-6 ppm), the benchmark's line case (issue 17)."""
    problem = PathConstrainedProblem(StraightLine([0.0, 0.0, 0.0], [0.8, 0.3, -0.2]),
                                     PathConstraints(tcp_velocity_limit=1.0, tcp_acceleration_limit=5.0), constrain_end=False)
    gp = problem.gridded(points)
    loose, tight = problem.solve_nlp(gp), problem.solve_nlp(gp, tol=1e-14)
    exact = problem.solve(gp).final_time
    assert tight.status == "optimal", tight.message
    assert abs(tight.final_time - exact) <= 1e-12 * exact
    # the NLP is rebuilt for other options (it was once cached by grid size alone, so a
    # second tol was silently ignored): the loose solve stops measurably farther away
    assert abs(loose.final_time - exact) > abs(tight.final_time - exact)


def test_polyline_stops_at_the_corner():
    """Reference: two analytic rest-to-rest trapezoids, 0.5 m along x (0.5 + 0.2 s) and
    0.4 m along y (0.4 + 0.2 s); the corner is a grid point with s_dot = 0."""
    poly = Polyline([[0, 0, 0], [0.5, 0, 0], [0.5, 0.4, 0]])
    problem = PathConstrainedProblem(poly, PathConstraints(tcp_velocity_limit=1.0, tcp_acceleration_limit=5.0))
    sol = problem.solve(1001)
    k = int(np.argmin(np.abs(sol.s - poly.corners[0])))
    assert sol.s[k] == poly.corners[0]
    assert sol.s_dot[k] == 0.0
    assert abs(sol.final_time - 1.3) <= 1e-5
    np.testing.assert_allclose(uniform_grid(poly, 5), np.sort(np.append(np.linspace(0, 1, 5), 5 / 9)))


# ----------------------------------------------------------------------------- the L1 problem
@pytest.fixture(scope="module")
def l1_problem():
    line = StraightLine(L1_START, L1_END)
    return PathConstrainedProblem(line, PathConstraints(force_limit=L1_FORCE), robot="L1", configuration=0)


@pytest.fixture(scope="module")
def l1_solution(l1_problem):
    return l1_problem.solve(500)


@pytest.mark.parametrize("points, constrain_end", [(100, True), (300, True), (300, False)])
def test_l1_reachability_equals_ipopt(l1_problem, points, constrain_end):
    """Reference: IPOPT on the same gridded problem, viscous friction exact in s_dot
    (exact Coulomb friction sign(q'(s)) in both), with and without the rows at the end."""
    problem = l1_problem if constrain_end else PathConstrainedProblem(l1_problem.path, l1_problem.constraints, robot="L1", constrain_end=False)
    gp = problem.gridded(points)
    a = problem.solve(gp)
    b = problem.solve_nlp(gp)
    assert a.status == "optimal", a.message
    assert b.status == "optimal", b.message
    assert abs(a.final_time - b.final_time) <= NLP_REL_TOL * b.final_time
    np.testing.assert_allclose(a.s_dot, b.s_dot, atol=1e-3 * np.max(b.s_dot))
    assert a.max_constraint_violation <= 1e-12
    assert b.max_constraint_violation <= 1e-8


def test_l1_force_on_arrival_is_within_the_limit(l1_solution):
    """With constrain_end the force at the last sample (s = 1, at rest, the last s_ddot)
    satisfies the limit; it is evaluated by the model's inverse dynamics."""
    tr = l1_solution.trajectory()
    assert tr["s_dot"][-1] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.abs(tr["tau"][-1]) <= L1_FORCE * (1 + LIMIT_REL_TOL))


def test_l1_shape_motor_3_at_its_bound(l1_solution):
    """Reference: Dressler (2012), ch. 3.5 -- the path-constrained solution has motor 3 at its
    bound. With these L1 parameters motor 3 (heaviest cart, largest friction and gravity
    load) is at its bound most of the time, although motor 2 travels farthest here."""
    tr = l1_solution.trajectory()
    at_bound = np.abs(tr["tau"]) >= AT_BOUND * L1_FORCE
    assert at_bound[:, 2].mean() > 0.8
    assert at_bound[:, 0].mean() < 0.05
    travel = np.abs(tr["q"][-1] - tr["q"][0])
    assert int(np.argmax(travel)) == 1  # motor 2 travels farthest with these parameters (see docstring)


def test_l1_forces_are_the_inverse_dynamics(l1_solution):
    """Reference: GantryTau3Dynamics.inverse_dynamics (exact friction) on the sampled motion;
    equal where s_dot > 0 (there sign(q_dot) = sign(q'(s)))."""
    tr = l1_solution.trajectory()
    moving = tr["s_dot"] > 1e-6
    dyn = GantryTau3Dynamics("L1", friction="exact")
    tau = dyn.inverse_dynamics(tr["T"][moving], tr["T_dot"][moving], tr["T_ddot"][moving], 0)
    np.testing.assert_allclose(tr["tau"][moving], tau, rtol=DYNAMICS_REL_TOL, atol=DYNAMICS_REL_TOL * L1_FORCE)
    kin = GantryTau3Kinematics("L1")
    q, q_dot, _ = kin.cart_motion(tr["T"], tr["T_dot"], tr["T_ddot"], 0)
    np.testing.assert_allclose(tr["q"], q, atol=1e-12)
    np.testing.assert_allclose(tr["q_dot"], q_dot, atol=1e-9)


def test_l1_energy_is_the_integral_of_the_forces(l1_solution):
    """Reference: the trapezoidal rule on a dense sampling of sum tau^2."""
    t = np.linspace(0.0, l1_solution.final_time, 20001)
    dense = np.trapezoid(np.sum(l1_solution.sample(t)["tau"] ** 2, axis=1), t)
    assert abs(dense - l1_solution.energy) <= ENERGY_QUAD_TOL * dense


def test_cart_rows_match_finite_differences_of_the_ik():
    """Reference: central differences of GantryTau3Kinematics.ik along the path for
    q'(s) (velocity rows c = q'^2) and q''(s) (acceleration rows c = q'')."""
    line = SplinePath([L1_START, [0.0, 2.9, -0.45], [0.1, 2.85, -0.55], L1_END])
    problem = PathConstrainedProblem(line, PathConstraints(cart_velocity_limit=1.0, cart_acceleration_limit=10.0), robot="L1")
    gp = problem.gridded(np.linspace(0, 1, 11))
    kin = GantryTau3Kinematics("L1")
    s = gp.s[1:-1]
    qp, qm, q0 = kin.ik(line(s + FD_STEP)), kin.ik(line(s - FD_STEP)), kin.ik(line(s))
    dq = (qp - qm) / (2 * FD_STEP)
    ddq = (qp - 2 * q0 + qm) / FD_STEP**2
    np.testing.assert_allclose(gp.c[1:-1, :3], dq**2, rtol=FD_TOL, atol=FD_TOL)
    np.testing.assert_allclose(gp.m[1:-1, 3:], dq, rtol=FD_TOL, atol=FD_TOL)
    np.testing.assert_allclose(gp.c[1:-1, 3:], ddq, rtol=1e-3, atol=1e-3)  # second difference: ~eps/h^2


def test_curved_path_with_cart_limits_equals_ipopt():
    """Reference: IPOPT on the same gridded problem; a spline (varying coefficients, viscous
    friction) with force and cart velocity limits."""
    line = SplinePath([L1_START, [0.0, 2.9, -0.45], [0.1, 2.85, -0.55], L1_END])
    problem = PathConstrainedProblem(line, PathConstraints(force_limit=L1_FORCE, cart_velocity_limit=0.6), robot="L1")
    gp = problem.gridded(150)
    a = problem.solve(gp)
    b = problem.solve_nlp(gp)
    assert a.status == "optimal", a.message
    assert b.status == "optimal", b.message
    assert abs(a.final_time - b.final_time) <= NLP_REL_TOL * b.final_time


def test_uncertified_greedy_steps_are_polished_to_the_optimum():
    """Reference: IPOPT on the same gridded problem from its own (sine) guess. A spline with
    per-axis acceleration limits: near points where T'_y or T'_z vanishes the bound on the
    next s_dot falls steeply with the current one, the greedy step is not certified, and
    the greedy profile (TOPP-RA's) is slower than the optimum."""
    spline = SplinePath([[0, 0, 0], [0.3, 0.2, 0], [0.6, 0.1, 0.2], [1, 0.4, 0.1]])
    problem = PathConstrainedProblem(spline, PathConstraints(tcp_speed_limit=0.8, tcp_acceleration_limit=3.0))
    gp = problem.gridded(300)
    greedy = problem.solve(gp, polish=False)
    polished = problem.solve(gp)
    reference = problem.solve_nlp(gp)
    assert greedy.status == "acceptable" and "not proven optimal" in greedy.message and "grid point 89" in greedy.message
    assert polished.status == "optimal" and polished.method == "reachability+ipopt", polished.message
    assert abs(polished.final_time - reference.final_time) <= NLP_REL_TOL * reference.final_time
    assert greedy.final_time > reference.final_time * (1 + 1e-5)  # what the polish buys here
    assert greedy.max_constraint_violation <= 1e-12  # the greedy profile is feasible


# ----------------------------------------------------------------------------- failures
def test_force_limit_below_gravity_and_friction_is_infeasible(l1_problem):
    """Motor 3 needs ~106 N against gravity plus 195 N Coulomb friction to move: 300 N cannot
    start the motion; the message names grid point 0 (s = 0) and the constraint."""
    problem = PathConstrainedProblem(l1_problem.path, PathConstraints(force_limit=300.0), robot="L1")
    sol = problem.solve(100)
    assert sol.status == "infeasible"
    assert not sol.success
    assert "grid point 0 (s = 0)" in sol.message and "tau3 <= 300" in sol.message
    assert np.isnan(sol.final_time)
    with pytest.raises(SolverError, match="infeasible"):
        sol.trajectory()


def test_path_outside_the_workspace_is_rejected():
    with pytest.raises(UnreachablePoseError, match="leaves the workspace at s = "):
        PathConstrainedProblem(StraightLine(L1_START, [0.2, 7.0, -0.6]), PathConstraints(force_limit=L1_FORCE), robot="L1")


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda p: p.solve(1), "at least 2 grid points"),
        (lambda p: p.solve([0.0]), "at least 2 grid points"),
        (lambda p: p.solve([0.0, 0.5, 0.4, 1.0]), "strictly increasing"),
        (lambda p: p.solve([0.0, 0.5, 0.5, 1.0]), "strictly increasing"),
        (lambda p: p.solve([0.1, 0.5, 1.0]), "start at s = 0 and end at s = 1"),
        (lambda p: p.solve(2.5), "at least 2 grid points|number of points"),
        (lambda p: PathConstraints(tcp_velocity_limit=-1.0), "expected positive limits"),
        (lambda p: PathConstraints(force_limit=[450, -1, 450]), "expected positive limits"),
        (lambda p: PathConstraints(tcp_acceleration_limit=[1, 2]), "three finite numbers"),
        (lambda p: PathConstraints(), "no limit given"),
        (lambda p: PathConstrainedProblem(p.path, PathConstraints(force_limit=450.0)), "need a robot"),
        (lambda p: PathConstrainedProblem(Polyline([[0, 0, 0], [1, 0, 0], [1, 1, 0]]), PathConstraints(tcp_speed_limit=1.0)).solve([0, 0.3, 1]), "corner"),
        (lambda p: p.solve(100).trajectory(dt=0.0), "dt: expected a positive"),
    ],
)
def test_bad_arguments(trapezoid_problem, call, match):
    with pytest.raises(InputError, match=match):
        call(trapezoid_problem)


def test_collocation_rejects_corners():
    with pytest.raises(InputError, match="without corners"):
        solve_path_collocation(Polyline([[-0.2, 2.75, -0.4], [0.0, 2.9, -0.45], [0.2, 3.0, -0.6]]), "L1", [L1_FORCE] * 3)


def test_solve_path_convex_shorthand(trapezoid_problem):
    sol = solve_path_convex(trapezoid_problem.path, trapezoid_problem.constraints, grid=100)
    assert sol.final_time == trapezoid_problem.solve(100).final_time


# ----------------------------------------------------------------------------- collocation
@pytest.fixture(scope="module")
def collocation_solutions():
    line = StraightLine(L1_START, L1_END)
    return {el: solve_path_collocation(line, "L1", [L1_FORCE] * 3, w=0.0, elements=el) for el in (25, 50)}


def test_collocation_agrees_with_the_convex_method(l1_problem, collocation_solutions):
    """Reference: the convex method, extrapolated in the grid (its duration converges like
    1/N from below), against the thesis' projection method by collocation (Dressler (2012),
    ch. 3.5, the "path constrained" row of Table 3.1 with w = 0). They must agree within
    the two discretisation errors: |T(50 el) - T(25 el)| for the collocation and
    |T(4000) - T(2000)| for the convex grid."""
    c25, c50 = collocation_solutions[25], collocation_solutions[50]
    assert c25.status == "optimal" and c50.status == "optimal", (c25.message, c50.message)
    t2000, t4000 = (l1_problem.solve(n).final_time for n in (2000, 4000))
    convex_limit = t4000 + (t4000 - t2000)
    bound = abs(c50.final_time - c25.final_time) + abs(t4000 - t2000)
    assert abs(c50.final_time - convex_limit) <= bound
    at_mesh = c50.sample(c50.t)
    assert np.all(np.abs(at_mesh["tau"]) <= L1_FORCE * (1 + 1e-6))  # bounds hold at the collocation points
    tr = c50.trajectory()
    assert np.all(np.abs(tr["tau"]) <= L1_FORCE * (1 + COLLOCATION_OVERSHOOT))  # polynomial s_ddot between them
    assert (np.abs(tr["tau"][:, 2]) >= AT_BOUND * L1_FORCE).mean() > 0.7
    assert tr["s"][0] == pytest.approx(0.0, abs=1e-9) and tr["s"][-1] == pytest.approx(1.0, abs=1e-9)
    assert np.isfinite(c50.energy) and c50.energy > 0


# ----------------------------------------------------------------------------- closed forms
def test_interval_closed_forms_match_brute_force():
    """Reference: membership of {b >= 0 : P b + Q sqrt(b) + R <= 0} on a dense grid of b.

    The returned set is ``[lo, hi]``, plus ``[b2, inf)`` where the set splits in two (then
    ``[lo, hi]`` is the part that contains rest); the scalar and vectorised forms agree."""
    rng = np.random.default_rng(7)
    P = rng.normal(size=400) * (rng.random(400) > 0.1)  # some exact zeros
    Q = rng.normal(size=400) * 3 * (rng.random(400) > 0.2)
    R = rng.normal(size=400) * 2
    x = np.linspace(0.0, 12.0, 24001)
    b = x**2
    lo_v, hi_v, b2_v = _intervals(P, Q, R)
    assert np.sum(np.isfinite(b2_v)) >= 10 and np.sum(lo_v > hi_v) >= 10  # split and empty sets are covered
    lo, hi, b2 = np.array([_interval(float(p), float(q), float(r)) for p, q, r in zip(P, Q, R)]).T
    np.testing.assert_array_equal(lo > hi, lo_v > hi_v)  # empty in both forms
    full = lo <= hi
    assert lo[full] == pytest.approx(lo_v[full], rel=1e-12, abs=1e-12)
    assert hi[full] == pytest.approx(hi_v[full], rel=1e-12, abs=1e-12)
    assert b2 == pytest.approx(b2_v, rel=1e-12)
    val = P[:, None] * b + Q[:, None] * x + R[:, None]
    inside = val <= 0
    claimed = (b >= lo[:, None]) & (b <= hi[:, None]) | (b >= b2[:, None])
    # away from the boundary points (rounding) membership must agree
    margin = np.abs(val) > 1e-9 * (1 + np.abs(P)[:, None] * b + np.abs(Q)[:, None] * x + np.abs(R)[:, None])
    disagree = np.flatnonzero(np.any(margin & (inside != claimed), axis=1))
    assert disagree.size == 0, [(P[k], Q[k], R[k], lo[k], hi[k], b2[k]) for k in disagree]
    split = np.isfinite(b2)
    np.testing.assert_array_equal(lo[split], 0.0)
    assert np.all(hi[split] < b2[split])
