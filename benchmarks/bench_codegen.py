"""Benchmark: generated C against the same model evaluated from Python, with instruction counts.

Generates and compiles the C libraries of L1 (3-link) and F1 into a temporary folder and
prints, per function and for the per-cycle bundles of the 4 ms loop,

* ns/call of the generated C in a C loop (``gtmodel.codegen.check.time_functions``),
* ns/call of the same CasADi Function called from Python (closed-form functions), or of
  the Python model's method (Newton functions: ``F1Closure.ik``/``fk``, which iterate the
  same CasADi step Functions), on the same input,
* the ratio Python/C,
* instructions per call counted by valgrind's callgrind (if valgrind is on PATH).

Controller of the 4 ms loop (Dressler (2012), ch. 7): ns per step of the generated
``kalman_step`` (state fed back), ``kalman_update`` (state struct) and ``ilc_correction``
over a 400-cycle run, next to the same CasADi Function called from Python and a NumPy
equivalent (Kalman: ``Mx @ x + My @ y`` with the Function's Jacobians, exact for the linear
step; ILC: ``table[k]``). The controller comes from ``--controller FILE`` (a controller file,
:mod:`gtmodel.codegen.controller_file`) or, by default, gtmodel.estimation's L1 Kalman step (x, y) and a 400-cycle learned table.

Filters of the laser tracker + IMU fusion (Cvitanic (2021), ch. 4; aim: EKF step < 20 us,
under 2 % of the 1 ms sample): ns per step of the generated ``kf_step`` (3-axis, nx 9) and
``ekf_step`` (19-D) and of their ``_update`` (state struct) over a 3000-step measurement
record, next to the same CasADi step Function called from Python (one call per step) and
per step of its ``mapaccum`` over the record (the Python filters' ``run``). The filters come
from ``--controller FILE`` when it holds them, else gtmodel.estimation's ``KalmanFilter`` /
``ExtendedKalmanFilter`` at 1 kHz. ``--json`` keys ``kf_step_ns``, ``ekf_step_ns``,
``python_kf_step_ns``, ``python_ekf_step_ns`` (and the details under ``filters``).
``python benchmarks/bench_codegen.py --robots "" --no-controller`` runs the filter rows alone.

Online re-timing (issue 17; aim: at most 500 us for N = 500, under 1/8 of the 4 ms cycle):
``gt_L1_retime`` (generated with ``retime_n_max``) on the shipped path problem
(``problems/l1_path_constrained.toml``: the L1 straight line, |tau_i| <= 450 N, viscous
friction, 500 grid points), median time per call through ctypes with the arguments converted
once (the C time plus a few us of call overhead), next to the Python solver on the same case in the same run
(``PathConstrainedProblem.solve``: the coefficient evaluation and the two passes, the
problem built once), and the largest relative difference of the two ``s_dot``. ``--json``
keys ``retime_us``, ``retime_python_us``, ``retime_python_passes_us`` (the passes alone),
``retime_max_rel_diff``, ``retime_n`` (details under ``retime``); ``--retime-n N`` sets the grid,
``--no-retime`` skips it.

Bundles: L1 = ik + jacobian + inverse_dynamics (aim < 1 us), F1 = ik + fk, both
warm-started from the previous sample (aim < 10 us); the F1 default starts (continuation
from the home pose) are listed separately. Run: ``python benchmarks/bench_codegen.py`` (``--json``: one JSON object on the last line of
stdout, the tables on stderr; ``--robots ""``: the controller only)
(``--cflags "-O3 -march=native"``: optional extra flags for the libraries, to see what
the target's instruction set gains; the generated code needs only ``-std=c99 -O2``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.signal

import casadi as ca

from gtmodel.codegen import Controller, check_controller, compile_shared, find_compiler, generate, load_controller, load_library
from gtmodel.codegen.check import sample_inputs, time_functions, timed_rows
from gtmodel.codegen.check.robot import _c_call
from gtmodel.codegen.check.controller import ILC_MARGIN, run_inputs
from gtmodel.codegen.check.filter import FILTER_CYCLES, TIMING_BLOCK, filter_record, python_filter_run, time_filters
from gtmodel.codegen.retime import RetimeFunction
from gtmodel.problems import load_problem
from gtmodel.trajectory import PathConstrainedProblem
from gtmodel.estimation import StationaryKalman, ilc_correction_function
from gtmodel.estimation.filters.end_effector import EndEffectorModel
from gtmodel.estimation.filters.kalman import ExtendedKalmanFilter, KalmanFilter
from gtmodel.robots.kinematic_expressions import configuration_signs

PATH_PROBLEM = Path(__file__).resolve().parents[1] / "problems" / "l1_path_constrained.toml"
BUNDLES = {"L1": ("ik", "jacobian", "inverse_dynamics"), "F1": ("ik", "fk")}

COUNTER = r"""
#include <stdlib.h>
#include <string.h>
#include "{header}"
int main(int argc, char **argv)
{{
    long i, n = argc > 2 ? atol(argv[2]) : 0;
    int status = 0;
    const char *which = argc > 1 ? argv[1] : "";
{blocks}
    return status != 0;
}}
"""


def _count_block(gen, spec, label: str, args) -> str:
    decl, call = _c_call(gen, spec, args)
    return "\n".join([f'    if (strcmp(which, "{label}") == 0) {{', *decl,
                      f"        for (i = 0; i < n; ++i) status |= {call};", "    }"])


def callgrind_counts(gen, lib: Path, rows, build: Path, calls: int = 200) -> dict[str, float]:
    """Instructions per call from callgrind: (Ir with ``calls`` calls - Ir with none) / calls."""
    if shutil.which("valgrind") is None:
        return {}
    labels = {label: f"f{k}" for k, label in enumerate(rows)}
    src = build / "bench_count.c"
    src.write_text(COUNTER.format(header=gen.header.name, blocks="\n".join(
        _count_block(gen, spec, labels[label], args) for label, (spec, args) in rows.items())))
    exe = build / "bench_count"
    subprocess.run([*find_compiler(), "-std=c99", "-O2", "-I", str(gen.out_dir), str(src), "-o", str(exe), "-L", str(lib.parent),
                    f"-l{gen.prefix}", f"-Wl,-rpath,{lib.parent}", "-lm"], check=True)
    out = {}
    for label, key in labels.items():
        ir = []
        for n in (0, calls):
            cg = build / f"cg_{key}_{n}.out"
            subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}", str(exe), key, str(n)],
                           check=True, capture_output=True)
            text = cg.read_text()
            line = next(l for l in text.splitlines() if l.startswith("summary:") or l.startswith("totals:"))
            ir.append(int(line.split()[1]))
        out[label] = (ir[1] - ir[0]) / calls
    return out


def _py_time(f, args, n: int) -> float:
    f(*args)
    t0 = time.perf_counter()
    for _ in range(n):
        f(*args)
    return (time.perf_counter() - t0) / n * 1e9


def python_times(gen, rows, n: int) -> dict[str, float]:
    """ns/call from Python: the CasADi Function (closed form) or the model's Newton method."""
    model = gen.model()
    out = {}
    for label, (spec, args) in rows.items():
        a = dict(zip([x.name for x in spec.args], args))
        if spec.newton is None:
            f = spec.build(model)
            cas = []
            for x in spec.args:
                v = a[x.name]
                cas.append(configuration_signs(int(v)) if x.kind == "configuration" else (float(v) if x.kind == "solution" else np.asarray(v)))
            out[label] = _py_time(f, cas, n)
        elif gen.kind == "f1" and spec.name == "ik":
            R = np.reshape(a["R"], (3, 3))
            out[label] = _py_time(lambda: model.closure.ik(a["T"], R, a["q0"]), (), max(n // 20, 20))
        elif gen.kind == "f1" and spec.name == "fk":
            R0 = None if a["R0"] is None else np.reshape(a["R0"], (3, 3))
            out[label] = _py_time(lambda: model.closure.fk(a["q"], a["T0"], R0), (), max(n // 20, 20))
    return out


def default_controller() -> Controller:
    """gtmodel.estimation's controller: the L1 Kalman step (x, y) and a 400-cycle learned table (3 actuators)."""
    n = np.arange(400)
    table = 20e-6 * np.sin(2 * np.pi * n / 160.0)[:, None] * scipy.signal.windows.tukey(400, 0.5)[:, None] * np.ones(3)
    return Controller(kalman_step=StationaryKalman().step_function(), ilc_correction=ilc_correction_function(table), ilc_table=table)


def controller_rows(controller: Controller, root: Path, n: int, cflags: str) -> dict[str, dict[str, float]]:
    """ns per step: generated C (C loop over the run), CasADi from Python, NumPy equivalent."""
    gen = generate("L1", root / "src", functions=("ik",), controller=controller)
    lib = load_library(gen, compile_shared(gen, root / "build", extra_flags=cflags.split()))
    report = check_controller(gen, library=lib, build_dir=root / "build", timing=True)
    if not report.passed:
        raise SystemExit("controller check failed:\n" + "\n".join(report.summary_lines()))
    c_ns = {f.name: f.ns_per_call for f in report.functions}
    inp = run_inputs(controller, 400, 0)
    rows: dict[str, dict[str, float]] = {}
    if controller.kalman_step is not None:
        f = controller.kalman_step
        x0, y0 = inp["x0"], inp["y"][0]
        xs, ys = ca.SX.sym("x", x0.size), ca.SX.sym("y", y0.size)
        fe = f if f.is_a("SXFunction") else f.expand()
        xn, zh = fe(xs, ys)
        linear = ca.Function("kalman_linear", [xs, ys], [ca.jacobian(xn, xs), ca.jacobian(xn, ys), ca.jacobian(zh, xs)])
        Mx, My, H = (np.asarray(v) for v in linear(x0, y0))  # the step is linear: exact
        py = _py_time(f, (x0, y0), n)
        npy = _py_time(lambda x, y: (Mx @ x + My @ y, H @ x), (x0, y0), n)
        for name in ("kalman_step", "kalman_update"):
            rows[name] = {"c_ns": c_ns[name], "casadi_python_ns": py, "numpy_ns": npy}
    if controller.ilc_correction is not None:
        table, zero = controller.ilc_table, np.zeros(controller.ilc_d)
        py = _py_time(controller.ilc_correction, (17.0,), n)
        npy = _py_time(lambda k: table[k] if 0 <= k < len(table) else zero, (17,), n)
        rows["ilc_correction"] = {"c_ns": c_ns["ilc_correction"], "casadi_python_ns": py, "numpy_ns": npy}
    return rows


def default_filters(dt: float = 0.001) -> Controller:
    """gtmodel.estimation's KF (3-axis) and EKF (19-D) at 1 kHz: white jerk 5 m/s^3 (5 rad/s^3), Table 7-like noise."""
    steps = {}
    for name, rotation, cls in (("kf_step", False, KalmanFilter), ("ekf_step", True, ExtendedKalmanFilter)):
        m = EndEffectorModel(dt, rotation=rotation)
        R = m.measurement_noise(6.4e-6, 0.012, 2e-5, 1e-3) if rotation else m.measurement_noise(6.4e-6, 0.012)
        x0 = np.zeros(m.nx)
        if rotation:
            x0[9] = 1.0  # the identity quaternion
        steps[name] = cls(m, m.process_noise(5.0, 5.0 if rotation else 0.0), R, x0, 1e-4 * np.eye(m.nx)).step_function()
    return Controller(dt=dt, **steps)


def filter_rows(controller: Controller, root: Path, n: int, cflags: str) -> dict[str, dict[str, float]]:
    """ns per step of the filters: generated C (step and update over the record), the Function from Python, its mapaccum."""
    filters = Controller(dt=controller.dt, kf_step=controller.kf_step, ekf_step=controller.ekf_step)
    gen = generate("L1", root / "src", functions=(), prefix="gt_fusion", controller=filters)
    lib = load_library(gen, compile_shared(gen, root / "build", extra_flags=cflags.split()))
    report = check_controller(gen, library=lib, build_dir=root / "build")
    if not report.passed:
        raise SystemExit("filter check failed:\n" + "\n".join(report.summary_lines()))
    records = {name: filter_record(filters, name, FILTER_CYCLES) for name in filters.filter_sizes}
    times = time_filters(gen, lib.path, records, root / "build", budget_s=0.3)
    rows: dict[str, dict[str, float]] = {}
    for name in filters.filter_sizes:
        f = getattr(filters, name)
        rec = records[name]
        run = python_filter_run(f, rec["z"], rec["x0"], rec["P0"])
        k = FILTER_CYCLES // 2
        py = _py_time(f, (run.x[k], run.P[k], rec["z"][k]), max(n // 4, 50))
        acc = f.mapaccum("run", FILTER_CYCLES, 2)
        t0 = time.perf_counter()
        acc(rec["x0"], rec["P0"], rec["z"].T)
        mapaccum_ns = (time.perf_counter() - t0) / FILTER_CYCLES * 1e9
        rows[name] = {"c_ns": times[f"{name} best"], "c_mean_ns": times[name], "c_update_ns": times[f"{name[:-5]}_update best"],
                      "c_update_mean_ns": times[f"{name[:-5]}_update"], "casadi_python_ns": py,
                      "casadi_mapaccum_ns": mapaccum_ns, "max_abs_diff": max(c.max_abs_diff for c in report.functions if c.name.startswith(name[:-5]))}
    return rows


def retime_row(root: Path, n: int, cflags: str, repeats: int = 200) -> dict[str, float]:
    """gt_L1_retime against the Python path solver on the shipped path problem with ``n`` grid points."""
    d = load_problem(PATH_PROBLEM).declaration
    problem = PathConstrainedProblem(d.path, d.constraints, d.robot, d.configuration, d.viscous_friction)
    gen = generate("L1", root / "src", functions=("ik",), retime_n_max=max(n, 1000))
    retime = RetimeFunction(load_library(gen, compile_shared(gen, root / "build", extra_flags=cflags.split())))
    gp = problem.gridded(n)
    S = gp.samples
    limits = retime.limits({"force_limit": d.constraints.force_limit}, viscous_friction=d.viscous_friction)
    args = (gp.s, S["T"], S["dT"], S["ddT"], limits)
    c = retime(*args, rest=gp.rest)
    py = problem.solve(n)
    call = retime.prepared(*args)
    c_us = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        call()
        c_us.append((time.perf_counter() - t0) * 1e6)
    py_us, passes_us = [], []
    for _ in range(max(repeats // 20, 5)):
        t0 = time.perf_counter()
        sol = problem.solve(n)
        py_us.append((time.perf_counter() - t0) * 1e6)
        passes_us.append(sol.solve_time * 1e6)
    scale = np.where(py.s_dot != 0, np.abs(py.s_dot), 1.0)
    return {
        "n": n, "c_us": float(np.median(c_us)), "c_best_us": float(np.min(c_us)), "python_us": float(np.median(py_us)),
        "python_passes_us": float(np.median(passes_us)), "max_rel_diff": float(np.max(np.abs(c.s_dot - py.s_dot) / scale)),
        "c_status": c.status.value, "python_status": py.status.value, "final_time_s": c.final_time, "python_final_time_s": py.final_time,
    }


def main(argv: list[str] | None = None) -> None:
    """Run the benchmark and print one table per robot and one for the controller (or JSON)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", default="L1,F1", help="comma-separated robots (default L1,F1)")
    ap.add_argument("--python-calls", type=int, default=2000, help="calls per function from Python")
    ap.add_argument("--no-callgrind", action="store_true", help="skip the instruction counts")
    ap.add_argument("--cflags", default="", help='extra compiler flags for the libraries, e.g. "-O3 -march=native" '
                    "(optional; the generated code needs only -std=c99 -O2)")
    ap.add_argument("--newton-check-every", type=int, default=None,
                    help="test Newton convergence every k steps (default: the declaration's; F1: 4 like Python)")
    ap.add_argument("--controller", type=Path, default=None, metavar="FILE",
                    help="controller file for the controller rows (default: gtmodel.estimation's L1 Kalman step and a 400-cycle table)")
    ap.add_argument("--no-controller", action="store_true", help="skip the controller rows (Kalman step, ILC)")
    ap.add_argument("--no-filters", action="store_true", help="skip the KF/EKF rows of the tracker + IMU fusion")
    ap.add_argument("--no-retime", action="store_true", help="skip the online re-timing row (gt_L1_retime vs the Python path solver)")
    ap.add_argument("--retime-n", type=int, default=500, help="grid points of the re-timing row (default 500)")
    ap.add_argument("--json", action="store_true", help="print one JSON object (ns per call per function) on the last line instead of tables")
    args = ap.parse_args(argv)
    doc: dict = {"robots": {}, "controller": {}, "filters": {}}
    out = sys.stdout
    if args.json:
        sys.stdout = sys.stderr  # the tables go to stderr, the JSON document to stdout
    with tempfile.TemporaryDirectory(prefix="gt_bench_") as tmp:
        for robot in [r for r in args.robots.split(",") if r]:
            root = Path(tmp) / robot
            gen = generate(robot, root / "src", newton_check_every=args.newton_check_every)
            lib = compile_shared(gen, root / "build", extra_flags=args.cflags.split())
            load_library(gen, lib)
            data = sample_inputs(gen, 50, seed=3)
            rows = timed_rows(gen, data)
            c = time_functions(gen, lib, data, root / "build", budget_s=0.2)
            py = python_times(gen, rows, args.python_calls)
            ir = {} if args.no_callgrind else callgrind_counts(gen, lib, rows, root / "build")
            print(f"\n{robot}: {gen.version}" + (f"; extra flags {args.cflags}" if args.cflags else ""))
            hdr = f"{'function':<38}{'C ns/call':>11}{'Python ns/call':>16}{'Py/C':>8}{'instr/call':>12}"
            print(hdr)
            print("-" * len(hdr))
            doc["robots"][robot] = {label: {"c_ns": c[label], "python_ns": py[label], "instructions": ir.get(label)} for label in rows}
            for label in rows:
                ins = f"{ir[label]:>12.0f}" if label in ir else f"{'-':>12}"
                print(f"{label:<38}{c[label]:>11.0f}{py[label]:>16.0f}{py[label] / c[label]:>8.0f}{ins}")
            bundle = BUNDLES.get(robot, ())
            if bundle and all(b in c for b in bundle):
                tc, tp = sum(c[b] for b in bundle), sum(py[b] for b in bundle)
                ins = f"{sum(ir[b] for b in bundle):>12.0f}" if all(b in ir for b in bundle) else f"{'-':>12}"
                aim = 1000 if robot == "L1" else 10000
                print(f"{'bundle ' + '+'.join(bundle):<38}{tc:>11.0f}{tp:>16.0f}{tp / tc:>8.0f}{ins}   (aim < {aim} ns: "
                      f"{'met' if tc < aim else 'NOT met'})")
        loaded = load_controller(args.controller) if args.controller else None
        if not args.no_controller and (loaded is None or loaded.kalman_step is not None or loaded.ilc_correction is not None):
            controller = loaded if loaded is not None and (loaded.kalman_step or loaded.ilc_correction) else default_controller()
            controller = Controller(kalman_step=controller.kalman_step, ilc_correction=controller.ilc_correction,
                                    ilc_table=controller.ilc_table, dt=controller.dt)
            rows = controller_rows(controller, Path(tmp) / "controller", args.python_calls, args.cflags)
            doc["controller"] = rows
            print(f"\ncontroller ({args.controller or 'gtmodel.estimation, L1 defaults'}): ns per step over a 400-cycle run "
                  f"(ILC: k = -{ILC_MARGIN} .. N + {ILC_MARGIN - 1})")
            hdr = f"{'function':<20}{'C ns':>10}{'CasADi/Python ns':>18}{'NumPy ns':>10}{'CasADi/C':>10}{'NumPy/C':>9}"
            print(hdr)
            print("-" * len(hdr))
            for name, r in rows.items():
                print(f"{name:<20}{r['c_ns']:>10.0f}{r['casadi_python_ns']:>18.0f}{r['numpy_ns']:>10.0f}"
                      f"{r['casadi_python_ns'] / r['c_ns']:>10.0f}{r['numpy_ns'] / r['c_ns']:>9.0f}")
        if not args.no_filters:
            filters = loaded if loaded is not None and loaded.filter_sizes else default_filters()
            rows = filter_rows(filters, Path(tmp) / "filters", args.python_calls, args.cflags)
            doc["filters"] = rows
            for name, r in rows.items():
                doc[f"{name}_ns"], doc[f"python_{name}_ns"] = r["c_ns"], r["casadi_python_ns"]
            print(f"\nfilters of the tracker + IMU fusion ({args.controller if loaded is not None and loaded.filter_sizes else 'gtmodel.estimation, 1 kHz'}): "
                  f"ns per step over a {FILTER_CYCLES}-step record" + (f"; extra flags {args.cflags}" if args.cflags else "")
                  + f"; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
            hdr = (f"{'function':<12}{'C ns':>9}{'C mean':>9}{'update':>9}{'upd mean':>10}{'CasADi/Python ns':>18}{'mapaccum ns':>13}"
                   f"{'Python/C':>10}{'max |C - Py|':>14}")
            print(hdr)
            print("-" * len(hdr))
            for name, r in rows.items():
                print(f"{name:<12}{r['c_ns']:>9.0f}{r['c_mean_ns']:>9.0f}{r['c_update_ns']:>9.0f}{r['c_update_mean_ns']:>10.0f}"
                      f"{r['casadi_python_ns']:>18.0f}{r['casadi_mapaccum_ns']:>13.0f}{r['casadi_python_ns'] / r['c_ns']:>10.0f}{r['max_abs_diff']:>14.1e}")
            print(f"C ns: the fastest block of {TIMING_BLOCK} consecutive steps (the step's own time); C mean: over the whole loop "
                  "(includes the preemptions of a loaded machine); update: the state-struct function.")
            if "ekf_step" in rows:
                c = rows["ekf_step"]["c_ns"]
                print(f"EKF step {c / 1000:.1f} us = {c / 1e4:.2f} % of the 1 ms sample (aim < 20 us: {'met' if c < 20000 else 'NOT met'})")
        if not args.no_retime:
            r = retime_row(Path(tmp) / "retime", args.retime_n, args.cflags)
            doc["retime"] = r
            doc.update(retime_us=r["c_us"], retime_python_us=r["python_us"], retime_python_passes_us=r["python_passes_us"],
                       retime_max_rel_diff=r["max_rel_diff"], retime_n=r["n"])
            print(f"\nonline re-timing, {PATH_PROBLEM.name}, N = {r['n']} grid points (load average {os.getloadavg()[0]:.1f} "
                  f"on {os.cpu_count()} CPUs)")
            print(f"  gt_L1_retime (ctypes call)   {r['c_us']:>10.0f} us median, {r['c_best_us']:.0f} us best   "
                  f"(aim <= 500 us: {'met' if r['c_us'] <= 500 else 'NOT met'})")
            print(f"  Python PathConstrainedProblem.solve {r['python_us']:>7.0f} us median (passes alone {r['python_passes_us']:.0f} us); "
                  f"Python/C {r['python_us'] / r['c_us']:.0f}")
            print(f"  max |s_dot C - Python| / |s_dot| = {r['max_rel_diff']:.1e}; status C {r['c_status']}, Python {r['python_status']}; "
                  f"final time {r['final_time_s']:.6f} s")
    print("\nC: mean over a C loop of one input (warm start = a nearby sample); Python: the CasADi Function called "
          "with NumPy inputs, or for the F1 Newton functions the Python model's method (same step Functions).")
    if args.json:
        sys.stdout = out
        print(json.dumps(doc))


if __name__ == "__main__":
    main()
