"""Start-up CPU time of the ``gtmodel`` command against bare Python and ``import casadi`` (a benchmark, not a test).

Usage: python benchmarks/bench_cli_startup.py [--json] [--repeat 5]

Measured side by side in one run, each a fresh process (``python -m gtmodel.cli ...``,
the console script's own work), its CPU time (user + system, of the child process):

- ``help``: ``gtmodel --help``;
- ``schema_list``: ``gtmodel schema --list``;
- ``missing_file``: ``gtmodel solve nope.toml`` (a mistyped path: exit 2, nothing written);
- ``unknown_field``: ``gtmodel solve bad.toml`` with an unknown field in a copy of
  ``problems/l1_time_optimal.toml`` (exit 2, an ``invalid_input`` summary written);
- ``wrong_type``: the same with a wrong type (``w = "zero"``, exit 2): both are reported
  by the kind's light schema (:mod:`gtmodel.problems.kinds.schemas`) before the kind and
  its solvers' modules (CasADi, SciPy, python-control) are imported;
- the peers: ``python -c pass`` (the interpreter's own start) and ``python -c "import
  casadi"`` (the one library every solve needs).

Printed: the minimum over ``--repeat`` runs of each (the least disturbed by other jobs on
a shared machine), and each command's ratio to ``python -c pass`` and to ``import casadi``.
The goal of issue 24: the gtmodel commands well under 1 s of CPU. With ``--json`` the last line
of stdout is one JSON object.
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

REPO = Path(__file__).resolve().parents[1]


def cpu_of(cmd: list[str], cwd: Path, expect: int) -> float:
    """CPU seconds (user + system) of one child process running ``cmd``; checks its exit code."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, cwd=cwd, env=dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg"), capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != expect:
        raise SystemExit(f"{' '.join(cmd)}: exit {proc.returncode}, expected {expect}\n{proc.stdout}\n{proc.stderr}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    """Run the benchmark (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="one JSON object on the last line")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each command (the minimum is reported)")
    args = ap.parse_args()
    py = sys.executable
    with tempfile.TemporaryDirectory(prefix="bench_cli_") as tmp:
        work = Path(tmp)
        bad = work / "bad.toml"
        base = (REPO / "problems" / "l1_time_optimal.toml").read_text(encoding="utf-8")
        bad.write_text(base + "\nunknown_field = 1\n", encoding="utf-8")
        mistyped = work / "mistyped.toml"
        mistyped.write_text(base.replace("w = 0.0 ", 'w = "zero" ', 1), encoding="utf-8")
        commands = {
            "python_pass": ([py, "-c", "pass"], 0),
            "import_casadi": ([py, "-c", "import casadi"], 0),
            "help": ([py, "-m", "gtmodel.cli", "--help"], 0),
            "schema_list": ([py, "-m", "gtmodel.cli", "schema", "--list"], 0),
            "missing_file": ([py, "-m", "gtmodel.cli", "solve", "nope.toml"], 2),
            "unknown_field": ([py, "-m", "gtmodel.cli", "solve", str(bad), "--out", str(work / "out"), "-q"], 2),
            "wrong_type": ([py, "-m", "gtmodel.cli", "solve", str(mistyped), "--out", str(work / "out2"), "-q"], 2),
        }
        times: dict[str, list[float]] = {k: [] for k in commands}
        for _ in range(args.repeat):  # interleaved: a change of load hits every command alike
            for name, (cmd, expect) in commands.items():
                times[name].append(cpu_of(cmd, work, expect))
        if (work / "results").exists():
            raise SystemExit("gtmodel solve nope.toml wrote results/: it must write nothing")
    best = {k: min(v) for k, v in times.items()}
    result = {"cpu_s": best, "runs": times, "repeat": args.repeat, "loadavg": os.getloadavg(),
              "vs_python": {k: best[k] / best["python_pass"] for k in best},
              "vs_casadi": {k: best[k] / best["import_casadi"] for k in best}}
    print(f"CPU time, minimum of {args.repeat} runs (load average {result['loadavg'][0]:.2f} on {os.cpu_count()} cores):")
    for k in commands:
        print(f"  {k:<14} {best[k]:6.3f} s   {result['vs_python'][k]:5.2f}x python -c pass   {result['vs_casadi'][k]:5.2f}x import casadi")
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    main()
