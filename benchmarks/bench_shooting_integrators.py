"""Multiple shooting's integrators on the drive problems: speed and correctness, to choose the default.

Each ``problems/drive_*.toml`` is solved by ``gtmodel solve`` with ``[transcription] method =
"multiple_shooting"`` and each integrator (``rk``, ``radau``, ``collocation``; the file's other
tables unchanged, the transcription's defaults: 50 intervals, 4 steps, piecewise-constant
voltage), in a child process whose CPU time is measured (``resource.getrusage`` of the
children). Printed per run: status, exit code, the objective against the independent reference
(``tests/problems/data/drive_references.json``, plain-CasADi multiple shooting on the finest
mesh; 50 piecewise-constant intervals cannot reach it, its 100-interval value is printed beside),
verified, the worst bound excess between the nodes (``verification.bounds.between_nodes``,
relative to ``max(1, |bound|)``), CPU-s; then per integrator the runs that are ``optimal``,
verified and within 5 % of the reference, and the total CPU.

Usage::

    nice python benchmarks/bench_shooting_integrators.py [--json] [--problems two_mass,belt] [--integrators rk,radau]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ("motor_gear_load", "two_mass", "flexible_joint", "belt", "ball_screw")
INTEGRATORS = ("rk", "radau", "collocation")


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(problem: str, integrator: str, work: Path, timeout: float) -> dict:
    """Solve ``drive_<problem>`` by multiple shooting with ``integrator``; its figures."""
    text = (ROOT / "problems" / f"drive_{problem}.toml").read_text()
    name = f"ms_{problem}_{integrator}"
    text = text.replace(f'name = "drive_{problem}"', f'name = "{name}"')
    text += f'\n[transcription]\nmethod = "multiple_shooting"\nintegrator = "{integrator}"\n'
    path = work / "problems" / f"{name}.toml"
    path.write_text(text)
    out = work / f"out_{name}"
    before = _children_cpu()
    try:
        proc = subprocess.run([sys.executable, "-m", "gtmodel", "solve", str(path), "--no-plots", "--no-report", "-q",
                               "--out", str(out)], capture_output=True, text=True, timeout=timeout)
        code, printed = proc.returncode, proc.stdout + proc.stderr
    except subprocess.TimeoutExpired:
        code, printed = None, ""
    cpu = _children_cpu() - before
    row = {"problem": f"drive_{problem}", "integrator": integrator, "exit_code": code, "cpu_s": round(cpu, 2),
           "printed_chars": len(printed), "casadi_in_output": "casadi" in printed.lower()}
    summary = out / "summary.json"
    if code is None or not summary.exists():
        row["status"] = "timeout" if code is None else "no summary"
        return row
    s = json.loads(summary.read_text())
    refs = json.loads((ROOT / "tests" / "problems" / "data" / "drive_references.json").read_text())[f"drive_{problem}"]
    ref = refs.get("objective", refs["final_time"])
    ref100 = refs.get("objective_by_intervals", refs["by_intervals"]).get("100")
    ver = s.get("verification") or {}
    between = (ver.get("bounds") or {}).get("between_nodes") or {}
    obj = s.get("objective")
    row.update(status=s["status"], objective=obj, verified=ver.get("passed"),
               relative_error=(obj - ref) / ref if isinstance(obj, (int, float)) else None,
               relative_error_100=(obj - ref100) / ref100 if isinstance(obj, (int, float)) and ref100 else None,
               worst_bound_excess=between.get("max_scaled_violation"), bound_where=between.get("where"),
               casadi_in_summary="casadi/" in summary.read_text().lower() or "input 0 (" in summary.read_text().lower())
    return row


def main(argv: list[str] | None = None) -> int:
    """Run the grid; print a table (or one JSON line with ``--json``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--problems", default=",".join(PROBLEMS))
    ap.add_argument("--integrators", default=",".join(INTEGRATORS))
    ap.add_argument("--timeout", type=float, default=900.0, help="per run, wall s")
    a = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "problems").mkdir()
        os.symlink(ROOT / "models", work / "models")
        for problem in a.problems.split(","):
            for integrator in a.integrators.split(","):
                row = run(problem, integrator, work, a.timeout)
                rows.append(row)
                if not a.json:
                    err = row.get("relative_error")
                    exc = row.get("worst_bound_excess")
                    obj = row.get("objective")
                    print(f"{row['problem']:22s} {integrator:12s} {row['status']:13s} exit {row['exit_code']} "
                          f"obj {obj if obj is None else f'{obj:.6g}'} rel {err if err is None else f'{err:+.4f}'} "
                          f"verified {row.get('verified')} excess {exc if exc is None else f'{exc:.4f}'} "
                          f"cpu {row['cpu_s']:.1f} s casadi-text {row['casadi_in_output'] or row.get('casadi_in_summary')}",
                          flush=True)
    per = {}
    for integ in a.integrators.split(","):
        mine = [r for r in rows if r["integrator"] == integ]
        good = [r for r in mine if r.get("status") == "optimal" and r.get("verified") and r.get("relative_error") is not None
                and abs(r["relative_error"]) < 0.05]
        per[integ] = {"runs": len(mine), "optimal_verified_within_5pct": len(good), "cpu_s_total": round(sum(r["cpu_s"] for r in mine), 1),
                      "crashes": sum(1 for r in mine if r.get("exit_code") not in (0, 1)),
                      "optimal_with_bound_excess": sum(1 for r in mine if r.get("status") == "optimal"
                                                       and (r.get("worst_bound_excess") or 0) > 0.01)}
    if a.json:
        print(json.dumps({"runs": rows, "per_integrator": per}))
    else:
        for integ, p in per.items():
            print(f"{integ:12s} {p}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
