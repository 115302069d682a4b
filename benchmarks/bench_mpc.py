"""Real-time MPC step as generated C against the same MPC solved per step in Python (a benchmark, not a test).

Usage: python benchmarks/bench_mpc.py [FILE.toml ...] [--json] [--steps 10000]

For each MPC file (default every ``codegen/mpc/*.toml``: the L1 and the composed DC motor),
measured side by side in one run, because these machines are noisy:

- the generated C step (``gt_<name>_step`` through ctypes: CasADi's ``sqpmethod`` + ``qrqp`` (``daqp`` with
  state or path constraints; ``fatrop`` for ``solver = "fatrop"``)
  code-generated, one SQP iteration per period by default) in the closed loop of the file's
  ``[check]`` (mismatched plant, noise, step disturbance, one-sample delay), the motion run
  again from ``_init`` until at least ``--steps`` steps: per-step time, median, p99 and
  max, the first step of the first run apart, in wall time (``step_*_s``) and in the CPU
  time of this thread (``cpu_step_*_s``: the step's own work, without the preemptions of
  a shared machine). The ctypes call is inside the timing (about 1-2 us);
- its static memory: ``sizeof(<prefix>_memory)`` and the stack work arrays of one step, and with
  DAQP the per-thread arena its allocations go to (``arena_bytes``, its peak use
  ``arena_peak_bytes`` and the allocations that did not fit it, ``heap_calls``, 0 expected);
- the tracking error RMS of the MPC over that of the feedforward alone on the same plant
  (``tracking_rms_ratio_to_feedforward``) and the applied-input bound violations;
- ``ratio_to_python``: the same horizon problem solved per step in Python by CasADi + IPOPT
  (the same NLP Function; warm-started from the previous step's solution; at 50 states of
  the closed loop), its median wall time per step over the C step's median.

With ``--json`` the last line of stdout is one JSON object
``{"mpc": [{"name", "horizon", "period_s", "step_median_s", "step_p99_s", "step_max_s",
"tracking_rms_ratio_to_feedforward", "bound_violations", "ratio_to_python", ...}, ...]}``.
"""

from __future__ import annotations

import argparse
import json
import logging
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from gtmodel.problems.mpc_check import build_mpc, closed_loop_check
from gtmodel.problems.mpc_file import load_mpc_file

ROOT = Path(__file__).resolve().parents[1]
#: States of the closed loop at which the Python (IPOPT) step is timed.
PYTHON_STATES = 50


def python_step_s(setup, summary) -> float:
    """Median wall time [s] of one MPC step solved in Python by IPOPT (warm-started from the last solution)."""
    c = setup.controller
    solver = c.nlp_solver("ipopt")
    bounds = c.bounds()
    w = np.r_[c.w_initial, np.zeros(c.n_slack)]
    times = []
    for k in np.linspace(0, summary.t.size - 1, PYTHON_STATES).round().astype(int):
        p = c.parameters(summary.t[k], summary.x[k])
        t0 = time.perf_counter()
        sol = solver(x0=w, p=p, **bounds)
        times.append(time.perf_counter() - t0)
        w = np.asarray(sol["x"]).reshape(-1)
    return statistics.median(times)


def bench(path: Path, steps: int, build: Path) -> dict:
    """All figures of one MPC file."""
    setup = load_mpc_file(path)
    generated, library = build_mpc(setup, build / setup.name)
    repeat = -(-steps // setup.t.size)
    wall = closed_loop_check(setup, generated, library, repeat=repeat, clock=time.perf_counter)
    cpu = closed_loop_check(setup, generated, library, repeat=repeat, clock=time.thread_time)
    st, cst = wall.mpc.step_times(), cpu.mpc.step_times()
    py = python_step_s(setup, wall.mpc)
    c = setup.controller
    return {
        "name": setup.name, "solver": c.solver, "qpsol": c.qpsol if c.solver == "sqpmethod" else "", "constraint_rows": c.constraint_rows,
        "horizon": c.horizon, "period_s": c.dt, "blocks": c.blocks, "sqp_iterations": c.sqp_iterations,
        "steps": int(wall.mpc.step_s.size), "first_step_s": st["first"],
        "step_median_s": st["median"], "step_p99_s": st["p99"], "step_max_s": st["max"],
        "cpu_step_median_s": cst["median"], "cpu_step_p99_s": cst["p99"], "cpu_step_max_s": cst["max"],
        "memory_bytes": wall.memory_bytes, "work_bytes": wall.work_bytes,
        "arena_bytes": wall.heap[2] if wall.heap else 0, "arena_peak_bytes": wall.heap[0] if wall.heap else 0,
        "heap_calls": wall.heap[1] if wall.heap else 0,
        "tracking_rms": wall.mpc.rms_error, "feedforward_rms": wall.feedforward.rms_error,
        "tracking_rms_ratio_to_feedforward": wall.ratio_to_feedforward,
        "bound_violations": wall.mpc.bound_violations + cpu.mpc.bound_violations,
        "status_counts": wall.mpc.status_counts,
        "python_step_median_s": py, "ratio_to_python": py / st["median"],
    }


def main() -> None:
    """Run the benchmark (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path, help="MPC files (default codegen/mpc/*.toml)")
    ap.add_argument("--json", action="store_true", help="end with one JSON line")
    ap.add_argument("--steps", type=int, default=10000, help="at least this many C steps per MPC (default 10000)")
    args = ap.parse_args()
    logging.getLogger("gtmodel").setLevel(logging.WARNING)
    files = args.files or sorted((ROOT / "codegen" / "mpc").glob("*.toml"))
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_mpc_") as tmp:
        for path in files:
            r = bench(path, args.steps, Path(tmp))
            rows.append(r)
            print(f"{r['name']}: {r['solver']} {r['qpsol']}, horizon {r['horizon']} x {r['period_s'] * 1e3:g} ms, {r['blocks']} input blocks, "
                  f"{r['sqp_iterations']} SQP iteration(s), {r['constraint_rows']} constraint rows, {r['steps']} C steps")
            print(f"  C step wall: median {r['step_median_s'] * 1e6:.1f} us, p99 {r['step_p99_s'] * 1e6:.1f} us, "
                  f"max {r['step_max_s'] * 1e6:.1f} us (first {r['first_step_s'] * 1e6:.1f} us)")
            print(f"  C step CPU : median {r['cpu_step_median_s'] * 1e6:.1f} us, p99 {r['cpu_step_p99_s'] * 1e6:.1f} us, "
                  f"max {r['cpu_step_max_s'] * 1e6:.1f} us")
            print(f"  static memory {r['memory_bytes']} B + stack work {r['work_bytes']} B"
                  + (f" + QP arena {r['arena_bytes']} B per thread (peak {r['arena_peak_bytes']} B, {r['heap_calls']} heap calls)" if r["arena_bytes"] else "")
                  + f"; statuses {r['status_counts']}")
            print(f"  tracking RMS {r['tracking_rms']:.4g} vs feedforward {r['feedforward_rms']:.4g}: "
                  f"ratio {r['tracking_rms_ratio_to_feedforward']:.4g}; bound violations {r['bound_violations']}")
            print(f"  Python (CasADi + IPOPT) per step: median {r['python_step_median_s'] * 1e3:.2f} ms = "
                  f"{r['ratio_to_python']:.0f}x the C step")
    if args.json:
        print(json.dumps({"mpc": rows}))


if __name__ == "__main__":
    main()
