"""Time per IPOPT iteration on a large mesh, and where it goes (a benchmark, not a test).

Usage: python benchmarks/bench_large_mesh.py [problem.toml] [--json] [--grid 50,400]

The problem (default ``problems/benchmarks/orbit_raising.toml``, Bryson and Ho's orbit
raising) is transcribed by collocation on each mesh of ``--grid`` and solved by IPOPT.
Measured side by side in one run:

- ``marginal_ms_per_iteration`` (CPU): ``(t(30) - t(10)) / (i(30) - i(10))``, the process CPU
  time of a solve limited to 30 iterations minus that of one limited to 10, per iteration
  between them, so that the one-off work (MUMPS's analysis, IPOPT's set-up) is left out;
  ``derivatives_ms_per_iteration``: the part of it in evaluating the NLP functions and
  derivatives (CasADi's ``t_proc_nlp_*``), the rest is IPOPT and MUMPS;
  ``build_s``: building the transcription in Python (and its derivative functions);
- ``ratio_largest_over_smallest``: the marginal time per iteration at the largest mesh over
  that at the smallest (linear growth in the mesh is the grid ratio, 8 for 50 -> 400);
- ``cold`` and ``coarse_start`` at the largest mesh: the whole solve from the declared
  guess, and from a 50-element solve interpolated onto the mesh
  (:data:`gtmodel.trajectory.model_ocp.COARSE_START_MIN_ELEMENTS`), each with the file as
  shipped and with the redundant bounds ``|u1|, |u2| <= 1`` added (a degenerate NLP, as a
  user might write it): status, iterations, solve time [s] (the coarse pass included).

With ``--json`` the last line of stdout is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

from gtmodel.modeling import CollocationTranscription
from gtmodel.problems import load_problem
from gtmodel.trajectory.model_ocp import COARSE_START_ELEMENTS

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "problems/benchmarks/orbit_raising.toml"


def marginal(opt, elements: int) -> dict:
    """Marginal CPU ms per iteration (and its derivative part) and the build time on ``elements`` elements."""
    runs = []
    for it in (10, 30):
        t = time.perf_counter()
        tr = CollocationTranscription(opt, elements=elements, solver_options={"record_time": True, "max_iter": it}, verify=False)
        build = time.perf_counter() - t
        r = tr.solve()
        s = r.stats
        runs.append((r.iterations, s["t_proc_total"], sum(v for k, v in s.items() if k.startswith("t_proc_nlp_")), build))
    (i1, t1, e1, b1), (i2, t2, e2, _) = runs
    n = max(i2 - i1, 1)
    return {"marginal_ms_per_iteration": 1e3 * (t2 - t1) / n, "derivatives_ms_per_iteration": 1e3 * (e2 - e1) / n, "build_s": b1}


def whole(opt, elements: int, coarse: bool) -> dict:
    """A whole solve on ``elements`` elements, from the declared guess or a coarse solve."""
    guess, extra = None, 0.0
    if coarse:
        c = CollocationTranscription(opt, elements=COARSE_START_ELEMENTS, verify=False).solve()
        guess, extra = (c if c.status in ("optimal", "acceptable") else None), c.solve_time
    r = CollocationTranscription(opt, elements=elements, verify=False).solve(initial_guess=guess)
    return {"status": str(r.status), "message": r.message, "iterations": r.iterations, "solve_s": r.solve_time + extra, "objective": r.objective}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("problem", nargs="?", default=str(DEFAULT))
    ap.add_argument("--json", action="store_true", help="print one JSON object on the last line")
    ap.add_argument("--grid", default="50,400", help="elements of the meshes")
    a = ap.parse_args()
    grid = [int(x) for x in a.grid.split(",")]
    print(f"load average {os.getloadavg()[0]:.2f} (2 cores shared)")
    opt = load_problem(a.problem).declaration.optimization
    out: dict = {"problem": Path(a.problem).name, "per_mesh": {}}
    for n in grid:
        m = marginal(opt, n)
        out["per_mesh"][str(n)] = m
        print(f"{n:5d} elements: {m['marginal_ms_per_iteration']:8.2f} CPU ms/iteration ({m['derivatives_ms_per_iteration']:.2f} in "
              f"derivatives, the rest IPOPT + MUMPS); transcription built in {m['build_s']:.2f} s")
    lo, hi = out["per_mesh"][str(grid[0])], out["per_mesh"][str(grid[-1])]
    out["ratio_largest_over_smallest"] = hi["marginal_ms_per_iteration"] / lo["marginal_ms_per_iteration"]
    out["mesh_ratio"] = grid[-1] / grid[0]
    print(f"per-iteration time x{out['ratio_largest_over_smallest']:.1f} for x{out['mesh_ratio']:.0f} the mesh")
    degenerate = load_problem(a.problem).declaration.optimization
    inputs = degenerate.model.variables("input")
    if not {"u1", "u2"} <= set(inputs):
        raise SystemExit(f"{a.problem}: no inputs u1, u2 (the thrust direction) to bound")
    for name in ("u1", "u2"):
        degenerate.set_bounds(inputs[name], -1.0, 1.0)
    for label, o in (("as shipped", opt), ("with |u1|, |u2| <= 1", degenerate)):
        key = "shipped" if o is opt else "redundant_bounds"
        out[key] = {"cold": whole(o, grid[-1], False), "coarse_start": whole(o, grid[-1], True)}
        for how, r in out[key].items():
            print(f"{grid[-1]} elements, {label:22s} {how:13s}: {r['status']:10s} {r['iterations']:4d} iterations {r['solve_s']:8.2f} s  "
                  f"objective {r['objective']:.9f}")
    out["load_average"] = os.getloadavg()[0]
    if a.json:
        print(json.dumps(out))


if __name__ == "__main__":
    main()
