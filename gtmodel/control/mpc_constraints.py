"""State bounds and path constraints of a real-time MPC, soft (an exact penalty) or hard.

The constrained quantities ``c(x, u)`` (``m`` scalars: the states with a finite bound, then
the path constraints ``lb <= h(x, u) <= ub``) are imposed on the predicted states
``x_1..x_H`` of the horizon (or every ``every``-th of them and ``x_H``) (with the input of the same period, ``u_{min(j, H-1)}``)
and, with ``between`` (the default of :func:`~gtmodel.control.mpc.mpc_controller`), on the
states after each substep of the prediction within the periods that end there (with the
input held over that period, ``u_{j-1}``): a DC motor's current rises with ``L/R = 1 ms``
inside a 4 ms period under a held voltage, and the flexible-joint drive's MPC, its rows at
the samples only, held 9.98 A of 10 there and drew 13.23 A between them. Each
finite side is one row, scaled by ``sigma_i`` (the spread of ``c_i`` along the reference,
at least ``1e-3 (1 + max |c_i|)``, as the default weights of Bryson's rule):

.. math::

    (c_i(x_j, u_j) - lb_i) / \\sigma_i + s^{lo}_i \\ge 0, \\qquad
    (ub_i - c_i(x_j, u_j)) / \\sigma_i + s^{hi}_i \\ge 0, \\qquad s \\ge 0,

one slack per side and scalar, shared by the stages of the horizon (the largest scaled
violation over the horizon: an L-infinity penalty), with the cost
``rho * sum(s + s^2)``. The linear part makes the penalty exact (Nocedal & Wright,
*Numerical Optimization*, 2nd ed., Thm. 17.3: the constrained optimum whenever a feasible
one exists and ``rho`` exceeds the sum of the constraint's multipliers over the horizon);
the quadratic part keeps the QP's Hessian positive definite in the slacks. The QP stays
feasible whatever the measured state (a disturbance that pushes the state beyond a bound),
so the loop never fails on an infeasible QP. ``hard``: no slacks (the rows ``>= 0`` as
they are; an infeasible QP is then a failure of the step).

The reference problem's bounds and path constraints come from its
:class:`~gtmodel.modeling.Optimization` as the problem file declared them
(:func:`problem_constraints`): the state bounds of ``[bounds]`` (over the model's own), the
path constraints of ``[optimization] constraints`` and, for the robot, those of
:func:`gtmodel.trajectory.point_to_point.build_optimization` (cart travel, spherical-joint
angles, optional velocity limits).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError

__all__ = ["DEFAULT_PENALTY", "MPCConstraints", "mpc_constraints", "problem_constraints"]

#: Default ``rho`` over ``H max_i(Q_ii scale_i^2)`` (the tracking cost of one reference scale of
#: error in the worst state over the whole horizon).
DEFAULT_PENALTY = 1e2


@dataclass
class MPCConstraints:
    """Constrained quantities of an MPC (see the module docstring).

    Parameters
    ----------
    function : casadi.Function
        ``c(x (nx,1), u (nu,1)) -> (m,1)``.
    lb, ub : numpy.ndarray
        ``(m,)`` bounds (one side may be infinite, never both).
    scale : numpy.ndarray
        ``(m,)`` positive scales ``sigma``.
    names : list of str
        ``(m,)`` names (``"T[0]"``, ``"cart_travel[1]"``).
    hard : bool
        No slacks.
    weight : float
        ``rho`` of the penalty (unused when ``hard``).
    every : int
        The predicted states constrained: ``x_j`` for ``j`` a multiple of ``every`` and the
        last, ``x_H`` (1: every predicted state).
    between : bool
        Also the states after each substep of the prediction within the periods ending at a
        constrained ``x_j`` (no effect with one substep per period).
    """

    function: ca.Function = field(repr=False)
    lb: np.ndarray
    ub: np.ndarray
    scale: np.ndarray
    names: list[str]
    hard: bool = False
    weight: float = 1.0
    every: int = 1
    between: bool = False

    def stages(self, horizon: int) -> list[int]:
        """The indices ``j`` (``1..H``) of the predicted states ``x_j`` with constraint rows.

        Parameters
        ----------
        horizon : int
            ``H``.

        Returns
        -------
        list of int
            Increasing, ending with ``H``.
        """
        return [j for j in range(1, horizon + 1) if j % self.every == 0 or j == horizon]

    @property
    def size(self) -> int:
        """Number of constrained scalars ``m``."""
        return int(self.lb.size)

    @property
    def sides(self) -> list[tuple[int, int]]:
        """``(scalar, sign)`` of every finite side: ``+1`` the lower, ``-1`` the upper."""
        return [(i, s) for i in range(self.size) for s, b in ((1, self.lb[i]), (-1, self.ub[i])) if math.isfinite(b)]

    @property
    def n_slack(self) -> int:
        """Slack variables (one per finite side; 0 when hard)."""
        return 0 if self.hard else len(self.sides)

    def rows(self, x: Any, u: Any) -> Any:
        """The scaled rows ``>= 0`` (without slacks) at one stage, in the order of :attr:`sides`.

        Parameters
        ----------
        x, u : casadi.MX or casadi.SX
            ``(nx,1)``, ``(nu,1)`` state and input.

        Returns
        -------
        casadi.MX or casadi.SX
            ``(len(sides), 1)``.
        """
        c = self.function(x, u)
        return ca.vertcat(*[s * (c[i] - (self.lb[i] if s > 0 else self.ub[i])) / float(self.scale[i]) for i, s in self.sides])

    def violation(self, x: Any, u: Any) -> np.ndarray:
        """Scaled violation ``max(lb - c, c - ub, 0) / sigma`` of each scalar at numeric states.

        Parameters
        ----------
        x : array_like
            ``(M, nx)`` states.
        u : array_like
            ``(M, nu)`` inputs.

        Returns
        -------
        numpy.ndarray
            ``(M, m)``.
        """
        c = np.asarray(self.function.map(len(x))(np.asarray(x, float).T, np.asarray(u, float).T)).T.reshape(len(x), -1)
        return np.maximum(np.maximum(self.lb - c, c - self.ub), 0.0) / self.scale


def _bounds_by_name(table: dict[str, Any] | None, names: list[str], label: str, default: float) -> np.ndarray:
    out = np.full(len(names), default)
    for key, value in (table or {}).items():
        if key not in names:
            raise InputError(f"{label}.{key}: expected a state of the model ({', '.join(names)}), got {key!r}")
        v = float(value)
        if math.isnan(v):
            raise InputError(f"{label}.{key}: expected a number, got {value!r}")
        out[names.index(key)] = v
    return out


def problem_constraints(optimization: Any, x_names: list[str], u_names: list[str]) -> tuple[np.ndarray, np.ndarray, ca.Function | None, np.ndarray, np.ndarray, list[str]]:
    """The state bounds and path constraints of a reference problem, over the MPC model's variables.

    Parameters
    ----------
    optimization : gtmodel.modeling.Optimization
        The reference problem as declared by its file (its model's state and input scalar
        names those of the MPC's model).
    x_names, u_names : list of str
        The MPC model's scalar state and input names (the order of ``x``, ``u``).

    Returns
    -------
    x_lb, x_ub : numpy.ndarray
        ``(nx,)`` state bounds (the model's overridden by the file's; ``-inf``/``inf``: none).
    path : casadi.Function or None
        ``h(x, u) -> (nh,1)`` of the path constraints (``None``: none), the problem's
        parameter values substituted, the state derivatives by the model's ODE.
    path_lb, path_ub : numpy.ndarray
        ``(nh,)`` their bounds.
    path_names : list of str
        ``(nh,)`` their names.

    Raises
    ------
    InputError
        A state or input of the problem's model that the MPC's model lacks, or a path
        constraint of the time, the final time, an algebraic variable or a timed value (an
        MPC over states and inputs cannot impose it).
    """
    dae = optimization.flat()
    missing = [n for n in list(dae.x_names) + list(dae.u_names) if n not in x_names + u_names]
    if missing:
        raise InputError(f"reference problem: its variable {missing[0]!r} is not one of the MPC model's ({', '.join(x_names + u_names)})")
    lb, ub = optimization.bounds_vectors(dae, "x")
    x_lb, x_ub = np.full(len(x_names), -np.inf), np.full(len(x_names), np.inf)
    for i, n in enumerate(dae.x_names):
        x_lb[x_names.index(n)], x_ub[x_names.index(n)] = lb[i], ub[i]
    cons = optimization.path_constraints
    if not cons:
        return x_lb, x_ub, None, np.zeros(0), np.zeros(0), []
    x = ca.SX.sym("x", len(x_names))
    u = ca.SX.sym("u", len(u_names))
    pv = dae.parameter_vector(optimization.parameters)
    e = ca.vertcat(*[c.expr for c in cons])
    if dae.nx and ca.depends_on(e, dae.xdot):
        e = ca.substitute(e, dae.xdot, dae.ode_expr)
    for label, sym in (("the time", dae.t), ("the final time", optimization.final_time),
                       ("an algebraic variable", dae.z if dae.nz else ca.SX(0, 1)),
                       *[(f"the timed value {v.symbol}", v.symbol) for v in optimization.special_symbols()]):
        if sym.numel() and ca.depends_on(e, sym):
            names = ", ".join(c.name for c in cons)
            raise InputError(f"reference problem: a path constraint ({names}) depends on {label}; the MPC imposes "
                             "constraints of states and inputs only (give mpc.problem_constraints = false)")
    xs = ca.vertcat(*[x[x_names.index(n)] for n in dae.x_names]) if dae.nx else ca.SX(0, 1)
    us = ca.vertcat(*[u[u_names.index(n)] for n in dae.u_names]) if dae.nu else ca.SX(0, 1)
    e = ca.substitute([e], [dae.x, dae.u, dae.p], [xs, us, ca.DM(pv)])[0]
    path = ca.Function("path", [x, u], [e], ["x", "u"], ["h"])
    names = [c.name if c.expr.numel() == 1 else f"{c.name}[{k}]" for c in cons for k in range(c.expr.numel())]
    return x_lb, x_ub, path, np.concatenate([c.lb for c in cons]), np.concatenate([c.ub for c in cons]), names


def mpc_constraints(
    x_names: list[str],
    u_names: list[str],
    x_ref: np.ndarray,
    u_ref: np.ndarray,
    x_lb: Any = None,
    x_ub: Any = None,
    path: ca.Function | None = None,
    path_lb: Any = None,
    path_ub: Any = None,
    path_names: list[str] | None = None,
    hard: bool = False,
    weight: float | None = None,
    cost_scale: float = 1.0,
    every: int = 1,
    between: bool = False,
) -> MPCConstraints | None:
    """The constrained quantities of an MPC: state bounds and path constraints (see the module docstring).

    Parameters
    ----------
    x_names, u_names : list of str
        Scalar names of the states and inputs.
    x_ref, u_ref : numpy.ndarray
        ``(N, nx)``, ``(N, nu)`` the reference (for the scales).
    x_lb, x_ub : array_like or dict, optional
        ``(nx,)`` state bounds, or tables ``{state name: bound}`` (``-inf``/``inf``: none).
    path : casadi.Function, optional
        ``h(x, u) -> (nh,1)``.
    path_lb, path_ub : array_like, optional
        ``(nh,)`` bounds of ``h``.
    path_names : list of str, optional
        Names of the rows of ``h``.
    hard : bool, optional
        Hard constraints (no slacks; default soft).
    weight : float, optional
        ``rho``; default ``DEFAULT_PENALTY * cost_scale``.
    cost_scale : float, optional
        ``H max_i(Q_ii scale_i^2)`` of the tracking cost.
    every : int, optional
        Constrain every ``every``-th predicted state and the last (default 1: all of them;
        fewer rows, a cheaper QP, where the constraints are far from active between them).
    between : bool, optional
        Also constrain the states after each substep of the prediction (default False; see
        :class:`MPCConstraints`).

    Returns
    -------
    MPCConstraints or None
        ``None`` when no side is finite.

    Raises
    ------
    InputError
        An unknown state name in a table, bounds of the wrong size, ``lb > ub``, a
        non-positive weight, ``every < 1``.
    """
    if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
        raise InputError(f"constraint_every: expected an integer >= 1, got {every!r}")
    nx, nu = len(x_names), len(u_names)
    lbx = _bounds_by_name(x_lb, x_names, "state_lb", -np.inf) if isinstance(x_lb, dict) or x_lb is None else np.asarray(x_lb, float).reshape(-1)
    ubx = _bounds_by_name(x_ub, x_names, "state_ub", np.inf) if isinstance(x_ub, dict) or x_ub is None else np.asarray(x_ub, float).reshape(-1)
    if lbx.size != nx or ubx.size != nx or np.any(lbx > ubx):
        raise InputError(f"state_lb, state_ub: expected {nx} bounds each with lb <= ub")
    keep = np.flatnonzero(np.isfinite(lbx) | np.isfinite(ubx))
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    exprs, lb, ub, names = [x[int(i)] for i in keep], list(lbx[keep]), list(ubx[keep]), [x_names[int(i)] for i in keep]
    if path is not None:
        h = path(x, u)
        plb = np.broadcast_to(np.asarray(-np.inf if path_lb is None else path_lb, float), (h.numel(),))
        pub = np.broadcast_to(np.asarray(np.inf if path_ub is None else path_ub, float), (h.numel(),))
        if np.any(plb > pub):
            raise InputError("path_lb, path_ub: expected lb <= ub")
        pn = path_names or [f"path[{k}]" for k in range(h.numel())]
        for k in range(h.numel()):
            if math.isfinite(plb[k]) or math.isfinite(pub[k]):
                exprs.append(h[k])
                lb.append(plb[k])
                ub.append(pub[k])
                names.append(pn[k])
    if not exprs:
        return None
    f = ca.Function("c", [x, u], [ca.vertcat(*exprs)], ["x", "u"], ["c"])
    c = np.asarray(f.map(len(x_ref))(np.asarray(x_ref, float).T, np.asarray(u_ref, float).T)).T.reshape(len(x_ref), -1)
    scale = np.maximum(np.ptp(c, axis=0), 1e-3 * (1.0 + np.max(np.abs(c), axis=0)))
    rho = DEFAULT_PENALTY * float(cost_scale) if weight is None else float(weight)
    if not (math.isfinite(rho) and rho > 0):
        raise InputError(f"constraint_weight: expected a positive penalty weight, got {weight!r}")
    return MPCConstraints(function=f, lb=np.asarray(lb), ub=np.asarray(ub), scale=scale, names=names, hard=bool(hard), weight=rho, every=int(every),
                          between=bool(between))
