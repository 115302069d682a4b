"""The drive family solved by gtmodel's default path, each member against its independent reference (a benchmark, not a test).

Usage: python benchmarks/bench_drive_family.py [--members N] [--seed S] [--json] [--cached] [--update-cache]
[--no-reference] [--only NAME,...] [--keep DIR] [--method collocation|multiple_shooting] [--reference-start own|gtmodel]

For each member of :func:`gtmodel.modeling.library.drive_family.drive_family` (the first N,
default all 40), in this one process:

- the problem file and model module are written (:func:`~gtmodel.modeling.library.drive_family.write_problem`)
  and solved exactly as ``gtmodel solve FILE --no-plots`` solves them (:func:`gtmodel.problems.run_problem`:
  collocation, verification, refinement, all at their defaults); ``status``, ``verified``
  (``summary.json``'s ``verification.passed``), ``objective``, and ``cpu_s``: the process time
  around the call (load, solve, verification, refinement, writing the folder);
- its reference (``benchmarks/drive_family_reference.py``: the member's ODE written by hand,
  direct multiple shooting in plain CasADi, RK4 steps with the bounds at every step, two
  resolutions) solved in the same run, its CPU time ``reference_cpu_s`` the peer of ``cpu_s``
  (``cpu_ratio = cpu_s / reference_cpu_s``); with ``--cached``, read from the cache
  ``tests/modeling/library/data/drive_family_references.json`` when its parameter hash is the
  member's (``reference_cpu_s`` then as measured when it was cached; ``reference_cached`` true); with
  ``--reference-start gtmodel`` a reference solved in the run starts its coarsest solve from gtmodel's answer
  (:func:`gtmodel_start`; its solves stay its own, the start selects the basin) and says so
  (``reference_start``, the cache's ``start``);
  ``--update-cache`` writes the references solved in the run to the cache; with ``--no-reference`` none is
  solved (a member without a fresh cached one has no relative error: gtmodel's status, verification, CPU and
  bound excess alone);
- ``relative_error``: gtmodel's objective against the reference's (the final time, or the copper loss);
- ``worst_bound_excess``: gtmodel's answer re-simulated densely by SciPy on the hand-written
  ODE under its own input (each element's polynomial, clipped to the voltage bound), the
  largest excess of the current or speed over its bound anywhere, relative (0.01 = 1 %);
  ``end_error`` the re-simulated end state's distance from the target (relative to each state's scale) and
  ``simulated_objective`` the objective of that motion (the final time, or the copper loss integrated along);
- ``passed``: ``optimal``, verified, ``|relative_error| <= 0.5 %`` and ``worst_bound_excess <= 1 %``;
  ``pass_rate`` over the members run. A member whose reference failed (IPOPT's status not
  :data:`REFERENCE_OK`; ``reference_failed``) has no relative error and does not pass:
  ``pass_rate_with_reference`` leaves such members out. For a member that does not pass, the summary's message,
  why refinement stopped and its warnings are printed.

``--method multiple_shooting`` writes ``[transcription] method = "multiple_shooting"`` into each problem file
(direct multiple shooting at its defaults; no mesh refinement): its input is piecewise constant on 50 intervals, so
its objective is O(h) off the reference and not judged; a member then ``passed`` when the run raised nothing, its
message carries no raw CasADi text, and it is not ``optimal`` with a bound exceeded by over 1 % anywhere between
the nodes (the criteria of issue 64 for multiple shooting). Each file declares ``max_cpu_s =`` :data:`SHOOTING_CPU_S`
(the issue's worst CPU time): a shooting solve through an implicit integrator costs about 0.6 CPU-s per iteration on a
stiff member, and one the budget stops ends ``max_iterations`` naming it, which passes the shooting criteria.

With ``--json`` the last line of stdout is ``{"members": [{"name", "status", "verified",
"relative_error", "cpu_s", "worst_bound_excess", ...}], "pass_rate"}``.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this checkout's gtmodel
sys.path.insert(0, str(Path(__file__).resolve().parent))  # drive_family_reference

import drive_family_reference as ref  # noqa: E402

from gtmodel.errors import GtModelError  # noqa: E402
from gtmodel.modeling.library.drive_family import DriveMember, drive_family, write_problem  # noqa: E402
from gtmodel.problems import run_problem  # noqa: E402

#: The pass criteria of issue 64: relative error to the reference and bound excess between nodes.
MAX_RELATIVE_ERROR = 5e-3
MAX_BOUND_EXCESS = 1e-2
#: ``[transcription] max_cpu_s`` of each member's file with ``--method multiple_shooting`` (CPU-s; issue 64's worst).
SHOOTING_CPU_S = 300.0
#: IPOPT's statuses of a reference that counts, and the largest relative difference of its two resolutions: otherwise
#: (a failed solve, or local optima at different resolutions) the member has no relative error and does not pass.
REFERENCE_OK = ref._SUCCEEDED
MAX_REFERENCE_SPREAD = ref.MAX_SPREAD
#: CasADi's own error text, which no message of a multiple-shooting run may carry (issue 64: "one line: the stage, the
#: likely cause, the fix").
RAW_CASADI = re.compile(r"Error in Function|casadi_|\.cpp:\d+|CasADi - ")


def reference_failed(reference: dict) -> bool:
    """True when a reference does not count: IPOPT failed at a resolution, or its two finest differ by over 2 %."""
    return (reference["status"] not in REFERENCE_OK or reference.get("coarse_status", "Solve_Succeeded") not in REFERENCE_OK
            or not abs(reference["spread"]) <= MAX_REFERENCE_SPREAD)


def gtmodel_pieces(solution: Any, vmax: float) -> list[tuple[float, float, np.ndarray]] | None:
    """The voltage of a collocation solution as pieces ``(t0, t1, coefficients in tau)`` (:func:`ref.resimulate`).

    Each element's input polynomial through its collocation points (degree ``points - 1``),
    as the solution holds it; None when the solution holds none.
    """
    col = getattr(solution, "collocation", None)
    dae = getattr(solution, "dae", None)
    if col is None or dae is None or "src.v" not in dae.u_vars:
        return None
    j = dae.u_vars["src.v"].start
    edges, tau = col.breaks(), np.asarray(col.tau_root[1:], dtype=float)
    if col.shooting is not None:  # multiple shooting: the input through its node value and samples, of its degree
        deg = 0 if col.shooting == "constant" else 1
        rows = [np.concatenate([[col.un[k, j]], col.uc[k, :, j]]) for k in range(col.elements)]
        return [(float(edges[k]), float(edges[k + 1]), np.polyfit(np.asarray(col.tau_root, dtype=float), rows[k], deg))
                for k in range(col.elements)]
    deg = tau.size - 1
    return [(float(edges[k]), float(edges[k + 1]), np.polyfit(tau, col.uc[k, :, j], deg) if deg else col.uc[k, :, j].copy())
            for k in range(col.elements)]


#: Where the rest state's motor angle is found in a result when the reduction kept its alias (the EMF's flange).
ALIASES = {"rotor.phi": ("rotor.phi", "emf.phi")}


def gtmodel_start(member: DriveMember, solution: Any, intervals: int = 2 * ref.RESOLUTIONS[-1]) -> dict | None:
    """gtmodel's answer as a start for the reference's coarsest solve (``--reference-start gtmodel``).

    The five states of :meth:`DriveMember.rest_state` at ``intervals + 1`` equal steps over the
    answer's final time and the voltage at the steps' midpoints (:meth:`OptimizationResult.sample`);
    None when the answer holds no polynomials (``sample`` missing or raising a
    :class:`~gtmodel.errors.GtModelError`) or a state is not found: the reference then uses its own starts.
    """
    try:
        tf = float(solution.final_time)
        t = np.linspace(0.0, tf, intervals + 1)
        at, mid = solution.sample(t), solution.sample((t[:-1] + t[1:]) / 2)
    except (AttributeError, TypeError, GtModelError):  # no answer (a failed run) or no polynomials: no start
        return None
    found = {**at["outputs"], **at["algebraics"], **at["states"]}
    rows = []
    for name in member.rest_state(0.0):
        hit = next((found[a] for a in ALIASES.get(name, (name,)) if a in found), None)
        if hit is None:
            return None
        rows.append(np.asarray(hit, dtype=float).reshape(-1))
    return {"X": np.vstack(rows), "U": np.asarray(mid["inputs"]["src.v"], dtype=float).reshape(-1), "final_time": tf}


#: The reference of a member run with ``--no-reference`` and no fresh cache entry: none (no relative error, not passed).
MISSING = {"objective": float("nan"), "spread": float("nan"), "status": "not computed (--no-reference)", "cpu_s": 0.0,
           "worst_bound_excess": float("nan")}


def run_member(member: DriveMember, folder: Path, reference: dict | None, solve_reference: bool = True,
               method: str = "collocation", reference_start: str = "own") -> dict:
    """Solve one member by ``gtmodel solve``'s path and compare it with its reference (solved here if None and
    ``solve_reference``; else :data:`MISSING`); ``method`` the problem file's ``[transcription] method``;
    ``reference_start`` ``"gtmodel"`` starts a reference solved here from gtmodel's answer (:func:`gtmodel_start`)."""
    problem = write_problem(member, folder)
    if method != "collocation":
        problem.write_text(problem.read_text(encoding="utf-8") + f'\n[transcription]\nmethod = "{method}"\n'
                           f"max_cpu_s = {SHOOTING_CPU_S:g}\n", encoding="utf-8")
    cpu = time.process_time()
    try:
        outcome = run_problem(problem, folder / f"{member.name}_out", plots=False)
    except Exception as exc:  # a crash is the benchmark's finding, not its end: the member's row says it, not passed
        return {"name": member.name, "method": method, "status": "raised", "verified": False, "relative_error": None,
                "cpu_s": time.process_time() - cpu, "worst_bound_excess": None, "objective": None,
                "message": f"{type(exc).__name__}: {exc}"[:500], "refinement_stop": "", "warnings": [],
                "reference_objective": float("nan"), "reference_spread": float("nan"), "reference_status": MISSING["status"],
                "reference_cpu_s": 0.0, "reference_cached": False, "cpu_ratio": None, "reference_failed": True,
                "passed": False}
    cpu = time.process_time() - cpu
    if str(outcome.status) == "interrupted":  # Ctrl-C or SIGTERM (gtmodel's handler made it a status): the run ends here
        raise KeyboardInterrupt(outcome.summary.get("message", "interrupted"))
    summary = outcome.summary
    p = member.parameters()
    cached = reference is not None
    if reference is None and solve_reference:
        start = gtmodel_start(member, outcome.solution) if reference_start == "gtmodel" else None
        reference = ref.reference(p, start=start)
        if start is not None:
            reference["start"] = "gtmodel"
    elif reference is None:
        reference = dict(MISSING)
    objective = summary.get("objective")
    row: dict[str, Any] = {
        "name": member.name, "status": str(outcome.status), "verified": bool((summary.get("verification") or {}).get("passed")),
        "relative_error": None, "cpu_s": cpu, "worst_bound_excess": None, "objective": objective,
        "reference_objective": reference["objective"], "reference_spread": reference["spread"],
        "reference_status": reference["status"], "reference_start": reference.get("start", "own"), "reference_cpu_s": reference["cpu_s"], "reference_cached": cached,
        "cpu_ratio": cpu / reference["cpu_s"] if reference["cpu_s"] else None,
        "reference_worst_bound_excess": reference["worst_bound_excess"], "end_error": None,
        "elements": (summary.get("transcription") or {}).get("elements"),
        "message": summary.get("message", ""), "refinement_stop": summary.get("refinement_stop", ""),
        "warnings": summary.get("warnings", []), "reference": reference,
    }
    row["reference_failed"] = reference_failed(reference)
    finer = reference.get("finer_failed")
    observed = reference.get("observed_order", reference.get("order"))
    row["reference_note"] = (f"the reference's observed order {observed:.2f} is pre-asymptotic (below {ref.MIN_ORDER:g}) and its "
                             f"solve at {finer['intervals']} intervals ended {finer['status']}: its two finest extrapolated "
                             f"with order {reference['order']:g}" if finer and observed is not None and reference.get("order") else "")
    if objective is not None and np.isfinite(objective) and not row["reference_failed"]:
        row["relative_error"] = (objective - reference["objective"]) / abs(reference["objective"])
    pieces = gtmodel_pieces(outcome.solution, member.vmax) if outcome.solution is not None else None
    if pieces:
        sim = ref.resimulate(p, pieces)
        row["worst_bound_excess"], row["end_error"] = sim["worst_bound_excess"], sim["end_error"]
        row["simulated_objective"] = sim["objective"]  # the objective of the motion SciPy re-simulated (T, or the copper loss)
    row["method"] = method
    if method != "collocation":  # multiple shooting: no crash, no raw CasADi text, never optimal over a bound by > 1 %
        excess = row["worst_bound_excess"]
        row["passed"] = bool(not RAW_CASADI.search(row["message"]) and not (
            row["status"] == "optimal" and (excess is None or excess > MAX_BOUND_EXCESS)))
        return row
    row["passed"] = bool(row["status"] == "optimal" and row["verified"] and row["relative_error"] is not None
                         and abs(row["relative_error"]) <= MAX_RELATIVE_ERROR and row["worst_bound_excess"] is not None
                         and row["worst_bound_excess"] <= MAX_BOUND_EXCESS)
    return row


