"""The published optimal-control benchmark set, solved by gtmodel and by rockit (a benchmark, not a test).

Usage: python benchmarks/bench_ocp_suite.py [FILE ...] [--json] [--no-cli] [--no-rockit] [--repeat N] [--drives]

Every problem file of ``problems/benchmarks/`` (or the files given) names its source and
its published optimum (``[benchmark]``). Measured side by side in one run, because these
machines are noisy:

- ``objective``: gtmodel's optimum in the published quantity (``sign * objective``),
  ``relative_error`` to the published value, ``iterations`` (IPOPT; summed over the
  refinement passes), ``verified`` and ``max_scaled_deviation`` (the verification by
  simulation, :mod:`gtmodel.modeling.ocp.verification`), ``elements`` (after refinement);
- ``solve_s`` (IPOPT; summed over the refinement passes) and ``verification_s`` (the
  verification by simulation, summed over the passes too), medians over the repeats, and
  their ratio ``verification_over_solve`` (the verification should cost at most the solve);
  ``verification_cpu_s`` and ``solve_cpu_s``: their CPU times (the wall times on a shared machine
  mostly measure waiting; the solve's from the result's ``timing``, a coarse start's IPOPT call
  included), ``verification_over_solve_cpu`` their ratio (at most 1 is the aim),
  ``whole_call_over_solve_cpu`` the whole call's CPU over the solve's, and ``timing`` the
  result's phases (:mod:`gtmodel._timing`);
- ``whole_call_s``: gtmodel's whole call, cold: flattening, transcription, solve and
  verification (:meth:`gtmodel.trajectory.model_ocp.OptimalControl.solve` of a freshly
  loaded problem; refinement passes and, with ``[[data]]``, the estimates' statistics
  included);
- ``rockit_*``: the same problem built in rockit (``rockit-meco``, the ``bench`` extra)
  from the same model equations, bounds, boundary values, initial guess and IPOPT
  options, with the same Radau collocation (``DirectCollocation``, the file's elements and
  points; rockit holds a control constant on each element), its whole call (building the
  ``Ocp`` and solving; ``expand=True``, rockit's fastest evaluation), objective, relative
  error and iterations; ``ratio_to_rockit`` is ``whole_call_s / rockit_whole_call_s``, and
  no ratio at all (null, with ``peer_failed`` saying why, e.g. ``"rockit:
  Infeasible_Problem_Detected, no ratio"``; the printed row says it too) when a call of
  rockit did not reach its optimum (a status other than ``optimal``, a NaN objective);
  a model with algebraic variables is given to rockit as the explicit ODE a rockit user
  writes (the algebraic variables eliminated symbolically, as gtmodel's collocation does),
  its bounds as double inequalities and its guess as numbers (a straight line in
  ``ocp.t`` where it moves; a zero guess, rockit's default, not written);
  rockit holds a control constant per element, so where the optimal control jumps inside
  an element (bang-bang, state constraints) its optimum is further from the published one;
- ``rockit_refined_mesh_*`` (files with ``[transcription] refine``): rockit solved once more,
  untimed and outside the ratio, on the mesh gtmodel's refinement ended with (rockit's
  ``FunctionGrid``; rockit has no refinement of its own), to show that both transcriptions
  reach the same optimum on the same mesh;
- ``cli_s``: the wall time of a user's ``python -m gtmodel solve FILE --no-plots --out TMP``
  process (imports, problem layer, solve, result folder); ``cli_minus_whole_call_s`` is
  what the process adds to the in-process whole call;
- the honest ratio, from that fresh process alone: ``process_cpu_s``, the whole process's
  CPU time (user + system of the child: interpreter start, imports, loading and reducing the
  model, building, solving, verifying, writing the folder); ``process_solver_cpu_s``, the
  solver's CPU time in the same process (its ``summary.json``, ``timing.solve``: the IPOPT
  calls, a coarse start's included); ``process_over_solver_cpu``, their ratio (the aim: at
  most 3); ``process_run_cpu_s`` (``timing.total``: load to writing) and
  ``process_verification_cpu_s`` (``timing.verification``, at most the solver's is the aim).
  A table at the end prints these, the in-process ``whole_call_over_solve_cpu`` and the
  ratios to rockit.

How the comparison is kept fair: both sides start from the same loaded problem file (each
call loads it again, so nothing built by one call serves the next), both timers start
before anything of the problem is built (rockit's import is done before its timer, as
gtmodel's is) and stop when the solution is back; both sides run in this one process,
one after the other for each problem (gtmodel, rockit, CLI; with ``--repeat N`` that
cycle N times, and the medians are reported), so they see the same load. CPU times
(``*_cpu_s``, ``ratio_to_rockit_cpu``; for the CLI the child's user + system time) are
reported beside the wall times: on a machine shared with other jobs the wall time mostly
measures waiting. gtmodel's package bytecode is compiled once before the CLI runs, as
``pip install`` does (this sandbox sets ``PYTHONDONTWRITEBYTECODE``, which would make
each CLI process compile the package from source, a cost no installed user pays).

``gas_oil`` (parameter estimation from 21 measurements at fixed interior times): rockit
has no value at a fixed interior time, but the 38 elements of the file put every
measurement time on rockit's control grid (``h = 0.025``). Its least-squares objective is
written as a rockit user would, ``ocp.sum(W * (y - Y)**2, grid="control",
include_last=True)`` with ``W`` and ``Y`` parameters on the control grid
(``ocp.parameter(grid="control", include_last=True)``, ``W`` zero where nothing was
measured); the state rockit reads at grid point ``k`` is the one gtmodel interpolates at
``tau = 1`` of element ``k - 1`` (Radau: the element's last collocation point, equal to
the next start by continuity), so both solve the same NLP. What differs: gtmodel also
reports the estimates' standard deviations (:func:`gtmodel.modeling.ocp.estimation.estimate_statistics`),
inside its timed call. A problem whose measurement times are off the grid, or whose Mayer
term is not exactly the least-squares sum, is reported "not translated".

With ``--json`` the last line of stdout is ``{"problems": [{...}, ...]}``.
"""


