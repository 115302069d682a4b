"""Benchmark: generated C against the same CasADi Functions called from Python.

Generates and compiles the C library for a parameter set (default L1) into a temporary
folder, then times per call:

* the C functions ``ik``, ``jacobian``, ``inverse_dynamics`` in a C loop (a small timing
  harness using ``clock_gettime``, linked against the generated shared library),
* the same C functions called through ctypes (for reference: Python call overhead),
* the CasADi Functions they were generated from, called from Python as ``f(T, s)`` with
  NumPy inputs,

and prints the ratio Python/C. Not a test; run as ``python benchmarks/bench_codegen.py``.
"""

from __future__ import annotations

import argparse
import ctypes
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from gtmodel.codegen import compile_shared, find_compiler, generate, load_library
from gtmodel.codegen.specs import RobotModel
from gtmodel.robots.kinematics import configuration_signs

FUNCTIONS = ("ik", "jacobian", "inverse_dynamics")

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "{prefix}.h"

static double now_ns(void)
{{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}}

int main(int argc, char **argv)
{{
    long n = argc > 1 ? atol(argv[1]) : 100000L;
    const double T0[3] = {{{T0}}};
    double T[3], Td[3] = {{{Td}}}, Tdd[3] = {{{Tdd}}}, out[9];
    volatile double sink = 0.0;
    int status = 0;
    long i;
    double t0, t1;
    T[0] = T0[0]; T[1] = T0[1]; T[2] = T0[2];

    /* each loop perturbs the input so nothing can be hoisted out of it */
    t0 = now_ns();
    for (i = 0; i < n; ++i) {{
        T[0] = T0[0] + 1e-9 * (double)(i & 1023);
        status |= {prefix}_ik(T, 0, out);
        sink += out[0];
    }}
    t1 = now_ns();
    printf("ik %.3f\n", (t1 - t0) / (double)n);

    t0 = now_ns();
    for (i = 0; i < n; ++i) {{
        T[0] = T0[0] + 1e-9 * (double)(i & 1023);
        status |= {prefix}_jacobian(T, 0, out);
        sink += out[0];
    }}
    t1 = now_ns();
    printf("jacobian %.3f\n", (t1 - t0) / (double)n);

    t0 = now_ns();
    for (i = 0; i < n; ++i) {{
        T[0] = T0[0] + 1e-9 * (double)(i & 1023);
        status |= {prefix}_inverse_dynamics(T, Td, Tdd, 0, out);
        sink += out[0];
    }}
    t1 = now_ns();
    printf("inverse_dynamics %.3f\n", (t1 - t0) / (double)n);
    printf("status %d\n", status);
    return status != 0;
}}
"""


def _fmt(x: np.ndarray) -> str:
    return ", ".join(repr(float(v)) for v in x)


def time_c_loop(generated, lib_path: Path, build: Path, T: np.ndarray, Td: np.ndarray, Tdd: np.ndarray, n: int) -> dict[str, float]:
    """ns/call of the C functions timed in a C loop (harness linked against the library)."""
    src = build / "bench_harness.c"
    src.write_text(HARNESS.format(prefix=generated.prefix, T0=_fmt(T), Td=_fmt(Td), Tdd=_fmt(Tdd)))
    exe = build / "bench_harness"
    cc = find_compiler()
    subprocess.run(
        [*cc, "-std=c99", "-O2", "-Wall", "-Wextra", "-I", str(generated.out_dir), str(src), "-o", str(exe),
         "-L", str(lib_path.parent), f"-l{generated.prefix}", f"-Wl,-rpath,{lib_path.parent}", "-lm"],
        check=True,
    )
    out = subprocess.run([str(exe), str(n)], check=True, capture_output=True, text=True).stdout
    res = dict(line.split() for line in out.strip().splitlines())
    if int(res.pop("status")) != 0:
        raise SystemExit("C harness: a call returned a non-OK status")
    return {k: float(v) for k, v in res.items()}


def time_ctypes(lib, T: np.ndarray, Td: np.ndarray, Tdd: np.ndarray, n: int) -> dict[str, float]:
    """ns/call of the C functions called through ctypes (pointers prepared once)."""
    dp = ctypes.POINTER(ctypes.c_double)
    bufs = {k: np.ascontiguousarray(v, dtype=float) for k, v in dict(T=T, Td=Td, Tdd=Tdd).items()}
    p = {k: v.ctypes.data_as(dp) for k, v in bufs.items()}
    out = np.zeros(9)
    po = out.ctypes.data_as(dp)
    calls = {
        "ik": (lib["ik"].cfunc, (p["T"], 0, po)),
        "jacobian": (lib["jacobian"].cfunc, (p["T"], 0, po)),
        "inverse_dynamics": (lib["inverse_dynamics"].cfunc, (p["T"], p["Td"], p["Tdd"], 0, po)),
    }
    res = {}
    for name, (f, args) in calls.items():
        assert f(*args) == 0, name
        t0 = time.perf_counter()
        for _ in range(n):
            f(*args)
        res[name] = (time.perf_counter() - t0) / n * 1e9
    return res


def time_casadi(model: RobotModel, T: np.ndarray, Td: np.ndarray, Tdd: np.ndarray, n: int) -> dict[str, float]:
    """ns/call of the CasADi Functions called from Python with NumPy inputs."""
    s = configuration_signs(0)
    calls = {
        "ik": (model.kinematics.ik_function, (T, s)),
        "jacobian": (model.kinematics.jacobian_function, (T, s)),
        "inverse_dynamics": (model.dynamics.inverse_dynamics_function, (T, Td, Tdd, s)),
    }
    res = {}
    for name, (f, args) in calls.items():
        f(*args)  # warm-up
        t0 = time.perf_counter()
        for _ in range(n):
            f(*args)
        res[name] = (time.perf_counter() - t0) / n * 1e9
    return res


def main(argv: list[str] | None = None) -> None:
    """Run the benchmark and print a table (ns/call, ratios)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robot", default="L1")
    ap.add_argument("--c-calls", type=int, default=100_000, help="calls per function in the C loop")
    ap.add_argument("--ctypes-calls", type=int, default=20_000, help="calls per function through ctypes")
    ap.add_argument("--python-calls", type=int, default=2_000, help="calls per CasADi Function from Python")
    args = ap.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="gt_bench_") as tmp:
        gen = generate(args.robot, Path(tmp) / "src", functions=("ik", "fk", "jacobian", "inverse_dynamics"))
        lib_path = compile_shared(gen, Path(tmp) / "build")
        lib = load_library(gen, lib_path)
        model = RobotModel(gen.parameters, gen.friction)
        rng = np.random.default_rng(1)
        grid = model.kinematics.workspace_grid(0.1)
        T = grid[len(grid) // 2]
        Td = rng.uniform(-0.5, 0.5, 3)
        Tdd = rng.uniform(-2.0, 2.0, 3)

        c_loop = time_c_loop(gen, lib_path, Path(tmp) / "build", T, Td, Tdd, args.c_calls)
        c_types = time_ctypes(lib, T, Td, Tdd, args.ctypes_calls)
        py = time_casadi(model, T, Td, Tdd, args.python_calls)

    print(f"gtmodel codegen benchmark: robot {args.robot}, pose T = {np.round(T, 4).tolist()} m, configuration 0")
    print(f"  C loop: {args.c_calls} calls, ctypes: {args.ctypes_calls}, CasADi from Python: {args.python_calls}")
    hdr = f"{'function':<18}{'C loop ns':>11}{'ctypes ns':>11}{'CasADi/Py ns':>14}{'Py/C':>9}{'Py/ctypes':>11}"
    print(hdr)
    print("-" * len(hdr))
    for name in FUNCTIONS:
        c, ct, p = c_loop[name], c_types[name], py[name]
        print(f"{name:<18}{c:>11.1f}{ct:>11.1f}{p:>14.1f}{p / c:>9.0f}{p / ct:>11.1f}")
    print("Py/C: wall time per call of the CasADi Function called from Python over the generated C in a C loop.")


if __name__ == "__main__":
    main()
