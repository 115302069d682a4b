"""Calibration speed: gtmodel's default solver vs SciPy least_squares with finite differences.

Usage: python benchmarks/bench_calibration.py [--repeat N] [--json]

Problem: the L1 21-parameter (modified) model of Dressler (2012), Table 5.1, calibrated on
779 synthetic laser-tracker poses (IK of a workspace grid, 10 um Gaussian noise, seed 0),
started from the ideal model of Table 5.1 -- the size of the thesis' L1 calibration.

Printed, each as the median of ``--repeat`` runs in this process (machines are noisy):

1. gtmodel's default solver (:data:`gtmodel.calibration.kinematic.DEFAULT_SOLVER`):
   solve time (the solver runs, without the one-off CasADi build, which is printed
   separately) and the wall time of the whole ``CalibrationProblem.solve`` call (frame
   alignment, rank check, standard deviations and identifiability report included).
2. The peer: ``scipy.optimize.least_squares(method="lm")`` with its finite-difference
   Jacobian on the *same residuals* (all 21 parameters at once, the usual way of writing
   it), evaluated by the same CasADi graph through ``Function.buffer``, from the same
   aligned start, with the same tolerances. Ratio = peer / gtmodel. Both optima are
   printed and must agree to 1e-8 relative per parameter (asserted: correctness).
3. The other solvers (trf, ipopt, ipopt-gn): iterations, solve time, agreement.
4. Build/evaluation cost of four ways to write residuals + Jacobian over all poses
   (one 7-parameter arm group).
5. Greedy pose selection (eq. 5.9), ~1347 candidates -> 200.

With ``--json`` the last line of stdout is one JSON object: ``whole_call_ms`` (the whole
:func:`~gtmodel.calibration.kinematic.calibrate` call, its problem and graphs cached as in
any repeated use), ``scipy_ms`` (the peer of 2.), both as medians of ``--repeat``
interleaved runs plus their minima (``*_min_ms``) and their CPU times (``*_cpu_ms``,
``ratio_cpu``: on a loaded machine the wall times of the many short calls of the exact-
Jacobian path include waits for a CPU), ``solve_ms`` (the solver alone),
``ratio`` = scipy_ms / whole_call_ms, ``ratio_min``, both costs ``V`` (``cost``,
``scipy_cost`` [m^4]), ``cost_rel_diff``, gtmodel's ``iterations`` (Jacobian
evaluations), the peer's residual evaluations (``scipy_evaluations``) and the 1-minute
``load_average`` of the machine at the end (the figures are from a shared machine).

OpenBLAS threads are limited to 1 (set before NumPy is imported) for both sides: on a
shared 2-core machine multi-threaded BLAS made single small LAPACK calls take 10-40 ms.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import casadi as ca  # noqa: E402
import numpy as np  # noqa: E402
import scipy.optimize  # noqa: E402

from gtmodel.calibration.kinematic import (  # noqa: E402
    DEFAULT_SOLVER,
    LSQ_TOLERANCE,
    CalibrationProblem,
    calibrate,
)
from gtmodel.calibration.pose_selection import select_poses  # noqa: E402
from gtmodel.robots.closure import ThreeLinkClosure  # noqa: E402
from gtmodel.robots.kinematics import GantryTau3Kinematics  # noqa: E402
from gtmodel.robots.parameters import load_parameters  # noqa: E402

NOISE = 10e-6  # laser tracker [m]
N_POSES = 779  # Table 5.1
GRID_STEP = 0.115  # [m], 801 grid poses
AGREEMENT = 1e-8  # relative, per parameter
SEED = 0


def data() -> tuple[ThreeLinkClosure, ThreeLinkClosure, np.ndarray, np.ndarray]:
    true = ThreeLinkClosure(load_parameters("L1"))
    nominal = ThreeLinkClosure(load_parameters("L1_ideal"), model="modified")
    T = GantryTau3Kinematics(load_parameters("L1")).workspace_grid(GRID_STEP)
    T = T[np.unique(np.linspace(0, len(T) - 1, N_POSES).round().astype(int))]
    q = true.ik(T)
    return true, nominal, q, T + NOISE * np.random.default_rng(SEED).standard_normal(T.shape)


class ScipyPeer:
    """All 21 parameters, residuals of all arms from one expanded CasADi graph (buffer I/O)."""

    def __init__(self, model: ThreeLinkClosure, q: np.ndarray, T: np.ndarray) -> None:
        t0 = time.perf_counter()
        p = ca.SX.sym("p", model.n_parameters)
        qs, Ts, quat = ca.SX.sym("q", 3), ca.SX.sym("T", 3), ca.SX.sym("quat", 4)
        r = ca.vertcat(*[model.closure_function(a)(p, qs, Ts, quat) for a in range(3)])
        f = ca.Function("r", [p, qs, Ts, quat], [r]).map("r_all", "serial", len(q), [0], []).expand()
        self.p = np.zeros(model.n_parameters)
        self.inputs = [self.p, np.ascontiguousarray(q), np.ascontiguousarray(T), np.tile([1.0, 0, 0, 0], (len(q), 1))]
        self.out = np.zeros((len(q), 3))
        self.fb, self.ev = f.buffer()
        for i, a in enumerate(self.inputs):
            self.fb.set_arg(i, memoryview(a))
        self.fb.set_res(0, memoryview(self.out))
        self.build_time = time.perf_counter() - t0

        self.n_eval = 0

    def residuals(self, p: np.ndarray) -> np.ndarray:
        self.n_eval += 1
        self.p[:] = p
        self.ev()
        return self.out.ravel().copy()

    def solve(self, p0: np.ndarray, method: str = "lm") -> scipy.optimize.OptimizeResult:
        self.n_eval = 0
        return scipy.optimize.least_squares(
            self.residuals, p0, method=method, x_scale="jac", ftol=LSQ_TOLERANCE, xtol=LSQ_TOLERANCE, gtol=LSQ_TOLERANCE
        )


def graph_variants(model: ThreeLinkClosure, q: np.ndarray, T: np.ndarray) -> None:
    """Build and evaluation time of residuals + Jacobian of arm 1 (7 parameters)."""
    N = len(q)
    idx = [0, 3, 4, 5, 12, 13, 14]
    F = model.closure_function(0)
    x, pb = ca.SX.sym("x", 7), ca.SX.sym("p0", 21)
    qs, Ts, qu = ca.SX.sym("q", 3), ca.SX.sym("T", 3), ca.SX.sym("quat", 4)
    pe = [pb[i] for i in range(21)]
    for j, i in enumerate(idx):
        pe[i] = x[j]
    r = F(ca.vertcat(*pe), qs, Ts, qu)
    per_pose = ca.Function("f", [x, pb, qs, Ts, qu], [r, ca.densify(ca.jacobian(r, x))])
    x0 = model.parameter_vector()[idx]
    p0 = model.parameter_vector()
    Q, TT, QU = np.ascontiguousarray(q), np.ascontiguousarray(T), np.tile([1.0, 0, 0, 0], (N, 1))

    def binder(fun, args):
        fb, ev = fun.buffer()
        keep = [np.ascontiguousarray(a) for a in args]
        outs = [np.zeros(fun.nnz_out(i)) for i in range(fun.n_out())]
        for i, a in enumerate(keep):
            fb.set_arg(i, memoryview(a))
        for i, o in enumerate(outs):
            fb.set_res(i, memoryview(o))
        return ev, (fb, keep, outs)

    variants = []
    t0 = time.perf_counter()
    m = per_pose.map("m", "serial", N, [0, 1], [])
    variants.append(("map of the per-pose Function (serial)", time.perf_counter() - t0, m, [x0, p0, Q, TT, QU]))
    t0 = time.perf_counter()
    Qs, Tss = ca.SX.sym("Q", 3, N), ca.SX.sym("Ts", 3, N)
    pe_x = ca.vertcat(*pe)
    rs = ca.vertcat(*[F(pe_x, Qs[:, k], Tss[:, k], ca.DM([1, 0, 0, 0])) for k in range(N)])
    g = ca.Function("g", [x, pb, Qs, Tss], [rs, ca.densify(ca.jacobian(rs, x))])
    variants.append(("one SX graph, all poses (Python loop)", time.perf_counter() - t0, g, [x0, p0, Q, TT]))
    t0 = time.perf_counter()
    e = per_pose.map("e", "serial", N, [0, 1], []).expand()
    variants.append(("map(N).expand(): one SX graph per N", time.perf_counter() - t0, e, [x0, p0, Q, TT, QU]))
    t0 = time.perf_counter()
    K = 64
    M = -(-N // K) * K
    pad = lambda a: np.vstack([a, np.repeat(a[:1], M - N, axis=0)])  # noqa: E731
    c = per_pose.map("c", "serial", K, [0, 1], []).expand().map("cm", "serial", M // K, [0, 1], [])
    variants.append((f"blocks of {K} poses expanded, mapped (gtmodel)", time.perf_counter() - t0, c, [x0, p0, pad(Q), pad(TT), pad(QU)]))
    bound = [binder(f, a) for _, _, f, a in variants]  # keeps the arrays alive
    evs = [b[0] for b in bound]
    times: list[list[float]] = [[] for _ in variants]
    for _ in range(15):  # interleaved, median: the machine's load drifts
        for i, ev in enumerate(evs):
            ev()
            t = time.perf_counter()
            for _ in range(50):
                ev()
            times[i].append((time.perf_counter() - t) / 50)
    rows = [(name, b, statistics.median(ts)) for (name, b, _, _), ts in zip(variants, times)]
    print(f"\nresiduals + Jacobian of one arm group (7 parameters), {N} poses")
    print(f"  {'variant':48s} {'build [s]':>10s} {'eval [ms]':>10s}")
    for name, b, ev in rows:
        print(f"  {name:48s} {b:10.3f} {1e3 * ev:10.3f}")


def whole_call_vs_scipy(nominal: ThreeLinkClosure, q: np.ndarray, T: np.ndarray, repeat: int) -> dict:
    """Whole ``calibrate`` call vs the SciPy peer, interleaved runs (the machine is shared)."""
    res = calibrate(nominal, q, T)  # builds (or re-uses) the problem and its graphs
    peer = ScipyPeer(nominal, q, T)
    p0 = np.array(list(res.initial_parameters.values()))
    sol = peer.solve(p0)
    whole, scipy_t, solve, whole_cpu, scipy_cpu = [], [], [], [], []
    for _ in range(repeat):
        c0, t0 = time.process_time(), time.perf_counter()
        res = calibrate(nominal, q, T)
        whole.append(time.perf_counter() - t0)
        whole_cpu.append(time.process_time() - c0)
        solve.append(res.solve_time)
        c0, t0 = time.process_time(), time.perf_counter()
        sol = peer.solve(p0)
        scipy_t.append(time.perf_counter() - t0)
        scipy_cpu.append(time.process_time() - c0)
    w, sp = 1e3 * statistics.median(whole), 1e3 * statistics.median(scipy_t)
    return {
        "n_poses": int(len(q)),
        "n_parameters": int(nominal.n_parameters),
        "repeat": int(repeat),
        "whole_call_ms": w,
        "scipy_ms": sp,
        "ratio": sp / w,
        "whole_call_min_ms": 1e3 * min(whole),
        "scipy_min_ms": 1e3 * min(scipy_t),
        "ratio_min": min(scipy_t) / min(whole),
        "solve_ms": 1e3 * statistics.median(solve),
        "whole_call_cpu_ms": 1e3 * statistics.median(whole_cpu),
        "scipy_cpu_ms": 1e3 * statistics.median(scipy_cpu),
        "ratio_cpu": statistics.median(scipy_cpu) / statistics.median(whole_cpu),
        "cost": float(res.cost),
        "scipy_cost": float(2 * sol.cost),
        "cost_rel_diff": float(abs(res.cost - 2 * sol.cost) / abs(res.cost)),
        "status": str(res.status),
        "scipy_status": int(sol.status),
        "iterations": int(res.iterations),
        "scipy_evaluations": int(peer.n_eval),
        "load_average": os.getloadavg()[0],
    }


def main(repeat: int, as_json: bool = False) -> None:
    true, nominal, q, T = data()
    print(f"casadi {ca.__version__}, numpy {np.__version__}, scipy {scipy.__version__}; {len(q)} poses, 21 parameters")

    problem = CalibrationProblem(nominal)
    first = problem.solve(q, T)
    print(f"\none-off CasADi build: {first.build_time:.3f} s")
    walls, solves = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = problem.solve(q, T)
        walls.append(time.perf_counter() - t0)
        solves.append(res.solve_time)
    p_gt = res.parameter_vector
    p0 = np.array(list(res.initial_parameters.values()))

    peer = ScipyPeer(nominal, q, T)
    peers = {}
    for method in ("lm", "trf"):
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            sol = peer.solve(p0, method)
            times.append(time.perf_counter() - t0)
        peers[method] = (statistics.median(times), peer.n_eval, sol)
    t_peer, n_peer, sol = peers["lm"]
    p_peer = sol.x
    rel = np.abs(p_peer - p_gt) / np.abs(p_gt)

    t_solve, t_wall = statistics.median(solves), statistics.median(walls)
    print(f"\n{'':40s} {'time [ms]':>10s}  evaluations")
    print(f"{'gtmodel ' + DEFAULT_SOLVER + ' solve (3 arm NLPs, exact J)':40s} {1e3 * t_solve:10.2f}  {res.iterations} iterations (Jacobian evaluations)")
    print(f"{'gtmodel calibrate wall (all steps)':40s} {1e3 * t_wall:10.2f}")
    for method, (tp, ne, sp) in peers.items():
        d = np.max(np.abs(sp.x - p_gt) / np.abs(p_gt))
        print(f"{'scipy ' + method + ', 2-point FD, 21 params':40s} {1e3 * tp:10.2f}  {ne} residual (max rel. diff {d:.1e})")
    print(f"ratio peer (lm) / gtmodel: solve {t_peer / t_solve:.1f}x, wall {t_peer / t_wall:.1f}x; "
          f"peer (trf) / gtmodel: solve {peers['trf'][0] / t_solve:.1f}x, wall {peers['trf'][0] / t_wall:.1f}x")
    print(f"cost V: gtmodel {res.cost:.10e}, peer {2 * sol.cost:.10e} m^4")
    print(f"{'parameter':10s} {'gtmodel':>20s} {'scipy FD':>20s} {'rel. diff':>10s}")
    for name, a, b, d in zip(res.parameters, p_gt, p_peer, rel):
        print(f"{name:10s} {a:20.14f} {b:20.14f} {d:10.2e}")
    assert np.max(rel) < AGREEMENT, f"optima differ: max relative difference {np.max(rel):.3g} > {AGREEMENT}"
    print(f"optima agree: max relative difference {np.max(rel):.2e} < {AGREEMENT:g}")

    print(f"\n{'solver':10s} {'status':10s} {'iter':>5s} {'solve [ms]':>11s} {'build [s]':>10s} {'max rel. diff to default':>25s}")
    for solver in ("lm", "trf", "ipopt", "ipopt-gn"):
        r0 = problem.solve(q, T, solver=solver)
        ts = []
        for _ in range(max(1, repeat // 2)):
            r = problem.solve(q, T, solver=solver)
            ts.append(r.solve_time)
        d = np.max(np.abs(r.parameter_vector - p_gt) / np.abs(p_gt))
        print(f"{solver:10s} {r.status:10s} {r.iterations:5d} {1e3 * statistics.median(ts):11.2f} {r0.build_time:10.3f} {d:25.2e}")

    graph_variants(true, q, T)

    kin = GantryTau3Kinematics(load_parameters("L1"))
    Tc = kin.workspace_grid(0.095)
    Tc = Tc[np.unique(np.linspace(0, len(Tc) - 1, 1347).round().astype(int))]
    t0 = time.perf_counter()
    sel = select_poses(true, true.ik(Tc), 200, Tc)
    total = time.perf_counter() - t0
    print(
        f"\npose selection (eq. 5.9): {len(Tc)} -> 200 candidates in {sel.time:.2f} s (greedy), {total:.2f} s with the "
        f"Jacobian; cond {sel.initial_condition_number:.1f} -> {sel.condition_number:.1f}; "
        f"sigma_max^2/sigma_min = {sel.acceptance:.1f} (accepted: {sel.accepted})"
    )

    if as_json:
        out = whole_call_vs_scipy(nominal, q, T, max(repeat, 15))
        print(
            f"\nwhole calibrate call {out['whole_call_ms']:.2f} ms (min {out['whole_call_min_ms']:.2f}, "
            f"CPU {out['whole_call_cpu_ms']:.2f}), scipy {out['scipy_ms']:.2f} ms (min {out['scipy_min_ms']:.2f}, "
            f"CPU {out['scipy_cpu_ms']:.2f}): {out['ratio']:.1f}x (CPU {out['ratio_cpu']:.1f}x); "
            f"costs differ by {out['cost_rel_diff']:.1e} (relative)"
        )
        print(json.dumps(out))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--json", action="store_true", help="print one JSON object on the last line of stdout")
    args = ap.parse_args()
    main(args.repeat, args.json)