def _pct(x: float | None, fmt: str = "{:+.3f}") -> str:
    return "-" if x is None else fmt.format(100 * x) + " %"


def main(argv: list[str] | None = None) -> dict:
    """Run the benchmark; print a line per member, the pass rate, and (``--json``) one JSON object."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--members", type=int, default=40, help="run the first N members (default 40)")
    ap.add_argument("--seed", type=int, default=0, help="the family's seed (default 0)")
    ap.add_argument("--json", action="store_true", help="print one JSON object on the last line")
    ap.add_argument("--cached", action="store_true", help="use the cached references where fresh, not solved in this run")
    ap.add_argument("--keep", type=Path, default=None, help="write the problem files and result folders here (kept)")
    ap.add_argument("--only", default="", help="comma-separated member names (of the first N)")
    ap.add_argument("--update-cache", action="store_true", help="add the references solved in this run to the cache")
    ap.add_argument("--method", choices=("collocation", "multiple_shooting"), default="collocation",
                    help="the problem files' [transcription] method (default collocation)")
    ap.add_argument("--reference-start", choices=("own", "gtmodel"), default="own",
                    help="start a reference solved here from its own guesses (default) or from gtmodel's answer")
    ap.add_argument("--no-reference", action="store_true",
                    help="solve no reference: a member without a fresh cached one gets no relative error (and does not pass)")
    a = ap.parse_args(argv)
    logging.getLogger("gtmodel").setLevel(logging.ERROR)  # gtmodel solve --quiet: the rows say what happened
    cache = ref.load_cache() if a.cached else {}
    print(f"load average {os.getloadavg()[0]:.2f}; drive family seed {a.seed}, {a.members} member(s)", flush=True)
    members = drive_family(max(a.members, 1), a.seed)
    only = {n for n in a.only.split(",") if n}
    unknown = sorted(only - {m.name for m in members})
    if unknown:  # up-front, like argparse's own errors: exit 2, naming the argument and what it expected
        ap.error(f"--only: {', '.join(unknown)} not among the first {len(members)} member(s) of seed {a.seed} "
                 f"(names such as {members[0].name})")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = a.keep or Path(tmp)
        for member in members:
            if only and member.name not in only:
                continue
            row = run_member(member, folder, ref.cached(cache, member.name, member.parameter_hash()), not a.no_reference,
                             a.method, a.reference_start)
            rows.append(row)
            if a.update_cache and not row["reference_cached"] and row["reference_status"] != MISSING["status"]:
                fresh = ref.load_cache()  # re-read: another run may have added members meanwhile
                fresh[member.name] = {"parameter_hash": member.parameter_hash(), **row.pop("reference")}
                ref.CACHE.parent.mkdir(parents=True, exist_ok=True)
                ref.CACHE.write_text(json.dumps(dict(sorted(fresh.items())), indent=1) + "\n")
            row.pop("reference", None)
            ratio = "-" if row["cpu_ratio"] is None else f"{row['cpu_ratio']:.2f}"
            print(f"{row['name']:34s} {row['status']:14s} verified={str(row['verified']):5s} "
                  f"error {_pct(row['relative_error']):>11s} (ref spread {_pct(row['reference_spread'])})  "
                  f"{row['cpu_s']:7.1f} CPU-s (reference {row['reference_cpu_s']:.1f}{', cached' if row['reference_cached'] else ''}"
                  f"{', from gtmodel' if row.get('reference_start') == 'gtmodel' else ''}: "
                  f"x{ratio})  excess {_pct(row['worst_bound_excess'], '{:.3f}'):>9s}  "
                  f"{'PASS' if row['passed'] else 'FAIL'}", flush=True)
            if not row["passed"]:
                why = ["no reference: none cached, none solved (--no-reference)" if row["reference_status"] == MISSING["status"] else
                       f"the reference failed: IPOPT {row['reference_status']}, its resolutions {100 * row['reference_spread']:+.2f} % "
                       "apart" if row["reference_failed"] else "",
                       row["message"], row["refinement_stop"], row.get("reference_note", ""), *row["warnings"]]
                print("    " + "\n    ".join(w for w in why if w), flush=True)
    passed = sum(r["passed"] for r in rows)
    cpu = [r["cpu_s"] for r in rows]
    checked = [r for r in rows if not r["reference_failed"]]
    out = {"members": rows, "pass_rate": passed / len(rows), "seed": a.seed,
           "pass_rate_with_reference": sum(r["passed"] for r in checked) / len(checked) if checked else None,
           "median_cpu_s": statistics.median(cpu), "max_cpu_s": max(cpu),
           "median_cpu_ratio": statistics.median([r["cpu_ratio"] for r in rows if r["cpu_ratio"] is not None] or [float("nan")])}
    print(f"pass rate {passed}/{len(rows)} = {100 * out['pass_rate']:.0f} %; CPU-s median {out['median_cpu_s']:.1f}, "
          f"worst {out['max_cpu_s']:.1f}; median ratio to the reference's CPU {out['median_cpu_ratio']:.2f}")
    if a.json:
        print(json.dumps(out, default=float))
    return out


if __name__ == "__main__":
    main()