from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout's gtmodel (as the CLI processes below), not another installed one

from gtmodel.problems import load_problem  # noqa: E402
BENCHMARKS = ROOT / "problems" / "benchmarks"
#: The stiff motor and drive problems (``--drives``): no published optimum, timed for the verification's cost.
DRIVES = [ROOT / "problems" / "dc_motor_move.toml", *sorted((ROOT / "problems").glob("drive_*.toml"))]


def _fn(opt: Any, dae: Any, exprs: list, specials: Any = None) -> Any:
    """``(t, x, z, u, p, final_time) -> exprs`` with ``der()`` replaced by the model's right-hand side.

    Time and the final time are passed only where the expression uses them (rockit refuses
    a time symbol in an expression that does not need it). ``specials``: the problem's
    timed variables and integrals as rockit expressions (:func:`_specials`), substituted
    for their symbols.
    """
    e = ca.vertcat(*exprs) if exprs else ca.SX(0, 1)
    if dae.nx:
        e = ca.substitute(e, dae.xdot, dae.ode_expr)
    syms = [v.symbol for v in opt.special_symbols()]
    S = ca.vertcat(*syms) if syms else ca.SX(0, 1)
    f = ca.Function("f", [dae.t, dae.x, dae.z, dae.u, dae.p, opt.final_time, S], [e])
    uses_t, uses_T = ca.depends_on(e, dae.t), ca.depends_on(e, opt.final_time)
    uses_S = bool(syms) and ca.depends_on(e, S)

    def call(t: Any, x: Any, z: Any, u: Any, p: Any, T: Any) -> Any:
        return f(t if uses_t else 0, x, z, u, p, T if uses_T else 0, specials if uses_S else ca.DM.zeros(S.numel()))

    return call


def _guess_value(spec: Any, t: Any, t0: float, default: np.ndarray) -> Any:
    """A rockit initial guess from a gtmodel guess specification, as a rockit user writes it.

    A constant guess (none given: the start value) is a number or a vector; a guess through
    two points a straight line in ``ocp.t``, through more a piecewise linear expression.
    (Rockit evaluates an expression of ``ocp.t`` symbolically at every collocation point, about
    2 CPU-s per state on 200 elements; a constant, given as one, costs nothing; rockit 0.6.7's
    numeric ``(n, N + 1)`` guess for a state fails in ``DirectCollocation`` with a NameError.)
    """
    if spec is None or callable(spec):
        return np.asarray(default, dtype=float).reshape(-1)
    if isinstance(spec, tuple):
        tg, vg = np.asarray(spec[0], dtype=float), np.asarray(spec[1], dtype=float).reshape(len(spec[0]), -1)
        if tg.size == 1 or np.all(vg == vg[0]):
            return vg[0]
        if tg.size == 2:
            return vg[0] + (vg[1] - vg[0]) / (tg[1] - tg[0]) * (t - tg[0])
        out = vg[0]
        for k in range(tg.size - 1):
            slope = (vg[k + 1] - vg[k]) / (tg[k + 1] - tg[k])
            out = out + slope * (ca.fmin(ca.fmax(t, tg[k]), tg[k + 1]) - tg[k])
        return out
    return np.asarray(spec, dtype=float).reshape(-1)


def _bound(ocp: Any, e: Any, lb: float, ub: float) -> None:
    """``lb <= e <= ub`` in rockit, as a user writes it: one double inequality where both bounds are finite."""
    if np.isfinite(lb) and np.isfinite(ub):
        ocp.subject_to(lb <= (e <= ub))
    elif np.isfinite(lb):
        ocp.subject_to(e >= lb)
    elif np.isfinite(ub):
        ocp.subject_to(e <= ub)


