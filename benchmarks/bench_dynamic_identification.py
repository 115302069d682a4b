"""Dynamic identification speed: gtmodel's identify_dynamics vs a plain NumPy lstsq, 10^5 samples.

Usage: python benchmarks/bench_dynamic_identification.py [--samples N] [--repeat R]

Problem: the L1 inverse dynamics of Dressler (2012), eqs. 6.7-6.8, Table 6.3 model 2
(10 parameters), on a simulated 4 ms servo log of ``N`` samples (default 10^5 = 400 s)
along a fixed Fourier excitation, 5 N force noise, positions filtered at 10 Hz.

Printed (median of ``--repeat`` runs, machines are noisy):

1. regressor evaluation: ``DynamicRegressor.evaluate`` on the N samples (the CasADi
   graph ``Y = d tau / d theta`` mapped over the samples);
2. ``identify_dynamics`` on the same samples with ordinary least squares, no parallel
   filtering and no decimation (every sample fitted), wall time of the whole call
   (regressor evaluation, rank check by pivoted QR, solve, standard deviations,
   identifiability report, residual statistics);
3. the peer: ``numpy.linalg.lstsq`` on the same stacked regressor rows (already
   evaluated, so the peer is charged only its solve) -- the ratio is gtmodel / peer,
   and the two estimates must agree to 1e-8 relative per parameter (asserted);
4. for information, the default pipeline (parallel filtering of the regressor,
   decimation, two-step actuator weighting).

OpenBLAS threads are limited to 1 for both sides (shared 2-core machine).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from gtmodel.calibration.dynamic_identification import (  # noqa: E402
    DynamicRegressor,
    identify_dynamics,
    preprocess_log,
    simulate_log,
)
from gtmodel.calibration.excitation import FourierTrajectory  # noqa: E402

AGREEMENT = 1e-8  # relative, per parameter
MIN_SPEED = 0.05  # m/s, rows fitted
COEFFICIENTS = np.array([
    0.3823, 0.4933, 0.5069, 0.0003, 0.0145, 0.071, 0.005, 0.0224, 0.1255, 0.1762, 0.1252, -0.0071,
    -0.0465, 0.0211, -0.0302, -0.0974, -0.1988, -0.17, -0.1204, -0.111, -0.0951, -0.1063, -0.0129, -0.1171,
    0.1516, -0.2066, 0.1159,
])


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
    args = ap.parse_args()
    n = args.samples
    tr = FourierTrajectory.from_coefficients(COEFFICIENTS, 4, 10.0)
    t0 = time.perf_counter()
    log, _ = simulate_log(tr, (n - 1) * 0.004, force_noise=5.0, seed=0)
    print(f"simulated log: {log.n_samples} samples (4 ms) in {time.perf_counter() - t0:.2f} s")
    t0 = time.perf_counter()
    samples = preprocess_log(log, cutoff=10.0, decimate=1, trim=50)
    print(f"filtering (filtfilt, 10 Hz) and differentiation: {time.perf_counter() - t0:.3f} s, {samples.n_samples} samples kept")
    reg = DynamicRegressor("L1", "model_2")
    reg.evaluate(samples.x[:10], samples.x_dot[:10], samples.x_ddot[:10])  # build the CasADi function once
    t_eval, (Y, tau0, v) = timed(lambda: reg.evaluate(samples.x, samples.x_dot, samples.x_ddot), args.repeat)
    print(f"regressor evaluation ({samples.n_samples} x 3 x {reg.n_parameters}): {t_eval:.3f} s")

    runs = [identify_dynamics(samples, regressor=reg, weighting="none", min_speed=MIN_SPEED, parallel_filter=False) for _ in range(args.repeat)]
    res = runs[-1]
    t_gt = statistics.median(r.solve_time for r in runs)
    t_in = statistics.median(r.info["regressor_time_s"] for r in runs)
    t_rest = statistics.median(r.solve_time - r.info["regressor_time_s"] for r in runs)
    mask = np.abs(v) >= MIN_SPEED
    k, i = np.nonzero(mask)
    A = Y[k, i, :]
    b = (samples.tau - tau0)[k, i]
    t_np, (theta_np, *_) = timed(lambda: np.linalg.lstsq(A, b, rcond=None), args.repeat)
    rel = np.abs(res.theta - theta_np) / np.abs(theta_np)
    print(f"rows fitted: {A.shape[0]} x {A.shape[1]}")
    print(f"gtmodel identify_dynamics (whole call):      {t_gt:.3f} s")
    print(f"  of which regressor evaluation:             {t_in:.3f} s")
    print(f"  the rest (rank check, solve, std, report): {t_rest:.3f} s")
    print(f"numpy.linalg.lstsq on the same rows (peer):   {t_np:.3f} s")
    print(f"ratio gtmodel / peer:                         {t_gt / t_np:.1f}  (least-squares part alone: {t_rest / t_np:.1f})")
    print(f"largest relative difference of the estimates: {rel.max():.2e}")
    assert rel.max() < AGREEMENT, rel
    default = preprocess_log(log, cutoff=10.0)
    t_def, res_def = timed(lambda: identify_dynamics(default, regressor=reg), 1)
    print(f"default pipeline (parallel filter, decimation {default.decimate}, actuator weights): {t_def:.3f} s, {res_def.n_rows} rows")
    print("estimates (model 2):", ", ".join(f"{nm} {x:.3f}+-{s:.3f}" for nm, x, s in zip(res_def.names, res_def.theta, res_def.std)))


if __name__ == "__main__":
    main()
