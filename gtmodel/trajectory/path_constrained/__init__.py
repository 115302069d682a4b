"""Time-optimal motion along a given TCP path (Dressler (2012), ch. 3.5; Verscheure et al. (2009)).

The TCP follows a geometric path ``T(s)``, ``s`` in ``[0, 1]`` (:mod:`gtmodel.trajectory.path`),
from rest to rest. With ``T_dot = T'(s) s_dot`` and ``T_ddot = T''(s) s_dot^2 + T'(s) s_ddot``
every quantity of the robot becomes a function of the path state; the inverse dynamics of
the CasADi model (:class:`~gtmodel.robots.dynamics.GantryTau3Dynamics`, eqs. 6.7, 6.8) gives::

    tau(s) = m(s) s_ddot + c(s) s_dot^2 + d(s) s_dot + g(s)

where ``g`` holds gravity and Coulomb friction ``f_c sign(q'(s))`` (exact: ``s_dot >= 0`` so
the sign of ``q_dot = q'(s) s_dot`` is that of ``q'(s)``; it is 0 where ``q'(s) = 0``) and
``d = f_v q'(s)`` is viscous friction. The coefficients are extracted from the symbolic
model with ``casadi.jacobian`` (``m = dtau/ds_ddot``, ``c = 1/2 d2tau/ds_dot2``,
``d = dtau/ds_dot - 2 c s_dot`` at ``s_dot = 1``), never from a second hand-written model.
One CasADi Function maps path samples ``(T, T', T'')`` to all constraint coefficients;
path data are its inputs, so sweeps over paths, grids and limit values do not rebuild it.

Two methods are offered.

Convex reformulation (:class:`PathConstrainedProblem`, :func:`solve_path_convex`)
    Verscheure et al. (2009): with ``a = s_ddot`` and ``b = s_dot^2`` the dynamics are
    ``db/ds = 2 a`` and every constraint is ``lo <= m(s) a + c(s) b + d(s) sqrt(b) + g(s)
    <= hi`` -- linear in ``(a, b)`` without viscous friction -- and the duration
    ``integral ds / sqrt(b)`` is convex. On a grid ``s_0 < ... < s_N``, ``a_k`` is constant
    on ``[s_k, s_{k+1}]`` so ``b`` is piecewise linear, ``b_{k+1} = b_k + 2 a_k (s_{k+1} - s_k)``,
    and the duration ``sum_k 2 ds_k / (sqrt(b_k) + sqrt(b_{k+1}))`` is exact for that profile.
    Constraints hold at the grid points ("collocation" discretisation of TOPP-RA): those
    with ``s_ddot`` at ``s_k`` on ``(a_k, b_k)`` for ``k < N`` (the left end of the interval
    where ``a_k`` applies), those on ``b`` only at every grid point; ``b_0 = b_N = 0`` and
    ``b = 0`` at the corners of a polyline. By default (``constrain_end=True``) the rows with
    ``s_ddot`` also hold at ``s_N`` on ``(a_{N-1}, 0)``: the force on arrival, which TOPP-RA
    leaves unchecked and which otherwise exceeds the limit by about ``d sqrt(b_{N-1})``.

    The gridded problem is solved by the reachability (two-pass) method of TOPP-RA
    (Pham & Pham 2018): a backward pass computes the controllable sets ``K_k`` (the
    ``b_k`` from which the end can still be reached at rest), a forward pass takes at every
    step the largest ``b_{k+1}`` in ``K_{k+1}`` reachable from ``b_k``. The one-step problems
    in ``(a, b)`` are not solved as LPs: ``a`` is eliminated exactly (Fourier-Motzkin: for
    fixed ``b`` every row bounds ``a`` from one side, so ``a`` exists iff every lower bound is
    below every upper bound), which leaves closed-form conditions on ``b``: linear, or
    quadratic in ``sqrt(b)`` where viscous friction enters. They are evaluated in plain
    Python floats in the passes (the stage sets that do not depend on the passes are
    computed for all grid points at once with NumPy). Without viscous friction, and where
    the optimality certificate below holds, this is the exact optimum of the gridded
    problem (equal to TOPP-RA's to rounding, and to IPOPT's).

    Viscous friction. ``d sqrt(b)`` is concave in ``b``: in a one-sided row
    ``p a + r b + w sqrt(b) + e <= 0`` it is convex for ``w <= 0`` and not for ``w > 0`` (an
    upper force bound of a motor moving forward, a lower bound of one moving backward).
    The robot model of Verscheure et al. (2009) has Coulomb friction ``F_s(q) sign(q_dot)``,
    which enters ``g``; TOPP-RA handles dry friction only (its maintainer on viscous
    friction, hungpham2511/toppra#92: "the mathematical form becomes non-convex"). Here the
    viscous term is kept *exactly*: after eliminating ``a`` every condition on ``b`` is
    ``P x^2 + Q x + R <= 0`` in ``x = sqrt(b) >= 0``, whose solution set is computed from the
    roots. It is an interval (convex case, or a concave parabola with at most one positive
    root) except when a concave parabola has two positive roots: then the set is
    ``[0, b1] u [b2, inf)``. The part containing rest, ``[0, b1]``, is kept -- an inner
    approximation, so every computed set is a subset of the exact one and the profile is
    always feasible -- and the solution is reported ``"acceptable"`` (not ``"optimal"``)
    whenever the discarded part ``[b2, inf)`` meets the other constraints at that stage.
    This did not happen on the L1 problems of the tests (the second range lies beyond
    other force limits).

    Optimality certificate. The forward step maps ``b_k`` to
    ``u_k(b_k) = min(max K_{k+1}, min_j l_j(b_k))``, ``l_j(b) = b + 2 ds a_j(b)`` for the
    rows ``a <= a_j(b)``. If a piece active at the greedy ``b_k`` (the cap or a row) is
    nowhere above its value at ``b_k`` on ``[min K_k, b_k]``, then no smaller ``b_k`` can
    reach a larger ``b_{k+1}``, and by induction the greedy profile dominates every
    feasible profile grid point by grid point: it is the optimum, since the duration
    decreases in every ``b_k`` (this is TOPP-RA's optimality argument, made a per-step
    check). It holds on straight lines and for the L1 force problems of the tests, but
    fails where a bound on ``s_ddot`` drops steeply with ``s_dot`` -- an axis acceleration
    limit near a point where that axis' tangent vanishes (``|T''_j / T'_j| > 1 / (2 ds)``),
    a force row with ``m`` near 0 -- where the greedy (and TOPP-RA's) profile is feasible
    but slower than the optimum (1e-4 relative on a spline in the tests). There
    :meth:`PathConstrainedProblem.solve` starts IPOPT on the same gridded problem from the
    greedy profile (``method = "reachability+ipopt"``), or reports ``"acceptable"`` with
    ``polish=False``. The IPOPT transcription (:meth:`PathConstrainedProblem.solve_nlp`,
    variables ``s_dot_k``, viscous friction exact) reproduces the certified durations to
    about 1e-8 in the tests (which require 1e-6).

    Discretisation. As in TOPP-RA's collocation scheme, constraints are checked at the
    grid points only. Between them the forces drift with the state: by about
    ``(c b + d sqrt(b))`` across an interval, and right after rest, where ``s_dot`` grows like
    ``sqrt(s)``, by about ``d sqrt(2 a ds)`` (tens of N for the L1 at 500 points); a finer grid
    (or one refined near the ends) reduces it. The gridded duration converges to the
    continuous optimum from below as the grid is refined (roughly like ``1/N``).

Projection method (:func:`solve_path_collocation`)
    The thesis' formulation (Dressler (2012), ch. 3.5, Table 3.1 "path constrained"):
    states ``(s, s_dot)``, input ``s_ddot``, forces from the inverse dynamics along the path,
    free final time, objective ``final_time + w sum_i integral tau_i^2 dt``, declared as a
    :class:`gtmodel.modeling.Optimization` and solved by direct collocation with IPOPT.

Both return a :class:`PathSolution` (python-control ``OptimalControlResult`` style) whose
:meth:`PathSolution.trajectory` resamples the motion every 4 ms.

Modules: :mod:`.constraints` (limits and row bounds), :mod:`.coefficients` (the cached
CasADi Function of the row coefficients), :mod:`.gridding` (grids, the gridded problem),
:mod:`.reachability` (the two passes, interval algebra, certificate), :mod:`.convex`
(:class:`PathConstrainedProblem`, IPOPT polish), :mod:`.collocation` (the projection
method), :mod:`.solution` (:class:`PathSolution`).
"""

from gtmodel.trajectory.path_constrained.constraints import PathConstraints
from gtmodel.trajectory.path_constrained.gridding import GriddedPathProblem, uniform_grid
from gtmodel.trajectory.path_constrained.solution import PathSolution
from gtmodel.trajectory.path_constrained.convex import PathConstrainedProblem, solve_path_convex
from gtmodel.trajectory.path_constrained.collocation import solve_path_collocation

__all__ = [
    "PathConstraints",
    "PathConstrainedProblem",
    "GriddedPathProblem",
    "PathSolution",
    "solve_path_convex",
    "solve_path_collocation",
    "uniform_grid",
]