def _set_initial(ocp: Any, var: Any, value: Any) -> None:
    """``ocp.set_initial(var, value)`` unless ``value`` is numeric zero, rockit's default guess."""
    if isinstance(value, np.ndarray) and not np.any(value):
        return
    ocp.set_initial(var, value)


def _data_fit_objective(ocp: Any, opt: Any, dae: Any, args: tuple, N: int) -> Any:
    """The least-squares term of the ``[[data]]`` tables in rockit, or why it cannot be written.

    rockit has no value at a fixed interior time, but it has signals on the control grid:
    with every measurement time on that grid (``t_i = t0 + k_i h``, the problem file's
    mesh is chosen so), ``y(t_i)`` is the value at grid point ``k_i`` and the objective
    ``sum_i w_i (y(t_i) - y_i)^2`` is ``ocp.sum(W * (y - Y)**2, grid='control',
    include_last=True)`` with ``W`` and ``Y`` parameters on the control grid
    (``ocp.parameter(grid='control', include_last=True)``; ``W`` is zero where nothing was
    measured). gtmodel reads ``y(t_i)`` from the collocation polynomial at ``tau = 1`` of
    the element left of ``t_i``, which is the state at the next element's start (Radau:
    the last collocation point, continuity), the value rockit's grid sum reads. Returns a
    string (the reason) when the problem's Mayer term is not exactly the least-squares sum
    or a time is off the grid.
    """
    from gtmodel.modeling.ocp.estimation import least_squares  # only where a data table is

    if opt.free_final_time:
        return "a data fit with a free final time"
    syms = ca.vertcat(*[v.symbol for v in opt.special_symbols()])
    rest = ca.Function("rest", [syms, dae.p], [opt.mayer - least_squares(opt)])
    rng = np.random.default_rng(0)
    if any(abs(float(rest(rng.normal(size=syms.numel()), rng.normal(size=dae.p.numel())))) > 1e-12 for _ in range(3)):
        return "a Mayer term other than the least-squares sum of the data"
    t0, h = opt.start_time, (opt.final_time_value - opt.start_time) / N
    total = 0
    for fit in opt.data_fits:
        s = (fit.times - t0) / h
        k = np.round(s).astype(int)
        if np.any(np.abs(s - k) > 1e-9) or np.unique(k).size != k.size:
            return f"data {fit.name!r}: a measurement time off the control grid (h = {h:g} s)"
        weight, value = np.zeros(N + 1), np.zeros(N + 1)
        weight[k], value[k] = fit.weights, fit.values
        W = ocp.parameter(grid="control", include_last=True)
        Y = ocp.parameter(grid="control", include_last=True)
        ocp.set_value(W, weight)
        ocp.set_value(Y, value)
        y = _fn(opt, dae, [_measured_expr(opt, fit)])(*args)
        total = total + ocp.sum(W * (y - Y) ** 2, grid="control", include_last=True)
    return total


def _measured_expr(opt: Any, fit: Any) -> Any:
    """The model expression a data fit measures (the expression of its timed variables)."""
    by_symbol = {id(v.symbol): v for v in opt.timed_variables}
    return by_symbol[id(fit.symbols[0])].expr


