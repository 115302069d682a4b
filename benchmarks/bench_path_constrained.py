"""Path-constrained time-optimal motion: gtmodel's reachability solver against TOPP-RA.

Usage: python benchmarks/bench_path_constrained.py [--repeat 7] [--json] [--nlp-max 100000]

TOPP-RA (``pip install toppra``, Pham & Pham 2018) is the reference implementation of the
reachability method (Cython LP solver "seidel"). Both solve the same gridded problem, on
the same grid (``points`` uniformly spaced values of ``s`` in [0, 1]) with the same
discretisation: TOPP-RA's *collocation* scheme (constraints involving ``s_ddot`` at the
left end of each interval on ``(u_k, x_k)``, first-order constraints at every grid point,
rest at both ends), which is gtmodel's scheme (:mod:`gtmodel.trajectory.path_constrained`).

Cases, in one run:

1. the straight line ``(0, 0, 0) -> (0.8, 0.3, -0.2)`` m with per-axis TCP velocity
   ``<= 1 m/s`` and acceleration ``<= 5 m/s^2`` (TOPP-RA: JointVelocityConstraint and
   JointAccelerationConstraint on the 3 TCP coordinates; analytic optimum 1.000 s);
2. the L1 straight line ``(-0.2, 2.75, -0.4) -> (0.2, 3.0, -0.6)`` m with ``|tau_i| <= 450 N``
   and Coulomb friction, *without* viscous friction (TOPP-RA cannot represent it,
   hungpham2511/toppra#92). TOPP-RA gets the force rows through its generic
   :class:`toppra.constraint.LinearConstraint` with the coefficient arrays ``m, c, g`` that
   gtmodel evaluated from the CasADi model on the grid, so both solve identical data;
   its time counts only TOPP-RA's own work, while gtmodel's total includes that evaluation;
3. the same with viscous friction (gtmodel only, no peer).

gtmodel's durations come out slightly shorter, by an amount that grows with the grid:
TOPP-RA lowers every forward step by 1e-8 in ``s_dot^2`` (``toppra.constants.TINY``) as a
safety margin, which accumulates over the accelerating stretches.

Printed: duration [s], duration difference [ppm of TOPP-RA's], wall times [ms] (the best
of ``--repeat`` runs: these machines are shared and noisy) and the time ratio
gtmodel / TOPP-RA. "gt total" is path evaluation + solve (what a caller pays), "gt solve"
the two passes alone. TOPP-RA's time is instance construction (its constraint
evaluation) + ``compute_parameterization``. No assertions: timings depend on the machine.

``--json``: only case 1, on N = 100, 500, 2000, 10^4 and 10^5 points, then ONE JSON object on
the last line of stdout: ``ratio_to_toppra`` (gt total / TOPP-RA, both setup + solve, best of
``--repeat``), the wall times, the durations of both, and the exact gridded optimum from
IPOPT (:meth:`PathConstrainedProblem.solve_nlp`, tol 1e-14, bounds not relaxed) for N <= ``--nlp-max``, with
gtmodel's distance to it in ppm. Without TOPP-RA the ratios are ``null`` and ``"toppra"``
says it is missing (``pip install toppra``: a benchmark-only dependency, not in pyproject).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import logging
import sys
import time

import numpy as np

from gtmodel.trajectory.path import StraightLine
from gtmodel.trajectory.path_constrained import GriddedPathProblem, PathConstrainedProblem, PathConstraints

GRIDS = (100, 500, 2000)
JSON_GRIDS = (100, 500, 2000, 10_000, 100_000)


def _toppra(required: bool = True):
    try:
        import toppra
        import toppra.algorithm
        import toppra.constraint
        from toppra.interpolator import AbstractGeometricPath
    except ImportError as exc:  # pragma: no cover
        print(f"TOPP-RA MISSING: toppra is not installed ({exc}); pip install toppra (benchmark-only, not a gtmodel dependency)")
        if required:
            sys.exit(1)
        return None, None
    logging.getLogger("toppra").setLevel(logging.ERROR)
    return toppra, AbstractGeometricPath


def make_toppra_path(path, AbstractGeometricPath):
    """Wrap a gtmodel path (TCP coordinates as the 3 'joints') for TOPP-RA."""

    class GtPath(AbstractGeometricPath):
        def __call__(self, path_positions, order=0):
            s = np.atleast_1d(np.asarray(path_positions, dtype=float))
            out = path.evaluate(s)[order]
            return out if np.ndim(path_positions) else out[0]

        @property
        def dof(self):
            return 3

        @property
        def path_interval(self):
            return np.array([0.0, 1.0])

        @property
        def waypoints(self):
            return None

    return GtPath()


def force_constraint(toppra, gp: GriddedPathProblem, limit: float):
    """TOPP-RA generic linear constraint ``-F <= m u + c x + g <= F`` from gtmodel's arrays."""
    from toppra.constraint import DiscretizationType, LinearConstraint

    class Forces(LinearConstraint):
        def __init__(self):
            super().__init__()
            self.identical = True
            self.discretization_type = DiscretizationType.Collocation
            self.dof = 3

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            F = np.vstack([np.eye(3), -np.eye(3)])
            g = np.full(6, limit)
            return gp.m, gp.c, gp.g, F, g, None, None

    return Forces()


