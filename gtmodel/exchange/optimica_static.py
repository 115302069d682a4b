"""A static Optimica problem (no states, no inputs) solved as one NLP.

JModelica.org users wrote estimation problems without dynamics in Optimica too: the thesis'
``GTPKinCalib`` (Dressler (2012), ch. 3.5) is a model of data arrays, free kinematic
parameters, residual equations and a ``cost`` to minimise, with ``objective =
cost(finalTime)`` in its ``optimization`` class. Such a problem has the same value at every
time, so collocating it over a horizon only repeats it; :func:`solve_static` solves it once:
the algebraic variables and the free parameters are the variables of one IPOPT NLP, the
model's equations its equality constraints, the objective the ``objective`` expression with
every timed variable ``v(t)`` read as ``v``. After IPOPT, the algebraic variables are
computed again from the equations at the optimal parameters (Newton), so the objective
reported is that of the parameters to round-off, not to IPOPT's constraint tolerance.

Supported: ``objective`` (Mayer) only, free parameters with bounds; a static problem with an
``objectiveIntegrand`` or a ``constraint`` section is refused (:class:`StaticProblemError`).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gtmodel.errors import InputError
from gtmodel.modeling import Optimization

__all__ = ["StaticProblemError", "StaticResult", "solve_static", "is_static"]

_log = logging.getLogger("gtmodel")


class StaticProblemError(InputError):
    """The problem is not a static one :func:`solve_static` solves (states, inputs, constraints)."""


@dataclass
class StaticResult:
    """The solution of a static problem.

    Parameters
    ----------
    status : str
        ``"optimal"`` when IPOPT converged, else IPOPT's return status.
    objective : float
        The objective at the solution (the algebraic variables recomputed from the
        equations at the optimal parameters).
    parameters : dict of str to numpy.ndarray
        The free parameters' optimal values (flattened), by name.
    algebraics : dict of str to numpy.ndarray
        The algebraic variables at the solution (flattened), by name.
    iterations : int
        IPOPT's iterations.
    solve_time : float
        CPU time of the NLP's construction and solve, s.
    message : str
        IPOPT's return status.
    initial_parameters : dict of str to numpy.ndarray
        The free parameters' start values (``initialGuess``), by name.
    """

    status: str
    objective: float
    parameters: dict[str, np.ndarray]
    algebraics: dict[str, np.ndarray]
    iterations: int
    solve_time: float
    message: str = ""
    initial_parameters: dict[str, np.ndarray] = field(default_factory=dict)


def is_static(opt: Optimization) -> bool:
    """Whether the problem's model has neither states nor inputs.

    Parameters
    ----------
    opt : Optimization
        The problem.

    Returns
    -------
    bool
    """
    return not opt.model.variables("state") and not opt.model.variables("input")


def solve_static(opt: Optimization, *, tol: float = 1e-12, max_iter: int = 500) -> StaticResult:
    """Solve a static Optimica problem (no states, no inputs) as one NLP.

    Parameters
    ----------
    opt : Optimization
        The problem, e.g. from :func:`gtmodel.exchange.optimica.load_optimica`.
    tol : float, optional
        IPOPT's ``tol`` (and its constraint tolerance).
    max_iter : int, optional
        IPOPT's iteration limit.

    Returns
    -------
    StaticResult
        Never None; a non-converged solve is a status.

    Raises
    ------
    StaticProblemError
        If the model has states or inputs, or the problem has an integrand, integrals,
        constraints or data fits.
    """
    t_cpu = time.process_time()
    if not is_static(opt):
        raise StaticProblemError(f"{opt.model.name}: not a static problem (it has states or inputs); solve it by collocation")
    lagrange = ca.SX(opt.lagrange)
    if (lagrange.numel() and not (lagrange.is_constant() and float(ca.DM(ca.evalf(lagrange))) == 0.0)) or opt.integrals:
        raise StaticProblemError(f"{opt.model.name}: a static problem with an objectiveIntegrand or integrals is not supported")
    if opt.path_constraints or opt.declared_point_constraints or opt.data_fits:
        raise StaticProblemError(f"{opt.model.name}: a static problem with constraints or data fits is not supported "
                                 "(objective and free parameters only)")
    dae = opt.flat()
    p_value = np.array(dae.p_value, dtype=float).reshape(-1)
    for name, value in opt.parameters.items():
        if name in dae.p_vars:
            p_value[dae.p_vars[name]] = np.ravel(value)
    free_idx, lbs, ubs, starts, names = [], [], [], [], []
    for name, (lb, ub, start) in opt.free_parameters.items():
        sl = dae.p_vars[name]
        idx = np.arange(dae.p.numel())[sl]
        free_idx.append(idx)
        lbs.append(np.broadcast_to(lb, idx.shape))
        ubs.append(np.broadcast_to(ub, idx.shape))
        starts.append(np.clip(p_value[idx] if start is None else np.broadcast_to(start, idx.shape), lbs[-1], ubs[-1]))
        names.append(name)
    fidx = np.concatenate(free_idx) if free_idx else np.zeros(0, dtype=int)
    pf = ca.SX.sym("pf", int(fidx.size))
    p_expr = ca.SX(ca.DM(p_value))
    for k, i in enumerate(fidx):
        p_expr[int(i)] = pf[k]
    t0 = ca.SX(opt.start_time)
    g = ca.substitute(dae.alg_expr, ca.vertcat(dae.t, dae.p), ca.vertcat(t0, p_expr))
    mayer = ca.SX(opt.mayer)
    for v in opt.timed_variables:  # a static problem: v(t) is v
        mayer = ca.substitute(mayer, v.symbol, v.expr)
    mayer = ca.substitute(mayer, ca.vertcat(opt.final_time, dae.t, dae.p), ca.vertcat(ca.SX(opt.final_time_value), t0, p_expr))
    w = ca.vertcat(dae.z, pf)
    if ca.depends_on(ca.vertcat(g, mayer), ca.vertcat(dae.x, dae.u)) if dae.x.numel() + dae.u.numel() else False:
        raise StaticProblemError(f"{opt.model.name}: not a static problem")
    solver = ca.nlpsol("static", "ipopt", {"x": w, "f": mayer, "g": g},
                       {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "ipopt.tol": tol,
                        "ipopt.constr_viol_tol": tol, "ipopt.max_iter": int(max_iter)})
    nz = int(dae.z.numel())
    x0 = np.concatenate([np.ravel(dae.z_start), *starts]) if starts else np.ravel(dae.z_start)
    lbx = np.concatenate([np.full(nz, -np.inf), *lbs]) if lbs else np.full(nz, -np.inf)
    ubx = np.concatenate([np.full(nz, np.inf), *ubs]) if ubs else np.full(nz, np.inf)
    sol = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=0, ubg=0)
    stats = solver.stats()
    w_opt = np.ravel(np.asarray(sol["x"], dtype=float))
    pf_opt = w_opt[nz:]
    z_opt = _polish(g, dae.z, pf, w_opt[:nz], pf_opt)
    objective = float(ca.DM(ca.Function("J", [dae.z, pf], [mayer])(z_opt, pf_opt)))
    status = "optimal" if stats.get("success") else str(stats.get("return_status", "failed"))
    params, initial, o = {}, {}, 0
    for name, idx, st in zip(names, free_idx, starts):
        params[name] = pf_opt[o:o + idx.size].copy()
        initial[name] = np.asarray(st, dtype=float).copy()
        o += idx.size
    algebraics = {name: np.ravel(z_opt)[np.arange(nz)[sl]] for name, sl in dae.z_vars.items()}
    elapsed = time.process_time() - t_cpu
    _log.info("static problem %s: %s, objective %.10g, %d iterations, %.2f CPU-s", opt.model.name, status, objective,
              int(stats.get("iter_count", 0)), elapsed)
    return StaticResult(status, objective, params, algebraics, int(stats.get("iter_count", 0)), elapsed,
                        str(stats.get("return_status", "")), initial)


def _polish(g: ca.SX, z: ca.SX, pf: ca.SX, z0: np.ndarray, pf_opt: np.ndarray) -> np.ndarray:
    """The algebraic variables solving ``g(z, p) = 0`` at the optimal parameters (Newton from IPOPT's)."""
    if not z.numel():
        return z0
    f = ca.Function("g", [z, pf], [g])
    newton = ca.rootfinder("polish", "newton", f, {"abstol": 1e-15, "max_iter": 50, "error_on_fail": False})
    return np.ravel(np.asarray(newton(z0, pf_opt), dtype=float))