def rockit_solve(decl: Any, mesh: np.ndarray | None = None) -> dict[str, Any]:
    """Build ``decl`` (an ``optimal_control`` declaration) in rockit and solve it; the whole call timed.

    ``mesh``: element boundaries normalised to ``[0, 1]`` (gtmodel's refined mesh), given to
    rockit as a ``FunctionGrid``; default the file's uniform elements.
    """
    from rockit import DirectCollocation, FreeTime, Ocp
    from rockit.sampling_method import FunctionGrid, UniformGrid

    start, cpu = time.perf_counter(), time.process_time()
    opt = decl.optimization
    dae = opt.flat()
    if dae.nz:
        # a rockit user writes the model's explicit ODE (the 3-state motor of dc_motor_min_energy,
        # not its 29 algebraic aliases): the algebraic variables eliminated symbolically, as
        # gtmodel's collocation does (gtmodel.modeling.ocp.elimination); before, the peer passed
        # no algebraic variables at all, so der() read zero and IPOPT reported the NLP infeasible
        from gtmodel.modeling.ocp.elimination import reduced_problem

        idx = [np.arange(dae.p_vars[n].start, dae.p_vars[n].stop) for n in opt.free_parameters]
        free_index = np.concatenate(idx).astype(int) if idx else np.zeros(0, dtype=int)
        reduction = reduced_problem(opt, dae, free_index)
        if reduction is None:
            return {"objective": float("nan"), "iterations": -1, "whole_call_s": float("nan"),
                    "status": "not translated: algebraic variables that do not reduce to an explicit ODE"}
        opt, dae = reduction.optimization, reduction.dae
    t0 = opt.start_time
    ocp = Ocp(t0=t0, T=FreeTime(opt.final_time_guess) if opt.free_final_time else opt.final_time_value)
    noms = decl.nominal
    X, U = [], []
    for name, sl in dae.x_vars.items():
        X.append(ocp.state(sl.stop - sl.start, scale=noms.get(name, 1.0)))
    for name, sl in dae.u_vars.items():
        U.append(ocp.control(sl.stop - sl.start, scale=noms.get(name, 1.0)))
    Xv = ca.vertcat(*X) if X else ca.MX(0, 1)
    Uv = ca.vertcat(*U) if U else ca.MX(0, 1)
    pvec = dae.parameter_vector(opt.parameters)
    P = [ca.MX(float(v)) for v in pvec]
    for name, (lb, ub, start_value) in opt.free_parameters.items():
        sl = dae.p_vars[name]
        var = ocp.variable(sl.stop - sl.start)
        for i, k in enumerate(range(sl.start, sl.stop)):
            P[k] = var[i]
            _bound(ocp, var[i], lb[i], ub[i])
        ocp.set_initial(var, start_value if start_value is not None else np.clip(pvec[sl], lb, ub))
    Pv = ca.vertcat(*P) if P else ca.MX(0, 1)
    Z = ca.MX(0, 1)
    T = ocp.T
    args = (ocp.t, Xv, Z, Uv, Pv, T)
    ocp.set_der(Xv, _fn(opt, dae, [dae.ode_expr])(*args))
    # timed variables at the start/final time and integrals as rockit signals (an integral: a
    # quadrature state from 0, read at the final time), each with the time it is read at;
    # an interior time is not translated (rockit's formulation has no value at a fixed time)
    special, when = [], []
    fit_symbols = {id(s) for fit in opt.data_fits for s in fit.symbols}
    data_term = _data_fit_objective(ocp, opt, dae, args, decl.method.elements) if opt.data_fits else None
    if isinstance(data_term, str):
        return {"objective": float("nan"), "iterations": -1, "whole_call_s": float("nan"), "status": f"not translated: {data_term}"}
    for v in opt.special_symbols():
        if id(v.symbol) in fit_symbols:  # a measurement: in the data term (grid sum) only
            special.append(ca.MX(0))
            when.append("data")
        elif not hasattr(v, "time"):
            q = ocp.state()
            ocp.set_der(q, _fn(opt, dae, [v.expr])(*args))
            ocp.subject_to(ocp.at_t0(q) == 0)
            special.append(q)
            when.append("final")
        elif v.time in ("start", "final"):
            special.append(_fn(opt, dae, [v.expr])(*args))
            when.append(v.time)
        else:
            return {"objective": float("nan"), "iterations": -1, "whole_call_s": float("nan"),
                    "status": f"not translated: a variable at the interior time {v.time} s"}
    specials = ca.vertcat(*special) if special else None
    for kind, var in (("x", Xv), ("u", Uv)):
        lb, ub = opt.bounds_vectors(dae, kind)
        for i in range(lb.size):
            _bound(ocp, var[i], lb[i], ub[i])
    if opt.free_final_time:
        lo, hi = opt.final_time_bounds
        _bound(ocp, T, lo, hi)
    for c in opt.path_constraints:
        e = _fn(opt, dae, [c.expr], specials)(*args)
        for i in range(c.lb.size):
            _bound(ocp, e[i], c.lb[i], c.ub[i])
    syms = [v.symbol for v in opt.special_symbols()]
    for c in opt.point_constraints:
        e = _fn(opt, dae, [c.expr], specials)(*args)
        at_time = c.at
        if c.at == "timed":  # read at the one time of the specials it uses
            times = {w for sym, w in zip(syms, when) if ca.depends_on(c.expr, sym)}
            if len(times) != 1:
                return {"objective": float("nan"), "iterations": -1, "whole_call_s": float("nan"),
                        "status": "not translated: a constraint on values at two times"}
            at_time = times.pop()
        at = ocp.at_t0 if at_time == "start" else ocp.at_tf
        for i in range(c.lb.size):
            if c.lb[i] == c.ub[i]:
                ocp.subject_to(at(e[i]) == c.lb[i])
                continue
            _bound(ocp, at(e[i]), c.lb[i], c.ub[i])
    if data_term is not None:
        # the least-squares Mayer term of the data tables is the control-grid sum (checked in
        # _data_fit_objective); a timed value outside it is not translated
        if any(ca.depends_on(c.expr, v.symbol) for c in [*opt.path_constraints, *opt.point_constraints]
               for v in opt.special_symbols() if id(v.symbol) in fit_symbols):
            return {"objective": float("nan"), "iterations": -1, "whole_call_s": float("nan"),
                    "status": "not translated: a measured value in a constraint"}
        objective = data_term
    else:
        objective = ocp.at_tf(_fn(opt, dae, [opt.mayer], specials)(*args))
    if not (opt.lagrange.is_constant() and float(opt.lagrange) == 0.0):
        objective = objective + ocp.integral(_fn(opt, dae, [opt.lagrange])(*args))
    sign = opt.objective_sign  # maximize: rockit minimises the negative
    ocp.add_objective(sign * objective)
    # the initial guess; a zero guess is rockit's default and not written (rockit 0.6.7 sets a
    # guess element by element, each call hashing the whole NLP: 2 CPU-s for a zero input on 200 elements)
    for name, sl in dae.x_vars.items():
        _set_initial(ocp, X[list(dae.x_vars).index(name)], _guess_value(opt.initial_guesses.get(name), ocp.t, t0, dae.x_start[sl]))
    for k, name in enumerate(dae.u_vars):
        default = opt.model._vars[name].start
        _set_initial(ocp, U[k], _guess_value(opt.initial_guesses.get(name), ocp.t, t0, default))
    ocp.solver("ipopt", {"print_time": False, "expand": True,
                         "ipopt": {"print_level": 0, "sb": "yes", "max_iter": decl.solver.max_iter, "tol": decl.solver.tol}})
    if mesh is None:
        N, grid = decl.method.elements, UniformGrid()
    else:
        N, grid = len(mesh) - 1, FunctionGrid(lambda n: [float(v) for v in mesh])
    ocp.method(DirectCollocation(N=N, M=1, degree=decl.method.points, scheme=decl.method.scheme, grid=grid))
    try:
        sol = ocp.solve()
    except RuntimeError as exc:  # IPOPT did not converge (rockit raises): no solution to report
        elapsed = time.perf_counter() - start
        found = re.search(r"return_status is '([^']+)'", str(exc))
        return {"objective": float("nan"), "iterations": -1, "whole_call_s": elapsed, "whole_call_cpu_s": time.process_time() - cpu,
                "status": f"failed: {found.group(1) if found else str(exc).splitlines()[-1][:120]}"}
    elapsed, elapsed_cpu = time.perf_counter() - start, time.process_time() - cpu
    stats = sol.stats
    value = float(sol.value(objective))  # the objective itself (a maximum reported positive, as gtmodel does)
    status = "optimal"
    return {"objective": value, "iterations": int(stats.get("iter_count", 0)), "whole_call_s": elapsed, "whole_call_cpu_s": elapsed_cpu,
            "status": status if stats.get("success", False) else str(stats.get("return_status", status))}


