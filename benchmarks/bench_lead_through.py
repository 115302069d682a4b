"""Benchmark: the generated lead-through controller step against the same step called from Python.

Dressler (2012), ch. 8: the two-sensor lead-through law runs every 4 ms. Generates and
compiles the step of the shipped surface-tracking controller
(``problems/irb140_lead_through_surface.toml``, its ``LeadThroughLaw``) into a temporary
folder and prints, over the default recorded session (2000 steps,
``gtmodel.codegen.check.lead_through.lead_through_record``):

* ns per step of the generated ``lead_through_update`` (state struct) in a C loop (mean,
  and the fastest block of 100 steps); aim: under 5 us (issue 29);
* ns per step of the same CasADi Function called from Python, one call per step, and per
  step of its ``mapaccum`` over the whole record;
* the ratios Python / C.

Run: ``python benchmarks/bench_lead_through.py`` (``--json``: one JSON object on the last
line of stdout with ``c_update_ns``, ``c_update_best_ns``, ``python_call_ns``,
``python_mapaccum_ns``, ``ratio_call``, ``ratio_mapaccum``).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gtmodel.codegen import Controller, compile_shared, generate
from gtmodel.codegen.check.lead_through import lead_through_record, time_lead_through
from gtmodel.problems import load_problem

PROBLEM = Path(__file__).resolve().parents[1] / "problems" / "irb140_lead_through_surface.toml"


def python_times(f, record, repeats: int = 3) -> tuple[float, float]:
    """ns per step of one Function call per step, and of the mapaccum over the record (best of ``repeats``)."""
    N = len(record["F_h"])
    calls, whole = [], []
    run = f.mapaccum("run", N)
    for _ in range(repeats):
        x = record["x0"]
        t0 = time.perf_counter_ns()
        for k in range(N):
            x = f(x, record["F_h"][k], record["F_t"][k], record["n_n"][k])[0]
        calls.append((time.perf_counter_ns() - t0) / N)
        t0 = time.perf_counter_ns()
        run(record["x0"], record["F_h"].T, record["F_t"].T, record["n_n"].T)
        whole.append((time.perf_counter_ns() - t0) / N)
    return min(calls), min(whole)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="one JSON object on the last line of stdout")
    args = parser.parse_args(argv)
    law = load_problem(PROBLEM).declaration.law
    step = law.step_function()
    record = lead_through_record()
    with tempfile.TemporaryDirectory(prefix="gtmodel-bench-lt-") as tmp:
        generated = generate(out_dir=Path(tmp) / "lt", controller=Controller(lead_through_step=step, dt=law.dt), functions=[],
                             prefix="gt")
        library = compile_shared(generated, Path(tmp) / "build")
        c = time_lead_through(generated, library, record, Path(tmp) / "build")
    call_ns, whole_ns = python_times(step, record)
    out = {"c_update_ns": c["lead_through_update"], "c_update_best_ns": c["lead_through_update best"],
           "python_call_ns": call_ns, "python_mapaccum_ns": whole_ns,
           "ratio_call": call_ns / c["lead_through_update"], "ratio_mapaccum": whole_ns / c["lead_through_update"],
           "steps": len(record["F_h"])}
    table = sys.stderr if args.json else sys.stdout
    print(f"lead-through step over {out['steps']} recorded steps (ns per step)", file=table)
    print(f"  generated C lead_through_update   {out['c_update_ns']:10.1f}  (best block {out['c_update_best_ns']:.1f})", file=table)
    print(f"  Python Function call per step      {call_ns:10.1f}  ratio {out['ratio_call']:6.1f}x", file=table)
    print(f"  Python mapaccum over the record    {whole_ns:10.1f}  ratio {out['ratio_mapaccum']:6.1f}x", file=table)
    print(f"  aim: C under 5000 ns: {'met' if out['c_update_ns'] < 5000 else 'NOT met'}", file=table)
    if args.json:
        print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