def best_of(fn, repeat):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def duration(sd: np.ndarray, s: np.ndarray) -> float:
    return float(np.sum(2 * np.diff(s) / (sd[:-1] + sd[1:])))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--json", action="store_true", help="case 1 on 100 ... 10^5 points, one JSON object on the last line")
    ap.add_argument("--grids", type=int, nargs="+", default=list(JSON_GRIDS), help="grid sizes of --json (default 100 500 2000 10000 100000)")
    ap.add_argument("--nlp-max", type=int, default=100_000, help="largest N cross-checked with IPOPT in --json mode")
    args = ap.parse_args()
    if args.json:
        json_main(args)
        return
    toppra, AbstractGeometricPath = _toppra()
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    print(f"toppra {getattr(toppra, '__version__', '0.6.x')} (solver wrapper 'seidel', collocation scheme), best of {args.repeat} runs")
    header = f"{'case':22s} {'points':>6s} {'T gtmodel [s]':>15s} {'T toppra [s]':>15s} {'dT [ppm]':>9s} {'gt solve':>9s} {'gt total':>9s} {'toppra':>9s} {'total ratio':>11s}"
    print(header)
    print("-" * len(header))

    # 1. kinematic limits
    line = StraightLine([0.0, 0.0, 0.0], [0.8, 0.3, -0.2])
    kin = PathConstrainedProblem(line, PathConstraints(tcp_velocity_limit=1.0, tcp_acceleration_limit=5.0), constrain_end=False)
    tp_path = make_toppra_path(line, AbstractGeometricPath)
    vlim = np.array([[-1.0, 1.0]] * 3)
    alim = np.array([[-5.0, 5.0]] * 3)
    for n in GRIDS:
        t_total, sol = best_of(lambda: kin.solve(n), args.repeat)
        gp = kin.gridded(n)
        t_solve = min(kin.solve(gp).solve_time for _ in range(args.repeat))
        grid = gp.s

        def run_toppra():
            inst = algo.TOPPRA(
                [constraint.JointVelocityConstraint(vlim), constraint.JointAccelerationConstraint(alim, discretization_scheme=constraint.DiscretizationType.Collocation)],
                tp_path, gridpoints=grid, solver_wrapper="seidel", parametrizer="ParametrizeConstAccel",
            )
            return inst.compute_parameterization(0, 0)

        t_tp, (sdd, sd, _) = best_of(run_toppra, args.repeat)
        T_tp = duration(sd, grid)
        print(f"{'TCP vel+acc (T*=1 s)':22s} {n:6d} {sol.final_time:15.10f} {T_tp:15.10f} {(sol.final_time - T_tp) / T_tp * 1e6:9.3f} "
              f"{t_solve * 1e3:9.2f} {t_total * 1e3:9.2f} {t_tp * 1e3:9.2f} {t_total / t_tp:11.2f}")

    # 2. L1 forces, Coulomb friction only (TOPP-RA cannot do viscous friction)
    l1_line = StraightLine([-0.2, 2.75, -0.4], [0.2, 3.0, -0.6], robot="L1")
    l1 = PathConstrainedProblem(l1_line, PathConstraints(force_limit=450.0), robot="L1", viscous_friction=False, constrain_end=False)
    tp_l1 = make_toppra_path(l1_line, AbstractGeometricPath)
    for n in GRIDS:
        t_total, sol = best_of(lambda: l1.solve(n), args.repeat)
        gp = l1.gridded(n)
        t_solve = min(l1.solve(gp).solve_time for _ in range(args.repeat))
        grid = gp.s

        def run_toppra():
            inst = algo.TOPPRA([force_constraint(toppra, gp, 450.0)], tp_l1, gridpoints=grid, solver_wrapper="seidel", parametrizer="ParametrizeConstAccel")
            return inst.compute_parameterization(0, 0)

        t_tp, (sdd, sd, _) = best_of(run_toppra, args.repeat)
        T_tp = duration(sd, grid) if sd is not None else float("nan")
        print(f"{'L1 450 N, Coulomb':22s} {n:6d} {sol.final_time:15.10f} {T_tp:15.10f} {(sol.final_time - T_tp) / T_tp * 1e6:9.3f} "
              f"{t_solve * 1e3:9.2f} {t_total * 1e3:9.2f} {t_tp * 1e3:9.2f} {t_total / t_tp:11.2f}")

    # 3. L1 forces with viscous friction (no peer)
    l1v = PathConstrainedProblem(l1_line, PathConstraints(force_limit=450.0), robot="L1")
    for n in GRIDS:
        t_total, sol = best_of(lambda: l1v.solve(n), args.repeat)
        gp = l1v.gridded(n)
        t_solve = min(l1v.solve(gp).solve_time for _ in range(args.repeat))
        print(f"{'L1 450 N, +viscous':22s} {n:6d} {sol.final_time:15.10f} {'-':>15s} {'-':>9s} {t_solve * 1e3:9.2f} {t_total * 1e3:9.2f} {'-':>9s} {'-':>11s}  ({sol.status}, {sol.method})")

    # 4. the direct (free-path) minimum-time problem: iterations and wall time, against the
    #    thesis' 199 IPOPT iterations (Table 3.1) and the path-constrained solve of the same poses
    from pathlib import Path

    from gtmodel.problems import load_problem, solve_problem

    THESIS_ITERATIONS = 199
    problem = load_problem(Path(__file__).resolve().parents[1] / "problems" / "l1_time_optimal.toml")
    t0 = time.perf_counter()
    direct = solve_problem(problem)
    total = time.perf_counter() - t0
    r = direct.result
    _, line_sol = best_of(lambda: l1v.solve(500), 1)
    print()
    print(f"direct minimum time (problems/l1_time_optimal.toml): {r.status}, T_f {r.final_time:.4f} s, "
          f"{r.iterations} IPOPT iterations ({r.iterations / THESIS_ITERATIONS:.2f} x the thesis' {THESIS_ITERATIONS}), "
          f"solve {r.solve_time:.2f} s, build + solve {total:.2f} s; path-constrained on the same poses "
          f"{line_sol.final_time:.4f} s in {line_sol.solve_time * 1e3:.1f} ms (ratio {r.solve_time / line_sol.solve_time:.0f})")


