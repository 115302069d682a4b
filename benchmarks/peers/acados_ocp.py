"""acados SQP on gtmodel's minimum-time point-to-point problem: the offline peer of ``benchmarks/bench_solve.py`` (issue 46).

Runs ONLY in acados' own venv (``benchmarks/acados_env.sh python benchmarks/peers/acados_ocp.py
PROBLEM.npz [--build DIR] [--repeat 3] [--hessian EXACT] [--serve]``); it imports nothing of gtmodel and prints
one JSON line on stdout (acados' build messages go to stderr); with ``--serve`` it builds, prints
``{"ready": true}`` and then answers each line ``solve`` on stdin with one solve's JSON line until
``quit`` (``benchmarks/bench_solve.py`` alternates these solves with gtmodel's, round by round).

The problem is the one gtmodel exports (``bench_solve.export_acados``): ``PROBLEM.npz`` with the
element count ``N``, the Radau points ``tau`` (``d`` of them, the last one 1) and their basis at 0,
``L0``, the force scale ``u_nom``, the scaled input bounds, the path, start and final constraints'
bounds, the final time's bounds and guess, the initial guess at the nodes and collocation times, and
the file names of three functions saved by CasADi's ``Function.save`` (the model with its parameters
substituted, the same equations as gtmodel's NLP): ``ode(x, u) -> x'``, ``path(x, u) -> g``,
``start(x, u) -> e`` and ``final(x, u) -> e`` (``u`` the physical force).

Formulation, acados 0.2.2 having neither ``p_global`` nor a time input to its integrators nor a
stage-0 nonlinear constraint of its own:

- time scaling: ``tau = t / T`` in ``[0, 1]``; ``T`` is a state with zero dynamics (acados'
  usual minimum-time form), its bounds at stage 0; the objective is the terminal cost ``T``
  (``EXTERNAL``); ``N`` intervals of ``d``-stage GAUSS_RADAU_IIA IRK, one step each;
- the point constraints' rows that bound one state (``T - pose``, ``T_dot``) are state bounds of
  stage 0 and ``N``; the path constraints (cart travel, spherical-joint angle) are ``h`` and
  ``h_e``: they hold at the ``N + 1`` nodes (gtmodel bounds them at its ``N * d`` collocation
  points, the nodes 1..N among them);
- ``--controls polynomial`` (gtmodel's discretisation): the force of interval ``k`` is the
  polynomial through its ``d`` collocation values (the controls, ``d * nu`` scaled forces
  ``U_kj = tau_kj / u_nom``), so that the IRK's equations are gtmodel's Radau collocation; the time
  within the interval is a clock state (``c' = 1``, ``c_0 = 0``) less the stage parameter ``k / N``.
  The end accelerations (``T_ddot = 0``, on the force) are rows of ``h`` bounded at stage 0 only, at
  the polynomial extrapolated to the start (``L0 . U_0``, bounded there too, as gtmodel does), and
  ``h_e`` at the final force ``U_{N-1,d}`` carried to the last node by a state ``u_f`` with zero
  dynamics and the row ``u_f - U_{N-1,d} = 0`` of stage ``N - 1``; rows that do not apply at a stage
  have the bounds +-BIG. acados 0.2.2 does not solve this form: HPIPM returns NaN at the second
  SQP iteration (qp_status 3), whatever the regularisation, globalisation, step length, HPIPM
  mode, mu0, BIG, Levenberg-Marquardt term or softening (the first step takes T to 0.496 s,
  shorter than the optimum; without the ``BIG`` rows it fails at the 10th); the dense
  FULL_CONDENSING_HPIPM goes on but stalls (stationarity 5e-6 after 500 iterations, T 0.67545 s, 208 s);
- ``--controls constant`` (acados' usual form, the one measured): the force constant over an
  interval (``nu`` scaled controls). The end accelerations cannot then be zero without a whole
  interval at rest, and are left out: in the continuous problem they bind nothing (the force may
  jump at the ends), so both discretisations tend to the same optimum as the mesh is refined, and
  at a given mesh acados' final time is the shorter (0.6716 s against gtmodel's 0.6754 s at 50
  intervals).

Problems without path constraints have no ``h``; the model's finite state bounds hold at every node
(and the final time's bounds too: at stage 0 alone HPIPM let a QP step of the double integrator take
``T`` to -830); with ``--soft W`` the final point constraints (and the rows of ``h``) are an exact L1
penalty of weight ``W`` (``final_state_violation`` reports what is left of them): from a guessed final
time shorter than the optimum (the COPS robot arm's 9 s) the first linearised QP cannot reach the final
state, and HPIPM then returns NaN rather than a sign of infeasibility.

The solve: ``SQP`` (not RTI) with the exact Hessian (``--hessian``), regularised by
``--regularize``, ``--globalization``, ``PARTIAL_CONDENSING_HPIPM``, tolerances ``--tol`` (1e-8:
stationarity, equality, inequality, complementarity), at most 500 iterations; each of the
``--repeat`` solves starts from the exported guess (the duals zeroed), and its CPU time is the thread
CPU around ``solver.solve()`` (and acados' own ``time_tot``). ``ACADOS_OPTIONS`` (JSON) sets any
other solver option (experiments); ``ACADOS_PRINT`` acados' print level.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

import casadi as ca
import numpy as np
from acados.acados_template import AcadosModel, AcadosOcp, AcadosOcpSolver

#: Bound of a row of ``h`` at a stage where it does not apply.
BIG = 1e6


def lagrange_basis(tau: np.ndarray, s: ca.SX) -> list:
    """The Lagrange basis polynomials through the points ``tau``, at the symbol ``s``.

    Parameters
    ----------
    tau : numpy.ndarray
        The collocation points in ``(0, 1]``.
    s : casadi.SX
        The time within the interval, in ``[0, 1]``.

    Returns
    -------
    list of casadi.SX
        ``ell_j(s)``, one per point.
    """
    out = []
    for j, tj in enumerate(tau):
        e = ca.SX(1)
        for r, tr in enumerate(tau):
            if r != j:
                e = e * (s - tr) / (tj - tr)
        out.append(e)
    return out


def build(problem: dict, funcs: dict, folder: str, hessian: str, regularize: str, tol: float,
          globalization: str = "MERIT_BACKTRACKING", levenberg: float = 0.0, soft: float = 0.0,
          qp: str = "PARTIAL_CONDENSING_HPIPM", controls: str = "polynomial") -> tuple[AcadosOcpSolver, dict]:
    """The acados solver of the exported problem (generated and compiled in ``folder``).

    Parameters
    ----------
    problem : dict
        The arrays of ``PROBLEM.npz``.
    funcs : dict of str to casadi.Function
        ``ode``, ``path``, ``start``, ``final``.
    folder : str
        Where acados writes its generated code and library.
    hessian : {"EXACT", "GAUSS_NEWTON"}
        acados' ``hessian_approx``.
    regularize : str
        acados' ``regularize_method``.
    tol : float
        The four NLP tolerances.
    globalization : {"MERIT_BACKTRACKING", "FIXED_STEP"}
        acados' ``globalization``.
    levenberg : float
        acados' ``levenberg_marquardt`` (a multiple of the identity added to the Hessian).
    soft : float
        When positive, the final point constraints (state bounds and rows of ``h_e``) and the
        rows of ``h`` are soft with this L1 weight (an exact penalty: the same optimum when the
        weight exceeds their multipliers, and the linearised QPs stay feasible when the guessed
        final time is too short to reach the final state, where acados' HPIPM returns NaN); 0: hard.
    qp : str
        acados' ``qp_solver``.
    controls : {"polynomial", "constant"}
        The force within an interval: gtmodel's polynomial through ``d`` values (with the clock
        state), or acados' usual constant (the end accelerations' rows then left out).

    Returns
    -------
    solver : AcadosOcpSolver
        The compiled solver.
    dims : dict
        ``nx``, ``nu``, ``nh`` and the index slices of the state and of ``h``.
    """
    N, d = int(problem["N"]), int(problem["d"])
    tau, L0, u_nom = np.asarray(problem["tau"], float), np.asarray(problem["L0"], float), np.asarray(problem["u_nom"], float)
    ode, path, start, final = funcs["ode"], funcs["path"], funcs["start"], funcs["final"]
    n, m = ode.size1_in(0), ode.size1_in(1)
    poly = controls == "polynomial"
    y = ca.SX.sym("y", n)  # the model's state (T, T_dot)
    Tf, clock, uf = ca.SX.sym("T"), ca.SX.sym("c"), ca.SX.sym("u_f", m)
    x = ca.vertcat(y, Tf, clock, uf) if poly else ca.vertcat(y, Tf)
    nU = d * m if poly else m
    U = ca.SX.sym("U", nU)  # the scaled forces at the d collocation points (or the interval's constant force)
    k_over_N = ca.SX.sym("k_over_N")
    if poly:
        s = N * (clock - k_over_N)  # time within the interval, in [0, 1]
        ell = lagrange_basis(tau, s)
        Uj = [U[j * m:(j + 1) * m] for j in range(d)]
        force = u_nom * sum(ell[j] * Uj[j] for j in range(d))
        u_start = sum(float(L0[j]) * Uj[j] for j in range(d))
        f_expl = ca.vertcat(Tf * ode(y, force), 0, 1, ca.SX.zeros(m))
    else:
        f_expl = ca.vertcat(Tf * ode(y, u_nom * U), 0)
    xdot = ca.SX.sym("xdot", x.numel())
    model = AcadosModel()
    model.name = f"gt_ocp_peer_{controls}"
    model.x, model.u, model.p, model.xdot = x, U, k_over_N, xdot
    model.f_expl_expr = f_expl
    model.f_impl_expr = xdot - f_expl
    sb = split_rows(start, problem["start_lb"], problem["start_ub"])
    fb = split_rows(final, problem["final_lb"], problem["final_ub"])
    zero_u = ca.SX.zeros(m)
    g = path(y, zero_u)
    ng = g.numel()
    if poly:
        h = ca.vertcat(g, start(y, u_nom * u_start)[sb["rows"]], u_start, uf - Uj[d - 1])
        h_e = ca.vertcat(path(y, zero_u), final(y, u_nom * uf)[fb["rows"]])
        lh_e = np.r_[problem["path_lb"], fb["lb"]]
        uh_e = np.r_[problem["path_ub"], fb["ub"]]
    else:  # the rows of the point constraints that depend on the force (the end accelerations) are left out
        h, h_e = g, path(y, zero_u)
        lh_e, uh_e = problem["path_lb"], problem["path_ub"]
    if h.numel():
        model.con_h_expr = h
    if h_e.numel():
        model.con_h_expr_e = h_e
    model.cost_expr_ext_cost = ca.SX(0)
    model.cost_expr_ext_cost_e = Tf
    ocp = AcadosOcp()
    ocp.model = model
    ocp.dims.N = N
    ocp.parameter_values = np.zeros(1)
    ocp.cost.cost_type, ocp.cost.cost_type_e = "EXTERNAL", "EXTERNAL"
    c = ocp.constraints
    c.idxbu = np.arange(nU)
    c.lbu, c.ubu = np.tile(problem["u_lb"], nU // m), np.tile(problem["u_ub"], nU // m)
    # stage 0: the start's state rows as bounds, the final time's bounds (constant along the horizon), the clock at 0
    idx0, lb0, ub0 = list(sb["idx"]), list(sb["lbx"]), list(sb["ubx"])
    idx0 += [n] + ([n + 1] if poly else [])
    lb0 += [problem["tf_bounds"][0]] + ([0.0] if poly else [])
    ub0 += [problem["tf_bounds"][1]] + ([0.0] if poly else [])
    # the model's finite state bounds: along the horizon, and at stage 0 and N where no point constraint fixes the state
    x_lb, x_ub = np.asarray(problem["x_lb"], float), np.asarray(problem["x_ub"], float)
    finite = [i for i in range(n) if np.isfinite(x_lb[i]) or np.isfinite(x_ub[i])]
    idxe, lbe, ube = list(fb["idx"]), list(fb["lbx"]), list(fb["ubx"])
    for i in finite:
        if i not in idx0:
            idx0.append(i), lb0.append(max(x_lb[i], -BIG)), ub0.append(min(x_ub[i], BIG))
        if i not in idxe:
            idxe.append(i), lbe.append(max(x_lb[i], -BIG)), ube.append(min(x_ub[i], BIG))
    # the final time's bounds at every stage too: with them at stage 0 alone, HPIPM's first QP of the double
    # integrator (no h) returned a step to T = -830 as solved
    tf_lo, tf_hi = (float(v) for v in problem["tf_bounds"])
    c.idxbx = np.array(finite + [n])
    c.lbx = np.r_[np.maximum(x_lb[finite], -BIG), tf_lo]
    c.ubx = np.r_[np.minimum(x_ub[finite], BIG), tf_hi]
    if n not in idxe:
        idxe.append(n), lbe.append(tf_lo), ube.append(tf_hi)
    c.idxbx_0, c.lbx_0, c.ubx_0 = np.array(idx0), np.array(lb0, float), np.array(ub0, float)
    c.idxbxe_0 = np.array([i for i in range(len(idx0)) if lb0[i] == ub0[i]])
    if idxe:
        c.idxbx_e, c.lbx_e, c.ubx_e = np.array(idxe), np.array(lbe, float), np.array(ube, float)
    nh = h.numel()
    dims = {"nx": x.numel(), "nu": nU, "nh": nh, "ng": ng, "ns": len(sb["rows"]) if poly else 0, "m": m, "n": n, "poly": poly,
            "start_nl": sb, "final_nl": fb}
    if nh:
        c.lh, c.uh = np.full(nh, -BIG), np.full(nh, BIG)  # the stage bounds are set per stage after the build
        c.lh[:ng], c.uh[:ng] = problem["path_lb"], problem["path_ub"]
    if h_e.numel():
        c.lh_e, c.uh_e = np.asarray(lh_e, float), np.asarray(uh_e, float)
    if soft > 0:  # the final point constraints (state bounds and rows of h_e) and the rows of h as an exact L1 penalty
        if nh:
            c.idxsh = np.arange(nh)
            ocp.cost.zl = ocp.cost.zu = np.full(nh, soft)
            ocp.cost.Zl = ocp.cost.Zu = np.zeros(nh)
        nsbx_e, nhe = len(fb["idx"]), int(h_e.numel())
        c.idxsbx_e = np.arange(nsbx_e)
        if nhe:
            c.idxsh_e = np.arange(nhe)
        ocp.cost.zl_e = ocp.cost.zu_e = np.full(nsbx_e + nhe, soft)
        ocp.cost.Zl_e = ocp.cost.Zu_e = np.zeros(nsbx_e + nhe)
    o = ocp.solver_options
    o.tf = 1.0
    o.integrator_type = "IRK"
    o.collocation_type = "GAUSS_RADAU_IIA"
    o.sim_method_num_stages = d
    o.sim_method_num_steps = 1
    o.sim_method_newton_iter = 5
    o.hessian_approx = hessian
    o.regularize_method = regularize
    o.globalization = globalization
    o.levenberg_marquardt = levenberg
    o.nlp_solver_type = "SQP"
    o.nlp_solver_max_iter = 500
    o.nlp_solver_tol_stat = o.nlp_solver_tol_eq = o.nlp_solver_tol_ineq = o.nlp_solver_tol_comp = tol
    o.qp_solver = qp
    for key, value in json.loads(os.environ.get("ACADOS_OPTIONS", "{}")).items():  # experiments: any solver option
        setattr(o, key, value)
    o.qp_solver_iter_max = 200
    o.print_level = int(os.environ.get("ACADOS_PRINT", 0))
    os.makedirs(folder, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(folder)  # acados writes its generated code under the working directory
    try:
        out = sys.stdout
        sys.stdout = sys.stderr  # the build's messages must not reach the JSON line
        try:
            solver = AcadosOcpSolver(ocp, json_file="gt_ocp_peer.json", verbose=False)
        finally:
            sys.stdout = out
    finally:
        os.chdir(cwd)
    return solver, dims


def split_rows(fun: ca.Function, lb: np.ndarray, ub: np.ndarray) -> dict:
    """The rows of a point constraint ``fun(x, u)`` that bound one state (``x_i - c``), and the others.

    Parameters
    ----------
    fun : casadi.Function
        ``start`` or ``final``.
    lb, ub : numpy.ndarray
        Its bounds.

    Returns
    -------
    dict
        ``idx``, ``lbx``, ``ubx``: the state bounds; ``rows``, ``lb``, ``ub``: the other rows (nonlinear, or on the force).
    """
    xs, us = ca.SX.sym("x", fun.size1_in(0)), ca.SX.sym("u", fun.size1_in(1))
    e = fun(xs, us)
    J = ca.Function("J", [xs, us], [ca.jacobian(e, xs), ca.jacobian(e, us), e])
    rng = np.random.default_rng(1)
    probes = [[np.asarray(v) for v in J(rng.normal(size=xs.numel()), rng.normal(size=us.numel()))] for _ in range(2)]
    jx, ju, e0 = (np.asarray(v) for v in J(np.zeros(xs.numel()), np.zeros(us.numel())))
    out = {"idx": [], "lbx": [], "ubx": [], "rows": [], "lb": [], "ub": []}
    for r in range(e0.shape[0]):
        unit = np.flatnonzero(jx[r]) if not ju[r].any() else []
        affine = all(np.allclose(p[0][r], jx[r]) and not p[1][r].any() for p in probes)
        if len(unit) == 1 and jx[r, unit[0]] == 1.0 and affine:
            out["idx"].append(int(unit[0]))
            out["lbx"].append(float(lb[r]) - float(e0[r, 0]))
            out["ubx"].append(float(ub[r]) - float(e0[r, 0]))
        else:
            out["rows"].append(r)
            out["lb"].append(float(lb[r]))
            out["ub"].append(float(ub[r]))
    return out


def stage_bounds(problem: dict, dims: dict, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The bounds of ``h`` at stage ``k``: the path rows always, the start rows at 0, the final force's row at ``N - 1``.

    Parameters
    ----------
    problem : dict
        The arrays of ``PROBLEM.npz``.
    dims : dict
        From :func:`build`.
    k : int
        The stage.

    Returns
    -------
    lh, uh : numpy.ndarray
        The lower and upper bounds.
    """
    N, m, ns = int(problem["N"]), dims["m"], dims["ns"]
    if not dims["poly"]:
        return np.asarray(problem["path_lb"], float), np.asarray(problem["path_ub"], float)
    sb = dims["start_nl"]
    lo = [problem["path_lb"], np.full(ns, -BIG), np.full(m, -BIG), np.full(m, -BIG)]
    hi = [problem["path_ub"], np.full(ns, BIG), np.full(m, BIG), np.full(m, BIG)]
    if k == 0:
        lo[1], hi[1] = sb["lb"], sb["ub"]
        lo[2], hi[2] = problem["u_lb"], problem["u_ub"]
    if k == N - 1:
        lo[3], hi[3] = np.zeros(m), np.zeros(m)
    return np.concatenate(lo).astype(float), np.concatenate(hi).astype(float)


