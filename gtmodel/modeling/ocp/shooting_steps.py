"""The fixed-step integrators of a multiple-shooting interval, on the model's explicit form.

:class:`~gtmodel.modeling.ocp.shooting.ShootingTranscription` integrates each interval of
a model whose algebraic variables can be eliminated symbolically on its explicit form
``xdot = F(t, x, z(t, x, u, p), u, p)``: ``z`` is the expression of
:func:`gtmodel.modeling.simulation.explicit._eliminate` (the elimination that the generated C,
``gtmodel codegen --model``, and the FMU use; block triangular form, each block affine in its
own variables solved in order), so an ODE integrator runs on a DAE without a rootfinder:

* ``"rk"``: classical Runge-Kutta 4 (order 4, explicit), the method of CasADi's ``rk``
  plugin, as one SX function;
* ``"radau"``: the 2-stage Radau IIA method (order 3, L-stable, stiffly accurate; Hairer &
  Wanner, *Solving ODE II*, sec. IV.5), its stage equations solved by the unrolled
  simplified Newton iteration of :meth:`~gtmodel.modeling.simulation.explicit.ExplicitODE.step`
  (the exact Jacobian at the start of the step, factorised once): for stiff models (a DC
  motor's armature, a stiff shaft), whose time constants are shorter than a step.

Both return the states and algebraic variables at every step's end, so that bounds and path
constraints are imposed there (between the shooting nodes, not only at them) and the
result's rows are points the integrator computed.

``"collocation"`` (:func:`collocation_steps`) is gtmodel's own fixed-step Radau IIA
collocation (degree :data:`COLLOCATION_DEGREE`, the scheme of CasADi's ``collocation``
plugin), for DAEs too (the algebraic variables at the stage points are unknowns of the
step's rootfinder, so equations that are not affine in them are solved by Newton's
method). CasADi's plugin starts its rootfinder from the step's start value repeated at
every stage (constants); here the start is an input: the stage values of a simulation of
the initial guess (:meth:`~gtmodel.modeling.ocp.shooting.ShootingTranscription.solve`),
as deviations from the step's start, so that a stiff or nonlinear interval begins its
Newton iteration on a trajectory of the model (the flexible joint's collocation-integrated
shooting failed at iteration 0 from the constants: issue 64).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gtmodel.errors import ModelError
from gtmodel.modeling.dae import FlatDAE
from gtmodel.modeling.simulation.explicit import (
    NEWTON_ITERATIONS,
    NEWTON_TOLERANCE,
    STEP_NEWTON_ITERATIONS,
    _eliminate,
    fixed_step,
)

__all__ = ["ExplicitAlgebraics", "explicit_algebraics", "fixed_steps", "collocation_steps", "stage_grid", "stage_guess",
           "EXPLICIT_INTEGRATORS", "COLLOCATION_DEGREE", "ROOTFINDER_OPTIONS"]

#: Integrators of :func:`fixed_steps` (on the explicit form).
EXPLICIT_INTEGRATORS = ("rk", "radau")
#: Collocation points per step of :func:`collocation_steps` (Radau IIA, order 5).
COLLOCATION_DEGREE = 3
#: Options of the Newton rootfinder of one collocation step (CasADi ``newton``): it stops at
#: ``max |residual| <= abstol`` or a step below ``abstolStep``, and raises when it does not.
ROOTFINDER_OPTIONS = {"max_iter": 50, "abstol": 1e-9, "abstolStep": 1e-12, "line_search": True, "error_on_fail": True}


@dataclass(frozen=True)
class ExplicitAlgebraics:
    """The algebraic variables of a flat DAE as expressions of ``(t, x, u, p)``, or why not.

    Parameters
    ----------
    z : casadi.SX or None
        ``(nz, 1)`` in the DAE's symbols ``t, x, u, p``; None when they cannot be eliminated
        symbolically.
    reason : str
        Why not (empty when eliminated).
    """

    z: ca.SX | None
    reason: str = ""


def explicit_algebraics(dae: FlatDAE) -> ExplicitAlgebraics:
    """Eliminate the algebraic variables of ``dae`` as codegen does (symbolically only).

    Parameters
    ----------
    dae : FlatDAE
        The flattened model.

    Returns
    -------
    ExplicitAlgebraics
        ``z(t, x, u, p)`` when every algebraic block is affine in its own variables (solved
        in block triangular order); otherwise None and the reason (a structurally singular
        system, or the number of variables that only a Newton iteration solves).
    """
    if dae.nz == 0:
        return ExplicitAlgebraics(ca.SX(0, 1))
    try:
        z, _, newton = _eliminate(dae, NEWTON_ITERATIONS, NEWTON_TOLERANCE)
    except ModelError as exc:
        return ExplicitAlgebraics(None, str(exc))
    if newton:
        return ExplicitAlgebraics(None, f"{newton} of its {dae.nz} algebraic variables are solved by a Newton iteration "
                                        "(equations not affine in them)")
    return ExplicitAlgebraics(z)


def fixed_steps(problem: dict[str, ca.SX], steps: int, method: str) -> ca.Function:
    """``steps`` equal steps of ``method`` over ``tau`` in ``[0, 1]``, with the quadratures and every step's end.

    Parameters
    ----------
    problem : dict of str to casadi.SX
        ``x`` (nx, 1) states, ``p`` (np, 1) parameters, ``t`` the scalar normalised time,
        ``ode`` (nx, 1) ``dx/dtau``, ``quad`` (nq, 1) ``dq/dtau``, ``zout`` (nz, 1) the
        algebraic variables as expressions of ``x, p, t``.
    steps : int
        Equal steps.
    method : {"rk", "radau"}
        Classical Runge-Kutta 4, or the 2-stage Radau IIA method by
        :data:`~gtmodel.modeling.simulation.explicit.STEP_NEWTON_ITERATIONS` simplified
        Newton steps (:func:`~gtmodel.modeling.simulation.explicit.fixed_step`, the code of
        :meth:`~gtmodel.modeling.simulation.explicit.ExplicitODE.step`).

    Returns
    -------
    casadi.Function
        ``(x0 (nx,1), z0 (nz,1), p) -> (xf (nx,1), zf (nz,1), qf (nq,1), xs (nx,steps),
        zs (nz,steps), ok (1,1))``: the end, its algebraic variables, the quadratures, the
        states and algebraic variables at the end of each step, and 1 when every stage
        Newton iteration converged (always 1 for ``"rk"``).
    """
    x, p, t, zout = problem["x"], problem["p"], problem["t"], problem["zout"]
    f = ca.Function("rhs", [x, p, t], [problem["ode"], problem["quad"]])
    dt = 1.0 / steps
    n = x.numel()
    xc, tk = ca.SX.sym("x", n), ca.SX.sym("t")
    x_next, dq, ok = fixed_step(lambda xs, ts: (*f(xs, p, ts), ca.SX(1.0)), xc, tk, dt, "rk4" if method == "rk" else "radau2",
                                STEP_NEWTON_ITERATIONS, NEWTON_TOLERANCE)
    z_next = ca.substitute(zout, ca.vertcat(x, t), ca.vertcat(x_next, tk + dt))
    # one step as an SX function, repeated by mapaccum: the graph (and its derivatives) of one step,
    # not of all of them (64 unrolled Radau steps of a 5-state drive took 3.6 GB to build)
    step = ca.Function("step", [xc, p, tk], [x_next, dq, z_next, ok])
    x0, z0, pm = ca.MX.sym("x0", n), ca.MX.sym("z0", zout.numel()), ca.MX.sym("p", p.numel())
    xs, dqs, zs, oks = step.mapaccum("steps", steps)(x0, pm, ca.DM(np.arange(steps) * dt).T)
    return ca.Function("interval", [x0, z0, pm], [xs[:, -1], zs[:, -1], ca.sum2(dqs), xs, zs, ca.mmin(oks)],
                       ["x0", "z0", "p"], ["xf", "zf", "qf", "xs", "zs", "ok"])


def stage_grid(steps: int, degree: int = COLLOCATION_DEGREE) -> tuple[np.ndarray, np.ndarray]:
    """The normalised times of :func:`collocation_steps`: step starts and stage points.

    Parameters
    ----------
    steps : int
        Equal steps over ``[0, 1]``.
    degree : int, optional
        Radau points per step.

    Returns
    -------
    starts : numpy.ndarray
        ``(steps,)`` the start of each step.
    stages : numpy.ndarray
        ``(steps, degree)`` the stage points of each step (the last one its end).
    """
    c = np.array(ca.collocation_points(degree, "radau"), dtype=float)
    starts = np.arange(steps, dtype=float) / steps
    return starts, starts[:, None] + c[None, :] / steps


def collocation_steps(problem: dict[str, ca.SX], steps: int, degree: int = COLLOCATION_DEGREE) -> ca.Function:
    """``steps`` equal Radau IIA collocation steps over ``tau`` in ``[0, 1]``, each solved by a Newton rootfinder.

    Parameters
    ----------
    problem : dict of str to casadi.SX
        ``x`` (nx, 1) states, ``p`` (np, 1) parameters, ``t`` the scalar normalised time,
        ``ode`` (nx, 1) ``dx/dtau``, ``quad`` (nq, 1) ``dq/dtau``; a DAE solved by the
        rootfinder also ``z`` (nz, 1) and ``alg`` (nz, 1) ``0 = alg``; a DAE made explicit
        instead ``zout`` (nz, 1), the algebraic variables as expressions of ``x, p, t``.
    steps : int
        Equal steps.
    degree : int, optional
        Radau collocation points per step (default :data:`COLLOCATION_DEGREE`).

    Returns
    -------
    casadi.Function
        ``(x0 (nx,1), z0 (nz,1), p, dv (m, steps)) -> (xf (nx,1), zf (nz,1), qf (nq,1),
        xs (nx,steps), zs (nz,steps), ok (1,1), xc (nx, steps*degree), zc (nz, steps*degree))``.
        ``dv`` is the guess of each step's stage values (``m = degree (nx + nz')``, ``nz'``
        the algebraic variables in the rootfinder: 0 with ``zout``) as deviations from the
        step's start ``[x; z]`` repeated (zeros: CasADi's constant start); ``xs``/``zs`` the
        step ends, ``xc``/``zc`` every stage point (the points of :func:`stage_grid`), ``ok``
        always 1 (a rootfinder that does not converge raises: :data:`ROOTFINDER_OPTIONS`).
    """
    x, p, t = problem["x"], problem["p"], problem["t"]
    explicit = "zout" in problem
    z = ca.SX(0, 1) if explicit else problem.get("z", ca.SX(0, 1))
    alg = ca.SX(0, 1) if explicit else problem.get("alg", ca.SX(0, 1))
    zout = problem["zout"] if explicit else z
    nx, nz, nzo = x.numel(), z.numel(), zout.numel()
    tau = [0.0, *ca.collocation_points(degree, "radau")]
    C, D, B = (np.array(m, dtype=float) for m in ca.collocation_coeff(tau[1:]))
    dt = 1.0 / steps
    f = ca.Function("dae", [x, z, p, t], [problem["ode"], alg, problem["quad"], zout])
    m = degree * (nx + nz)
    # the residual of one step: collocation equations and algebraic equations at each stage
    v, xs0, ts = ca.SX.sym("v", m), ca.SX.sym("xs0", nx), ca.SX.sym("ts")
    xc = [v[j * (nx + nz): j * (nx + nz) + nx] for j in range(degree)]
    zc = [v[j * (nx + nz) + nx: (j + 1) * (nx + nz)] for j in range(degree)]
    points = [xs0, *xc]
    res, quad, zo = [], 0, []
    for j in range(degree):
        ode_j, alg_j, q_j, zo_j = f(xc[j], zc[j], p, ts + tau[j + 1] * dt)
        slope = sum(C[r, j] * points[r] for r in range(degree + 1))
        res += [slope - dt * ode_j, alg_j]
        quad = quad + B[j] * dt * q_j
        zo.append(zo_j)
    x_end = sum(D[r] * points[r] for r in range(degree + 1))
    residual = ca.Function("residual", [v, xs0, p, ts], [ca.vertcat(*res)])
    after = ca.Function("after", [v, xs0, p, ts], [x_end, quad, ca.horzcat(*xc), ca.horzcat(*zo)])
    root = ca.rootfinder("stages", "newton", residual, dict(ROOTFINDER_OPTIONS))
    # one step on MX: (state [x; z'], p, t, dv) -> (next state, dq, stage x, stage z), repeated by mapaccum
    sm, pm, tm, dvm = ca.MX.sym("s", nx + nz), ca.MX.sym("p", p.numel()), ca.MX.sym("t"), ca.MX.sym("dv", m)
    vsol = root(ca.repmat(sm, degree, 1) + dvm, sm[:nx], pm, tm)
    x_next, dq, xcs, zcs = after(vsol, sm[:nx], pm, tm)
    z_next = vsol[m - nz:] if nz else ca.MX(0, 1)
    step = ca.Function("collocation_step", [sm, pm, tm, dvm], [ca.vertcat(x_next, z_next), dq, xcs, zcs])
    x0, z0, pa = ca.MX.sym("x0", nx), ca.MX.sym("z0", nzo if explicit else nz), ca.MX.sym("p", p.numel())
    dv = ca.MX.sym("dv", m, steps)
    start = ca.vertcat(x0, z0 if nz else ca.MX(0, 1))
    ss, dqs, xcs_all, zcs_all = step.mapaccum("collocation_steps", steps)(start, pa, ca.DM(np.arange(steps) * dt).T, dv)
    ends = [degree * (k + 1) - 1 for k in range(steps)]
    zs = zcs_all[:, ends] if nzo else ca.MX(0, steps)
    xs = ss[:nx, :]
    return ca.Function("interval", [x0, z0, pa, dv], [xs[:, -1], zs[:, -1] if nzo else ca.MX(0, 1), ca.sum2(dqs), xs, zs,
                                                     ca.MX(1.0), xcs_all, zcs_all if nzo else ca.MX(0, steps * degree)],
                       ["x0", "z0", "p", "dv"], ["xf", "zf", "qf", "xs", "zs", "ok", "xc", "zc"])


def stage_guess(problem: dict[str, ca.SX], x0: np.ndarray, z0: np.ndarray, params: np.ndarray, steps: int,
                degree: int = COLLOCATION_DEGREE) -> tuple[np.ndarray, int]:
    """The start of :func:`collocation_steps`' rootfinders: each interval's guess simulated at its stage points.

    Each interval is simulated from its node (its guessed state and algebraic variables) under
    its guessed inputs by a variable-step SUNDIALS integrator (CVODES for an ODE or a DAE made
    explicit, IDAS else), sampled at the step starts and stage points of :func:`stage_grid`,
    and returned as each step's stage values less the step's start (the ``dv`` input of
    :func:`collocation_steps`). An interval whose simulation fails keeps zeros (CasADi's start:
    the step's start value at every stage).

    Parameters
    ----------
    problem : dict of str to casadi.SX
        ``x``, ``p``, ``t`` (normalised time in ``[0, 1]``), ``ode``; a DAE also ``z`` and
        ``alg`` (as for :func:`collocation_steps`, without ``quad`` and ``zout``).
    x0 : numpy.ndarray
        ``(nx, N)`` the node states of the ``N`` intervals.
    z0 : numpy.ndarray
        ``(nz, N)`` their algebraic variables (a guess; IDAS makes them consistent).
    params : numpy.ndarray
        ``(np, N)`` each interval's integrator parameters.
    steps : int
        Steps per interval.
    degree : int, optional
        Stage points per step.

    Returns
    -------
    dv : numpy.ndarray
        ``(degree (nx + nz), steps N)``: interval ``k``'s steps in columns ``k steps`` to
        ``(k + 1) steps - 1``.
    failed : int
        Intervals whose simulation failed (zeros kept).
    """
    nx = problem["x"].numel()
    nz = problem["z"].numel() if "z" in problem else 0
    n_int = x0.shape[1]
    starts, stages = stage_grid(steps, degree)
    grid = np.unique(np.concatenate([starts, stages.reshape(-1)]))
    i_start = np.searchsorted(grid, starts)
    i_stage = np.searchsorted(grid, stages)  # (steps, degree)
    dv = np.zeros((degree * (nx + nz), steps * n_int))
    plugin = "idas" if nz else "cvodes"
    try:
        sim = ca.integrator("stage_guess", plugin, problem, 0.0, grid[1:], {"abstol": 1e-8, "reltol": 1e-6, "max_num_steps": 5000})
    except RuntimeError:
        return dv, n_int
    failed = 0
    for k in range(n_int):
        try:
            out = sim(x0=x0[:, k], z0=z0[:, k] if nz else ca.DM(0, 1), p=params[:, k])
        except RuntimeError:
            failed += 1
            continue
        xs = np.hstack([x0[:, k:k + 1], np.array(out["xf"], dtype=float)])
        zs = np.array(out["zf"], dtype=float) if nz else np.zeros((0, grid.size - 1))
        zs = np.hstack([zs[:, :1], zs]) if nz else np.zeros((0, grid.size))  # at tau = 0: the first output's
        vals = np.vstack([xs, zs])  # (nx + nz, grid)
        if not np.all(np.isfinite(vals)):
            failed += 1
            continue
        for s in range(steps):
            dv[:, k * steps + s] = (vals[:, i_stage[s]] - vals[:, [i_start[s]]]).T.reshape(-1)
    return dv, failed
