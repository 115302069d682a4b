"""The MPC's horizon problem by multiple shooting in fatrop's stage order (``solver = "fatrop"``).

The same optimal control problem as :mod:`gtmodel.control.mpc` (one input per period:
no move blocking), with the predicted states as variables (Bock & Plitt, IFAC 1984):
stage ``k = 0..H-1`` holds ``x_k``, ``u_k`` and the slacks ``s_k`` of the soft constraints
on ``x_k`` (``k >= 1``) and inside period ``k``, its rows are the gap ``x_{k+1} - F(x_k, u_k) = 0``, then (``k = 0``)
the initial condition ``x_0 - x = 0``, then (``k >= 1``) the constraint rows of
:class:`~gtmodel.control.mpc_constraints.MPCConstraints` at ``(x_k, u_k)`` and (with ``between``)
those of the states after the prediction's substeps inside period ``k``
(:func:`~gtmodel.control.mpc_nlp.period_states`, functions of ``x_k``, ``u_k``); stage ``H``
holds ``x_H``, the slacks of its constraint rows and those rows, and a last stage ``H + 1``
only ``x_{H+1} = x_H`` (the gap rows of stage ``H``: fatrop's last stage has no inputs to
hold slacks). The constraints must not depend on the input (the single shooting imposes
them at ``(x_H, u_{H-1})``; a stage cannot see another's input): refused otherwise.
The soft constraints have one slack per side and stage here (a stage-wise L1 penalty,
``rho (s + s^2)`` as the single shooting's), since fatrop's stages cannot share a variable.

CasADi's ``fatrop`` nlpsol (Vanroye et al., IROS 2023: an interior-point method on the
stage structure, given manually as :mod:`gtmodel.modeling.ocp.collocation_stages` does)
solves it with the exact Hessian; CasADi 3.8.2 generates C for it, which includes
``fatrop/ocp/OCPCInterface.h`` and links the wheel's ``libfatrop`` and ``libblasfeo``
(:data:`gtmodel.codegen.loop_step.SOLVER_LIBRARIES`). The solver object is created on the
heap by libfatrop at the first step and reused after.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.control.mpc_nlp import between_rows, period_states

__all__ = ["FATROP_MAX_ITER", "FATROP_TOL", "fatrop_problem"]

#: Interior-point iterations per period at most, and fatrop's tolerance.
FATROP_MAX_ITER, FATROP_TOL = 50, 1e-8


def fatrop_problem(c: Any, sqrt_psd: Any) -> tuple[ca.Function, ca.Function, dict[str, np.ndarray]]:
    """The multiple-shooting NLP of an MPC as a fatrop ``nlpsol``, its start and its bounds.

    Parameters
    ----------
    c : MPCController
        The MPC (``blocks == horizon``).
    sqrt_psd : callable
        ``L`` with ``L^T L = M`` of a weight matrix (the single shooting's factor).

    Returns
    -------
    solver : casadi.Function
        ``nlpsol(x0, p, lbx, ubx, lbg, ubg)``, ``p`` as :meth:`MPCController.parameters`.
    start : casadi.Function
        ``start(x (nx,1), w (nu H,1)) -> (z0, u (nu H,1) of z)``: the start of the NLP from the
        warm start ``w`` (states by the prediction), and ``unpack(z) -> inputs``.
    bounds : dict
        ``lbx``, ``ubx``, ``lbg``, ``ubg``.
    """
    H, nx, nu = c.horizon, c.nx, c.nu
    cons = c.constraints
    nr = 0 if cons is None else len(cons.sides)
    ns = 0 if cons is None or cons.hard else nr
    stages = set() if cons is None else set(cons.stages(H))  # the predicted states with rows (x_H always)
    Lq, Lf, Lr = (ca.DM(sqrt_psd(m)) for m in (c.Q, c.Qf, c.R))
    x0p, xr, ur = ca.MX.sym("x0", nx), ca.MX.sym("xr", nx, H), ca.MX.sym("ur", nu, H)
    X = [ca.MX.sym(f"x{k}", nx) for k in range(H + 1)]
    U = [ca.MX.sym(f"u{k}", nu) for k in range(H)]
    inner = between_rows(c)  # the states inside period k (functions of x_k, u_k): rows of stage k
    # constrained states of stage k: x_k (k >= 1; x_H at stage H) and those inside period k
    n_con = [int(k in stages and k >= 1) + (inner if k < H and k + 1 in stages else 0) for k in range(H + 1)]
    S = [ca.MX.sym(f"s{k}", ns if n_con[k] else 0) for k in range(H + 1)]
    XE = ca.MX.sym("xe", nx)
    w, g, lbx, ubx, lbg, ubg, f = [], [], [], [], [], [], 0
    rho = 0.0 if cons is None else cons.weight
    for k in range(H):
        w += [X[k], U[k], S[k]]
        lbx += [np.full(nx, -np.inf), c.u_lb, np.zeros(S[k].numel())]
        ubx += [np.full(nx, np.inf), c.u_ub, np.full(S[k].numel(), np.inf)]
        xn, inside = period_states(c, X[k], U[k]) if k + 1 in stages else (c.step(X[k], U[k]), [])
        g.append(X[k + 1] - xn)
        lbg.append(np.zeros(nx))
        ubg.append(np.zeros(nx))
        if k == 0:
            g.append(X[0] - x0p)
            lbg.append(np.zeros(nx))
            ubg.append(np.zeros(nx))
        here = ([cons.rows(X[k], U[k])] if k >= 1 and k in stages else []) + [cons.rows(xi, U[k]) for xi in inside]
        if here:  # x_k's rows, then those of the states inside period k (one slack per side and stage serves them all)
            g += [r + (S[k] if ns else 0) for r in here]
            lbg.append(np.zeros(nr * len(here)))
            ubg.append(np.full(nr * len(here), np.inf))
        f = f + ca.sumsqr(ca.mtimes(Lr, U[k] - ur[:, k])) + ca.sumsqr(ca.mtimes(Lf if k == H - 1 else Lq, X[k + 1] - xr[:, k]))
        f = f + rho * (ca.sum1(S[k]) + ca.sumsqr(S[k]))
    w += [X[H], S[H]]
    lbx += [np.full(nx, -np.inf), np.zeros(S[H].numel())]
    ubx += [np.full(nx, np.inf), np.full(S[H].numel(), np.inf)]
    f = f + rho * (ca.sum1(S[H]) + ca.sumsqr(S[H]))
    n_stage = H + 1
    if cons is not None:  # the last stage H+1: x only, equal to x_H
        g.append(XE - X[H])
        lbg.append(np.zeros(nx))
        ubg.append(np.zeros(nx))
        g.append(cons.rows(X[H], ca.DM.zeros(nu)) + (S[H] if ns else 0))
        lbg.append(np.zeros(nr))
        ubg.append(np.full(nr, np.inf))
        w.append(XE)
        lbx.append(np.full(nx, -np.inf))
        ubx.append(np.full(nx, np.inf))
        n_stage = H + 2
    z = ca.vertcat(*w)
    p = ca.vertcat(x0p, ca.vec(xr), ca.vec(ur))
    ng = [nx + nr * n_con[0]] + [nr * n_con[k] for k in range(1, H)] + ([nr, 0] if cons is not None else [0])
    nus = [nu + S[k].numel() for k in range(H)] + ([ns, 0] if cons is not None else [0])
    opts = {"structure_detection": "manual", "N": n_stage - 1, "nx": [nx] * n_stage, "nu": nus, "ng": ng,
            "expand": True, "print_time": False, "error_on_fail": False,
            "fatrop": {"print_level": 0, "max_iter": FATROP_MAX_ITER, "tol": FATROP_TOL}}
    solver = ca.nlpsol("mpc_fatrop", "fatrop", {"x": z, "p": p, "f": f, "g": ca.vertcat(*g)}, opts)
    # start: states predicted from the warm start (single shooting), slacks 0
    xs, ws = ca.MX.sym("x", nx), ca.MX.sym("w", nu * H)
    parts, xk = [], xs
    for k in range(H):
        uk = ws[k * nu:(k + 1) * nu]
        parts += [xk, uk, ca.DM.zeros(S[k].numel())]
        xk = c.step(xk, uk)
    parts += [xk, ca.DM.zeros(S[H].numel())]
    if cons is not None:
        parts.append(xk)
    idx = np.concatenate([np.arange(sum(e.numel() for e in w[: 3 * k]) + nx, sum(e.numel() for e in w[: 3 * k]) + nx + nu) for k in range(H)])
    start = ca.Function("start", [xs, ws], [ca.vertcat(*parts)], ["x", "w"], ["z0"])
    bounds = {"lbx": np.concatenate(lbx), "ubx": np.concatenate(ubx), "lbg": np.concatenate(lbg), "ubg": np.concatenate(ubg)}
    cost = ca.Function("cost", [z, p], [f])
    return solver, start, {**bounds, "inputs": idx, "cost": cost}
