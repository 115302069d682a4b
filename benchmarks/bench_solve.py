"""Solve time and iterations of the shipped problems (a benchmark, not a test).

Usage: python benchmarks/bench_solve.py [problems/*.toml]   (default: the point_to_point problems)

Printed next to peers measured in the same run, because these machines are noisy:
- iterations against the thesis' Optimica/IPOPT figure for the same kind of problem
  (Dressler (2012), Table 3.1: 199 iterations for the direct minimum-time problem);
- wall time of the robot problem against a peer NLP of the same size built the same way:
  the minimum-time double integrator (3 axes, same elements and points), so the ratio
  shows what the robot model costs over the bare transcription.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.problems import load_problem, solve_problem

THESIS_ITERATIONS = 199  # Table 3.1, "direct, w = 0"


def peer_double_integrator(elements: int, points: int) -> tuple[float, float, int]:
    """Build + solve a 3-axis minimum-time double integrator of the same mesh size."""
    t0 = time.perf_counter()
    m = Model("double_integrator")
    x = m.state("x", 3)
    v = m.state("v", 3)
    u = m.input("u", 3, lb=-1.0, ub=1.0)
    m.equation(m.der(x), v)
    m.equation(m.der(v), u)
    opt = Optimization(m, final_time=2.0, free_final_time=True, final_time_bounds=(0.1, 10.0))
    opt.set_objective(mayer=opt.final_time)
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.add_point_constraint(v, at="start", lb=0.0, ub=0.0)
    opt.add_point_constraint(x - np.array([0.4, 0.25, -0.2]), at="final", lb=0.0, ub=0.0)
    opt.add_point_constraint(v, at="final", lb=0.0, ub=0.0)
    tr = CollocationTranscription(opt, elements=elements, points=points)
    build = time.perf_counter() - t0
    res = tr.solve()
    return build, res.solve_time, res.iterations


def main(paths: list[str]) -> None:
    import tomllib

    files = [Path(p) for p in paths] or sorted(
        p for p in Path(__file__).resolve().parents[1].glob("problems/*.toml") if tomllib.loads(p.read_text())["kind"] == "point_to_point"
    )
    print(f"casadi {ca.__version__}")
    print(f"{'problem':28s} {'status':10s} {'T_f [s]':>8s} {'iter':>5s} {'iter/thesis':>11s} {'solve [s]':>9s} {'total [s]':>9s} {'peer solve [s]':>14s} {'ratio':>6s}")
    for f in files:
        problem = load_problem(f)
        d = problem.declaration
        t0 = time.perf_counter()
        sol = solve_problem(problem)
        total = time.perf_counter() - t0
        r = sol.result
        _, peer_solve, peer_iter = peer_double_integrator(d.elements, d.points)
        print(
            f"{problem.name:28s} {r.status:10s} {r.final_time:8.4f} {r.iterations:5d} {r.iterations / THESIS_ITERATIONS:11.2f} "
            f"{r.solve_time:9.2f} {total:9.2f} {peer_solve:14.3f} {r.solve_time / peer_solve:6.1f}"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