def rockit_or_failure(decl: Any, mesh: np.ndarray | None = None) -> dict[str, Any]:
    """:func:`rockit_solve`, or a row saying why rockit failed (its exception: a drive of ``--drives``)."""
    try:
        return rockit_solve(decl, mesh)
    except Exception as exc:  # noqa: BLE001 - rockit's own exceptions, reported in the row, not raised
        return {"objective": float("nan"), "iterations": -1, "whole_call_s": float("nan"), "whole_call_cpu_s": float("nan"),
                "status": f"failed: {type(exc).__name__}: {str(exc)[:100]}"}


def cli_time(path: Path) -> dict[str, Any]:
    """A user's fresh process ``python -m gtmodel solve FILE --no-plots --quiet --out TMP``: its wall time,
    its CPU time (user + system of the child: interpreter start, imports, problem layer, solve, result
    folder), exit code, and from the ``summary.json`` it wrote (``timing``) the solver's CPU time (the IPOPT
    calls), the verification's and the run's (``total``: load to writing, the interpreter and imports before
    the problem file is read left out)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    with tempfile.TemporaryDirectory(prefix="gtmodel_bench_") as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "gtmodel", "solve", str(path), "--no-plots", "--quiet", "--out", str(Path(tmp) / "out")],
                              env=env, capture_output=True, text=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        out = {"wall": wall, "cpu": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), "exit": proc.returncode}
        try:
            summary = json.loads((Path(tmp) / "out" / "summary.json").read_text())
        except (OSError, ValueError):
            summary = {}
        timing, nan = summary.get("timing", {}), float("nan")
        for key, phase in (("solve_cpu", "solve"), ("verification_cpu", "verification"), ("run_cpu", "total")):
            out[key] = float(timing.get(phase, {}).get("cpu_s", nan))
        passes = summary.get("refinement") or []
        if passes and all(p.get("solve_cpu_time") is not None for p in passes):  # refined: every pass's solver and verification
            out["solve_cpu"] = float(sum(p["solve_cpu_time"] for p in passes))
            out["verification_cpu"] = float(sum(p.get("verification_cpu_time") or 0.0 for p in passes))
        return out


def gtmodel_solve(path: Path) -> tuple[Any, Any, float, float]:
    """Load ``path`` and time gtmodel's whole call on it, cold (a fresh declaration): ``(problem, result, wall s, CPU s)``."""
    problem = load_problem(path)
    start, cpu = time.perf_counter(), time.process_time()
    res = problem.declaration.solve()
    return problem, res, time.perf_counter() - start, time.process_time() - cpu


