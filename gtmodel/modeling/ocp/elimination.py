"""The algebraic variables eliminated from the collocation NLP (ModelingToolkit's observed equations).

A model composed from library components flattens to a DAE whose algebraic variables are
mostly aliases and explicit linear relations (a drive's flexible joint: 5 states, 1 input,
25 algebraic variables). Where every algebraic variable can be written as an expression
``z = z(t, x, u, p)`` (:func:`~gtmodel.modeling.simulation.explicit.eliminated_algebraics`:
block-triangular form, each block solved by a division or a small linear solve) and the
Jacobian of each block in its own variables is constant (it depends on no state, input,
algebraic variable, time or free parameter: no division by an expression the NLP's search
could make zero; a block may read earlier ones nonlinearly, as a friction torque reads a
speed), the collocation NLP carries only the states, inputs and free parameters
(JModelica's alias and BLT elimination): :func:`reduced_problem` maps the problem and its
model to a problem over a model without algebraic variables,

* the right-hand side, the path constraints, the Lagrange term, the integrals, the point
  constraints (start, final, timed at the start or final time) and the Mayer term with ``z``
  substituted;
* the bounds of the algebraic variables as path constraints on their expressions (imposed,
  as the bounds were, at the collocation points and at the start; with Legendre points at
  the final time too),

which the transcription solves as it is (the same NLP up to the substitution: the
algebraic equations held exactly at the collocation points, and at the start the
variables consistent with the states, as
:func:`~gtmodel.modeling.ocp.collocation_nlp.consistent_algebraics` makes them), and
:meth:`Reduction.algebraics` gives the result its algebraic values back, evaluated at the
solution. The collocation's option ``eliminate_algebraics`` (default True) turns it off.

Kept in the NLP (:func:`reduced_problem` returns None and says why): a nonlinear algebraic
loop, a Jacobian that depends on the motion, algebraic equations that read ``der()`` of a
state, and a timed variable at an interior time that reads an algebraic variable or a
derivative (the NLP interpolates those through their values at the collocation points,
which an expression of the interpolated states would not reproduce).
"""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.modeling.dae import FlatDAE
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.terms import Constraint
from gtmodel.modeling.simulation.explicit import eliminated_algebraics

__all__ = ["Reduction", "reduced_problem", "eliminable", "fill_algebraics"]

_log = logging.getLogger("gtmodel")


def eliminable(opt: Optimization, dae: FlatDAE, free_index: np.ndarray) -> tuple[ca.SX | None, str]:
    """The algebraic variables as expressions of ``(t, x, u, p)``, or None and why not.

    Parameters
    ----------
    opt : Optimization
        The problem (its timed variables are read).
    dae : FlatDAE
        Its flat model.
    free_index : numpy.ndarray of int
        Indices of the free parameter elements in the parameter vector.

    Returns
    -------
    z : casadi.SX or None
        ``(nz, 1)`` expressions of ``dae.t, dae.x, dae.u, dae.p``; None when they are kept.
    reason : str
        Why they are kept (empty when eliminated).
    """
    if not dae.nz:
        return None, "no algebraic variables"
    if dae.nx and ca.depends_on(dae.alg_expr, dae.xdot):
        return None, "the algebraic equations read der() of a state"
    pf = ca.vertcat(*[dae.p[int(i)] for i in free_index]) if free_index.size else ca.SX(0, 1)
    jac = ca.jacobian(dae.alg_expr, dae.z)
    if ca.sprank(jac.sparsity()) < dae.nz:
        return None, "the algebraic equations are structurally singular in the algebraic variables"
    # block triangular form (as the elimination solves it): each block's Jacobian in its own variables
    # must be constant; a nonlinearity in variables solved by earlier blocks (a friction's tanh of a
    # speed) is substituted, as the NLP's constraints held it
    moving = ca.vertcat(dae.t, dae.x, dae.z, dae.u, pf)
    nb, rowperm, colperm, rowblock, colblock, _, _ = jac.sparsity().btf()
    for b in range(nb):
        rows, cols = list(rowperm[rowblock[b]:rowblock[b + 1]]), list(colperm[colblock[b]:colblock[b + 1]])
        jb = jac[rows, cols]
        if ca.depends_on(jb, ca.vertcat(*[dae.z[c] for c in cols])):
            return None, "a nonlinear algebraic loop: a block of the algebraic equations is not linear in its variables"
        if ca.depends_on(jb, moving):
            return None, "the Jacobian of a block of the algebraic equations in its variables is not constant (it depends on the motion)"
    mixed = ca.vertcat(dae.z, dae.xdot)
    for v in opt.timed_variables:
        if v.time not in ("start", "final") and ca.depends_on(v.expr, mixed):
            return None, "a timed variable at an interior time reads an algebraic variable or der() of a state"
    z = eliminated_algebraics(dae)
    if z is None:
        return None, "a nonlinear algebraic loop (solved by Newton's method)"
    return z, ""


