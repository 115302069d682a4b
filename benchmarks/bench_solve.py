"""Solve time of the minimum-time OCP against the same NLP written directly in casadi.Opti (a benchmark, not a test).

Usage: python benchmarks/bench_solve.py [problem.toml] [--json] [--repeat 3] [--grid 50,100,200,400] [--no-acados] [--published]

Measured side by side in one run, because these machines are noisy:
- ``solve_s``: gtmodel's solve of the problem (default ``problems/l1_time_optimal.toml``),
  the IPOPT call only (the NLP built and its compiled derivatives cached beforehand);
- ``peer_solve_s``: the same NLP (same model equations, mesh, constraints, force scaling,
  initial guess and IPOPT options, :data:`IPOPT_DEFAULTS` included) written directly in ``casadi.Opti``, the IPOPT call only;
- ``opti_expand_solve_cpu_s`` (printed first, as ``ratio_cpu_to_opti_expand``): the same Opti with
  ``expand=True`` (its MX graph expanded to SX: Opti's fastest form), CPU time, with its
  ``opti_expand_solve_s``, ``_iterations``, ``_status``, ``_final_time_s`` and ``_final_time_rel_diff``;
  the three solves alternated, ``--repeat`` rounds;
- ``best_solve_cpu_s`` and ``best_config``: the project's fastest configuration measured here
  (IPOPT or fatrop), ``best_ratio_cpu_to_opti_expand``; ``cpu_per_iteration_400_over_50``: the
  CPU per IPOPT iteration at the grid's largest mesh over the smallest (``ms_per_iteration_cpu_ratio``);
- ``acados_solve_cpu_s``: acados (0.2.2, in its own venv, ``benchmarks/acados_env.sh``; built once before
  the rounds, then one solve per round, alternated with gtmodel's IPOPT and fatrop solves and the Opti
  peers: :class:`AcadosServer`) on the same problem exported by :func:`export_acados` (the same
  model equations, bounds, boundary conditions, path constraints and initial guess), solved by
  ``benchmarks/peers/acados_ocp.py`` (:data:`ACADOS_ARGS`): time-scaled (``T`` a state with zero
  dynamics), ``N`` = the element count of GAUSS_RADAU_IIA IRK intervals (3 stages, as gtmodel's
  3 Radau points), the force constant per interval, SQP to convergence (1e-8) with the exact Hessian,
  PARTIAL_CONDENSING_HPIPM; the thread CPU of ``solver.solve()``, median of the ``--repeat`` rounds'
  solves from the guess (``acados_solve_cpu_s_all``); ``ratio_cpu_to_acados``: the median CPU of
  gtmodel's faster configuration in those same rounds (IPOPT or fatrop, ``ratio_cpu_to_acados_config``;
  both in ``ratio_cpu_to_acados_by_config``, round by round in ``ratio_cpu_to_acados_rounds``) over
  acados' median, None with ``peer_failed`` when an acados solve did not converge (status not 0);
  ``acados_iterations``, ``acados_status``, ``acados_statuses``, ``acados_final_time_s``,
  ``acados_final_time_rel_diff`` (from gtmodel's: the discretisations differ, see the peer's
  docstring), ``acados_config``; ``acados_skipped`` with the reason instead when acados' venv cannot
  be made (or ``--no-acados``) or the problem is not one the peer is written for;
- with ``--published``, ``acados_published``: the same peer (:data:`ACADOS_PUBLISHED_ARGS`) and gtmodel's
  solve on the published minimum-time benchmarks :data:`ACADOS_PUBLISHED` (COPS 3.0 robot arm, published
  9.14101; Bryson and Ho's double integrator, 2), each final time against its published value, the CPU of
  both and ``ratio_cpu_to_acados`` per file (:func:`published_rows`);
- ``final_time_s`` and ``peer_final_time_s``: the two optima;
- ``ms_per_iteration``: gtmodel's solve time per IPOPT iteration at 50, 100, 200 and 400
  elements (the cost of one iteration should grow linearly with the mesh);
- ``fatrop_solve_s``: the same problem with ``[solver] name = "fatrop"`` (the NLP ordered
  stage by stage, CasADi's fatrop plugin, given gtmodel's compiled derivatives), the solver
  call only; ``fatrop_final_time_s``, ``fatrop_iterations``, ``fatrop_speedup``
  (``peer_solve_s / fatrop_solve_s``) and ``fatrop_scaling_400_over_50``: its solve time at
  the grid's largest mesh over the 50-element one (from 200 elements on it includes the
  coarse 50-element solve it starts from, ``fatrop_coarse_start``);
- ``fatrop_solver_cpu_s``: the CPU time of the 50-element fatrop solve without the NLP's
  functions (``t_proc_total`` less every ``t_proc_nlp_*``: fatrop's own work and its
  plugin's), and ``fatrop_speedup_bound_cpu`` (``peer_solve_cpu_s / fatrop_solver_cpu_s``):
  the CPU speedup fatrop would reach if the derivatives cost nothing.
- ``fatrop_machine_blasfeo_solve_cpu_s``: the same 50-element fatrop solve in a child process with
  ``LD_PRELOAD`` of the BLASFEO built for the machine (``libblasfeo.so.0`` in the folder
  ``GTMODEL_HPIPM`` names, made by ``benchmarks/hpipm_build.sh``: BLASFEO 0.1.4.2, the wheel's
  version, for ``X64_INTEL_HASWELL`` instead of the wheel's ``GENERIC``) under CasADi's fatrop
  plugin; alternated, ``--repeat`` rounds, with a child loading the wheel's
  (``fatrop_wheel_blasfeo_solve_cpu_s``); ``fatrop_machine_blasfeo_speedup`` (wheel over machine),
  ``fatrop_machine_blasfeo_solver_cpu_s``, ``fatrop_machine_blasfeo_final_time_rel_diff`` (from
  the wheel child's optimum) and ``fatrop_machine_blasfeo_library`` (the file the child had mapped:
  the preload is checked, not assumed); it enters ``best_solve_cpu_s``. ``fatrop_machine_blasfeo_skipped``
  with the reason instead where the folder or library is missing (:func:`machine_blasfeo`).
Medians of ``--repeat`` solves; the ``*_cpu*`` keys are the same figures in process CPU time
(both solvers are single-threaded: CasADi's OpenBLAS under MUMPS is set to one thread when gtmodel is
imported, for the Opti peers in this process too; ``casadi_blas_threads`` says so; before, without
``OMP_NUM_THREADS=1``, its threads spun and doubled IPOPT's CPU at 400 elements), steadier than wall time on a shared machine. With
``--json`` the last line of stdout is one JSON object.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel._blas import casadi_blas_threads
from gtmodel.codegen.hpipm_source import HPIPM_ENV
from gtmodel.modeling.ocp.collocation_nlp import IPOPT_DEFAULTS, collocation_coefficients
from gtmodel.problems import load_problem
from gtmodel.trajectory import point_to_point as ptp
from gtmodel.trajectory.point_to_point import SOLVER_OPTIONS, build_optimization, solve_point_to_point

from bench_mpc import ACADOS_ENV, acados_available  # the one check of acados' venv (benchmarks/ is on sys.path)

ROOT = Path(__file__).resolve().parents[1]
#: acados' venv maker and the offline minimum-time peer run inside it (issue 46, item 1).
ACADOS_PEER = ROOT / "benchmarks" / "peers" / "acados_ocp.py"
#: The peer's options (see its docstring): the force constant per interval (acados' usual form; gtmodel's
#: polynomial per interval, with a clock state, makes acados 0.2.2's HPIPM return NaN at the second SQP iteration
#: whatever the regularisation, globalisation or step), the exact Hessian projected to positive definite (PROJECT:
#: 65 iterations; with the final time bounded at stage 0 only, 87, MIRROR 171, CONVEXIFY and PROJECT_REDUC_HESS
#: ended in HPIPM's NaN), full steps (MERIT_BACKTRACKING took 176 iterations).
ACADOS_ARGS = ("--controls", "constant", "--regularize", "PROJECT", "--globalization", "FIXED_STEP")
#: Published minimum-time benchmarks of ``problems/benchmarks/`` the peer also solves (``--published``), and its
#: options there: the final constraints an exact L1 penalty and a Levenberg-Marquardt term of 1 (from the files'
#: guessed final times, shorter than the optimum, the first linearised QPs have no solution reaching the final
#: state, and HPIPM returns NaN; without the term the double integrator's second QP does).
ACADOS_PUBLISHED = ("robot_arm", "double_integrator_min_time")
ACADOS_PUBLISHED_ARGS = ACADOS_ARGS + ("--soft", "1000", "--levenberg", "1")


def peer_opti(decl, expand: bool = False) -> tuple[float, float, int, str, float]:
    """The NLP of ``decl`` written directly in casadi.Opti; returns (solve s, final time, iterations, status, CPU s).

    ``expand``: Opti's fastest form, its MX graph expanded to SX before IPOPT (``expand=True``).
    """
    opt, _ = build_optimization(decl)
    dae = opt.flat()
    N, d = decl.method.elements, decl.method.points
    co = collocation_coefficients(d, decl.method.scheme)
    pvec = dae.parameter_vector({**opt.parameters, **decl.named_parameters})
    args = [dae.t, dae.x, dae.z, dae.u, dae.p, opt.final_time]
    xdot = dae.ode_expr

    def fn(exprs):
        e = ca.vertcat(*exprs) if exprs else ca.SX(0, 1)
        return ca.Function("f", args, [ca.substitute(e, dae.xdot, xdot)])

    ode, path = fn([dae.ode_expr]), fn([c.expr for c in opt.path_constraints])
    lagr, mayer = fn([opt.lagrange]), fn([opt.mayer])
    u_lb, u_ub = opt.bounds_vectors(dae, "u")
    u_nom = np.asarray(decl.force_limit, dtype=float)  # the same scaling as gtmodel's nominal
    opti = ca.Opti()
    tf = opti.variable()
    X = [[opti.variable(dae.nx) for _ in range(d + 1)] for _ in range(N)] + [[opti.variable(dae.nx)]]
    U = [[opti.variable(dae.nu) for _ in range(d)] for _ in range(N)]
    p = ca.DM(pvec)
    t0 = opt.start_time
    h = (tf - t0) / N
    J = 0
    for k in range(N):
        for j in range(1, d + 1):
            t = t0 + (k + co["root"][j]) * h
            u = U[k][j - 1] * u_nom
            xp = sum(co["C"][r, j] * X[k][r] for r in range(d + 1))
            opti.subject_to(h * ode(t, X[k][j], ca.MX(0, 1), u, p, tf) == xp)
            lo, hi = np.concatenate([c.lb for c in opt.path_constraints]), np.concatenate([c.ub for c in opt.path_constraints])
            opti.subject_to(opti.bounded(lo, path(t, X[k][j], ca.MX(0, 1), u, p, tf), hi))
            opti.subject_to(opti.bounded(u_lb / u_nom, U[k][j - 1], u_ub / u_nom))
            J += co["B"][j - 1] * h * lagr(t, X[k][j], ca.MX(0, 1), u, p, tf)
        xend = sum(co["D"][r] * X[k][r] for r in range(d + 1))
        opti.subject_to(X[k + 1][0] == xend)
    u0 = sum(co["L0"][j] * U[0][j] for j in range(d)) * u_nom
    uN = sum(co["L1"][j] * U[-1][j] for j in range(d)) * u_nom
    for c in opt.point_constraints:
        e = ca.Function("e", args, [ca.substitute(c.expr, dae.xdot, xdot)])
        val = e(t0, X[0][0], ca.MX(0, 1), u0, p, tf) if c.at == "start" else e(tf, X[N][0], ca.MX(0, 1), uN, p, tf)
        opti.subject_to(opti.bounded(c.lb, val, c.ub))
    opti.subject_to(opti.bounded(opt.final_time_bounds[0], tf, opt.final_time_bounds[1]))
    opti.minimize(J + mayer(tf, X[N][0], ca.MX(0, 1), uN, p, tf))
    # the same initial guess as gtmodel's: the declared guesses at the collocation times
    tfg = opt.final_time_guess
    guess = {name: opt.initial_guesses[name] for name in ("T", "T_dot", "tau")}
    for k in range(N + 1):
        for j in range(d + 1 if k < N else 1):
            t = t0 + (k + co["root"][j]) * (tfg - t0) / N
            opti.set_initial(X[k][j], np.concatenate([np.ravel(guess["T"](t)), np.ravel(guess["T_dot"](t))]))
            if 1 <= j and k < N:
                opti.set_initial(U[k][j - 1], np.clip(np.ravel(guess["tau"](t)) / u_nom, -1, 1))
    opti.set_initial(tf, tfg)
    ipopt = {"max_iter": decl.solver.max_iter, "tol": decl.solver.tol, "print_level": int(os.environ.get("PEER_PRINT", 0)), "sb": "yes", **IPOPT_DEFAULTS, **SOLVER_OPTIONS}
    opti.solver("ipopt", {"print_time": False, "record_time": True, "error_on_fail": False, "expand": bool(expand)}, ipopt)
    sol = opti.solve()
    st = sol.stats()
    return float(st["t_wall_total"]), float(sol.value(tf)), int(st["iter_count"]), str(st["return_status"]), float(st["t_proc_total"])


def export_acados(decl, folder: Path) -> Path:
    """The minimum-time point-to-point problem ``decl`` for the acados peer: :func:`export_acados_ocp` of its Optimization.

    Parameters
    ----------
    decl : PointToPoint
        A minimum-time problem (objective ``final_time``, free final time, Radau collocation).
    folder : pathlib.Path
        Where the files go.

    Returns
    -------
    pathlib.Path
        ``folder / "problem.npz"``.
    """
    opt, _ = build_optimization(decl)
    return export_acados_ocp(opt, decl.method, {**opt.parameters, **decl.named_parameters},
                             np.asarray(decl.force_limit, dtype=float), folder)


def export_acados_ocp(opt, method, parameters: dict, u_nom: np.ndarray, folder: Path) -> Path:
    """A minimum-time :class:`~gtmodel.modeling.Optimization` for the acados peer (:data:`ACADOS_PEER`): ``problem.npz`` and its functions.

    The same model equations as gtmodel's NLP (the flattened DAE's explicit ODE, its parameters
    substituted), saved by CasADi's ``Function.save``: ``ode(x, u) -> x'``, ``path(x, u)`` (the
    path constraints), ``start(x, u)`` and ``final(x, u)`` (the point constraints, ``x'``
    substituted: a rest-to-rest acceleration depends on the input); the state and input bounds, the
    Radau points, the input scale and the initial guess (gtmodel's: the declared guesses, else the
    variables' start values, at the nodes and collocation times of the guessed final time, clipped
    into the bounds).

    Parameters
    ----------
    opt : gtmodel.modeling.Optimization
        Objective ``final_time`` alone, free final time, no algebraic variables or free parameters.
    method : object
        Its transcription (``elements``, ``points``, ``scheme`` = ``"radau"``).
    parameters : dict
        The model's parameter values.
    u_nom : numpy.ndarray
        The inputs' scale (the peer's controls are ``u / u_nom``).
    folder : pathlib.Path
        Where the files go.

    Returns
    -------
    pathlib.Path
        ``folder / "problem.npz"``.

    Raises
    ------
    ValueError
        The problem is not one the peer is written for.
    """
    from gtmodel.modeling.ocp.guesses import guess_values

    dae = opt.flat()
    N, d = method.elements, method.points
    if method.scheme != "radau" or not opt.free_final_time or dae.nz or opt.free_parameters or opt.special_symbols():
        raise ValueError("the acados peer is written for a free final time, Radau collocation, no algebraic variables, "
                         "free parameters or timed variables")
    co = collocation_coefficients(d, method.scheme)
    pvec = ca.DM(dae.parameter_vector(parameters))
    x, u = ca.SX.sym("x", dae.nx), ca.SX.sym("u", dae.nu)

    def fn(name, exprs):
        e = ca.substitute(ca.vertcat(*exprs), dae.xdot, dae.ode_expr) if exprs else ca.SX(0, 1)
        e = ca.substitute(e, ca.vertcat(dae.x, dae.u, dae.p), ca.vertcat(x, u, pvec))
        if ca.depends_on(e, ca.vertcat(dae.t, opt.final_time)):
            raise ValueError(f"{name} depends on time: the acados peer is written for time-invariant equations")
        return ca.Function(name, [x, u], [e])

    lagr = fn("lagrange", [opt.lagrange])
    rng = np.random.default_rng(0)
    if any(abs(float(lagr(rng.normal(size=dae.nx), rng.normal(size=dae.nu)))) > 0 for _ in range(3)) or \
            not ca.is_equal(opt.mayer, opt.final_time):
        raise ValueError("the acados peer is written for the objective final_time alone")
    folder.mkdir(parents=True, exist_ok=True)
    starts = [c for c in opt.point_constraints if c.at == "start"]
    finals = [c for c in opt.point_constraints if c.at == "final"]
    if len(starts) + len(finals) != len(opt.point_constraints):
        raise ValueError("the acados peer is written for point constraints at the start and final times only")
    funcs = {"ode": fn("ode", [dae.ode_expr]), "path": fn("path", [c.expr for c in opt.path_constraints]),
             "start": fn("start", [c.expr for c in starts]), "final": fn("final", [c.expr for c in finals])}
    for name, f in funcs.items():
        f.save(str(folder / f"{name}.casadi"))
    x_lb, x_ub = opt.bounds_vectors(dae, "x")
    u_lb, u_ub = opt.bounds_vectors(dae, "u")
    tfg, t0 = opt.final_time_guess, opt.start_time

    def guess(kind, t):
        out = []
        for name, sl in (dae.x_vars if kind == "x" else dae.u_vars).items():
            default = np.asarray(opt.model._vars[name].start, dtype=float).reshape(-1)
            out.append(guess_values(opt.initial_guesses.get(name), sl.stop - sl.start, name, default, t))
        lo, hi = (x_lb, x_ub) if kind == "x" else (u_lb, u_ub)
        return np.clip(np.hstack(out), lo, hi)

    x_guess = guess("x", t0 + np.arange(N + 1) * (tfg - t0) / N)
    tc = np.array([t0 + (k + co["tau"][j]) * (tfg - t0) / N for k in range(N) for j in range(d)])
    u_guess = (guess("u", tc) / u_nom).reshape(N, d, dae.nu)
    cat = np.concatenate

    def bounds(cs, i):
        return cat([np.ravel(c.lb if i == 0 else c.ub) for c in cs]) if cs else np.zeros(0)

    path = folder / "problem.npz"
    np.savez(path, N=N, d=d, tau=co["tau"], L0=co["L0"], u_nom=u_nom, u_lb=u_lb / u_nom, u_ub=u_ub / u_nom, x_lb=x_lb, x_ub=x_ub,
             path_lb=bounds(opt.path_constraints, 0), path_ub=bounds(opt.path_constraints, 1),
             start_lb=bounds(starts, 0), start_ub=bounds(starts, 1), final_lb=bounds(finals, 0), final_ub=bounds(finals, 1),
             tf_bounds=np.asarray(opt.final_time_bounds, float), tf_guess=tfg, x_guess=x_guess, u_guess=u_guess,
             **{f"{name}_file": f"{name}.casadi" for name in funcs})
    return path


class AcadosServer:
    """The acados peer (:data:`ACADOS_PEER` ``--serve`` in its venv) built once, then one solve per :meth:`solve`.

    So that its solves alternate with gtmodel's in the same rounds (the machine's load falls on
    both); :func:`acados_open` makes one, or says why it cannot.

    Parameters
    ----------
    problem : pathlib.Path
        The exported ``problem.npz`` (:func:`export_acados`), in a folder that outlives the server.
    args : tuple of str
        The peer's options.
    """

    def __init__(self, problem: Path, args: tuple = ACADOS_ARGS):
        self.log = problem.parent / "acados_peer.stderr"
        with open(self.log, "w") as err:
            self.proc = subprocess.Popen([str(ACADOS_ENV), "python", str(ACADOS_PEER), str(problem), "--serve", *args],
                                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err, text=True,
                                         env={**os.environ, "OMP_NUM_THREADS": "1"})
        if not self.proc.stdout.readline():
            self.close()
            raise RuntimeError(self.failure())

    def failure(self) -> str:
        """The peer's exit and the last lines of its stderr."""
        tail = self.log.read_text(errors="replace").strip().splitlines()[-3:] if self.log.exists() else []
        return f"the acados peer failed (exit {self.proc.poll()}): " + " | ".join(tail)

    def solve(self) -> dict:
        """One solve from the exported guess: ``solve_cpu_s``, ``time_tot_s``, ``iterations``, ``status``, ``final_time_s``, ``config``.

        Returns
        -------
        dict
            The peer's JSON answer.
        """
        self.proc.stdin.write("solve\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(self.failure())
        return json.loads(line)

    def close(self) -> None:
        """End the peer."""
        try:
            if self.proc.poll() is None:
                self.proc.stdin.write("quit\n")
                self.proc.stdin.close()
        except OSError:
            pass
        self.proc.wait(timeout=60)


def acados_open(export, folder: Path, args: tuple = ACADOS_ARGS) -> AcadosServer | str:
    """An :class:`AcadosServer` on a problem exported into ``folder``, or the reason there is none.

    Parameters
    ----------
    export : callable
        ``export(folder) -> problem.npz`` (:func:`export_acados` or :func:`export_acados_ocp` bound to a problem).
    folder : pathlib.Path
        Where the problem goes and acados generates and compiles its solver (kept while the server runs).
    args : tuple of str
        The peer's options.

    Returns
    -------
    AcadosServer or str
    """
    reason = acados_available()
    if reason:
        return reason
    try:
        problem = export(folder)
    except ValueError as e:
        return f"not run: {e}"
    try:
        return AcadosServer(problem, args)
    except RuntimeError as e:
        return str(e)


def acados_summary(runs: list[dict], reference_final_time: float) -> dict:
    """acados' figures over its solves of the rounds: the median CPU, the first solve's iterations and status.

    Parameters
    ----------
    runs : list of dict
        :meth:`AcadosServer.solve` answers, one per round.
    reference_final_time : float
        gtmodel's final time, for ``acados_final_time_rel_diff``.

    Returns
    -------
    dict
        ``acados_solve_cpu_s`` (median), ``acados_solve_cpu_s_all``, ``acados_time_tot_s``, ``acados_iterations``,
        ``acados_status`` (0: converged), ``acados_statuses``, ``acados_final_time_s``,
        ``acados_final_time_rel_diff``, ``acados_config``; and ``acados_failed``, why the ratio is withheld
        (a status other than 0 in a round, a final time not finite), else None.
    """
    statuses = [int(r["status"]) for r in runs]
    final = float(runs[0]["final_time_s"])
    bad = [s for s in statuses if s != 0]
    failed = (f"acados: status {bad[0]} in {len(bad)} of {len(runs)} rounds, no ratio" if bad else
              None if np.isfinite(final) else "acados: final time not finite, no ratio")
    return {"acados_solve_cpu_s": statistics.median(r["solve_cpu_s"] for r in runs),
            "acados_solve_cpu_s_all": [r["solve_cpu_s"] for r in runs],
            "acados_time_tot_s": statistics.median(r["time_tot_s"] for r in runs),
            "acados_iterations": int(runs[0]["iterations"]), "acados_status": statuses[0], "acados_statuses": statuses,
            "acados_final_time_s": final, "acados_final_time_rel_diff": abs(final - reference_final_time) / abs(reference_final_time),
            "acados_config": runs[0]["config"], "acados_failed": failed}


def ratio_to_acados(configs: dict[str, list[float]], acados_cpu: list[float], failed: str | None) -> dict:
    """gtmodel's configurations against acados, each solve measured in the same rounds as acados'.

    Parameters
    ----------
    configs : dict of str to list of float
        gtmodel's CPU per solve of each configuration, one per round.
    acados_cpu : list of float
        acados' CPU per solve, one per round (the same rounds).
    failed : str or None
        Why acados gives no ratio (:func:`acados_summary`), or None.

    Returns
    -------
    dict
        ``ratio_cpu_to_acados`` (the fastest configuration's median over acados' median, the
        configuration in ``ratio_cpu_to_acados_config``), ``ratio_cpu_to_acados_by_config`` and
        ``ratio_cpu_to_acados_rounds`` (that configuration's ratio round by round); all None, with
        ``peer_failed``, when acados failed.
    """
    if failed:
        return {"ratio_cpu_to_acados": None, "ratio_cpu_to_acados_config": None, "ratio_cpu_to_acados_by_config": None,
                "ratio_cpu_to_acados_rounds": None, "peer_failed": failed}
    theirs = statistics.median(acados_cpu)
    by = {name: statistics.median(cpu) / theirs for name, cpu in configs.items()}
    best = min(by, key=by.get)
    return {"ratio_cpu_to_acados": by[best], "ratio_cpu_to_acados_config": best, "ratio_cpu_to_acados_by_config": by,
            "ratio_cpu_to_acados_rounds": [m / t for m, t in zip(configs[best], acados_cpu)], "peer_failed": None}


def published_rows(repeat: int) -> dict:
    """acados and gtmodel on the published minimum-time benchmarks :data:`ACADOS_PUBLISHED`, each against its published value.

    Parameters
    ----------
    repeat : int
        Solves per figure (gtmodel: after one warm-up solve, the median solver CPU of its
        ``timing``, refinement passes included; acados: the peer's median).

    Returns
    -------
    dict
        Per file: ``published``, ``elements``; ``acados_final_time_s``, ``acados_rel_diff_published``,
        ``acados_status``, ``acados_iterations``, ``acados_solve_cpu_s`` (or ``acados_skipped``);
        ``final_time_s``, ``rel_diff_published``, ``solve_cpu_s``, ``refinement_passes`` (gtmodel's);
        ``ratio_cpu_to_acados`` (None, with ``peer_failed``, when an acados solve did not converge).
        gtmodel's and acados' solves alternate, one each per round.
    """
    import functools
    import tomllib

    from bench_ocp_suite import solve_cpu  # the suite's solver CPU of a result (refinement passes included)

    rows = {}
    for name in ACADOS_PUBLISHED:
        path = ROOT / "problems" / "benchmarks" / f"{name}.toml"
        published = float(tomllib.loads(path.read_text())["benchmark"]["published"])
        decl = load_problem(path).declaration
        opt = decl.optimization
        row = {"published": published, "elements": decl.method.elements}
        export = functools.partial(export_acados_ocp, opt, decl.method, opt.parameters, np.ones(opt.flat().nu))
        runs, aruns = [], []
        with tempfile.TemporaryDirectory(prefix="gtmodel_acados_ocp_") as tmp:
            server = acados_open(export, Path(tmp), ACADOS_PUBLISHED_ARGS)
            load_problem(path).declaration.solve()  # compile (or load the cached) derivatives once
            try:
                for _ in range(max(1, repeat)):  # alternated: gtmodel, then acados, in each round
                    runs.append(load_problem(path).declaration.solve())
                    if not isinstance(server, str):
                        aruns.append(server.solve())
            finally:
                if not isinstance(server, str):
                    server.close()
        r = runs[0]
        row.update({"final_time_s": float(r.final_time), "rel_diff_published": abs(float(r.final_time) - published) / published,
                    "status": str(r.status), "refinement_passes": len(r.refinement),
                    "solve_cpu_s": statistics.median(solve_cpu(x) for x in runs)})
        if isinstance(server, str):
            row["acados_skipped"] = server
        else:
            a = acados_summary(aruns, published)
            row.update({"acados_final_time_s": a["acados_final_time_s"], "acados_rel_diff_published": a["acados_final_time_rel_diff"],
                        "acados_status": a["acados_status"], "acados_iterations": a["acados_iterations"],
                        "acados_solve_cpu_s": a["acados_solve_cpu_s"], "acados_final_state_violation": aruns[0]["final_state_violation"],
                        "acados_config": a["acados_config"]})
            ratio = ratio_to_acados({"gtmodel": [solve_cpu(x) for x in runs]}, a["acados_solve_cpu_s_all"], a["acados_failed"])
            row.update({"ratio_cpu_to_acados": ratio["ratio_cpu_to_acados"], "peer_failed": ratio["peer_failed"]})
        rows[name] = row
    return rows


def solve_rounds(decl, fat, server, repeat: int) -> tuple[list, list, list, list, list]:
    """The solves compared, alternated round by round so that the machine's load falls on all of them.

    Parameters
    ----------
    decl, fat : PointToPoint
        The problem solved by IPOPT and by fatrop (:func:`with_solver`).
    server : AcadosServer or str
        acados, built beforehand (:func:`acados_open`), or why it is not there.
    repeat : int
        Rounds.

    Returns
    -------
    tuple of lists
        Per round: gtmodel's IPOPT solves and fatrop solves (:func:`ours`), acados' (:meth:`AcadosServer.solve`;
        empty without acados), Opti ``expand=True`` and the shipped Opti (:func:`peer_opti`).
    """
    mine, fruns, aruns, fast, peer = [], [], [], [], []
    for _ in range(repeat):
        mine.append(ours(decl))
        fruns.append(ours(fat))
        if not isinstance(server, str):
            aruns.append(server.solve())
        fast.append(peer_opti(decl, expand=True))
        peer.append(peer_opti(decl))
    return mine, fruns, aruns, fast, peer


def ours(decl) -> tuple[float, float, int, str, float, dict | None]:
    """gtmodel's solve (the solver call); returns (solve s, final time, iterations, status, CPU s, its coarse start or None, its stats)."""
    s = solve_point_to_point(decl)
    r = s.result
    coarse = r.stats.get("coarse_start") or {}  # a coarse start's CPU time is part of the solve's, as its wall time is
    return (r.solve_time, r.final_time, r.iterations, str(r.status), float(r.stats["t_proc_total"]) + float(coarse.get("t_proc_total") or 0.0),
            r.stats.get("coarse_start"), r.stats)


def solver_cpu(stats: dict) -> float:
    """CPU time of a solve less that of the NLP's functions (``t_proc_nlp_*``): the solver's own and its plugin's."""
    return float(stats["t_proc_total"]) - sum(float(v) for k, v in stats.items() if k.startswith("t_proc_nlp_"))


#: The shared BLASFEO built for the machine, in the folder of :data:`~gtmodel.codegen.hpipm_source.HPIPM_ENV`
#: (``benchmarks/hpipm_build.sh``), with the soname of the wheel's: preloaded, CasADi's plugins bind to it.
MACHINE_BLASFEO = "libblasfeo.so.0"


def machine_blasfeo() -> Path | str:
    """The machine's shared BLASFEO (:data:`MACHINE_BLASFEO` in the folder ``GTMODEL_HPIPM`` names), or why there is none."""
    folder = os.environ.get(HPIPM_ENV, "").strip()
    if not folder:
        return f"{HPIPM_ENV} unset (export {HPIPM_ENV}=\"$(benchmarks/hpipm_build.sh)\" builds the folder)"
    lib = Path(folder).expanduser() / MACHINE_BLASFEO
    if not lib.is_file():
        return f"{lib} missing (benchmarks/hpipm_build.sh links it from the folder's libblasfeo.a)"
    return lib.resolve()


def mapped_blasfeo() -> str:
    """The files of the process' mapped ``libblasfeo`` (``/proc/self/maps``), resolved and joined by ``", "``; ``""`` if none."""
    fields = (line.split() for line in Path("/proc/self/maps").read_text().splitlines())
    return ", ".join(sorted({str(Path(f[5]).resolve()) for f in fields if len(f) >= 6 and Path(f[5]).name.startswith("libblasfeo.so")}))


def peer_declaration(problem: str):
    """The problem's declaration as the peers solve it, on the file's mesh (no refinement after a failed verification).

    The L1's 50-element plan fails its verification under the clipped forces and would be refined (61 elements,
    then 122 to check its objective). Also sets gtmodel's solver options to record CPU time in the stats, as the peers'.
    """
    decl = load_problem(problem).declaration
    ptp.SOLVER_OPTIONS = {**SOLVER_OPTIONS, "record_time": True}
    return dataclasses.replace(decl, refinement=dataclasses.replace(decl.refinement, on_failure=False))


def fatrop_child(problem: str, repeat: int) -> dict:
    """The 50-element fatrop solve of ``problem`` in this process (the child of :func:`fatrop_blasfeo_rounds`): medians of ``repeat``."""
    fat = with_solver(peer_declaration(problem), "fatrop")
    ours(fat)
    runs = [ours(fat) for _ in range(repeat)]
    return {"cpu_s": statistics.median(r[4] for r in runs), "solver_cpu_s": statistics.median(solver_cpu(r[6]) for r in runs),
            "iterations": runs[0][2], "status": runs[0][3], "final_time_s": runs[0][1], "library": mapped_blasfeo()}


def fatrop_blasfeo_rounds(problem: str, lib: Path, rounds: int, repeat: int = 3) -> dict | str:
    """The fatrop solve with the wheel's BLASFEO and with ``lib`` preloaded, children alternated ``rounds`` times.

    Returns the keys ``fatrop_machine_blasfeo_*`` and ``fatrop_wheel_blasfeo_solve_cpu_s`` (medians over the
    rounds), or the reason when a child failed or the preload did not take (its mapped library not ``lib``).
    """
    def child(preload: bool) -> dict | str:
        env = {**os.environ, "OMP_NUM_THREADS": "1"}
        env.pop("LD_PRELOAD", None)
        if preload:
            env["LD_PRELOAD"] = str(lib)
        run = subprocess.run([sys.executable, __file__, problem, "--fatrop-child", "--repeat", str(repeat)], env=env,
                             capture_output=True, text=True, timeout=600)
        if run.returncode != 0:
            return f"the child failed (exit {run.returncode}): {run.stderr.strip().splitlines()[-1:]}"
        return json.loads(run.stdout.strip().splitlines()[-1])

    wheel, machine = [], []
    for _ in range(rounds):
        for preload, into in ((False, wheel), (True, machine)):
            r = child(preload)
            if isinstance(r, str):
                return r
            into.append(r)
    if machine[0]["library"] != str(lib) or wheel[0]["library"] == str(lib):
        return f"the preload did not take: the child mapped {machine[0]['library'] or 'no libblasfeo'}, not {lib}"
    cpu_w, cpu_m = statistics.median(r["cpu_s"] for r in wheel), statistics.median(r["cpu_s"] for r in machine)
    return {"fatrop_machine_blasfeo_solve_cpu_s": cpu_m, "fatrop_wheel_blasfeo_solve_cpu_s": cpu_w,
            "fatrop_machine_blasfeo_speedup": cpu_w / cpu_m,
            "fatrop_machine_blasfeo_solver_cpu_s": statistics.median(r["solver_cpu_s"] for r in machine),
            "fatrop_machine_blasfeo_iterations": machine[0]["iterations"], "fatrop_machine_blasfeo_status": machine[0]["status"],
            "fatrop_machine_blasfeo_final_time_rel_diff": abs(machine[0]["final_time_s"] - wheel[0]["final_time_s"]) / abs(wheel[0]["final_time_s"]),
            "fatrop_machine_blasfeo_library": str(lib)}


def with_solver(decl, name: str, elements: int | None = None):
    """``decl`` solved by ``name`` (and on ``elements`` elements)."""
    return dataclasses.replace(decl, solver=dataclasses.replace(decl.solver, name=name), elements=elements or decl.method.elements)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("problem", nargs="?", default=str(ROOT / "problems/l1_time_optimal.toml"))
    ap.add_argument("--json", action="store_true", help="print one JSON object on the last line")
    ap.add_argument("--repeat", type=int, default=3, help="solves per figure (median)")
    ap.add_argument("--grid", default="50,100,200,400", help="elements of the per-iteration grid")
    ap.add_argument("--no-acados", action="store_true", help="skip the acados peer")
    ap.add_argument("--published", action="store_true", help="also acados and gtmodel on ACADOS_PUBLISHED, against the published optima")
    ap.add_argument("--fatrop-child", action="store_true", help=argparse.SUPPRESS)  # fatrop_blasfeo_rounds' child
    a = ap.parse_args()
    if a.fatrop_child:
        print(json.dumps(fatrop_child(a.problem, a.repeat)))
        return
    decl = peer_declaration(a.problem)
    print(f"casadi {ca.__version__}; load average {os.getloadavg()[0]:.2f} (2 cores shared)")
    ours(decl)  # compile (or load the cached) derivatives once
    fat = with_solver(decl, "fatrop")  # fatrop on the same transcription (stage-wise order)
    ours(fat)
    build = tempfile.TemporaryDirectory(prefix="gtmodel_acados_ocp_")
    server = "skipped (--no-acados)" if a.no_acados else acados_open(lambda folder: export_acados(decl, folder), Path(build.name))
    try:
        mine, fruns, aruns, fast, peer = solve_rounds(decl, fat, server, a.repeat)
    finally:
        if not isinstance(server, str):
            server.close()
        build.cleanup()
    solve_s, peer_s = statistics.median(m[0] for m in mine), statistics.median(p[0] for p in peer)
    out = {
        "problem": Path(a.problem).name,
        "casadi_blas_threads": casadi_blas_threads(),
        "elements": decl.method.elements,
        "solve_s": solve_s,
        "iterations": mine[0][2],
        "status": mine[0][3],
        "peer_solve_s": peer_s,
        "peer_iterations": peer[0][2],
        "peer_status": peer[0][3],
        "final_time_s": mine[0][1],
        "peer_final_time_s": peer[0][1],
        "speedup": peer_s / solve_s,
        "solve_cpu_s": statistics.median(m[4] for m in mine),
        "peer_solve_cpu_s": statistics.median(p[4] for p in peer),
        "final_time_rel_diff": abs(mine[0][1] - peer[0][1]) / abs(peer[0][1]),
        "opti_expand_solve_cpu_s": statistics.median(p[4] for p in fast),
        "opti_expand_solve_s": statistics.median(p[0] for p in fast),
        "opti_expand_iterations": fast[0][2], "opti_expand_status": fast[0][3], "opti_expand_final_time_s": fast[0][1],
        "opti_expand_final_time_rel_diff": abs(mine[0][1] - fast[0][1]) / abs(fast[0][1]),
    }
    out["ratio_cpu_to_opti_expand"] = out["solve_cpu_s"] / out["opti_expand_solve_cpu_s"]
    print(f"gtmodel (IPOPT) CPU / Opti expand=True CPU: {out['ratio_cpu_to_opti_expand']:.3f}x (the fastest Opti; goal <= 0.1)")
    print(f"{'':14s} {'CPU [s]':>10s} {'wall [s]':>10s} {'iter':>5s} {'T_f [s]':>14s}  status")
    print(f"{'gtmodel':14s} {out['solve_cpu_s']:10.3f} {solve_s:10.3f} {mine[0][2]:5d} {mine[0][1]:14.10f}  {mine[0][3]}")
    print(f"{'Opti expand':14s} {out['opti_expand_solve_cpu_s']:10.3f} {out['opti_expand_solve_s']:10.3f} {fast[0][2]:5d} {fast[0][1]:14.10f}  {fast[0][3]}")
    print(f"{'Opti shipped':14s} {out['peer_solve_cpu_s']:10.3f} {peer_s:10.3f} {peer[0][2]:5d} {peer[0][1]:14.10f}  {peer[0][3]}")
    out["speedup_cpu"] = out["peer_solve_cpu_s"] / out["solve_cpu_s"]
    print(f"speedup over the shipped Opti: CPU {out['speedup_cpu']:.1f}x (wall {out['speedup']:.1f}x); final times differ by "
          f"{out['final_time_rel_diff']:.2e} (relative; {out['opti_expand_final_time_rel_diff']:.2e} from Opti expand=True)")
    if isinstance(server, str):
        out["acados_skipped"] = server
        print(f"acados: {server}")
    else:
        out.update(acados_summary(aruns, mine[0][1]))
        print(f"{'acados':14s} {out['acados_solve_cpu_s']:10.3f} {'':>10s} {out['acados_iterations']:5d} {out['acados_final_time_s']:14.10f}  "
              f"{out['acados_status']} ({out['acados_config']}; final time {out['acados_final_time_rel_diff']:.2e} relative from gtmodel's)")
    ms, ms_cpu = {}, {}
    for n in (int(x) for x in a.grid.split(",")):
        dn = dataclasses.replace(decl, elements=n)  # the shortcut (an InitVar): replacing ``method`` alone is undone by it
        ours(dn)
        runs = [ours(dn) for _ in range(max(1, a.repeat - 1))]
        ms[str(n)] = statistics.median(1e3 * r[0] / max(r[2], 1) for r in runs)
        ms_cpu[str(n)] = statistics.median(1e3 * r[4] / max(r[2], 1) for r in runs)
        print(f"{n:5d} elements: {ms[str(n)]:8.2f} ms/iteration, CPU {ms_cpu[str(n)]:8.2f} ({runs[0][2]} iterations, T_f {runs[0][1]:.10f} s)")
    out["ms_per_iteration"] = ms
    out["ms_per_iteration_cpu"] = ms_cpu
    keys = sorted(ms, key=int)
    out["ms_per_iteration_ratio"] = ms[keys[-1]] / ms[keys[0]]
    out["ms_per_iteration_cpu_ratio"] = ms_cpu[keys[-1]] / ms_cpu[keys[0]]
    # fatrop (its solves in the rounds above), the 50-element case and the grid's largest
    out["fatrop_solve_s"] = statistics.median(r[0] for r in fruns)
    out["fatrop_solve_cpu_s"] = statistics.median(r[4] for r in fruns)
    out["fatrop_iterations"], out["fatrop_status"], out["fatrop_final_time_s"] = fruns[0][2], fruns[0][3], fruns[0][1]
    out["fatrop_final_time_rel_diff"] = abs(fruns[0][1] - peer[0][1]) / abs(peer[0][1])
    out["fatrop_speedup"] = peer_s / out["fatrop_solve_s"]
    out["fatrop_speedup_cpu"] = out["peer_solve_cpu_s"] / out["fatrop_solve_cpu_s"]
    out["fatrop_solver_cpu_s"] = statistics.median(solver_cpu(r[6]) for r in fruns)
    out["fatrop_speedup_bound_cpu"] = out["peer_solve_cpu_s"] / out["fatrop_solver_cpu_s"]
    big = with_solver(decl, "fatrop", int(keys[-1]))
    bruns = [ours(big) for _ in range(max(1, a.repeat - 1))]
    out["fatrop_solve_s_largest"] = statistics.median(r[0] for r in bruns)
    out["fatrop_solve_cpu_s_largest"] = statistics.median(r[4] for r in bruns)
    out["fatrop_iterations_largest"], out["fatrop_final_time_s_largest"] = bruns[0][2], bruns[0][1]
    out["fatrop_coarse_start"] = bruns[0][5]
    out["fatrop_scaling_400_over_50"] = out["fatrop_solve_s_largest"] / out["fatrop_solve_s"]
    out["fatrop_scaling_400_over_50_cpu"] = out["fatrop_solve_cpu_s_largest"] / out["fatrop_solve_cpu_s"]
    lib = machine_blasfeo()
    machine = fatrop_blasfeo_rounds(a.problem, lib, a.repeat) if isinstance(lib, Path) else lib
    configs = [(out["solve_cpu_s"], "gtmodel, IPOPT (MUMPS), compiled derivatives"),
               (out["fatrop_solve_cpu_s"], "gtmodel, fatrop (stage-wise), compiled derivatives")]
    if isinstance(machine, str):
        out["fatrop_machine_blasfeo_skipped"] = machine
        print(f"fatrop with the machine's BLASFEO: skipped, {machine}")
    else:
        out.update(machine)
        configs.append((machine["fatrop_machine_blasfeo_solve_cpu_s"],
                        "gtmodel, fatrop (stage-wise), compiled derivatives, the machine's BLASFEO (LD_PRELOAD)"))
        print(f"fatrop with the machine's BLASFEO ({lib}): {machine['fatrop_machine_blasfeo_solve_cpu_s']:.3f} CPU-s against "
              f"{machine['fatrop_wheel_blasfeo_solve_cpu_s']:.3f} with the wheel's ({machine['fatrop_machine_blasfeo_speedup']:.2f}x; "
              f"without the functions {machine['fatrop_machine_blasfeo_solver_cpu_s']:.3f}), "
              f"{machine['fatrop_machine_blasfeo_iterations']} iterations, optimum {machine['fatrop_machine_blasfeo_final_time_rel_diff']:.1e} relative from the wheel's")
    best = min(configs)
    out["best_solve_cpu_s"], out["best_config"] = best
    out["best_ratio_cpu_to_opti_expand"] = best[0] / out["opti_expand_solve_cpu_s"]
    out["cpu_per_iteration_400_over_50"] = out["ms_per_iteration_cpu_ratio"]
    if "acados_solve_cpu_s" in out:  # like with like: gtmodel's configurations solved in the same rounds as acados
        out.update(ratio_to_acados({configs[0][1]: [m[4] for m in mine], configs[1][1]: [r[4] for r in fruns]},
                                   out["acados_solve_cpu_s_all"], out["acados_failed"]))
        if out["peer_failed"]:
            print(f"gtmodel CPU / acados CPU: {out['peer_failed']}")
        else:
            print(f"gtmodel CPU / acados CPU, the same {a.repeat} rounds: {out['ratio_cpu_to_acados']:.3f}x ({out['ratio_cpu_to_acados_config']}; "
                  f"rounds {', '.join(f'{v:.3f}' for v in out['ratio_cpu_to_acados_rounds'])}; goal <= 1; acados {out['acados_solve_cpu_s']:.3f} "
                  f"CPU-s, {out['acados_iterations']} SQP iterations, status {out['acados_status']})")
    print(f"fatrop     {out['fatrop_solve_s']:10.3f} {fruns[0][2]:5d} {fruns[0][1]:14.10f}  {fruns[0][3]}  "
          f"({out['fatrop_speedup']:.1f}x the Opti peer, CPU {out['fatrop_speedup_cpu']:.1f}x; {keys[-1]} elements {out['fatrop_solve_s_largest']:.3f} s, "
          f"{out['fatrop_scaling_400_over_50']:.1f}x the {decl.method.elements}-element time, CPU {out['fatrop_scaling_400_over_50_cpu']:.1f}x, {bruns[0][2]} iterations, {bruns[0][3]})")
    print(f"best: {out['best_config']} {out['best_solve_cpu_s']:.3f} CPU-s = {out['best_ratio_cpu_to_opti_expand']:.3f}x Opti expand=True; "
          f"CPU per iteration {keys[-1]} / {keys[0]} elements (IPOPT): {out['cpu_per_iteration_400_over_50']:.1f}x")
    print(f"fatrop without the NLP's functions: {out['fatrop_solver_cpu_s']:.3f} CPU-s, {out['fatrop_speedup_bound_cpu']:.1f}x the peer "
          "(the speedup if the derivatives cost nothing)")
    if a.published and not a.no_acados:
        out["acados_published"] = published_rows(a.repeat)
        for name, row in out["acados_published"].items():
            if "acados_skipped" in row:
                print(f"{name}: acados {row['acados_skipped']}")
                continue
            print(f"{name} ({row['elements']} elements; published {row['published']:g}): gtmodel T_f {row['final_time_s']:.7f} "
                  f"({row['rel_diff_published']:.1e} rel., {row['solve_cpu_s']:.4f} CPU-s, {row['refinement_passes']} refinement passes), "
                  f"acados T_f {row['acados_final_time_s']:.7f} ({row['acados_rel_diff_published']:.1e} rel., "
                  f"{row['acados_solve_cpu_s']:.4f} CPU-s, {row['acados_iterations']} iterations, status {row['acados_status']}); "
                  f"CPU ratio {row['ratio_cpu_to_acados']:.2f}x")
    out["load_average"] = os.getloadavg()[0]
    if a.json:
        print(json.dumps(out))


if __name__ == "__main__":
    t = time.perf_counter()
    main()