def solve_cpu(res: Any) -> float:
    """The solver's CPU time of a result, s: its ``timing["solve"]`` (the IPOPT calls, a coarse start's
    included); refined, the passes' ``timing["solve"]`` (or ``solve_cpu_time``) when they record it, else their
    solve (wall) time."""
    passes = [p.get("timing", {}).get("solve", {}).get("cpu_s", p.get("solve_cpu_time")) for p in res.refinement]
    if passes and all(v is not None for v in passes):  # each pass's solver (a refinement after a failed check: its start's too)
        return float(sum(passes))
    if "solve" in res.timing:
        return float(res.timing["solve"]["cpu_s"])
    return float(res.solve_time)


def peer_failure(peers: list[dict[str, Any]], name: str = "rockit") -> str | None:
    """Why a peer's calls give no ratio, or None when every call reached its optimum.

    Parameters
    ----------
    peers : list of dict
        The peer's records of one problem (:func:`rockit_solve`'s), one per repeat.
    name : str, optional
        The peer's name in the reason. Default ``"rockit"``.

    Returns
    -------
    str or None
        ``"rockit: Infeasible_Problem_Detected, no ratio"`` and the like: the first record whose
        status is not ``optimal`` or whose objective or time is not a finite number.
    """
    for q in peers:
        status = str(q.get("status", "no status"))
        if status != "optimal":
            return f"{name}: {status.removeprefix('failed: ')}, no ratio"
        for key in ("objective", "whole_call_s", "whole_call_cpu_s"):
            value = q.get(key)
            if value is None or not np.isfinite(value):
                return f"{name}: optimal but its {key} is {value}, no ratio"
    return None


def peer_columns(peers: list[dict[str, Any]], bench: dict[str, Any], whole: float, whole_cpu: float) -> dict[str, Any]:
    """The ``rockit_*`` columns of a row and the ratios to it, None (with ``peer_failed``) when rockit failed.

    Parameters
    ----------
    peers : list of dict
        rockit's records of the problem, one per repeat (:func:`rockit_solve`).
    bench : dict
        The problem's ``[benchmark]`` table (``sign``, ``published``).
    whole, whole_cpu : float
        gtmodel's whole call, the medians of wall and CPU seconds.

    Returns
    -------
    dict
        The columns; ``ratio_to_rockit`` and ``ratio_to_rockit_cpu`` are the ratios of the
        medians, or None when a call of the peer did not reach its optimum; ``peer_failed``
        then says why (else None).
    """
    peer, pub = peers[-1], bench["published"]
    pv = bench["sign"] * peer["objective"]
    pw = float(np.median([q["whole_call_s"] for q in peers]))
    pc = float(np.median([q.get("whole_call_cpu_s", float("nan")) for q in peers]))
    failed = peer_failure(peers)
    return {
        "rockit_objective": pv, "rockit_relative_error": abs(pv - pub) / abs(pub), "rockit_iterations": peer["iterations"],
        "rockit_status": peer["status"], "rockit_whole_call_s": pw, "rockit_whole_call_cpu_s": pc,
        "rockit_whole_call_s_all": [q["whole_call_s"] for q in peers],
        "ratio_to_rockit": None if failed else whole / pw, "ratio_to_rockit_cpu": None if failed else whole_cpu / pc,
        "peer_failed": failed,
    }


def _ratio_text(r: dict[str, Any], key: str, width: int) -> str:
    """A ratio column of the printed tables: the number, or ``-`` (no peer, or a failed one: the row says why)."""
    value = r.get(key)
    return f"{value:{width}.3f}" if value is not None else f"{'-':>{width}s}"


