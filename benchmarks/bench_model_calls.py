"""Benchmark: calls of the L1 model Functions from Python (issue 17, item 5).

For each model Function of L1 (``ik``, ``fk``, ``jacobian``, ``inverse_dynamics``,
``forward_dynamics``) on one valid sample, in one run on the same inputs:

* ``call_us``: the CasADi Function called with NumPy arrays (``f(T, ...)``, the old path of
  every single-sample call: each argument and result converted to/from ``casadi.DM``),
* ``buffer_us`` / ``buffer_compiled_us``: one sample through ``Function.buffer`` with
  preallocated NumPy arrays (:class:`gtmodel.robots.mapped.MappedFunction`), interpreted and
  through the Function's generated C loaded as ``casadi.external`` (``compiled=True``),
* ``api_us`` / ``api_compiled_us``: the public method (``GantryTau3Dynamics.inverse_dynamics``
  etc., argument checks included), ``compiled=False`` / ``True``,
* ``batch_us_per_sample`` / ``batch_compiled_us_per_sample``: the public method on N = 1000
  samples (``Function.map``), per sample,

and the ratios ``call_us / buffer_compiled_us`` and ``api_us / api_compiled_us``. Times are
the minimum over 5 repeats (a shared machine). Every compiled result is checked equal to the
interpreted one to 1e-12 before timing. Run: ``python benchmarks/bench_model_calls.py``
(``--json``: one JSON object on the last line of stdout; ``--n N``: batch size).
"""

from __future__ import annotations

import argparse
import json
import sys
import timeit
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gtmodel.robots.dynamics import GantryTau3Dynamics  # noqa: E402
from gtmodel.robots.mapped import MappedFunction  # noqa: E402


def _time(fn, number: int) -> float:
    """Minimum over 5 repeats of the time per call [us]."""
    return min(timeit.repeat(fn, number=number, repeat=5)) / number * 1e6


def _cases(d: GantryTau3Dynamics, n: int, rng: np.random.Generator) -> dict:
    """Per Function: (Function, one sample's column inputs, public method of N samples, its arguments)."""
    G = d.kinematics.workspace_grid(0.1)
    T = G[rng.choice(len(G), n)]
    Td, Tdd = rng.normal(0, 0.5, (n, 3)), rng.normal(0, 3.0, (n, 3))
    s = np.ones((3, 1)) * -1.0  # configuration 0
    k, dd = d.kinematics, d
    q = k.ik(T)
    tau = d.inverse_dynamics(T, Td, Tdd)
    col = lambda a: a[0][:, None]  # noqa: E731
    return {
        "ik": (k.ik_function, [col(T), s], lambda c: c.kinematics.ik, (T,)),
        "fk": (k.fk_function, [col(q), np.ones((1, 1))], lambda c: c.kinematics.fk, (q,)),
        "jacobian": (k.jacobian_function, [col(T), s], lambda c: c.kinematics.jacobian, (T,)),
        "inverse_dynamics": (dd.inverse_dynamics_function, [col(T), col(Td), col(Tdd), s], lambda c: c.inverse_dynamics, (T, Td, Tdd)),
        "forward_dynamics": (dd.forward_dynamics_function, [col(T), col(Td), col(tau), s], lambda c: c.forward_dynamics, (T, Td, tau)),
    }


def main(argv: list[str] | None = None) -> dict:
    """Run the benchmark; print a table (or, with ``--json``, one JSON object) and return the figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object on the last line")
    ap.add_argument("--n", type=int, default=1000, help="batch size (default 1000)")
    a = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    d, dc = GantryTau3Dynamics("L1"), GantryTau3Dynamics("L1", compiled=True)
    results: dict = {}
    for name, (f, one, method, batch) in _cases(d, a.n, rng).items():
        mi, mc = MappedFunction(f), MappedFunction(f, compiled=True)
        single = [x[0] for x in batch]
        ref, got = method(d)(*batch), method(dc)(*batch)
        assert np.allclose(ref, got, rtol=1e-12, atol=1e-12), name
        assert all(np.allclose(x, y, rtol=1e-12, atol=1e-12) for x, y in zip(mi(*one), mc(*one))), name
        r = {
            "call_us": _time(lambda: f(*one), 2000),
            "buffer_us": _time(lambda: mi(*one), 5000),
            "buffer_compiled_us": _time(lambda: mc(*one), 5000),
            "api_us": _time(lambda: method(d)(*single), 2000),
            "api_compiled_us": _time(lambda: method(dc)(*single), 2000),
            "batch_us_per_sample": _time(lambda: method(d)(*batch), 5) / a.n,
            "batch_compiled_us_per_sample": _time(lambda: method(dc)(*batch), 5) / a.n,
            "how": mc.how,
        }
        r["call_to_buffer_compiled"] = r["call_us"] / r["buffer_compiled_us"]
        r["api_to_api_compiled"] = r["api_us"] / r["api_compiled_us"]
        r["batch_to_batch_compiled"] = r["batch_us_per_sample"] / r["batch_compiled_us_per_sample"]
        results[name] = r
    idyn = results["inverse_dynamics"]
    out = {
        "robot": "L1",
        "n_batch": a.n,
        "inverse_dynamics_call_us": idyn["call_us"],
        "inverse_dynamics_buffer_compiled_us": idyn["buffer_compiled_us"],
        "inverse_dynamics_api_us": idyn["api_us"],
        "inverse_dynamics_api_compiled_us": idyn["api_compiled_us"],
        "inverse_dynamics_batch_compiled_us_per_sample": idyn["batch_compiled_us_per_sample"],
        "functions": results,
    }
    if a.json:
        print(json.dumps(out))
    else:
        keys = [k for k in next(iter(results.values())) if k != "how"]
        print(f"L1 model calls from Python [us; batch N = {a.n}] (min of 5 repeats)")
        print(f"{'function':18s}" + "".join(f"{k[:22]:>24s}" for k in keys))
        for name, r in results.items():
            print(f"{name:18s}" + "".join(f"{r[k]:24.3f}" for k in keys))
    return out


if __name__ == "__main__":
    main()
