"""Condensed Radau collocation (each element's collocation states eliminated by Newton's method) against gtmodel's transcription (a benchmark, not a test).

Usage: OMP_NUM_THREADS=1 python benchmarks/bench_condensed.py [problem.toml] [--elements 50,400] [--solver fatrop,ipopt]
[--repeat 3] [--compile-assembly] [--json]

The question (issue 46, item 3): does a transcription whose stages hold only the element start state, the
final-time copy and the inputs (7 states and 9 inputs per stage on the L1 Gantry-Tau, instead of 7 and 27
with the collocation states as stage controls) make the minimum-time solve cheaper? The condensed NLP is the
same discretisation as gtmodel's (Radau IIA, ``points`` per element, the inputs at the collocation points, the
path constraints and input bounds at the points, the start constraints, path constraints and input bounds at
the start with the inputs' polynomial extrapolated, the final constraints at the last point), so its optimum
is gtmodel's (the independent check: ``final_time_rel_diff``, the two solvers' optima compared).

Per element ``k``, with ``p_k = (x_k, T_k, U_k)`` (start state, final-time copy, scaled inputs at the points)
and ``X_k`` the states at the points, the collocation equations ``G(X_k, p_k) = 0`` (``h f(x_j, u_j) =
sum_r C_rj x_r``) are solved by CasADi's ``fast_newton`` rootfinder (abstol 1e-13), from the straight line
between ``x_k`` and ``x_{k+1}``. The element's outputs ``o`` (end state, path constraints at the points, the
final constraints) and their derivatives follow from the implicit function theorem (one SX function per
element, compiled): ``S = -G_X^-1 G_p``, ``J = o_p + o_X S``; the Hessian of ``lam' o`` is
``Z' W Z`` with ``Z = [I; S]`` and ``W`` the Hessian of ``lam' o + mu' G`` in ``(p, X)``, ``mu = -G_X^-T o_X' lam``
(the condensing of the KKT system of the collocation equations, as acados' IRK with sensitivities does it).
The NLP's Jacobian and Hessian are assembled from them (a first-order surrogate of ``o`` around the point,
``casadi.no_grad``, differentiated by CasADi, plus the elements' quadratic terms) and given to fatrop through
its function cache (``nlp_g``, ``nlp_jac_g``, ``nlp_hess_l``: gtmodel's own route, ``collocation_stages.fatrop_cache``)
and to IPOPT as ``jac_g``/``hess_lag``; the element functions compiled (``jit``, gcc -O2), their assembly
interpreted (with ``--compile-assembly`` compiled too: faster, but its code grows with the mesh). The peer: gtmodel's solve of the same
problem on the same mesh with the same solver (``[solver] name``), measured in the same run, alternated.

Measured (2 cores shared with two other processes; process CPU time, medians of 3 after a warm-up, the two
alternated; casadi 3.8.2; L1 minimum time, ``problems/l1_time_optimal.toml``; gtmodel's optimum 0.6754484421 s):

``OMP_NUM_THREADS=1 python benchmarks/bench_condensed.py --elements 50`` (this file: element functions compiled, their
assembly into the NLP's Jacobian and Hessian interpreted by CasADi's MX virtual machine):

====================  ===========  ==========  ============  =====================================
50 elements           CPU [s]      iterations  ms/iteration  final time [s]
====================  ===========  ==========  ============  =====================================
condensed, fatrop     0.993        55          18.1          0.6754484421 (6.7e-15 rel. from gtmodel)
gtmodel, fatrop       0.198        51          3.87          0.6754484421
condensed, IPOPT      1.541        66          23.4          0.6754484421 (4.2e-12)
gtmodel, IPOPT        0.252        49          5.14          0.6754484421
====================  ===========  ==========  ============  =====================================

CPU per iteration of the condensed fatrop solve: Hessian 10.2 ms, Jacobian 4.8 ms, constraints 1.8 ms (their
assembly interpreted). ``--compile-assembly`` (this file's mapped assembly compiled): fatrop 0.831 CPU-s, 55
iterations, 15.1 ms/iteration (Hessian 8.5, Jacobian 3.7, constraints 1.7 ms), ratio 4.2x to gtmodel's 0.199 s. A
prototype (not kept) with the assembly unrolled per element (one ``mtimes`` and one ``bilin`` per element instead of
mapped calls) and compiled (gcc -O2: ~2 min at 50 elements, not finished in 24 min at 400, the code growing with
the mesh; IPOPT's ``nlp_g`` left interpreted there: 1.71 CPU-s, 66 iterations): fatrop 0.424 CPU-s, 55 iterations, 7.7 ms/iteration
(constraints 1.7, Jacobian 2.0, Hessian 2.7 ms, fatrop's own work and its plugin's 1.3 ms against 3.5 ms on
gtmodel's transcription), the same optimum; the rootfinder with CasADi's own derivatives of it (reverse over
forward through ``fast_newton``), all compiled: 1.51 CPU-s, 27 ms/iteration (Hessian 21.6 ms).

``OMP_NUM_THREADS=1 python benchmarks/bench_condensed.py --elements 400 --solver fatrop --repeat 1``: condensed
13.3 CPU-s, 76 iterations from the guess, 175 ms/iteration (Hessian 102, Jacobian 48, constraints 14, fatrop's own
11 ms), final time 0.6711046399 s; gtmodel's fatrop 1.70 CPU-s (34 iterations from its 50-element coarse start,
whose CPU is included: 50 ms/iteration), 0.6711046394 s (8.5e-10 relative); ratio 7.8x. CPU per iteration 400
over 50 elements: 9.7x condensed (175 / 18.1; the goal <= 9x), fatrop's own work 8.4x (10.9 / 1.3 ms).

VERDICT. Condensing pays in the solver (fatrop's own work per iteration 1.3 ms against 3.5 ms: Riccati on 16
stage variables instead of 34) and loses more in the functions: each element's exact first and second derivatives
by the implicit function theorem are ~95,000 SX instructions (``el_hess`` 68,687: the 18-by-16 sensitivity
``S``, the adjoint ``mu``, ``Z' W Z``; ``el_jac`` 25,993), against the transcription's per-point derivatives, and
every call of ``nlp_g``, ``nlp_jac_g`` and ``nlp_hess_l`` solves the element's Newton iteration again (the plugins
keep no state between calls). Best measured: 0.424 s against gtmodel's 0.198-0.218 s. The goal (<= 0.1x Opti
``expand=True``, ~0.098 s) is out of reach this way: fatrop's 55 iterations at 1.3 ms are 0.072 s before any
function, leaving ~10 microseconds per element and iteration for a Newton solve and second-order sensitivities.
acados (this structure in C with HPIPM) takes 0.36 s, 65 iterations, 5.5 ms each with 3 inputs per stage. And
the condensed NLP is not robust on coarse meshes: on 12 elements (h = 0.056 s) the element's full-step Newton
iteration from the straight line fails near the friction's steep tanh and neither solver converges (IPOPT:
3000 iterations; fatrop: 375, ``SOLVER_RET_UNKNOWN``), where gtmodel's transcription solves in 40 iterations;
mesh refinement and the coarse start rely on such meshes. Fewer iterations (a better start) would help either
transcription alike.

Medians of ``--repeat`` solves after one warm-up; with ``--json`` the last line of stdout is one JSON object
(per mesh and solver: ``condensed_cpu_s``, ``condensed_iterations``, ``condensed_ms_per_iteration``,
``condensed_final_time_s``, ``condensed_t_proc`` (CPU per NLP function), ``peer_cpu_s``, ``peer_iterations``,
``peer_ms_per_iteration``, ``peer_final_time_s``, ``ratio_cpu_to_peer``, ``final_time_rel_diff``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel.problems import load_problem
from gtmodel.trajectory import point_to_point as ptp
from gtmodel.trajectory.point_to_point import SOLVER_OPTIONS

from bench_solve import export_acados, ours, with_solver  # the same problem functions as the acados peer's

ROOT = Path(__file__).resolve().parents[1]
#: The rootfinder of the collocation equations of one element and its tolerance.
ROOTFINDER = ("fast_newton", {"abstol": 1e-13, "max_iter": 30, "error_on_fail": False})
#: Compilation of the element functions.
JIT = {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O2"], "verbose": False}}


def element_functions(ode: ca.Function, path: ca.Function, final: ca.Function, N: int, d: int, u_nom: np.ndarray, jit: dict) -> dict:
    """The condensed element: its rootfinder and its outputs with first and second derivatives.

    Parameters
    ----------
    ode, path, final : casadi.Function
        ``(x, u) ->`` the state derivative (nx,), the path constraints, the final constraints (``u`` unscaled, N).
    N, d : int
        Elements (uniform mesh: ``h = T / N``) and Radau points per element.
    u_nom : numpy.ndarray
        The inputs' scale, shape (nu,): the NLP's inputs are ``u / u_nom``.
    jit : dict
        Function options compiling them (:data:`JIT`), or ``{}``.

    Returns
    -------
    dict
        ``rf(X_guess, p) -> X`` (``p = (x_k, T, U)``, (nx + 1 + nu d,); ``X`` (nx d,)); ``jac(p, X) -> (o, do/dp)``;
        ``hess(p, X, lam) -> d2(lam' o)/dp2`` (``o``: the end state, the path constraints at the points, the final
        constraints at the end state and the last point's input); ``no``, ``npar``.
    """
    nx, nu = int(ode.size1_in(0)), int(ode.size1_in(1))
    tau = np.array(ca.collocation_points(d, "radau"))
    C = np.array(ca.collocation_coeff(tau.tolist())[0])  # (d + 1, d): derivative of basis r at point j
    npar = nx + 1 + nu * d
    p, X = ca.SX.sym("p", npar), ca.SX.sym("X", nx * d)
    h = p[nx] / N
    xs = [p[:nx]] + [X[j * nx:(j + 1) * nx] for j in range(d)]
    us = [p[nx + 1 + j * nu:nx + 1 + (j + 1) * nu] * u_nom for j in range(d)]
    G = ca.vertcat(*[h * ode(xs[j + 1], us[j]) - sum(C[r, j] * xs[r] for r in range(d + 1)) for j in range(d)])
    o = ca.vertcat(xs[d], *[path(xs[j + 1], us[j]) for j in range(d)], final(xs[d], us[d - 1]))
    A, B = ca.jacobian(G, X), ca.jacobian(G, p)
    S = -ca.solve(A, B)
    oX = ca.jacobian(o, X)
    J = ca.jacobian(o, p) + ca.mtimes(oX, S)
    lam, mu = ca.SX.sym("lam", o.numel()), ca.SX.sym("mu", nx * d)
    W, _ = ca.hessian(ca.dot(lam, o) + ca.dot(mu, G), ca.vertcat(p, X))
    Z = ca.vertcat(ca.DM.eye(npar), S)
    H = ca.mtimes([Z.T, ca.substitute(W, mu, -ca.solve(A.T, ca.mtimes(oX.T, lam))), Z])
    Gf = ca.Function("G", [X, p], [G], {"cse": True})
    rf = ca.rootfinder("rf", ROOTFINDER[0], Gf, ROOTFINDER[1])
    Xg, pm = ca.MX.sym("Xg", nx * d), ca.MX.sym("p", npar)
    return {"rf": ca.Function("el_root", [Xg, pm], [rf(Xg, pm)], jit),
            "jac": ca.Function("el_jac", [p, X], [o, J], {"cse": True, **jit}),
            "hess": ca.Function("el_hess", [p, X, lam], [H], {"cse": True, **jit}), "no": int(o.numel()), "npar": npar}


def condensed_solver(folder: Path, solver: str, jit: bool = True, compile_assembly: bool = False) -> dict:
    """The condensed NLP of the problem exported by :func:`bench_solve.export_acados` in ``folder``, and its solver.

    Stage ``k`` of fatrop: the states ``(x_k, T_k)``, the inputs ``U_k``; its rows: the continuity
    ``x_{k+1} - x_end(p_k)`` and the tie ``T_{k+1} - T_k``, then the path constraints at its points (stage 0: the
    start constraints, path constraints and input bounds at the start; stage ``N - 1``: the final constraints).

    Parameters
    ----------
    folder : pathlib.Path
        ``problem.npz`` and its functions.
    solver : {"fatrop", "ipopt"}
        The nlpsol plugin.
    jit : bool, optional
        Compile the element functions (:data:`JIT`; the NLP's assembly of them is interpreted, a few mapped calls);
        default True (False: CasADi's interpreter, no compiler needed).
    compile_assembly : bool, optional
        Compile the NLP's ``nlp_g``, ``nlp_jac_g`` and ``nlp_hess_l`` as well (their code grows with the mesh:
        minutes of gcc at 50 elements, not finished in 24 min at 400). Default False.

    Returns
    -------
    dict
        ``solver`` (casadi.Function), ``args`` (its bounds and initial guess), ``tf_index``.
    """
    z = np.load(folder / "problem.npz")
    N, d = int(z["N"]), int(z["d"])
    ode, path, start, final = (ca.Function.load(str(folder / f"{n}.casadi")) for n in ("ode", "path", "start", "final"))
    nx, nu, u_nom = int(ode.size1_in(0)), int(ode.size1_in(1)), z["u_nom"]
    el = element_functions(ode, path, final, N, d, u_nom, JIT if jit else {})
    npar, no, npath = el["npar"], el["no"], int(path.size1_out(0)) * d
    tau = np.array(ca.collocation_points(d, "radau"))
    w = ca.MX.sym("w", N * npar + nx)
    E, XN = ca.reshape(w[:N * npar], npar, N), w[N * npar:]
    Xk, Tk, Uk = E[:nx, :], E[nx:nx + 1, :], E[nx + 1:, :]
    Xnext = ca.horzcat(Xk[:, 1:], XN)
    E0 = ca.no_grad(E)  # the point the surrogates are expanded about
    guess = ca.no_grad(ca.vertcat(*[Xk + float(tau[j]) * (Xnext - Xk) for j in range(d)]))
    Xs = ca.no_grad(el["rf"].map(N, "serial")(guess, E0))
    Ov, Jv = (ca.no_grad(v) for v in el["jac"].map(N, "serial")(E0, Xs))
    dE = E - E0
    Jk, dk = ca.MX.sym("J", no, npar), ca.MX.sym("dE", npar)
    O = Ov + ca.Function("lin", [Jk, dk], [ca.mtimes(Jk, dk)]).map(N, "serial")(Jv, dE)  # value and Jacobian exact
    cont = Xnext - O[:nx, :]
    tie = Tk[:, 1:] - Tk[:, :-1]
    u_start = ca.mtimes(ca.reshape(Uk[:, 0], nu, d), ca.DM(z["L0"])) * u_nom
    startc = ca.vertcat(start(Xk[:, 0], u_start), path(Xk[:, 0], u_start), u_start / u_nom)
    g, lbg, ubg, sel, ng = [], [], [], np.zeros((no, N), dtype=int), []
    sign = np.ones((no, N))
    row = 0
    for k in range(N):
        dyn = ca.vertcat(cont[:, k], tie[:, k]) if k < N - 1 else cont[:, k]
        sel[:nx, k], sign[:nx, k] = np.arange(row, row + nx), -1.0  # the rows of the end state (cont = x_next - x_end)
        row += dyn.shape[0]
        parts = [(O[nx:nx + npath, k], np.tile(z["path_lb"], d), np.tile(z["path_ub"], d))]
        sel[nx:nx + npath, k] = np.arange(row, row + npath)
        if k == 0:
            parts.append((startc, np.concatenate([z["start_lb"], z["path_lb"], z["u_lb"]]),
                          np.concatenate([z["start_ub"], z["path_ub"], z["u_ub"]])))
        if k == N - 1:
            first = row + sum(int(e.shape[0]) for e, _, _ in parts)
            sel[nx + npath:, k] = np.arange(first, first + no - nx - npath)
            parts.append((O[nx + npath:, k], z["final_lb"], z["final_ub"]))
        else:
            sel[nx + npath:, k], sign[nx + npath:, k] = 0, 0.0  # the final constraints: the last element's alone
        stage = ca.vertcat(*[e for e, _, _ in parts])
        g += [dyn, stage]
        lbg += [np.zeros(dyn.shape[0]), *[lo for _, lo, _ in parts]]
        ubg += [np.zeros(dyn.shape[0]), *[hi for _, _, hi in parts]]
        ng.append(int(stage.shape[0]))
        row += stage.shape[0]
    g = ca.vertcat(*g)
    tf_index = nx + (N - 1) * npar
    scale = SOLVER_OPTIONS["obj_scaling_factor"]
    f = w[tf_index] * (scale if solver == "fatrop" else 1.0)  # fatrop has no obj_scaling_factor: gtmodel scales f
    cj = JIT if compile_assembly else {}
    lam_f, lam_g, p0 = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", g.shape[0]), ca.MX.sym("p", 0, 1)
    Lam = ca.reshape(lam_g[sel.ravel(order="F").tolist()], no, N) * ca.DM(sign)
    Hv = ca.no_grad(el["hess"].map(N, "serial")(E0, Xs, Lam))
    Hk = ca.MX.sym("H", npar, npar)
    quad = ca.sum2(ca.Function("quad", [Hk, dk], [0.5 * ca.bilin(Hk, dk, dk)]).map(N, "serial")(Hv, dE))
    hess, grad = ca.hessian(lam_f * f + ca.dot(lam_g, g) + quad, w)
    jac = ca.Function("nlp_jac_g", [w, p0], [g, ca.jacobian(g, w)], ["x", "p"], ["g", "jac_g_x"], cj)
    g_fn = ca.Function("nlp_g", [w, p0], [g], ["x", "p"], ["g"], cj)
    opts = {"print_time": False, "record_time": True, "error_on_fail": False}
    if solver == "fatrop":
        opts.update({"structure_detection": "manual", "N": N, "nx": [nx + 1] * N + [nx], "nu": [nu * d] * N + [0], "ng": ng + [0],
                     "fatrop": {"max_iter": 3000, "tol": 1e-8, "print_level": 0},
                     "cache": {"nlp_g": g_fn, "nlp_jac_g": jac,
                               "nlp_hess_l": ca.Function("nlp_hess_l", [w, p0, lam_f, lam_g], [grad, hess], ["x", "p", "lam_f", "lam_g"],
                                                         ["grad_gamma_x", "hess_gamma_x_x"], cj)}})
    else:
        opts.update({"jac_g": jac, "hess_lag": ca.Function("nlp_hess_l", [w, p0, lam_f, lam_g], [ca.triu(hess)],
                                                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"], cj),
                     "ipopt": {"max_iter": 3000, "tol": 1e-8, "print_level": 0, "sb": "yes", "mumps_mem_percent": 20, **SOLVER_OPTIONS}})
    bound = lambda x, t, u: np.concatenate([x, [t], np.tile(u, d)])  # noqa: E731
    inf = np.inf
    lbw = np.concatenate([bound(z["x_lb"], z["tf_bounds"][0] if k == N - 1 else -inf, z["u_lb"]) for k in range(N)] + [z["x_lb"]])
    ubw = np.concatenate([bound(z["x_ub"], z["tf_bounds"][1] if k == N - 1 else inf, z["u_ub"]) for k in range(N)] + [z["x_ub"]])
    w0 = np.concatenate([np.concatenate([z["x_guess"][k], [float(z["tf_guess"])], z["u_guess"][k].ravel()]) for k in range(N)] + [z["x_guess"][N]])
    return {"solver": ca.nlpsol("condensed", solver, {"x": w, "f": f, "g": g_fn(w, p0) if compile_assembly else g}, opts),
            "args": {"x0": w0, "lbx": lbw, "ubx": ubw, "lbg": np.concatenate(lbg), "ubg": np.concatenate(ubg)}, "tf_index": tf_index}


def run_condensed(c: dict) -> tuple[float, int, float, str, dict]:
    """One condensed solve from the guess: (process CPU s, iterations, final time s, status, CPU per NLP function)."""
    t = time.process_time()
    sol = c["solver"](**c["args"])
    cpu = time.process_time() - t
    st = c["solver"].stats()
    return (cpu, int(st["iter_count"]), float(sol["x"][c["tf_index"]]), str(st.get("unified_return_status", st.get("return_status"))),
            {k: float(v) for k, v in st.items() if k.startswith("t_proc_nlp") and v})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("problem", nargs="?", default=str(ROOT / "problems/l1_time_optimal.toml"))
    ap.add_argument("--elements", default="50,400", help="meshes")
    ap.add_argument("--solver", default="fatrop,ipopt", help="nlpsol plugins")
    ap.add_argument("--repeat", type=int, default=3, help="solves per figure (median)")
    ap.add_argument("--compile-assembly", action="store_true", help="compile the NLP's functions too (slow to build)")
    ap.add_argument("--json", action="store_true", help="print one JSON object on the last line")
    a = ap.parse_args()
    decl = load_problem(a.problem).declaration  # the NLP on the exported mesh: no refinement after a failed verification
    decl = dataclasses.replace(decl, refinement=dataclasses.replace(decl.refinement, on_failure=False))
    ptp.SOLVER_OPTIONS = {**SOLVER_OPTIONS, "record_time": True}  # CPU time in the peer's stats
    print(f"casadi {ca.__version__}; load average {os.getloadavg()[0]:.2f}; OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS')}")
    out: dict = {"problem": Path(a.problem).name, "rows": {}}
    for n in (int(x) for x in a.elements.split(",")):
        with tempfile.TemporaryDirectory(prefix="gtmodel_condensed_") as tmp:
            folder = export_acados(dataclasses.replace(decl, elements=n), Path(tmp)).parent
            for solver in a.solver.split(","):
                t = time.process_time()
                c = condensed_solver(folder, solver, compile_assembly=a.compile_assembly)
                build = time.process_time() - t
                peer_decl = with_solver(decl, solver, n)
                run_condensed(c), ours(peer_decl)  # warm-up (the peer compiles or loads its derivatives)
                mine, peer = [], []
                for _ in range(a.repeat):  # alternated: the machine's load falls on both
                    mine.append(run_condensed(c))
                    peer.append(ours(peer_decl))
                cpu, pcpu = statistics.median(m[0] for m in mine), statistics.median(p[4] for p in peer)
                row = {"elements": n, "solver": solver, "condensed_build_cpu_s": build, "condensed_cpu_s": cpu,
                       "condensed_iterations": mine[0][1], "condensed_ms_per_iteration": 1e3 * cpu / max(mine[0][1], 1),
                       "condensed_final_time_s": mine[0][2], "condensed_status": mine[0][3],
                       "condensed_t_proc": {k: statistics.median(m[4].get(k, 0.0) for m in mine) for k in mine[0][4]},
                       "peer_cpu_s": pcpu, "peer_iterations": peer[0][2], "peer_ms_per_iteration": 1e3 * pcpu / max(peer[0][2], 1),
                       "peer_final_time_s": peer[0][1], "peer_status": peer[0][3], "peer_coarse_start": bool(peer[0][5]),
                       "ratio_cpu_to_peer": cpu / pcpu, "final_time_rel_diff": abs(mine[0][2] - peer[0][1]) / abs(peer[0][1])}
                out["rows"][f"{solver}_{n}"] = row
                print(f"{n:4d} elements, {solver:6s}: condensed {cpu:.3f} CPU-s, {row['condensed_iterations']} it, "
                      f"{row['condensed_ms_per_iteration']:.2f} ms/it, T_f {mine[0][2]:.10f} ({mine[0][3]}); gtmodel {pcpu:.3f} CPU-s, "
                      f"{peer[0][2]} it{' (+ coarse start)' if peer[0][5] else ''}, {row['peer_ms_per_iteration']:.2f} ms/it, "
                      f"T_f {peer[0][1]:.10f}; ratio {row['ratio_cpu_to_peer']:.2f}x, T_f rel. diff {row['final_time_rel_diff']:.1e}; "
                      f"condensed CPU per function {row['condensed_t_proc']}", flush=True)
    out["load_average"] = os.getloadavg()[0]
    if a.json:
        print(json.dumps(out))


if __name__ == "__main__":
    main()
