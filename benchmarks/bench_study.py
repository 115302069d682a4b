"""Study scaling: 64 cases of ``l1_time_optimal`` with ``--workers 2`` against ``--workers 1``.

Usage: python benchmarks/bench_study.py [--json] [--grid 8] [--keep DIR]

The cases: the minimum-time motion of ``problems/l1_time_optimal.toml`` from its start to
an 8 x 8 grid of end positions (x -0.5..0.3 m, y 2.5..3.2 m, z = -0.6 m; all inside the
workspace), written as two study files of 32 cases each (y below / above 2.85 m) in a
temporary folder. In ONE run, each half is run from scratch with both settings, as a user
runs it (``python -m gtmodel.cli study ... --no-plots -q``, a fresh process each, so both
pay the imports): ``--workers 2`` (a local Dask cluster of 2 processes) and ``--workers 1``
(in-process, no Dask), in the order 2, 1 (first half), 1, 2 (second half): on a machine
whose load drifts, this ABBA order cancels a linear drift from the ratio.

Printed, per setting (summed over the two halves): the wall time of the command, the study's own timing (from its
``summary.json``: cluster start-up, execution, the sum of the cases' ``run_problem`` times)
and the machinery's overhead per case, ``(busy * workers - sum run_problem) / cases`` with
``busy`` the execution time after the cluster start-up (for 2 workers this includes the
idle tail when the last cases run), as a percentage of the mean case time. Then the
speed-up ``wall(workers 1) / wall(workers 2)`` (the whole command) and the same over the
execution alone. The machine is shared with other jobs: timings move with its load, so
the ratios are from one run and the load average is printed.

What the machine gives: before and after the study runs, a pure-Python CPU loop (no
gtmodel) is timed in 1 process and in 2 processes at once (``multiprocessing``); the ratio
``2 x t(1 process) / t(2 processes)`` is the speed-up any 2-process job could reach at that
moment (2.0 on two idle cores; ~1.0 when other jobs leave one core's worth). The study's
speed-up is also printed relative to it (``speedup_vs_machine``).

``--json``: one JSON object on the last line of stdout with these figures.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BASE = REPO / "problems" / "l1_time_optimal.toml"


def study_text(grid: int, half: int) -> str:
    """Half ``half`` (0, 1) of the benchmark's ``grid`` x ``grid`` end positions of l1_time_optimal."""
    y = [2.5 + 0.7 * k / (grid - 1) for k in range(grid)]
    ys = y[: grid // 2] if half == 0 else y[grid // 2:]
    return f"""name = "bench_study_{half}"
base = "{BASE.as_posix()}"
analysis = "generic"
plots = false

[design]
[[design.axes]]
field = "motion.end"
points = {{ x = {{ start = -0.5, stop = 0.3, num = {grid} }}, y = {{ start = {ys[0]!r}, stop = {ys[-1]!r}, num = {len(ys)} }}, z = -0.6 }}
"""


def _combine(a: dict, b: dict) -> dict:
    """Two runs of one setting (the halves) as one: times summed, means over all cases."""
    out = {"workers": a["workers"], "cases": a["cases"] + b["cases"],
           "counts": {k: a["counts"].get(k, 0) + b["counts"].get(k, 0) for k in {*a["counts"], *b["counts"]}}}
    for k in ("wall_s", "startup_s", "execute_s", "busy_s", "run_problem_s"):
        out[k] = (a[k] or 0.0) + (b[k] or 0.0)
    n = out["cases"]
    out["case_mean_s"] = out["run_problem_s"] / n
    out["overhead_per_case_s"] = (out["busy_s"] * out["workers"] - out["run_problem_s"]) / n
    out["overhead_percent"] = 100.0 * out["overhead_per_case_s"] / out["case_mean_s"]
    out["halves"] = [a, b]
    return out


def _spin(_: int) -> float:
    t0 = time.perf_counter()
    s = 0
    for i in range(SPIN_LOOPS):
        s += i
    return time.perf_counter() - t0


#: Iterations of the reference CPU loop (~1.5 s on an idle core of the development machine).
SPIN_LOOPS = 20_000_000


def machine_speedup() -> float:
    """What 2 processes gain over 1 on this machine now: ``2 t1 / t2`` of a pure-Python loop."""
    one = _spin(0)
    with multiprocessing.Pool(2) as pool:
        t0 = time.perf_counter()
        pool.map(_spin, [0, 1])
        two = time.perf_counter() - t0
    return 2.0 * one / two


def run(study: Path, out: Path, workers: int) -> dict:
    """One ``gtmodel study`` run from scratch; its wall time and the study's timing."""
    env = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "gtmodel.cli", "study", str(study), "--out", str(out), "--workers", str(workers),
                           "--no-plots", "-q"], env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"gtmodel study --workers {workers} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    s = json.loads((out / "summary.json").read_text())
    t = s["timing"]
    n = int(s["run_now"])
    busy = t["execute_s"] - (t.get("startup_s") or 0.0)
    per_case = t["run_problem_s"] / n
    overhead = (busy * workers - t["run_problem_s"]) / n
    return {"workers": workers, "cases": n, "counts": s["counts"], "wall_s": wall, "startup_s": t.get("startup_s"),
            "execute_s": t["execute_s"], "busy_s": busy, "run_problem_s": t["run_problem_s"], "case_mean_s": per_case,
            "overhead_per_case_s": overhead, "overhead_percent": 100.0 * overhead / per_case}