def initialise(solver: AcadosOcpSolver, problem: dict, dims: dict) -> None:
    """Set the exported initial guess (the duals zeroed) and the stage parameters and bounds.

    Parameters
    ----------
    solver : AcadosOcpSolver
        From :func:`build`.
    problem : dict
        The arrays of ``PROBLEM.npz``.
    dims : dict
        From :func:`build`.
    """
    N, m = int(problem["N"]), dims["m"]
    xg, ug, tfg = np.asarray(problem["x_guess"], float), np.asarray(problem["u_guess"], float), float(problem["tf_guess"])
    uf = ug[-1, -1]
    for k in range(N + 1):
        solver.set(k, "x", np.r_[xg[k], tfg, k / N, uf] if dims["poly"] else np.r_[xg[k], tfg])
        if k < N:
            solver.set(k, "u", ug[k].reshape(-1) if dims["poly"] else ug[k, -1])
            solver.set(k, "p", np.array([k / N]))
            if dims["nh"]:
                lh, uh = stage_bounds(problem, dims, k)
                solver.constraints_set(k, "lh", lh)
                solver.constraints_set(k, "uh", uh)
        for field in ("lam", "pi") if k < N else ("lam",):
            try:
                solver.set(k, field, np.zeros_like(solver.get(k, field)))
            except Exception:  # noqa: BLE001 (a field acados does not let set at this stage)
                pass


