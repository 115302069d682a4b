"""The MPC's real-time iteration on the stage structure, each QP by HPIPM's Riccati recursion (``solver = "hpipm"``).

The same optimal control problem as :mod:`gtmodel.control.mpc` (one input per period: no
move blocking), with the predicted states kept as variables (multiple shooting; Bock &
Plitt, IFAC 1984), in the order HPIPM's OCP QP takes them: ``z = [u_0, s_0, x_1, u_1, s_1, ...,
x_{H-1}, u_{H-1}, s_{H-1}, x_H]`` (the measured state ``x_0`` is a parameter, not a variable;
``s_k`` the slacks of stage ``k``'s soft rows), the rows per stage the gap ``F(x_k, u_k) - x_{k+1}
= 0``, then the constraint rows of :class:`~gtmodel.control.mpc_constraints.MPCConstraints` of
period ``k``: those of the states after each substep inside it and of its end ``x_{k+1}``, all
functions of ``(x_k, u_k)`` (:func:`~gtmodel.control.mpc_nlp.period_states`; where ``x_{k+1}``
is constrained), in the single shooting's order. The constraints must not depend on the input
(the single shooting imposes ``x_{k+1}``'s at ``u_{k+1}``, another stage's variable): refused. Soft
rows have one slack per side and stage (a stage-wise L1 penalty, fatrop's; the single shooting
shares one per side over the horizon: the same optimum wherever the rows can be held), with the
single shooting's ``rho (s + s^2)`` written in the slack ``sqrt(rho) s``: the QP's Hessian is then
2 there, beside the inputs' and states' weights, rather than ``2 rho`` (2e7 on the two-mass drive,
where HPIPM took 18 iterations on average and 50, its limit, at worst), and HPIPM's first barrier
parameter ``mu0`` is ``sqrt(rho)`` (8.5 iterations on average, 11 at worst; 10, CasADi's default,
without soft rows).

HPIPM's mode ``speed_abs`` stops on the complementarity alone (1e-8, absolute): exact where it gets
there (the converged iterations agree with IPOPT to 1e-10 along the closed loops), but where a soft
row is beyond its bound at the solution the row's multiplier is at least the penalty ``rho`` (2e7 to
3e9 on the drives) and that complementarity is out of reach: HPIPM stops at its iteration limit, and
the generated step returns its failure status and the last input (at 12 to 37 of 100 of the codegen
check's random states of three drives; ``benchmarks/bench_hpipm_rows.py``, which compares each
answer with IPOPT's on the same QP: ``plugin``, ``strict``). Dividing each QP's cost by its scale made
those converge but stopped HPIPM early elsewhere, 0.9 % off IPOPT's first input beside a nearly active
row (the belt drive), so the shipped drive MPCs stay with ``sqpmethod`` and DAQP's active set.
The rows' lower bounds are 0 or the back-off's (:func:`~gtmodel.control.mpc_memory.row_backoff`,
the step's input ``lbg``).

HPIPM bounds every variable and row on both sides (CasADi's interface replaces an infinite bound
by 1e8, with which HPIPM's interior point does not converge): the predicted states are kept
within :data:`STATE_BOX` reference scales beyond the reference's range (never active on a sane
horizon), an input without bounds within its plausible range, a row below its value along the
reference plus :data:`STATE_BOX` (:func:`row_box`), a slack below that too. The cost is the
single shooting's sum of squares ``sum ||L_R (u_k - u*_k)||^2 + ||L_Q (x_{k+1} - x*_{k+1})||^2``
(``L_{Q_f}`` at the last state), linear residuals in ``z``, and the slacks' penalty: its
Gauss-Newton Hessian is the exact one and constant, block-diagonal ``2 diag(R, 1, Q, R, 1, ...,
Q_f)``.

One iteration (the real-time iteration of Diehl, Bock & Schloeder, SIAM J. Control Optim.
43 (2005), as acados' SQP-RTI): the gaps, the rows and their Jacobians ``A_k = dF/dx``, ``B_k =
dF/du``, ``C_k``, ``D_k`` at ``z``, the QP in ``dz`` with the bounds shifted by ``z``, solved by
HPIPM (Frison & Diehl, IFAC 2020: an interior-point method whose linear algebra is a
Riccati recursion over the stages, ``O(H (nx + nu)^3)``, on BLASFEO) through CasADi's
``hpipm`` conic with the stage structure given (``N = H``, ``nx = [0, nx, ...]``,
``nu = [nu + slacks, ..., 0]``, ``ng`` the rows per stage), and the full step ``z + dz``.
``sqp_iterations`` such iterations per period. The states start from the warm start's inputs
predicted from ``x_0``, slacks 0 (no gaps at the first iteration: its QP is the single shooting's
but for the slacks, so the converged point is the same; acados' SQP-RTI keeps its last states,
shifted, instead); that prediction and the first iteration's linearisation are one Function whose
common subexpressions CasADi evaluates once (``cse``: the prediction's steps are the
linearisation's points).

CasADi 3.8.2 generates C for the conic; it includes ``hpipm_d_ocp_qp_ipm.h`` and links the
wheel's ``libhpipm`` and ``libblasfeo`` (:data:`gtmodel.codegen.loop_step.SOLVER_LIBRARIES`),
or with ``GTMODEL_HPIPM`` a static HPIPM and a BLASFEO built for the machine
(:mod:`gtmodel.codegen.hpipm_source`: the wheel's BLASFEO has generic kernels, and HPIPM's
interior point is 80 % of the step); HPIPM's memory (dimensions, QP, solution, IPM workspace) is
created at a thread's first QP (:func:`~gtmodel.codegen.hpipm_source.patch_hpipm_memory`; CasADi's
runtime sets it up in every QP) in the generated step's static arena
(:data:`gtmodel.codegen.loop_step.HEAP_ARENA_BYTES`). A QP that
HPIPM does not solve (iteration limit, a NaN) makes the generated call return an error: the
step returns its failure status and the last input.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.control.mpc_nlp import between_rows, period_states
from gtmodel.errors import InputError

__all__ = ["HPIPM_MAX_ITER", "HPIPM_MODE", "REFERENCE_QP", "hpipm_rti", "row_box"]

#: The box of the predicted states: the reference's range widened by this many state scales
#: (:func:`~gtmodel.control.reference.reference_scales`) each side.
STATE_BOX = 10.0
#: Interior-point iterations of HPIPM per QP at most (acados' default), and its mode: ``speed_abs`` (the
#: absolute formulation, residuals not computed in the iterations) took 0.80x the generated L1 step's
#: time of ``speed`` and 0.60x ``balance``'s, the same first input to 1e-9 (2026-11-23, one state sweep).
HPIPM_MAX_ITER, HPIPM_MODE = 50, "speed_abs"
#: The QP options of the IPOPT reference (``hpipm_rti(plugin="ipopt")``): CasADi's ``nlpsol`` conic, tolerance 1e-12.
REFERENCE_QP = {"nlpsol": "ipopt", "nlpsol_options": {"ipopt.tol": 1e-12, "ipopt.max_iter": 3000, "ipopt.print_level": 0,
                                                     "ipopt.sb": "yes", "print_time": False}}
#: HPIPM's first barrier parameter without soft rows (CasADi's default; with them ``sqrt(rho)``, the module docstring).
HPIPM_MU0 = 10.0


def _stage_rows(c: Any) -> tuple[int, int, list[int]]:
    """``(nr, ns, rowsets)``: the sides of the constraints, the slacks per constrained stage, and per stage ``k`` the
    states whose rows it carries (those inside period ``k`` and its end ``x_{k+1}``; 0 where ``x_{k+1}`` has none)."""
    cons = c.constraints
    if cons is None:
        return 0, 0, [0] * c.horizon
    nr, stages = len(cons.sides), set(cons.stages(c.horizon))
    return nr, 0 if cons.hard else nr, [(between_rows(c) + 1) * (k + 1 in stages) for k in range(c.horizon)]


def row_box(c: Any) -> np.ndarray:
    """The upper bounds of the scaled constraint rows (HPIPM bounds every row on both sides; see the module docstring).

    Parameters
    ----------
    c : MPCController
        The MPC with constraint rows.

    Returns
    -------
    numpy.ndarray
        ``(len(sides),)`` per side the largest scaled row along the reference plus :data:`STATE_BOX`
        (the rows' scales are the spreads of the constrained quantities along it: a row stays below this
        while the state stays within the box of the predicted states).
    """
    cons = c.constraints
    f = ca.Function("rows", [X := ca.SX.sym("x", c.nx), U := ca.SX.sym("u", c.nu)], [cons.rows(X, U)])
    along = np.asarray(f.map(c.x_ref.shape[0])(c.x_ref.T, c.u_ref.T))
    return np.max(along, axis=1) + STATE_BOX


def hpipm_rti(c: Any, sqrt_psd: Any, iterations: int | None = None, plugin: str = "hpipm", strict: bool = False) -> ca.Function:
    """The MPC's real-time iteration(s) by HPIPM on the multiple-shooting QP (see the module docstring).

    Parameters
    ----------
    c : MPCController
        The MPC (``blocks == horizon``; constraints of the states only).
    sqrt_psd : callable
        ``L`` with ``L^T L = M`` of a weight matrix (the single shooting's factor).
    iterations : int, optional
        Iterations (default ``c.sqp_iterations``).
    plugin : {"hpipm", "qpoases", "ipopt"}, optional
        The solver of each QP: HPIPM (the step's), or as a reference for HPIPM's answers on the same QPs
        (``benchmarks/bench_hpipm_rows.py``) qpOASES (an active-set method) or IPOPT to 1e-12 (:data:`REFERENCE_QP`).
    strict : bool, optional
        Raise (CasADi's ``error_on_fail``) where a QP is not solved, HPIPM at its iteration limit or minimum step
        included; by default the Function returns the solver's last iterate, as the generated step does not (it
        returns its failure status there).

    Returns
    -------
    casadi.Function
        ``rti(x0 (nx,1), w (nu H,1), p, lbu (nu H,1), ubu (nu H,1), lbg (m,1)) -> (u (nu H,1), f (1,1), lam)``:
        ``w`` the warm start's inputs, ``p`` as :meth:`MPCController.parameters`, ``lbu``/``ubu``
        the inputs' bounds, ``lbg`` the lower bounds of the ``m`` (:attr:`~MPCController.constraint_rows`)
        scaled constraint rows (0, or tightened: :func:`~gtmodel.control.mpc_memory.row_backoff`), in the
        single shooting's order; ``u`` the inputs after the iterations, ``f`` the cost there (NaN
        when the prediction fails), ``lam`` ``(iterations (H nx + m),1)`` the multipliers of each QP's rows.

    Raises
    ------
    InputError
        Another ``plugin``.
    """
    H, nx, nu = c.horizon, c.nx, c.nu
    k_it = c.sqp_iterations if iterations is None else int(iterations)
    cons = c.constraints
    nr, ns, rowsets = _stage_rows(c)
    # the slacks' variables scaled by 1 / sqrt(rho): the penalty sqrt(rho) s + s^2 (a Hessian of 2 beside the inputs' and
    # states', not rho's 2e7), and HPIPM's first barrier parameter that scale (see the module docstring)
    k_s = 1.0 / math.sqrt(cons.weight) if ns else 1.0
    mu0 = max(HPIPM_MU0, 1.0 / k_s)
    Lq, Lf, Lr = (ca.DM(sqrt_psd(m)) for m in (c.Q, c.Qf, c.R))
    x0, xr, ur = ca.SX.sym("x0", nx), ca.SX.sym("xr", nx, H), ca.SX.sym("ur", nu, H)
    U = [ca.SX.sym(f"u{k}", nu) for k in range(H)]
    S = [ca.SX.sym(f"s{k}", ns if rowsets[k] else 0) for k in range(H)]
    X = [x0] + [ca.SX.sym(f"x{k}", nx) for k in range(1, H + 1)]
    z = ca.vertcat(*[e for k in range(H) for e in (U[k], S[k], X[k + 1])])
    g, kind = [], []  # per stage its gap, then its rows (HPIPM's order); kind: 0 gap, 1 row
    for k in range(H):
        if rowsets[k]:  # the rows of the states inside period k, then its end, functions of (x_k, u_k)
            xn, inside = period_states(c, X[k], U[k])
            here = [cons.rows(xi, U[k]) + (k_s * S[k] if ns else 0) for xi in (*inside, xn)]
        else:
            xn, here = c.step(X[k], U[k]), []
        g += [xn - X[k + 1], *here]
        kind += [0] * nx + [1] * (nr * rowsets[k])
    g = ca.vertcat(*g)
    r = ca.vertcat(*[e for k in range(H) for e in (ca.mtimes(Lr, U[k] - ur[:, k]),
                                                    ca.mtimes(Lf if k == H - 1 else Lq, X[k + 1] - xr[:, k]))])
    s_all = ca.vertcat(*S)
    f = ca.sumsqr(r) + (cons.weight * (ca.sum1(k_s * s_all) + ca.sumsqr(k_s * s_all)) if ns else 0)
    p = ca.vertcat(x0, ca.vec(xr), ca.vec(ur))
    hess = ca.evalf(ca.substitute(ca.hessian(f, z)[0], ca.vertcat(z, p), ca.DM.zeros(z.numel() + p.numel())))
    jac = ca.sparsify(ca.jacobian(g, z))  # the -I blocks of x_{k+1} diagonal, as the conic requires
    lin = ca.Function("lin", [z, p], [g, jac, ca.gradient(f, z)], ["z", "p"], ["g", "jac", "grad"])
    cost_f = ca.Function("cost", [z, p], [f], ["z", "p"], ["f"])  # apart: a call of lin computes all its outputs
    # the first iteration at the states predicted from the warm start's inputs (slacks 0): the prediction and the
    # linearisation in one Function, its common subexpressions (the prediction's steps) evaluated once
    ws = ca.SX.sym("w", nu * H)
    xk, parts = x0, []
    for k in range(H):
        xk = c.step(xk, ws[k * nu:(k + 1) * nu])
        parts += [ws[k * nu:(k + 1) * nu], ca.DM.zeros(S[k].numel()), xk]
    z_start = ca.vertcat(*parts)
    first = ca.Function("first", [ws, p], [z_start, *lin(z_start, p)], ["w", "p"], ["z", "g", "jac", "grad"], {"cse": True})
    opts = {"N": H, "nx": [0] + [nx] * H, "nu": [nu + S[k].numel() for k in range(H)] + [0],
            "ng": [nr * n for n in rowsets] + [0],
            "hpipm": {"mode": HPIPM_MODE, "iter_max": HPIPM_MAX_ITER, "stat_max": HPIPM_MAX_ITER, "mu0": mu0}} if plugin == "hpipm" else \
        {"printLevel": "none", "nWSR": 100 * z.numel()} if plugin == "qpoases" else REFERENCE_QP
    if plugin not in ("hpipm", "qpoases", "ipopt"):
        raise InputError(f"plugin: expected 'hpipm', 'qpoases' or 'ipopt', got {plugin!r}")
    qp = ca.conic(f"mpc_{plugin}", "nlpsol" if plugin == "ipopt" else plugin, {"h": hess.sparsity(), "a": jac.sparsity()},
                  {**opts, "error_on_fail": bool(strict), "print_time": False})
    sizes = [(nu, S[k].numel(), nx) for k in range(H)]
    offsets = np.cumsum([0] + [sum(t) for t in sizes])
    u_idx = np.concatenate([np.arange(o, o + nu) for o in offsets[:-1]])
    s_idx = np.concatenate([np.arange(o + nu, o + nu + m) for o, (_, m, _) in zip(offsets[:-1], sizes)]).astype(int)
    x_idx = np.setdiff1d(np.arange(z.numel()), np.r_[u_idx, s_idx])
    row_idx = np.flatnonzero(np.array(kind) == 1)
    m = int(row_idx.size)
    X0, W, P = ca.MX.sym("x0", nx), ca.MX.sym("w", nu * H), ca.MX.sym("p", p.numel())
    LBU, UBU, LBG = ca.MX.sym("lbu", nu * H), ca.MX.sym("ubu", nu * H), ca.MX.sym("lbg", m)
    # HPIPM bounds every variable and row on both sides (CasADi's interface replaces an infinite bound by 1e8, with
    # which its interior point stops at its iteration limit): the predicted states within STATE_BOX scales of the
    # reference's range, the inputs within their bounds or, where none, their plausible range, the rows below
    # row_box, the slacks within [0, row_box]
    lim = c.limits()
    x_scale, _, _, _ = c.plausible_ranges(c.u_lb, c.u_ub)
    x_lo = ca.DM(np.tile(np.min(c.x_ref, axis=0) - STATE_BOX * x_scale, H))
    x_hi = ca.DM(np.tile(np.max(c.x_ref, axis=0) + STATE_BOX * x_scale, H))
    u_lo = ca.fmax(LBU, ca.DM(np.tile(lim["u_last"][0], H)))
    u_hi = ca.fmin(UBU, ca.DM(np.tile(lim["u_last"][1], H)))
    top = row_box(c) if nr else np.zeros(0)
    g_hi = ca.DM(np.tile(top, m // nr if nr else 0))
    s_hi = ca.DM(np.tile(top, s_idx.size // ns if ns else 0)) / k_s
    lam = []
    Z, gz, jz, grad = first(W, P)
    for it in range(k_it):
        if it:
            gz, jz, grad = lin(Z, P)
        lb, ub = ca.MX(z.numel(), 1), ca.MX(z.numel(), 1)
        lb[u_idx], ub[u_idx] = u_lo - Z[u_idx], u_hi - Z[u_idx]
        lb[x_idx], ub[x_idx] = x_lo - Z[x_idx], x_hi - Z[x_idx]
        lba, uba = -gz, -gz
        if m:
            lb[s_idx], ub[s_idx] = -Z[s_idx], s_hi - Z[s_idx]
            lba[row_idx], uba[row_idx] = LBG - gz[row_idx], g_hi - gz[row_idx]
        sol = qp(h=hess, g=grad, a=jz, lba=lba, uba=uba, lbx=lb, ubx=ub)
        Z = Z + sol["x"]
        lam.append(sol["lam_a"])
    cost = cost_f(Z, P)
    # the multipliers are an output: CasADi 3.8.2's HPIPM runtime writes them unconditionally (a call
    # whose lam_a output is unused gets a NULL pointer there and crashes)
    return ca.Function("rti", [X0, W, P, LBU, UBU, LBG], [Z[u_idx], cost, ca.vertcat(*lam)],
                       ["x0", "w", "p", "lbu", "ubu", "lbg"], ["u", "f", "lam"])
