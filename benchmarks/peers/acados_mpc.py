"""acados SQP-RTI on gtmodel's MPC problem: the peer of ``benchmarks/bench_mpc.py`` (issue 46).

Runs ONLY in acados' own venv (``benchmarks/acados_env.sh python benchmarks/peers/acados_mpc.py
PROBLEM.npz [--qp PARTIAL_CONDENSING_HPIPM|FULL_CONDENSING_HPIPM|FULL_CONDENSING_QPOASES]
[--hpipm-mode BALANCE|SPEED_ABS|SPEED|ROBUST] [--build DIR]``); it imports
nothing of gtmodel.

The problem is the one gtmodel exports (:func:`bench_mpc.export_problem`): ``PROBLEM.npz`` with the
weights ``Q``, ``R``, ``Qf``, the input bounds ``u_lb``, ``u_ub``, ``horizon``, ``period``, and
``step`` the file name of the prediction over one period ``F(x, u) -> x_next`` saved by CasADi's
``Function.save`` (the same Euler or RK4 step as the gtmodel step's). gtmodel's horizon problem,
for the NLP parameter ``p = [x; x*_{k+1..k+H}; u*_{k..k+H-1}]`` of ``MPCController.parameters``::

    min sum_{j<H} |u_j - u*_{k+j}|_R^2 + sum_{1<=j<H} |x_j - x*_{k+j}|_Q^2 + |x_H - x*_{k+H}|_Qf^2,
    x_0 = x, x_{j+1} = F(x_j, u_j), u_lb <= u_j <= u_ub

is written for acados as a multiple-shooting OCP with a DISCRETE integrator (``disc_dyn_expr = F``),
LINEAR_LS costs (stage ``j``: ``y = [x_j; u_j]``, ``W = blkdiag(Q, R) / dt``: acados 0.2.2 multiplies
the stage costs by the time step and not the terminal one, ``W_e = Qf``; the ``Q`` term of stage 0
is constant), the Gauss-Newton Hessian, ``SQP_RTI`` (one SQP iteration per call) and the given QP solver (an HPIPM one in
the given ``hpipm_mode``, acados' default ``BALANCE`` when not given).

With gtmodel's soft constraint rows (``rows`` in the file: ``h(x_j, u_j)``, the scaled rows of the states inside
period ``j`` and at its end, ``>= 0``; ``rows_upper``, ``rho``, ``rows_stages``) they are acados' nonlinear
constraints ``con_h_expr`` of stages ``0..H-1``, with gtmodel's hpipm step's slacks: one per side (``rows_sides``) and
stage as extra inputs, ``sqrt(rho) h + s >= 0``, penalised as gtmodel's ``rho (s + s^2)`` in the slack's scale ``sqrt(rho) s``
by a least-squares term beside the tracking's (the same NLP; acados' own soft constraints, a slack per row, penalise
the sum of a side's violations inside a period rather than its largest, another NLP where a row cannot be held);
acados' template puts ``h`` on every stage, so a stage
whose period gtmodel leaves without rows (``constraint_every``) gets them never active (``lh = -uh``).

The closed loop stays in gtmodel's process (the same plant, noise, disturbance, delay and error as its
check); this script answers it through stdin/stdout, one line per request:

- ``step p...``: one real-time iteration at ``p`` from the warm start shifted by one period (the
  last solution's ``x_{j+1}``, ``u_{j+1}``; its last entries kept; with ``--warm rollout`` the
  inputs shifted and the states they predict from ``p``'s ``x``, as gtmodel's single shooting),
  the call's CPU time of this thread recorded; answers ``status u...``;
- ``converge p...``: real-time iterations at ``p`` until the whole primal trajectory (every stage's
  inputs and states) moves by at most :data:`CONVERGE_TOL` relative (at most :data:`CONVERGE_MAX_ITER`;
  no shift); answers ``status iterations change u...``, ``change`` the last iteration's relative move
  (above the tolerance: not converged). The first input alone once stopped it early: held at its
  bound for two iterations while the rest still moved (0.18 relative from gtmodel's converged input);
- ``reset w...``: the next ``step`` starts from ``u_j`` = the inputs ``w`` (``nu * H``) and the
  states they predict from its ``x``;
- ``stats``: answers one JSON line ``{"cpu_step_s": [...], "qp_solver", "qp_variables"}``, and
  clears the recorded times; ``quit``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import casadi as ca
import numpy as np
from acados.acados_template import AcadosModel, AcadosOcp, AcadosOcpSolver


#: ``converge``: real-time iterations until the whole primal trajectory moves by at most this (relative), at most
#: :data:`CONVERGE_MAX_ITER` of them (a first input held at its bound stops moving while the rest still moves).
CONVERGE_TOL = 1e-12
CONVERGE_MAX_ITER = 500


def _num(v) -> str:
    return repr(float(v))


def build(problem: dict, step: ca.Function, qp: str, folder: str, hpipm_mode: str | None = None,
          rows: ca.Function | None = None) -> AcadosOcpSolver:
    """The acados solver of the problem (generated and compiled in ``folder``; ``hpipm_mode`` of an HPIPM QP solver;
    ``rows`` gtmodel's constraint rows of a period, ``h(x, u) -> (m,1)``, soft)."""
    nx, nu = step.size1_in(0), step.size1_in(1)
    H, dt = int(problem["horizon"]), float(problem["period"])
    ns = int(problem["rows_sides"]) if rows is not None else 0  # the slacks, one per side and stage: extra inputs
    x, u, s = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("s", ns)
    model = AcadosModel()
    model.name = "gt_peer"
    model.x, model.u = x, ca.vertcat(u, s)
    model.disc_dyn_expr = step(x, u)
    ocp = AcadosOcp()
    ocp.model = model
    ocp.dims.N = H
    ocp.cost.cost_type, ocp.cost.cost_type_e = "LINEAR_LS", "LINEAR_LS"
    ny = nx + nu + ns
    W = np.zeros((ny, ny))
    W[:nx, :nx], W[nx:nx + nu, nx:nx + nu], W[nx + nu:, nx + nu:] = problem["Q"], problem["R"], np.eye(ns)
    ocp.cost.W = W / dt
    ocp.cost.W_e = np.asarray(problem["Qf"], dtype=float)
    ocp.cost.Vx = np.vstack([np.eye(nx), np.zeros((nu + ns, nx))])
    ocp.cost.Vu = np.vstack([np.zeros((nx, nu + ns)), np.eye(nu + ns)])
    ocp.cost.Vx_e = np.eye(nx)
    ocp.cost.yref, ocp.cost.yref_e = np.zeros(ny), np.zeros(nx)
    lbu, ubu = np.asarray(problem["u_lb"], float), np.asarray(problem["u_ub"], float)
    ocp.constraints.x0 = np.zeros(nx)
    if rows is not None:  # gtmodel's soft constraint rows of each period as its hpipm step has them (the same NLP)
        # each row plus its side's slack of the stage, h = sqrt(rho) rows + s >= 0 (hard), the slack s = sqrt(rho) s_true in
        # [0, sqrt(rho) upper], and gtmodel's penalty rho (s_true + s_true^2) = s^2 + sqrt(rho) s = (s + sqrt(rho)/2)^2 - rho/4
        # as a least-squares term beside the tracking's (weight 1 / dt as theirs, reference -sqrt(rho)/2: stage yref)
        k = math.sqrt(float(problem["rho"]))
        m = int(rows.size1_out(0))
        upper = k * np.asarray(problem["rows_upper"], dtype=float)
        model.con_h_expr = k * rows(x, u) + ca.repmat(s, m // ns, 1)
        ocp.constraints.lh, ocp.constraints.uh = np.zeros(m), upper
        lbu, ubu = np.r_[lbu, np.zeros(ns)], np.r_[ubu, upper[:ns]]
    ocp.constraints.lbu, ocp.constraints.ubu = lbu, ubu
    ocp.constraints.idxbu = np.arange(nu + ns)
    o = ocp.solver_options
    o.tf = H * dt
    o.integrator_type = "DISCRETE"
    o.hessian_approx = "GAUSS_NEWTON"
    o.nlp_solver_type = "SQP_RTI"
    o.qp_solver = qp
    if hpipm_mode:
        o.hpipm_mode = hpipm_mode
    o.print_level = 0
    os.makedirs(folder, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(folder)  # acados writes its generated code under the working directory
    try:
        out = sys.stdout
        sys.stdout = sys.stderr  # the build's messages must not reach the protocol
        try:
            return AcadosOcpSolver(ocp, json_file="gt_peer.json", verbose=False)
        finally:
            sys.stdout = out
    finally:
        os.chdir(cwd)


def main() -> None:
    """Serve the requests of bench_mpc.py (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("problem", help="the .npz exported by bench_mpc.py")
    ap.add_argument("--qp", default="PARTIAL_CONDENSING_HPIPM", help="acados qp_solver")
    ap.add_argument("--hpipm-mode", default=None, choices=("BALANCE", "SPEED_ABS", "SPEED", "ROBUST"),
                    help="hpipm_mode of an HPIPM QP solver (default acados' BALANCE)")
    ap.add_argument("--warm", choices=("shift", "rollout"), default="shift",
                    help="warm start of a step: the last solution's states and inputs shifted (default), or its inputs shifted and "
                         "the states they predict from the new x (the single-shooting warm start of gtmodel's step)")
    ap.add_argument("--build", default=None, help="folder of acados' generated code (default beside the problem)")
    args = ap.parse_args()
    problem = dict(np.load(args.problem))
    step = ca.Function.load(os.path.join(os.path.dirname(os.path.abspath(args.problem)), str(problem["step"])))
    nx, nu = step.size1_in(0), step.size1_in(1)
    H = int(problem["horizon"])
    folder = args.build or os.path.join(os.path.dirname(os.path.abspath(args.problem)), f"acados_{args.qp.lower()}")
    rows = ca.Function.load(os.path.join(os.path.dirname(os.path.abspath(args.problem)), str(problem["rows"]))) if "rows" in problem else None
    solver = build(problem, step, args.qp, folder, args.hpipm_mode, rows)
    ns = int(problem["rows_sides"]) if rows is not None else 0
    s_ref = np.full(ns, -0.5 * math.sqrt(float(problem["rho"]))) if ns else np.zeros(0)
    if rows is not None:  # acados' template puts h on every stage: where gtmodel's period has no rows, never active
        upper = math.sqrt(float(problem["rho"])) * np.asarray(problem["rows_upper"], dtype=float)
        for j in np.flatnonzero(~np.asarray(problem["rows_stages"], dtype=bool)):
            solver.constraints_set(int(j), "lh", -upper)
    times: list[float] = []
    pending: np.ndarray | None = None

    def load(p: np.ndarray) -> None:
        x0 = p[:nx]
        xr, ur = p[nx:nx + nx * H].reshape(H, nx), p[nx + nx * H:].reshape(H, nu)
        solver.set(0, "lbx", x0)
        solver.set(0, "ubx", x0)
        for j in range(H):
            solver.set(j, "yref", np.r_[x0 if j == 0 else xr[j - 1], ur[j], s_ref])
        solver.set(H, "yref", xr[H - 1])

    def rollout(x0: np.ndarray, w: np.ndarray) -> None:
        x = x0.copy()
        solver.set(0, "x", x)
        for j in range(H):
            solver.set(j, "u", np.r_[w[j], np.zeros(ns)])
            x = np.asarray(step(x, w[j])).reshape(-1)
            solver.set(j + 1, "x", x)

    def primal() -> np.ndarray:
        """The whole primal trajectory: every stage's inputs and states."""
        return np.concatenate([solver.get(j, "u") for j in range(H)] + [solver.get(j, "x") for j in range(H + 1)])

    def shift() -> None:
        xs = [solver.get(j, "x") for j in range(H + 1)]
        us = [solver.get(j, "u") for j in range(H)]
        for j in range(H):
            solver.set(j, "x", xs[j + 1])
            solver.set(j, "u", us[min(j + 1, H - 1)])

    # the protocol on a copy of stdout; the process's own stdout (acados' C prints, e.g. a QP's failed status) to stderr
    proto = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = proto
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        cmd, vals = words[0], np.array([float(v) for v in words[1:]])
        if cmd == "quit":
            break
        if cmd == "reset":
            pending = vals.reshape(H, nu)
            continue
        if cmd == "stats":
            print(json.dumps({"cpu_step_s": times, "qp_solver": args.qp, "hpipm_mode": args.hpipm_mode,
                              "qp_variables": H * (nx + nu + ns) + nx if args.qp.startswith("PARTIAL") else H * (nu + ns)}), flush=True)
            times = []
            continue
        load(vals)
        if pending is not None:
            rollout(vals[:nx], pending)
            pending = None
        elif cmd == "step" and args.warm == "rollout":
            rollout(vals[:nx], [solver.get(min(j + 1, H - 1), "u")[:nu] for j in range(H)])
        elif cmd == "step":
            shift()
        if cmd == "step":
            t0 = time.thread_time()
            status = solver.solve()
            times.append(time.thread_time() - t0)
            print(status, *map(_num, solver.get(0, "u")[:nu]), flush=True)
        elif cmd == "converge":
            z_old, status, it, change = primal(), 0, 0, np.inf
            for it in range(1, CONVERGE_MAX_ITER + 1):
                status = solver.solve()
                z = primal()
                change = float(np.max(np.abs(z - z_old)) / max(1.0, float(np.max(np.abs(z)))))
                if change <= CONVERGE_TOL:
                    break
                z_old = z
            print(status, it, _num(change), *map(_num, solver.get(0, "u")[:nu]), flush=True)


if __name__ == "__main__":
    main()