def main() -> None:
    """Run the benchmark (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="one JSON object on the last line")
    ap.add_argument("--grid", type=int, default=8, help="grid size per axis (default 8: 64 cases)")
    ap.add_argument("--keep", type=Path, default=None, help="keep the study folders here (default: a temporary folder)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_study_") as tmp:
        root = args.keep if args.keep is not None else Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        studies = [root / f"bench_study_{h}.toml" for h in (0, 1)]
        for h, f in enumerate(studies):
            f.write_text(study_text(args.grid, h), encoding="utf-8")
        load0 = os.getloadavg()
        machine0 = machine_speedup()
        two_a = run(studies[0], root / "half0_workers2", 2)
        one_a = run(studies[0], root / "half0_workers1", 1)
        one_b = run(studies[1], root / "half1_workers1", 1)
        two_b = run(studies[1], root / "half1_workers2", 2)
        load1 = os.getloadavg()
        machine1 = machine_speedup()
        one, two = _combine(one_a, one_b), _combine(two_a, two_b)
    result = {
        "cases": one["cases"], "cpu_count": os.cpu_count(), "loadavg_before": load0, "loadavg_after": load1,
        "workers1": one, "workers2": two,
        "speedup_wall": one["wall_s"] / two["wall_s"],
        "speedup_execute": one["execute_s"] / two["execute_s"],
        "speedup_busy": one["busy_s"] / two["busy_s"],
        "machine_speedup_before": machine0, "machine_speedup_after": machine1,
    }
    result["speedup_vs_machine"] = result["speedup_wall"] / (0.5 * (machine0 + machine1))
    for r in (two, one):
        print(f"--workers {r['workers']}: wall {r['wall_s']:.1f} s (start-up {r['startup_s'] or 0:.1f} s, execution {r['execute_s']:.1f} s), "
              f"{r['cases']} cases {r['counts']}, mean case {r['case_mean_s']:.2f} s, "
              f"overhead {1e3 * r['overhead_per_case_s']:.0f} ms/case = {r['overhead_percent']:.1f} % of a case")
    print(f"speed-up 2 vs 1 worker: {result['speedup_wall']:.2f}x (whole command), {result['speedup_execute']:.2f}x (execution), "
          f"{result['speedup_busy']:.2f}x (execution after the cluster start-up)")
    print(f"the machine's own 2-process speed-up (pure-Python loop): {machine0:.2f}x before, {machine1:.2f}x after; "
          f"the study reached {result['speedup_vs_machine']:.2f} of it")
    print(f"load average before {load0[0]:.2f}, after {load1[0]:.2f} on {os.cpu_count()} cores (shared machine)")
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    main()