class _ReducedOptimization:
    """An :class:`Optimization` as the transcription reads it, its terms over the reduced model.

    The declared terms (constraints, objective, timed variables, integrals) are replaced;
    everything else (times, bounds, free parameters, guesses) is the original's.
    """

    def __init__(self, opt: Optimization, subst: Any, path: list[Constraint], point: list[Constraint]) -> None:
        self._opt = opt
        self.path_constraints = [dataclasses.replace(c, expr=subst(c.expr)) for c in opt.path_constraints] + path
        self.point_constraints = [dataclasses.replace(c, expr=subst(c.expr)) for c in opt.point_constraints] + point
        self.lagrange = subst(opt.lagrange)
        self.mayer = subst(opt.mayer)
        self.timed_variables = [dataclasses.replace(v, expr=subst(v.expr)) for v in opt.timed_variables]
        self.integrals = [dataclasses.replace(v, expr=subst(v.expr)) for v in opt.integrals]

    def special_symbols(self) -> list[Any]:
        """The timed variables and integrals, in the original's order (the same symbols)."""
        return [*self.timed_variables, *self.integrals]

    def __getattr__(self, name: str) -> Any:
        return getattr(self._opt, name)


@dataclasses.dataclass
class Reduction:
    """A problem whose algebraic variables are eliminated, and the way back.

    Parameters
    ----------
    optimization : object
        The problem over the reduced model, read by the transcription as an
        :class:`Optimization` (its terms with ``z`` substituted).
    dae : FlatDAE
        The reduced model: the states, inputs and parameters of the original, no algebraic
        variables, its right-hand side with ``z`` substituted.
    z : casadi.Function
        ``(t, x, u, p) -> z`` of the original model.
    eliminated : int
        Algebraic variables eliminated.
    """

    optimization: Any
    dae: FlatDAE
    z: ca.Function
    eliminated: int

    def algebraics(self, t: np.ndarray, x: np.ndarray, u: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The algebraic variables at given times, states, inputs (rows) and parameters.

        Parameters
        ----------
        t : numpy.ndarray
            Times, shape ``(n,)``.
        x, u : numpy.ndarray
            States ``(n, nx)`` and inputs ``(n, nu)``.
        p : numpy.ndarray
            The model parameter vector (free parameters at their values).

        Returns
        -------
        numpy.ndarray
            ``(n, nz)``.
        """
        t = np.asarray(t, dtype=float).reshape(-1)
        n = t.size
        if not n:
            return np.zeros((0, self.eliminated))
        xs, us = np.asarray(x, dtype=float).reshape(n, -1), np.asarray(u, dtype=float).reshape(n, -1)
        out = self.z.map(n)(t[None, :], xs.T, us.T, np.asarray(p, dtype=float).reshape(-1))
        return np.array(out, dtype=float).reshape(self.eliminated, n).T


def reduced_problem(opt: Optimization, dae: FlatDAE, free_index: np.ndarray, final_bounds: bool = False) -> Reduction | None:
    """The problem with its algebraic variables eliminated (see the module docstring), or None when they are kept.

    Parameters
    ----------
    opt : Optimization
        The problem.
    dae : FlatDAE
        Its flat model.
    free_index : numpy.ndarray of int
        Indices of the free parameter elements in the parameter vector.
    final_bounds : bool, optional
        Impose the bounds of the algebraic variables at the final time too (Legendre
        points: the final time is no collocation point). Default False.

    Returns
    -------
    Reduction or None
        None (with a log line saying why) when the algebraic variables stay in the NLP.
    """
    z_expr, reason = eliminable(opt, dae, free_index)
    if z_expr is None:
        if dae.nz:
            _log.info("collocation of %s: its %d algebraic variables stay in the NLP (%s)", dae.name, dae.nz, reason)
        return None

    def subst(e: ca.SX) -> ca.SX:
        if not isinstance(e, ca.SX):
            e = ca.SX(e)
        if dae.nx and e.numel():
            e = ca.substitute(e, dae.xdot, dae.ode_expr)
        return ca.substitute(e, dae.z, z_expr) if e.numel() else e

    z_lb, z_ub = opt.bounds_vectors(dae, "z")
    path: list[Constraint] = []
    for name, sl in dae.z_vars.items():
        idx = [i for i in range(sl.start, sl.stop) if np.isfinite(z_lb[i]) or np.isfinite(z_ub[i])]
        if idx:
            path.append(Constraint(f"bounds of {name}", z_expr[idx], z_lb[idx].copy(), z_ub[idx].copy()))
    point = [dataclasses.replace(c, at="final") for c in path] if final_bounds else []
    empty = ca.SX(0, 1)
    ode = subst(dae.ode_expr)
    outputs = {k: subst(v) for k, v in dae.output_exprs.items()}
    args = [dae.t, dae.x, empty, dae.u, dae.p]
    reduced = dataclasses.replace(
        dae, z=empty, ode_expr=ode, alg_expr=empty, output_exprs=outputs,
        ode=ca.Function("ode", args, [ode]), alg=ca.Function("alg", args, [empty]),
        outputs=ca.Function("outputs", args, list(outputs.values())),
        z_vars={}, z_names=[], z_start=np.zeros(0), z_lb=np.zeros(0), z_ub=np.zeros(0),
    )
    z_fn = ca.Function("eliminated_algebraics", [dae.t, dae.x, dae.u, dae.p], [z_expr])
    _log.debug("collocation of %s: %d algebraic variables eliminated from the NLP", dae.name, dae.nz)
    return Reduction(_ReducedOptimization(opt, subst, path, point), reduced, z_fn, dae.nz)


def fill_algebraics(colloc: Any, t: np.ndarray, xs: np.ndarray, us: np.ndarray, zs: np.ndarray, pvec: np.ndarray, tf: float,
                    consistent: ca.Function | None, reduction: Reduction | None) -> np.ndarray:
    """The algebraic variables of a collocation result at its mesh times ``t``, as the NLP defines them.

    Eliminated (``reduction``): ``colloc.zc`` (its collocation points) is set in place from the
    states and inputs there, and every mesh time's values are the expressions' at ``(t, xs,
    us)``. Kept: the values at the collocation points are the NLP's (``colloc.evaluate``); at
    the mesh times that are no collocation points (the start; with Legendre points the element
    ends) they are made consistent with the states and inputs there (``consistent``,
    :func:`~gtmodel.modeling.ocp.collocation_nlp.consistent_algebraics`, as in the point
    constraints), the inputs being the element's polynomial (``us``).

    Parameters
    ----------
    colloc : CollocationData
        The result's collocation data (its ``zc`` replaced when eliminated).
    t : numpy.ndarray
        Its mesh times ``(K,)``.
    xs, us, zs : numpy.ndarray
        States ``(K, nx)``, inputs ``(K, nu)`` and algebraic variables there as ``colloc.evaluate``
        interpolates them (``zs`` changed in place when kept).
    pvec : numpy.ndarray
        The model parameter vector (free parameters at their optimal values).
    tf : float
        The final time.
    consistent : casadi.Function or None
        The NLP's consistent algebraics ``(t, x, z_e, u, p, tf) -> z``.
    reduction : Reduction or None
        The elimination, or None when the algebraic variables are NLP variables.

    Returns
    -------
    numpy.ndarray
        ``(K, nz)``.
    """
    if reduction is not None:
        N, d = colloc.elements, colloc.points
        b = colloc.breaks()
        tp = (b[:-1, None] + np.asarray(colloc.tau_root, dtype=float)[None, 1:] * np.diff(b)[:, None]).reshape(-1)
        xp, up = colloc.xc[:, 1:, :].reshape(N * d, -1), colloc.uc.reshape(N * d, -1)
        colloc.zc = reduction.algebraics(tp, xp, up, pvec).reshape(N, d, reduction.eliminated)
        return reduction.algebraics(t, xs, us, pvec)
    if zs.shape[1] and consistent is not None:
        for i in np.flatnonzero([not str(k).startswith("collocation") for k in colloc.point_kinds()]):
            zs[i] = np.asarray(consistent(t[i], xs[i], zs[i], us[i], pvec, tf), dtype=float).reshape(-1)
    return zs
