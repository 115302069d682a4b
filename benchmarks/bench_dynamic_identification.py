"""Dynamic identification speed: gtmodel's identify_dynamics vs a plain NumPy lstsq, 10^5 samples.

Usage: python benchmarks/bench_dynamic_identification.py [--samples N] [--repeat R] [--peer-samples K]

Problem: the L1 inverse dynamics of Dressler (2012), eqs. 6.7-6.8, Table 6.3 model 2
(10 parameters), on a simulated 4 ms servo log of ``N`` samples (default 10^5 = 400 s)
along a fixed Fourier excitation, 5 N force noise, positions filtered at 10 Hz.

Printed (median of ``--repeat`` runs, machines are noisy):

1. how the regressor is evaluated: the CasADi graph ``Y = d tau / d theta`` compiled to
   C once and cached (``~/.cache/gtmodel/regressor``; the first run of a model pays the
   compilation), or the CasADi interpreter when no C compiler is found
   (``GTMODEL_COMPILE=0`` forces it);
2. the identification on N samples split into preprocessing (:func:`preprocess_log`:
   zero-phase filter and differentiation), regressor evaluation and least squares +
   statistics (:func:`identify_dynamics` with ordinary least squares, no parallel
   filtering, no decimation: every sample fitted; rank check, solve, standard
   deviations, identifiability report, residual statistics);
3. peer 1: ``numpy.linalg.lstsq`` on the same stacked regressor rows (already
   evaluated, so the peer is charged only its solve); ratios gtmodel / peer; the two
   estimates must agree to 1e-10 relative per parameter (asserted);
4. peer 2 for the regressor evaluation: a plain per-sample call of the same CasADi
   Function (``DynamicRegressor.cart_function(q, q_dot, q_ddot)`` in a Python loop),
   timed on ``--peer-samples`` samples and scaled to N; also the mapped interpreter (the
   evaluation path without a compiler);
5. for information, the default pipeline (parallel filtering of the regressor,
   decimation, two-step actuator weighting).

OpenBLAS threads are limited to 1 for both sides (shared 2-core machine).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import logging  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from gtmodel.calibration.identification import (  # noqa: E402
    DynamicRegressor,
    FourierTrajectory,
    identify_dynamics,
    preprocess_log,
    simulate_log,
)

AGREEMENT = 1e-10  # relative, per parameter
MIN_SPEED = 0.05  # m/s, rows fitted
COEFFICIENTS = np.array([
    0.3823, 0.4933, 0.5069, 0.0003, 0.0145, 0.071, 0.005, 0.0224, 0.1255, 0.1762, 0.1252, -0.0071,
    -0.0465, 0.0211, -0.0302, -0.0974, -0.1988, -0.17, -0.1204, -0.111, -0.0951, -0.1063, -0.0129, -0.1171,
    0.1516, -0.2066, 0.1159,
])


class _Collect(logging.Handler):
    """Keeps the gtmodel log messages (which evaluation path the regressor took)."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def timed(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--peer-samples", type=int, default=10_000, help="samples of the per-sample-call peer (scaled to N)")
    args = ap.parse_args()
    n = args.samples
    logger = logging.getLogger("gtmodel")
    collect = _Collect()
    logger.addHandler(collect)
    logger.setLevel(logging.INFO)

    tr = FourierTrajectory.from_coefficients(COEFFICIENTS, 4, 10.0)
    t0 = time.perf_counter()
    log, _ = simulate_log(tr, (n - 1) * 0.004, "L1", force_noise=5.0, seed=0)
    print(f"simulated log: {log.n_samples} samples (4 ms) in {time.perf_counter() - t0:.2f} s")
    t_pre, samples = timed(lambda: preprocess_log(log, cutoff=10.0, decimate=1, trim=50), args.repeat)
    N = samples.n_samples

    reg = DynamicRegressor("L1", "model_2")
    collect.messages.clear()
    t0 = time.perf_counter()
    reg.evaluate(samples.x, samples.x_dot, samples.x_ddot)  # builds (or loads) the evaluation Function once
    t_first = time.perf_counter() - t0
    path = "; ".join(m for m in collect.messages if m.startswith("DynamicRegressor")) or "CasADi interpreter (below the compile threshold)"
    print(f"regressor evaluation path: {path}")
    print(f"  first evaluation (incl. building/loading it): {t_first:.3f} s")

    runs = [identify_dynamics(samples, regressor=reg, weighting="none", min_speed=MIN_SPEED, parallel_filter=False) for _ in range(args.repeat)]
    res = runs[-1]
    t_id = statistics.median(r.solve_time for r in runs)
    t_reg = statistics.median(r.info["regressor_time_s"] for r in runs)
    t_ls = statistics.median(r.info["least_squares_time_s"] for r in runs)
    t_filt = statistics.median(r.info["filter_time_s"] for r in runs)

    Y, tau0, v = reg.evaluate(samples.x, samples.x_dot, samples.x_ddot)
    mask = np.abs(v) >= MIN_SPEED
    k, i = np.nonzero(mask)
    A = Y[k, i, :]
    b = (samples.tau - tau0)[k, i]
    t_np, (theta_np, *_) = timed(lambda: np.linalg.lstsq(A, b, rcond=None), args.repeat)
    rel = np.abs(res.theta - theta_np) / np.abs(theta_np)

    # peer 2: the same CasADi Function called per sample from Python, and mapped in the interpreter
    f = reg.cart_function
    K = min(args.peer_samples, N)
    xs, xds, xdds = samples.x[:K], samples.x_dot[:K], samples.x_ddot[:K]

    def per_sample():
        for j in range(K):
            f(xs[j], xds[j], xdds[j])

    t_loop, _ = timed(per_sample, 1)
    t_loop_N = t_loop * N / K
    os.environ["GTMODEL_COMPILE"] = "0"
    try:
        interp = DynamicRegressor("L1", "model_2")
        interp.evaluate(samples.x[:10], samples.x_dot[:10], samples.x_ddot[:10])
        t_interp, (Y_i, *_) = timed(lambda: interp.evaluate(samples.x, samples.x_dot, samples.x_ddot), 1)
    finally:
        del os.environ["GTMODEL_COMPILE"]
    dY = float(np.max(np.abs(Y_i - Y)) / np.max(np.abs(Y)))

    total = t_pre + t_id
    print(f"rows fitted: {A.shape[0]} x {A.shape[1]} ({N} samples)")
    print("identification on N samples (median of %d):" % args.repeat)
    print(f"  preprocessing (preprocess_log: filtfilt 10 Hz, gradient):   {t_pre:.3f} s")
    print(f"  identify_dynamics (whole call):                            {t_id:.3f} s")
    print(f"    regressor evaluation:                                    {t_reg:.3f} s")
    print(f"    parallel filtering of the regressor (off here):          {t_filt:.3f} s")
    print(f"    least squares + statistics:                              {t_ls:.3f} s")
    print(f"  preprocessing + identify_dynamics:                         {total:.3f} s")
    print(f"peer 1: numpy.linalg.lstsq on the same rows:                 {t_np:.3f} s")
    print(f"  ratio identify_dynamics / lstsq:                           {t_id / t_np:.1f}")
    print(f"  ratio (preprocessing + identify_dynamics) / lstsq:         {total / t_np:.1f}")
    print(f"  ratio least squares + statistics / lstsq:                  {t_ls / t_np:.2f}")
    print(f"  largest relative difference of the estimates:             {rel.max():.2e} (limit {AGREEMENT:g})")
    print(f"peer 2: per-sample call of the CasADi Function ({K} samples, scaled to {N}): {t_loop_N:.3f} s")
    print(f"  ratio regressor evaluation / per-sample calls:             {t_reg / t_loop_N:.3f} ({t_loop_N / t_reg:.0f}x faster)")
    print(f"  mapped CasADi interpreter (no compiler):                   {t_interp:.3f} s, ratio evaluation / interpreter {t_reg / t_interp:.2f}"
          f" (largest relative difference of Y {dY:.1e})")
    assert rel.max() < AGREEMENT, rel
    default = preprocess_log(log, cutoff=10.0)
    t_def, res_def = timed(lambda: identify_dynamics(default, regressor=reg), 1)
    print(f"default pipeline (parallel filter, decimation {default.decimate}, actuator weights): {t_def:.3f} s "
          f"(of which parallel filtering {res_def.info['filter_time_s']:.3f} s), {res_def.n_rows} rows")
    print("estimates (model 2):", ", ".join(f"{nm} {x:.3f}+-{s:.3f}" for nm, x, s in zip(res_def.names, res_def.theta, res_def.std)))


if __name__ == "__main__":
    main()