def run_one(path: Path, cli: bool, rockit: bool, repeat: int = 1) -> dict[str, Any]:
    """Solve one benchmark file with gtmodel (and rockit, and the CLI); the figures of one row.

    With ``repeat > 1`` each side is called ``repeat`` times, alternating (gtmodel, rockit,
    CLI, gtmodel, ...), every call cold (the problem loaded again, everything built again);
    the times are the medians and the ratio is the ratio of the medians.
    """
    walls, cpus, peers, clis, solves, checks, check_cpus, solve_cpus = [], [], [], [], [], [], [], []
    for _ in range(repeat):
        problem, res, wall, cpu = gtmodel_solve(path)
        walls.append(wall)
        cpus.append(cpu)
        solves.append(res.solve_time)
        solve_cpus.append(solve_cpu(res))
        checks.append(res.verification.time_s if res.verification is not None else float("nan"))
        check_cpus.append(res.verification.cpu_s if res.verification is not None else float("nan"))
        if rockit:
            peers.append(rockit_or_failure(load_problem(path).declaration))
        if cli:
            clis.append(cli_time(path))
    decl = problem.declaration
    bench = decl.benchmark
    if bench is None:  # a stiff drive of --drives: timed, no published value to compare with
        bench = {"sign": 1.0, "published": float("nan"), "source": "none (no [benchmark] table)"}
    whole, whole_cpu = float(np.median(walls)), float(np.median(cpus))
    value = bench["sign"] * res.objective
    pub = bench["published"]
    v = res.verification
    row: dict[str, Any] = {
        "name": problem.name,
        "source": bench["source"],
        "published": pub,
        "objective": value,
        "relative_error": abs(value - pub) / abs(pub),
        "status": str(res.status),
        "iterations": int(sum(p["iterations"] for p in res.refinement) if res.refinement else res.iterations),
        "elements": res.collocation.elements if res.collocation is not None else None,
        "verified": bool(v is not None and v.passed),
        "max_scaled_deviation": float(v.max_scaled_deviation) if v is not None else None,
        "tolerance": float(v.tolerance) if v is not None else None,
        "solve_s": float(np.median(solves)),
        "verification_s": float(np.median(checks)) if v is not None else None,
        "verification_over_solve": float(np.median(checks) / np.median(solves)) if v is not None else None,
        "verification_cpu_s": float(np.median(check_cpus)) if v is not None else None,
        "solve_cpu_s": float(np.median(solve_cpus)),
        "verification_over_solve_cpu": float(np.median(check_cpus) / np.median(solve_cpus)) if v is not None else None,
        "whole_call_over_solve_cpu": float(np.median(cpus) / np.median(solve_cpus)),
        "timing": res.timing,
        "repeat": repeat,
        "whole_call_s": whole,
        "whole_call_cpu_s": whole_cpu,
        "whole_call_s_all": walls,
    }
    if rockit:
        row.update(peer_columns(peers, bench, whole, whole_cpu))
    if rockit and res.refinement and res.collocation is not None:
        # not timed, not in the ratio: rockit on the mesh gtmodel's refinement ended with
        # (rockit has no refinement), to show both transcriptions reach the same optimum there
        br = np.asarray(res.collocation.breaks(), dtype=float)
        fine = rockit_or_failure(load_problem(path).declaration, mesh=(br - br[0]) / (br[-1] - br[0]))
        fv = bench["sign"] * fine["objective"]
        row.update({"rockit_refined_mesh_objective": fv, "rockit_refined_mesh_relative_error": abs(fv - pub) / abs(pub),
                    "rockit_refined_mesh_status": fine["status"]})
    if cli:
        row["cli_s"] = float(np.median([c["wall"] for c in clis]))
        row["cli_cpu_s"] = float(np.median([c["cpu"] for c in clis]))
        row["cli_exit"] = max(c["exit"] for c in clis)
        row["cli_minus_whole_call_s"] = row["cli_s"] - whole
        row["cli_minus_whole_call_cpu_s"] = row["cli_cpu_s"] - whole_cpu
        # the fresh process against its own solver (both from the same process: its rusage, its summary.json)
        ratios = [c["cpu"] / c["solve_cpu"] for c in clis]
        row.update({
            "process_cpu_s": row["cli_cpu_s"],
            "process_solver_cpu_s": float(np.median([c["solve_cpu"] for c in clis])),
            "process_verification_cpu_s": float(np.median([c["verification_cpu"] for c in clis])),
            "process_run_cpu_s": float(np.median([c["run_cpu"] for c in clis])),
            "process_over_solver_cpu": float(np.median(ratios)),
            "process_over_solver_cpu_all": ratios,
        })
    return row


def compile_bytecode() -> None:
    """Compile gtmodel's bytecode once, as ``pip install`` does (this sandbox sets PYTHONDONTWRITEBYTECODE,
    which would make every CLI process compile the package from source: about 1 CPU-s a user never pays)."""
    import compileall

    compileall.compile_dir(str(ROOT / "gtmodel"), quiet=1, force=False)


