"""The published optimal-control benchmark set, solved by gtmodel and by rockit (a benchmark, not a test).

Usage: python benchmarks/bench_ocp_suite.py [FILE ...] [--json] [--no-cli] [--no-rockit]

Every problem file of ``problems/benchmarks/`` (or the files given) names its source and
its published optimum (``[benchmark]``). Measured side by side in one run, because these
machines are noisy:

- ``objective``: gtmodel's optimum in the published quantity (``sign * objective``),
  ``relative_error`` to the published value, ``iterations`` (IPOPT; summed over the
  refinement passes), ``verified`` and ``max_scaled_deviation`` (the verification by
  simulation, :mod:`gtmodel.modeling.ocp.verification`), ``elements`` (after refinement);
- ``whole_call_s``: gtmodel's whole call, cold: flattening, transcription, solve and
  verification (:meth:`gtmodel.trajectory.model_ocp.OptimalControl.solve` of the loaded
  problem; refinement passes included when the file asks for them);
- ``rockit_*``: the same problem built in rockit (``rockit-meco``, the ``bench`` extra)
  from the same model equations, bounds, boundary values, initial guess and IPOPT
  options, with the same Radau collocation (``DirectCollocation``, the file's elements and
  points; rockit holds a control constant on each element), its whole call (building the
  ``Ocp`` and solving), objective, relative error and iterations; ``ratio_to_rockit`` is
  ``whole_call_s / rockit_whole_call_s``;
- ``cli_s``: the wall time of a user's ``python -m gtmodel solve FILE --no-plots --out TMP``
  process (imports, problem layer, solve, result folder).

With ``--json`` the last line of stdout is ``{"problems": [{...}, ...]}``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.problems import load_problem

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = ROOT / "problems" / "benchmarks"


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


def _guess_expr(spec: Any, t: Any, t0: float, default: np.ndarray) -> Any:
    """A rockit initial-guess expression of time from a gtmodel guess specification."""
    if spec is None:
        return default
    if isinstance(spec, tuple):
        tg, vg = np.asarray(spec[0], dtype=float), np.asarray(spec[1], dtype=float).reshape(len(spec[0]), -1)
        if tg.size == 1:
            return vg[0]
        # piecewise linear through the guess points (the problem files' guesses have two)
        out = vg[0]
        for k in range(tg.size - 1):
            slope = (vg[k + 1] - vg[k]) / (tg[k + 1] - tg[k])
            out = out + slope * (ca.fmin(ca.fmax(t, tg[k]), tg[k + 1]) - tg[k])
        return out
    if callable(spec):
        return default
    return np.asarray(spec, dtype=float).reshape(-1)


def rockit_solve(decl: Any) -> dict[str, Any]:
    """Build ``decl`` (an ``optimal_control`` declaration) in rockit and solve it; the whole call timed."""
    from rockit import DirectCollocation, FreeTime, Ocp

    start = time.perf_counter()
    opt = decl.optimization
    dae = opt.flat()
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
            if np.isfinite(lb[i]):
                ocp.subject_to(var[i] >= lb[i])
            if np.isfinite(ub[i]):
                ocp.subject_to(var[i] <= ub[i])
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
    for v in opt.special_symbols():
        if not hasattr(v, "time"):
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
            if np.isfinite(lb[i]):
                ocp.subject_to(var[i] >= lb[i])
            if np.isfinite(ub[i]):
                ocp.subject_to(var[i] <= ub[i])
    if opt.free_final_time:
        lo, hi = opt.final_time_bounds
        ocp.subject_to(T >= lo)
        ocp.subject_to(T <= hi)
    for c in opt.path_constraints:
        e = _fn(opt, dae, [c.expr], specials)(*args)
        for i in range(c.lb.size):
            if np.isfinite(c.lb[i]):
                ocp.subject_to(e[i] >= c.lb[i])
            if np.isfinite(c.ub[i]):
                ocp.subject_to(e[i] <= c.ub[i])
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
            if np.isfinite(c.lb[i]):
                ocp.subject_to(at(e[i]) >= c.lb[i])
            if np.isfinite(c.ub[i]):
                ocp.subject_to(at(e[i]) <= c.ub[i])
    objective = ocp.at_tf(_fn(opt, dae, [opt.mayer], specials)(*args))
    if not (opt.lagrange.is_constant() and float(opt.lagrange) == 0.0):
        objective = objective + ocp.integral(_fn(opt, dae, [opt.lagrange])(*args))
    sign = opt.objective_sign  # maximize: rockit minimises the negative
    ocp.add_objective(sign * objective)
    for name, sl in dae.x_vars.items():
        ocp.set_initial(X[list(dae.x_vars).index(name)], _guess_expr(opt.initial_guesses.get(name), ocp.t, t0, dae.x_start[sl]))
    for k, name in enumerate(dae.u_vars):
        default = opt.model._vars[name].start
        ocp.set_initial(U[k], _guess_expr(opt.initial_guesses.get(name), ocp.t, t0, default))
    ocp.solver("ipopt", {"print_time": False, "expand": True,
                         "ipopt": {"print_level": 0, "sb": "yes", "max_iter": decl.solver.max_iter, "tol": decl.solver.tol}})
    ocp.method(DirectCollocation(N=decl.method.elements, M=1, degree=decl.method.points, scheme=decl.method.scheme))
    try:
        sol = ocp.solve()
    except RuntimeError as exc:  # IPOPT did not converge (rockit raises): no solution to report
        elapsed = time.perf_counter() - start
        return {"objective": float("nan"), "iterations": -1, "whole_call_s": elapsed, "status": f"failed: {str(exc).splitlines()[-1][:120]}"}
    elapsed = time.perf_counter() - start
    stats = sol.stats
    value = float(sol.value(objective))  # the objective itself (a maximum reported positive, as gtmodel does)
    status = "optimal"
    return {"objective": value, "iterations": int(stats.get("iter_count", 0)), "whole_call_s": elapsed,
            "status": status if stats.get("success", False) else str(stats.get("return_status", status))}


def cli_time(path: Path) -> tuple[float, int]:
    """Wall time and exit code of ``python -m gtmodel solve FILE --no-plots --out TMP``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    with tempfile.TemporaryDirectory(prefix="gtmodel_bench_") as tmp:
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "gtmodel", "solve", str(path), "--no-plots", "--quiet", "--out", str(Path(tmp) / "out")],
                              env=env, capture_output=True, text=True)
        return time.perf_counter() - start, proc.returncode


