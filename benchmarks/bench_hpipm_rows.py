"""HPIPM on an MPC file's soft rows: how often its QP stops short, and how far its answer is (issue 65).

Why the drive MPC files keep ``solver = "sqpmethod"`` (DAQP) although the ``hpipm`` form's step is the
faster (``benchmarks/bench_mpc.py``). For each file: the MPC on acados' NLP (``bench_mpc.same_nlp``:
one input per period, the rows as declared, no back-off, no disturbance estimate) with ``solver =
"hpipm"``, at the random states of the generated step's codegen check
(:func:`gtmodel.codegen.check.loop_step.loop_samples`: states 10 % of their range off the reference,
a random input held one period before the horizon starts, the warm start the reference's input), and
at the same states without that input and with a tenth of the noise (``near``: the closed loop's
neighbourhood). At each: the step's first real-time iteration
(:func:`gtmodel.control.mpc_hpipm.hpipm_rti`), its QP solved by HPIPM, and the same QP by IPOPT to
1e-12 (the reference, ``plugin="ipopt"``; qpOASES called half of the check's QPs infeasible); HPIPM's own verdict from CasADi's
``error_on_fail`` (``strict``). Reported: the states where HPIPM stopped at its iteration limit or
minimum step (the generated step returns its failure status there), and the first input's distance
from IPOPT's over the input range, where HPIPM converged and where it stopped. States where IPOPT
fails are left out (counted).

Usage::

    python -P benchmarks/bench_hpipm_rows.py codegen/mpc/drive_*_mpc.toml [--samples 100] [--json]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_mpc import same_nlp  # noqa: E402

from gtmodel.codegen.check.loop_step import loop_samples  # noqa: E402
from gtmodel.codegen.loop_step import mpc_step  # noqa: E402
from gtmodel.control.mpc import _sqrt_psd  # noqa: E402  (the MPC's own weight factor: the step's QP exactly)
from gtmodel.control.mpc_hpipm import hpipm_rti  # noqa: E402
from gtmodel.errors import GtModelError  # noqa: E402
from gtmodel.problems.mpc_file import load_mpc_file  # noqa: E402

#: The ``near`` states' noise, a fraction of the check's.
NEAR = 0.1


def _quiet(f, *args):
    """``f(*args)`` with CasADi's solver prints kept off the terminal; None where it raises (a QP not solved)."""
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        try:
            return f(*args)
        except RuntimeError:
            return None


def measure(path: Path, n: int, seed: int = 0) -> dict:
    """The figures of one MPC file (see the module docstring)."""
    setup = load_mpc_file(path)
    c = replace(same_nlp(setup.controller), solver="hpipm")
    if c.constraints is None:
        return {"name": setup.name, "rows": 0}
    step = mpc_step(c, setup.name)
    fast, strict = hpipm_rti(c, _sqrt_psd), hpipm_rti(c, _sqrt_psd, strict=True)
    ref = hpipm_rti(c, _sqrt_psd, plugin="ipopt", strict=True)
    lbu, ubu = np.tile(c.u_lb, c.horizon), np.tile(c.u_ub, c.horizon)
    span = np.where(np.isfinite(c.u_ub - c.u_lb), c.u_ub - c.u_lb, 1.0)
    out = {"name": setup.name, "rows": c.constraint_rows, "penalty": c.constraints.weight, "samples": n}
    for label, held in (("check", True), ("near", False)):
        s = loop_samples(step, n, np.random.default_rng(seed))
        x = s["x"] if held else _nearer(step, n, np.random.default_rng(seed))
        limit, diff_ok, diff_limit, refused = 0, [], [], 0
        for i in range(n):
            t, xi = float(s["t"][i, 0]), np.asarray(x[i], dtype=float)
            if c.delay and held:  # the horizon starts after the random input held one period (the step's delay)
                t, xi = t + c.dt, np.asarray(c.step(xi, s["u_last"][i])).reshape(-1)
            args = (xi, c.w_initial, c.parameters(t, xi), lbu, ubu, np.zeros(c.constraint_rows))
            r = _quiet(ref, *args)
            if r is None:
                refused += 1
                continue
            u = np.asarray(_quiet(fast, *args)[0]).reshape(-1)[: c.nu]
            d = float(np.max(np.abs(u - np.asarray(r[0]).reshape(-1)[: c.nu]) / span))
            stopped = _quiet(strict, *args) is None
            limit += stopped
            (diff_limit if stopped else diff_ok).append(d)
        out[label] = {"hpipm_stopped": limit, "reference_failed": refused,
                      "converged_max_rel_diff": max(diff_ok, default=0.0), "converged_median_rel_diff": float(np.median(diff_ok)) if diff_ok else 0.0,
                      "converged_above_1e-4": int(np.sum(np.array(diff_ok) > 1e-4)),
                      "stopped_max_rel_diff": max(diff_limit, default=0.0)}
    return out


def _nearer(step, n: int, rng: np.random.Generator) -> np.ndarray:
    """The check's states with a tenth of its noise (the same draw as :func:`loop_samples`' states)."""
    xs = step.x_samples
    idx = rng.integers(0, xs.shape[0], n)
    rng.uniform(size=n)  # the times' draw
    scale = 0.1 * (1.0 + np.max(np.abs(xs), axis=0))
    return xs[idx] + NEAR * scale * rng.standard_normal((n, xs.shape[1]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+", type=Path, help="MPC files")
    ap.add_argument("--samples", type=int, default=100, help="random states per file and kind (default 100)")
    ap.add_argument("--json", action="store_true", help="print one JSON object per file")
    args = ap.parse_args()
    if args.samples < 1:
        ap.error(f"--samples: expected a positive number, got {args.samples}")
    for path in args.files:
        try:
            r = measure(path, args.samples)
        except GtModelError as e:
            sys.exit(f"bench_hpipm_rows.py: {e}")
        if args.json:
            print(json.dumps(r), flush=True)
            continue
        if not r["rows"]:
            print(f"{r['name']}: no constraint rows")
            continue
        print(f"{r['name']} ({r['rows']} rows, penalty {r['penalty']:.3g}), first input against IPOPT's over the input range:")
        for label in ("check", "near"):
            f = r[label]
            print(f"  {label:5s}: HPIPM stopped at {f['hpipm_stopped']} of {r['samples']} states (max {f['stopped_max_rel_diff']:.2g} off); "
                  f"converged: median {f['converged_median_rel_diff']:.2g}, max {f['converged_max_rel_diff']:.2g} off, "
                  f"{f['converged_above_1e-4']} beyond 1e-4; IPOPT failed at {f['reference_failed']}", flush=True)


if __name__ == "__main__":
    main()
