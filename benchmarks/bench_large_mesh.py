"""Time per IPOPT iteration on a large mesh, and where it goes (a benchmark, not a test).

Usage: python benchmarks/bench_large_mesh.py [problem.toml] [--json] [--grid 50,400] [--repeat 3] [--marginal-only]

The problem (default ``problems/benchmarks/orbit_raising.toml``, Bryson and Ho's orbit
raising) is transcribed by collocation on each mesh of ``--grid`` and solved by IPOPT.
Measured side by side in one run:

- ``marginal_ms_per_iteration`` (CPU): ``(t(30) - t(10)) / (i(30) - i(10))``, the CPU time of
  a solve limited to 30 iterations minus that of one limited to 10, per iteration between
  them, so that the one-off work (MUMPS's analysis, IPOPT's set-up) is left out: the median
  over ``--repeat`` alternated repeats (default 3), with its spread
  ``marginal_spread`` = (max - min) / median and the repeats themselves; ``t`` is the CPU
  time of this process read around the solve call (``time.process_time``), with CasADi's
  OpenBLAS on one thread, as gtmodel sets it on import (:mod:`gtmodel._blas`; IPOPT's
  ``t_proc_total`` and that BLAS threaded under MUMPS made the figure vary 4.7-73.7 ms between
  runs at 800 elements);
  ``derivatives_ms_per_iteration``: the part of it in evaluating the NLP functions and
  derivatives, its share of the 30-iteration solve's CPU (CasADi's ``t_proc_nlp_*``, nested
  inside that solve on the same clock, over ``t_proc_total``) times the marginal figure, so
  that it never exceeds it (a difference of the parts of two runs, each with its own noise, once
  exceeded the difference of their totals); ``ipopt_mumps_ms_per_iteration`` the rest;
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
import statistics
import time
from pathlib import Path

from gtmodel._blas import casadi_blas_threads
from gtmodel.modeling import CollocationTranscription
from gtmodel.problems import load_problem
from gtmodel.trajectory.model_ocp import COARSE_START_ELEMENTS

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "problems/benchmarks/orbit_raising.toml"


def transcriptions(opt, elements: int) -> tuple[dict, float]:
    """The transcriptions limited to 10 and 30 iterations on ``elements`` elements, and the build time [s] of the first."""
    out, build = {}, 0.0
    for it in (10, 30):
        t = time.perf_counter()
        out[it] = CollocationTranscription(opt, elements=elements, solver_options={"record_time": True, "max_iter": it}, verify=False)
        out[it].solver  # noqa: B018 - its nlpsol, built at first use, is part of the build (not of the first repeat)
        build = build or time.perf_counter() - t
    return out, build


def one_marginal(trs: dict) -> tuple[float, float]:
    """One repeat: the marginal CPU ms per iteration and its derivative part (see the module docstring)."""
    runs = {}
    for it, tr in trs.items():
        c0 = time.process_time()
        r = tr.solve()
        cpu = time.process_time() - c0
        s = r.stats
        share = min(1.0, sum(v for k, v in s.items() if k.startswith("t_proc_nlp_")) / max(s["t_proc_total"], 1e-300))
        runs[it] = (r.iterations, cpu, share)
    (i1, t1, _), (i2, t2, share) = runs[10], runs[30]
    total = 1e3 * (t2 - t1) / max(i2 - i1, 1)
    return total, share * total


def summarise(reps: list[tuple[float, float]], build: float) -> dict:
    """The median of the repeats' marginal figures, their spread and the parts (never above the total)."""
    tot = [t for t, _ in reps]
    med = statistics.median(tot)
    der = statistics.median([d for _, d in reps])
    der = min(der, med)
    return {"marginal_ms_per_iteration": med, "marginal_repeats_ms": tot,
            "marginal_spread": (max(tot) - min(tot)) / med if med > 0 else float("nan"),
            "derivatives_ms_per_iteration": der, "ipopt_mumps_ms_per_iteration": med - der, "build_s": build}


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
    ap.add_argument("--marginal-only", action="store_true", help="only the per-iteration figures (no whole solves)")
    ap.add_argument("--repeat", type=int, default=3, help="repeats of the marginal measurement, alternated over the meshes (default 3)")
    a = ap.parse_args()
    grid = [int(x) for x in a.grid.split(",")]
    print(f"load average {os.getloadavg()[0]:.2f} (2 cores shared); CasADi's OpenBLAS on {casadi_blas_threads()} thread(s)")
    opt = load_problem(a.problem).declaration.optimization
    out: dict = {"problem": Path(a.problem).name, "per_mesh": {}, "casadi_blas_threads": casadi_blas_threads()}
    built = {n: transcriptions(opt, n) for n in grid}
    reps: dict = {n: [] for n in grid}
    for _ in range(max(a.repeat, 1)):  # alternated: each mesh once per round, so that the machine's load falls on all
        for n in grid:
            reps[n].append(one_marginal(built[n][0]))
    for n in grid:
        m = summarise(reps[n], built[n][1])
        out["per_mesh"][str(n)] = m
        print(f"{n:5d} elements: {m['marginal_ms_per_iteration']:8.2f} CPU ms/iteration (median of {len(reps[n])}, spread "
              f"{100 * m['marginal_spread']:.0f} %; {m['derivatives_ms_per_iteration']:.2f} in derivatives, "
              f"{m['ipopt_mumps_ms_per_iteration']:.2f} IPOPT + MUMPS); transcription built in {m['build_s']:.2f} s")
    lo, hi = out["per_mesh"][str(grid[0])], out["per_mesh"][str(grid[-1])]
    out["ratio_largest_over_smallest"] = hi["marginal_ms_per_iteration"] / lo["marginal_ms_per_iteration"]
    out["mesh_ratio"] = grid[-1] / grid[0]
    print(f"per-iteration time x{out['ratio_largest_over_smallest']:.1f} for x{out['mesh_ratio']:.0f} the mesh")
    if a.marginal_only:
        out["load_average"] = os.getloadavg()[0]
        if a.json:
            print(json.dumps(out))
        return
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