def json_main(args) -> None:
    """Case 1 on ``args.grids`` (default :data:`JSON_GRIDS`); the figures as one JSON object on the last line."""
    toppra, AbstractGeometricPath = _toppra(required=False)
    version = importlib.metadata.version("toppra") if toppra is not None else None
    line = StraightLine([0.0, 0.0, 0.0], [0.8, 0.3, -0.2])
    kin = PathConstrainedProblem(line, PathConstraints(tcp_velocity_limit=1.0, tcp_acceleration_limit=5.0), constrain_end=False)
    vlim = np.array([[-1.0, 1.0]] * 3)
    alim = np.array([[-5.0, 5.0]] * 3)
    out = {"case": "straight line (0,0,0)->(0.8,0.3,-0.2) m, |v_i| <= 1 m/s, |a_i| <= 5 m/s^2, T* = 1 s",
           "toppra": f"toppra {version}, seidel, collocation" if version else "MISSING (pip install toppra)",
           "repeat": args.repeat, "timing": f"best of {args.repeat} runs on a shared machine",
           "ratio_to_toppra": {}, "gt_total_ms": {}, "gt_solve_ms": {}, "toppra_ms": {},
           "duration_s": {}, "toppra_duration_s": {}, "nlp_duration_s": {}, "duration_vs_nlp_ppm": {}}
    print(f"{'points':>7s} {'T gtmodel [s]':>15s} {'T ipopt [s]':>15s} {'dT [ppm]':>9s} {'gt total':>9s} {'toppra':>9s} {'ratio':>6s}")
    for n in args.grids:
        key = str(n)
        t_total, sol = best_of(lambda: kin.solve(n), args.repeat)
        gp = kin.gridded(n)
        t_solve = min(kin.solve(gp).solve_time for _ in range(args.repeat))
        t_tp = T_tp = None
        if toppra is not None:
            import toppra.algorithm as algo
            import toppra.constraint as constraint

            tp_path = make_toppra_path(line, AbstractGeometricPath)

            def run_toppra():
                inst = algo.TOPPRA(
                    [constraint.JointVelocityConstraint(vlim), constraint.JointAccelerationConstraint(alim, discretization_scheme=constraint.DiscretizationType.Collocation)],
                    tp_path, gridpoints=gp.s, solver_wrapper="seidel", parametrizer="ParametrizeConstAccel",
                )
                return inst.compute_parameterization(0, 0)

            t_tp, (_, sd, _) = best_of(run_toppra, args.repeat)
            T_tp = duration(sd, gp.s)
        T_nlp = None
        if n <= args.nlp_max:
            nlp = kin.solve_nlp(gp, tol=1e-14)
            T_nlp = nlp.final_time if nlp.status == "optimal" else None
        ppm = (sol.final_time - T_nlp) / T_nlp * 1e6 if T_nlp else None
        out["ratio_to_toppra"][key] = t_total / t_tp if t_tp else None
        out["gt_total_ms"][key] = t_total * 1e3
        out["gt_solve_ms"][key] = t_solve * 1e3
        out["toppra_ms"][key] = t_tp * 1e3 if t_tp else None
        out["duration_s"][key] = sol.final_time
        out["toppra_duration_s"][key] = T_tp
        out["nlp_duration_s"][key] = T_nlp
        out["duration_vs_nlp_ppm"][key] = ppm
        print(f"{n:7d} {sol.final_time:15.10f} {T_nlp or float('nan'):15.10f} {ppm if ppm is not None else float('nan'):9.2e} "
              f"{t_total * 1e3:9.2f} {t_tp * 1e3 if t_tp else float('nan'):9.2f} {t_total / t_tp if t_tp else float('nan'):6.2f}", flush=True)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