def run_one(path: Path, cli: bool, rockit: bool) -> dict[str, Any]:
    """Solve one benchmark file with gtmodel (and rockit, and the CLI); the figures of one row."""
    problem = load_problem(path)
    decl = problem.declaration
    bench = decl.benchmark
    if bench is None:
        raise SystemExit(f"{path}: no [benchmark] table (source and published value)")
    start = time.perf_counter()
    res = decl.solve()
    whole = time.perf_counter() - start
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
        "whole_call_s": whole,
    }
    if rockit:
        peer = rockit_solve(load_problem(path).declaration)
        pv = bench["sign"] * peer["objective"]
        peer["whole_call_s"] = peer["whole_call_s"] if np.isfinite(peer["whole_call_s"]) else float("nan")
        row.update({
            "rockit_objective": pv, "rockit_relative_error": abs(pv - pub) / abs(pub), "rockit_iterations": peer["iterations"],
            "rockit_status": peer["status"], "rockit_whole_call_s": peer["whole_call_s"],
            "ratio_to_rockit": whole / peer["whole_call_s"],
        })
    if cli:
        row["cli_s"], row["cli_exit"] = cli_time(path)
        row["cli_minus_whole_call_s"] = row["cli_s"] - whole
    return row


def main(argv: list[str] | None = None) -> int:
    """Run the suite and print a table (and, with ``--json``, one JSON line)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path, help="benchmark problem files (default: problems/benchmarks/*.toml)")
    ap.add_argument("--json", action="store_true", help="end with one JSON line {'problems': [...]}")
    ap.add_argument("--no-cli", action="store_true", help="skip the gtmodel solve processes")
    ap.add_argument("--no-rockit", action="store_true", help="skip rockit")
    a = ap.parse_args(argv)
    files = a.files or sorted(BENCHMARKS.glob("*.toml"))
    rows = []
    head = f"{'problem':28s} {'published':>12s} {'objective':>12s} {'rel.err':>8s} {'it':>5s} {'verified':>8s} {'dev':>8s} {'whole s':>8s} {'cli s':>6s} {'rockit rel':>10s} {'ratio':>6s}"
    print(head)
    for f in files:
        r = run_one(Path(f), cli=not a.no_cli, rockit=not a.no_rockit)
        rows.append(r)
        dev = r["max_scaled_deviation"]
        print(f"{r['name']:28s} {r['published']:12.7g} {r['objective']:12.7g} {r['relative_error']:8.1e} {r['iterations']:5d} "
              f"{str(r['verified']):>8s} {dev if dev is not None else float('nan'):8.1e} {r['whole_call_s']:8.3f} "
              f"{r.get('cli_s', float('nan')):6.2f} {r.get('rockit_relative_error', float('nan')):10.1e} {r.get('ratio_to_rockit', float('nan')):6.3f}",
              flush=True)
    if a.json:
        print(json.dumps({"problems": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