def main(argv: list[str] | None = None) -> int:
    """Run the suite and print a table (and, with ``--json``, one JSON line)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path, help="benchmark problem files (default: problems/benchmarks/*.toml)")
    ap.add_argument("--json", action="store_true", help="end with one JSON line {'problems': [...]}")
    ap.add_argument("--no-cli", action="store_true", help="skip the gtmodel solve processes")
    ap.add_argument("--no-rockit", action="store_true", help="skip rockit")
    ap.add_argument("--drives", action="store_true", help="also the stiff drives (problems/dc_motor_move.toml, problems/drive_*.toml; "
                    "no published value: their times and the verification against the solve)")
    ap.add_argument("--repeat", type=int, default=1, help="cold calls per side and problem; the medians are reported (default 1)")
    a = ap.parse_args(argv)
    if a.repeat < 1:
        ap.error("--repeat: expected a positive integer")
    files = a.files or sorted(BENCHMARKS.glob("*.toml"))
    if a.drives:
        files = [*files, *DRIVES]
    if not a.no_cli:
        compile_bytecode()
    rows = []
    head = (f"{'problem':28s} {'published':>12s} {'objective':>12s} {'rel.err':>8s} {'it':>5s} {'verified':>8s} {'dev':>8s} "
            f"{'solve s':>8s} {'verify s':>8s} {'whole s':>8s} {'cli s':>6s} {'cli-whole':>9s} {'rockit s':>8s} {'rockit rel':>10s} {'ratio':>6s} {'cpu ratio':>9s} "
            f"{'solve cpu':>9s} {'verify cpu':>10s} {'whole/solve cpu':>15s}")
    print(head)
    for f in files:
        r = run_one(Path(f), cli=not a.no_cli, rockit=not a.no_rockit, repeat=a.repeat)
        rows.append(r)
        print_row(r)
    print_time_table(rows)
    if a.json:
        print(json.dumps({"problems": rows}))
    return 0


def print_row(r: dict[str, Any]) -> None:
    """Print one row of the main table; a failed peer's row ends with why it has no ratio (``peer_failed``).

    Parameters
    ----------
    r : dict
        A row of :func:`run_one`.
    """
    dev = r["max_scaled_deviation"]
    nan = float("nan")
    print(f"{r['name']:28s} {r['published']:12.7g} {r['objective']:12.7g} {r['relative_error']:8.1e} {r['iterations']:5d} "
          f"{str(r['verified']):>8s} {dev if dev is not None else nan:8.1e} {r['solve_s']:8.3f} "
          f"{r['verification_s'] if r['verification_s'] is not None else nan:8.3f} {r['whole_call_s']:8.3f} "
          f"{r.get('cli_s', nan):6.2f} {r.get('cli_minus_whole_call_s', nan):9.2f} {r.get('rockit_whole_call_s', nan):8.3f} "
          f"{r.get('rockit_relative_error', nan):10.1e} {_ratio_text(r, 'ratio_to_rockit', 6)} {_ratio_text(r, 'ratio_to_rockit_cpu', 9)} "
          f"{r['solve_cpu_s']:9.3f} {r['verification_cpu_s'] if r['verification_cpu_s'] is not None else nan:10.3f} "
          f"{r['whole_call_over_solve_cpu']:15.2f}" + (f"  {r['peer_failed']}" if r.get("peer_failed") else ""),
          flush=True)


def print_time_table(rows: list[dict[str, Any]]) -> None:
    """Where the time goes, CPU s: the fresh process against its solver, the verification against the solve, rockit.

    ``process``: the user's fresh ``gtmodel solve`` process, all of it (``process_cpu_s``);
    ``solver``: its IPOPT calls (``process_solver_cpu_s``, its summary.json); ``process/solver``
    (``process_over_solver_cpu``); ``run``: its summary's ``total``, load to writing
    (``process_run_cpu_s``); ``verify``: its verification (``process_verification_cpu_s``) and
    ``verify/solver``; ``call/solve``: the in-process whole call over its solve
    (``whole_call_over_solve_cpu``); ``rockit``: the in-process whole call over rockit's
    (``ratio_to_rockit``, wall; ``ratio_to_rockit_cpu``, CPU).
    """
    nan = float("nan")
    print()
    print(f"{'CPU s (a fresh process; in process)':36s} {'process':>8s} {'solver':>7s} {'process/solver':>14s} {'run':>6s} "
          f"{'verify':>7s} {'verify/solver':>13s} {'call/solve':>10s} {'rockit':>7s} {'rockit cpu':>10s}")
    for r in rows:
        solver, check = r.get("process_solver_cpu_s", nan), r.get("process_verification_cpu_s", nan)
        print(f"{r['name']:36s} {r.get('process_cpu_s', nan):8.3f} {solver:7.3f} {r.get('process_over_solver_cpu', nan):14.2f} "
              f"{r.get('process_run_cpu_s', nan):6.3f} {check:7.3f} {check / solver if solver else nan:13.2f} "
              f"{r['whole_call_over_solve_cpu']:10.2f} {_ratio_text(r, 'ratio_to_rockit', 7)} {_ratio_text(r, 'ratio_to_rockit_cpu', 10)}"
              + (f"  {r['peer_failed']}" if r.get("peer_failed") else ""),
              flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