def main() -> None:
    """Build, solve ``--repeat`` times from the guess, and print one JSON line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("problem", help="the .npz exported by bench_solve.py")
    ap.add_argument("--build", default=None, help="folder of acados' generated code (default beside the problem)")
    ap.add_argument("--repeat", type=int, default=3, help="solves from the guess (median CPU)")
    ap.add_argument("--hessian", default="EXACT", choices=("EXACT", "GAUSS_NEWTON"))
    ap.add_argument("--regularize", default="MIRROR", help="acados regularize_method")
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--controls", choices=("polynomial", "constant"), default="polynomial",
                    help="the force within an interval: gtmodel's polynomial (clock state) or constant")
    ap.add_argument("--globalization", default="MERIT_BACKTRACKING", choices=("MERIT_BACKTRACKING", "FIXED_STEP"))
    ap.add_argument("--soft", type=float, default=0.0, help="L1 weight of the softened final constraints (0: hard)")
    ap.add_argument("--levenberg", type=float, default=0.0, help="acados levenberg_marquardt")
    ap.add_argument("--serve", action="store_true", help="after the build, one solve per line 'solve' on stdin (its JSON line), "
                    "until 'quit': bench_solve.py alternates it with gtmodel's solves")
    args = ap.parse_args()
    problem = dict(np.load(args.problem))
    here = os.path.dirname(os.path.abspath(args.problem))
    funcs = {k: ca.Function.load(os.path.join(here, str(problem[f"{k}_file"]))) for k in ("ode", "path", "start", "final")}
    folder = args.build or os.path.join(here, "acados_ocp_build")
    solver, dims = build(problem, funcs, folder, args.hessian, args.regularize, args.tol, args.globalization, args.levenberg, args.soft,
                         controls=args.controls)
    if args.serve:  # one solve per line "solve" on stdin, its JSON line on stdout; "quit" ends (bench_solve.py's rounds)
        print(json.dumps({"ready": True}), flush=True)
        for line in sys.stdin:
            if line.strip() != "solve":
                break
            one = solve_once(solver, problem, dims)
            print(json.dumps({**one, **outcome(solver, problem, dims, args)}), flush=True)
        return
    cpu, tot, its, statuses = [], [], [], []
    for _ in range(max(1, args.repeat)):
        one = solve_once(solver, problem, dims)
        cpu.append(one["solve_cpu_s"])
        tot.append(one["time_tot_s"])
        its.append(one["iterations"])
        statuses.append(one["status"])
    print(json.dumps({
        "solve_cpu_s": statistics.median(cpu), "time_tot_s": statistics.median(tot), "cpu_s_all": cpu,
        "iterations": its[0], "status": statuses[0], "statuses": statuses, **outcome(solver, problem, dims, args),
    }), flush=True)


def solve_once(solver: AcadosOcpSolver, problem: dict, dims: dict) -> dict:
    """One solve from the exported guess: its thread CPU, acados' ``time_tot``, SQP iterations and status.

    Parameters
    ----------
    solver : AcadosOcpSolver
        From :func:`build`.
    problem : dict
        The arrays of ``PROBLEM.npz``.
    dims : dict
        From :func:`build`.

    Returns
    -------
    dict
        ``solve_cpu_s``, ``time_tot_s``, ``iterations``, ``status``.
    """
    initialise(solver, problem, dims)
    t0 = time.thread_time()
    status = solver.solve()
    cpu = time.thread_time() - t0
    return {"solve_cpu_s": cpu, "time_tot_s": float(np.ravel(solver.get_stats("time_tot"))[0]),
            "iterations": int(np.ravel(solver.get_stats("sqp_iter"))[0]), "status": int(status)}


def outcome(solver: AcadosOcpSolver, problem: dict, dims: dict, args: argparse.Namespace) -> dict:
    """The last solve's final time, final-state violation and residuals, and the configuration's description.

    Parameters
    ----------
    solver : AcadosOcpSolver
        After a solve.
    problem : dict
        The arrays of ``PROBLEM.npz``.
    dims : dict
        From :func:`build`.
    args : argparse.Namespace
        The peer's options.

    Returns
    -------
    dict
        ``final_time_s``, ``final_state_violation``, ``residuals``, ``config``.
    """
    N, n = int(problem["N"]), dims["n"]
    res = solver.get_residuals()
    xs = np.array([solver.get(k, "x") for k in range(N + 1)])
    fb = dims["final_nl"]
    final_violation = float(np.max(np.abs(xs[N, fb["idx"]] - np.clip(xs[N, fb["idx"]], fb["lbx"], fb["ubx"])), initial=0.0))
    return {
        "final_time_s": float(xs[0, n]), "final_state_violation": final_violation, "residuals": [float(r) for r in np.ravel(res)],
        "config": f"acados 0.2.2 SQP, {args.hessian} Hessian ({args.regularize}), IRK GAUSS_RADAU_IIA {int(problem['d'])} stages x 1 step, "
                  f"N = {N}, forces {args.controls} per interval{f', final constraints soft (L1 {args.soft:g})' if args.soft else ''}"
                  f"{f', Levenberg-Marquardt {args.levenberg:g}' if args.levenberg else ''}, PARTIAL_CONDENSING_HPIPM, {args.globalization}, tol {args.tol:g}, "
                  "T a state with zero dynamics (time-scaled)",
    }


if __name__ == "__main__":
    main()
