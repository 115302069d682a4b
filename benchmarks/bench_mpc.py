"""Real-time MPC step as generated C against the same MPC solved per step in Python (a benchmark, not a test).

Usage: python benchmarks/bench_mpc.py [FILE.toml ...] [--json] [--steps 10000] [--no-acados]

For each MPC file (default every ``codegen/mpc/*.toml``: the L1 and the composed DC motor),
measured side by side in one run, because these machines are noisy:

- the generated C step (``gt_<name>_step`` through ctypes: CasADi's ``sqpmethod`` + ``qrqp`` (``daqp`` with
  state or path constraints; ``fatrop`` for ``solver = "fatrop"``)
  code-generated, one SQP iteration per period by default) in the closed loop of the file's
  ``[check]`` (mismatched plant, noise, step disturbance, one-sample delay), the motion run
  again from ``_init`` until at least ``--steps`` steps: per-step time, median, p99 and
  max, the first step of the first run apart, in wall time (``step_*_s``) and in the CPU
  time of this thread (``cpu_step_*_s``: the step's own work, without the preemptions of
  a shared machine). The ctypes call is inside the timing (about 1-2 us);
- its static memory: ``sizeof(<prefix>_memory)`` and the stack work arrays of one step, and with
  DAQP the per-thread arena its allocations go to (``arena_bytes``, its peak use
  ``arena_peak_bytes`` and the allocations that did not fit it, ``heap_calls``, 0 expected);
- the tracking error RMS of the MPC over that of the feedforward alone on the same plant
  (``tracking_rms_ratio_to_feedforward``) and the applied-input bound violations;
- ``ratio_to_python``: the same horizon problem solved per step in Python by CasADi + IPOPT
  (the same NLP Function; warm-started from the previous step's solution; at 50 states of
  the closed loop), its median wall time per step over the C step's median.

- beside it, acados (SQP-RTI, issue 46) on the same horizon problem, in its own venv
  (``benchmarks/acados_env.sh``; the peer ``benchmarks/peers/acados_mpc.py``, fed through a pipe
  by the same closed loop: the same plant, noise, disturbance, delay and error; the step's
  Function ``F`` saved by CasADi, the same weights, reference window, bounds, horizon and
  period): the thread CPU of acados' solve call per step, its tracking RMS, and the first input
  of its SQP iterated to convergence against gtmodel's (30 Gauss-Newton iterations) at 5 states
  of its run. acados 0.2.2 has no move blocking and no input-disturbance estimate: it solves the
  problem with one input per period and the file's soft constraint rows as declared (its nonlinear
  constraints, a slack per row: ``peers/acados_mpc.py``; no back-off), so each file gives three rows,
  ``configuration`` ``"same NLP hpipm"`` (gtmodel on that NLP, ``solver = "hpipm"``: the real-time
  iteration on the multiple-shooting QP by HPIPM, as acados'), ``"same NLP sqpmethod"`` (that NLP
  by single shooting and a dense QP, DAQP with rows) and ``"shipped"``
  (the file's blocks and rows), all against that acados run (``acados_rows`` the rows acados had; where no
  configuration converged with them, acados runs again without them after gtmodel's rounds, ``acados_rows`` 0 and
  ``acados_with_rows_failed`` says why: the L1's soft rows, ``rho`` 1e10, stopped every acados QP at its minimum step). The CPU per step is measured in
  ``--rounds`` alternated rounds (default 3: acados' peers, then each configuration, each
  round about ``--steps / rounds`` steps), so that the machine's load falls on all of them, and
  pooled (``cpu_steps`` steps of each configuration). Keys:
  ``acados_cpu_step_median_s``, ``acados_cpu_step_p99_s``, ``acados_cpu_step_max_s``,
  ``acados_tracking_rms``, ``acados_first_control_rel_diff`` (the largest relative difference of the first input
  of acados' real-time iterations repeated to convergence from that of gtmodel's own, ``hpipm_rti`` for
  :data:`AGREEMENT_RTI_ITERATIONS` iterations, the same full-step Gauss-Newton iteration, over the states where
  acados' converged, ``acados_agreement_states`` of :data:`AGREEMENT_STATES` for the peer with fewer), and
  ``acados_sqp_first_control_rel_diff`` (the same against gtmodel's line-search SQP, 40 iterations: the horizon
  problem may have several local optima, and the full step and the line search may end in different ones; on the
  L1 at one of the 5 states the line search's objective is 17.34 and the full steps' 17.69, 0.11 apart in the
  first input). The nearest-input figures (``nearest_*``) take only gtmodel's inputs whose solver says it solved
  (:class:`~gtmodel.control.mpc_solve.HorizonSolution`: every QP of the HPIPM iterations solved, the SQP converged);
  a state with neither is left out and counted (``agreement_states_unsolved``). The headline is acados at its fastest configuration that converged (of
  :data:`ACADOS_QPS`, the least median CPU per step among those whose every step returned
  status 0 and whose plant did not diverge): ``acados_config``, ``acados_cpu_step_*``,
  ``acados_tracking_rms`` and ``ratio_to_acados_median``, ``ratio_to_acados_p99``,
  ``tracking_rms_ratio_to_acados`` (printed first); acados' default QP solver
  (``PARTIAL_CONDENSING_HPIPM``) beside it, ``acados_default_*`` and
  ``ratio_to_acados_default_median`` / ``_p99``; every configuration's figures in
  ``acados_qps``. Issue 65's figures: ``acados_best_p99_ratio``, gtmodel's CPU p99 over that of acados' converged
  configuration of the least CPU p99 (``acados_best_config``, ``acados_best_cpu_step_median_s`` / ``_p99_s``), and
  ``first_control_rel_diff`` / ``first_control_range_diff``: that configuration's converged first input against the
  nearer of gtmodel's two converged ones (its real-time iterations', its line-search SQP's; relative and over the
  input range). No configuration converged: no ratio (None)
  and ``peer_failed`` says why.
  ``acados_skipped`` with the reason instead when the venv cannot be made (or ``--no-acados``).

With ``--json`` the last line of stdout is one JSON object
``{"mpc": [{"name", "horizon", "period_s", "step_median_s", "step_p99_s", "step_max_s",
"tracking_rms_ratio_to_feedforward", "bound_violations", "ratio_to_python", "hpipm_libraries", ...}, ...]}``
(``hpipm_libraries``: the folder of ``GTMODEL_HPIPM`` the hpipm step linked, built by
``benchmarks/hpipm_build.sh``, or ``"casadi wheel"``; gtmodel/codegen/hpipm_source.py).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import statistics
import subprocess
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel.codegen.hpipm_source import HPIPM_ENV, hpipm_libraries
from gtmodel.control.mpc_hpipm import row_box
from gtmodel.control.mpc_nlp import period_states
from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.problems.loop_check import STATUS_NAMES
from gtmodel.problems.mpc_check import build_mpc, closed_loop_check
from gtmodel.problems.mpc_file import load_mpc_file

ROOT = Path(__file__).resolve().parents[1]
#: States of the closed loop at which the Python (IPOPT) step is timed.
PYTHON_STATES = 50
#: acados' venv maker and the peer run inside it (issue 46).
ACADOS_ENV = ROOT / "benchmarks" / "acados_env.sh"
ACADOS_PEER = ROOT / "benchmarks" / "peers" / "acados_mpc.py"
#: acados' QP configurations measured (issue 65): its default first (``PARTIAL_CONDENSING_HPIPM``, hpipm_mode ``BALANCE``),
#: then HPIPM in ``SPEED_ABS`` and full condensing (HPIPM, qpOASES): the QP solvers of acados 0.2.2's wheel. A
#: configuration is ``"QP_SOLVER"`` or ``"QP_SOLVER HPIPM_MODE"``.
ACADOS_QPS = ("PARTIAL_CONDENSING_HPIPM", "PARTIAL_CONDENSING_HPIPM SPEED_ABS", "FULL_CONDENSING_HPIPM",
              "FULL_CONDENSING_HPIPM SPEED_ABS", "FULL_CONDENSING_QPOASES")
#: The configurations of each file: (acados' NLP, solver); "" the file's solver.
CONFIGURATIONS = ((True, "hpipm"), (True, "sqpmethod"), (False, ""))
#: States of the closed loop at which the converged first inputs are compared.
AGREEMENT_STATES = 5
#: The acados peer's ``converge`` tolerance (``benchmarks/peers/acados_mpc.py``: ``CONVERGE_TOL``): a state where its
#: iterations moved more at the last one is left out of the agreement (counted in ``acados_agreement_states``).
ACADOS_CONVERGE_TOL = 1e-12
#: gtmodel's real-time iterations (``hpipm_rti``: full-step Gauss-Newton SQP on the same NLP, acados' iteration) at an
#: agreement state, from the same start as the peer's, compared with acados' converged ones.
AGREEMENT_RTI_ITERATIONS = 200


def _num(v) -> str:
    return repr(float(v))


def export_problem(c, folder: Path) -> Path:
    """The controller's horizon problem for the acados peer: ``problem.npz`` and the step's CasADi file; with soft
    constraint rows the rows of one period as a CasADi file, their upper bounds, ``rho``, the number of sides (a slack
    each per stage) and the periods that carry them."""
    folder.mkdir(parents=True, exist_ok=True)
    c.step.save(str(folder / "step.casadi"))
    path = folder / "problem.npz"
    extra = {}
    cons = c.constraints
    if cons is not None:
        if cons.hard:
            raise ValueError("the acados peer takes soft rows only")
        x, u = ca.SX.sym("x", c.nx), ca.SX.sym("u", c.nu)
        x_next, inside = period_states(c, x, u)  # the rows of period j as the hpipm step has them: inside, then its end
        ca.Function("rows", [x, u], [ca.vertcat(*[cons.rows(xi, u) for xi in (*inside, x_next)])]).save(str(folder / "rows.casadi"))
        extra = {"rows": "rows.casadi", "rows_upper": np.tile(row_box(c), len(inside) + 1), "rho": cons.weight, "rows_sides": len(cons.sides),
                 "rows_stages": np.array([j + 1 in cons.stages(c.horizon) for j in range(c.horizon)])}
    np.savez(path, Q=c.Q, R=c.R, Qf=c.Qf, u_lb=c.u_lb, u_ub=c.u_ub, horizon=c.horizon, period=c.dt, step="step.casadi", **extra)
    return path


class AcadosPeer:
    """The acados peer (``benchmarks/peers/acados_mpc.py`` in its venv) as a controller ``(t, x) -> (status, u)``.

    The delay compensation of the gtmodel step (``delay = 1``: the horizon from ``F(x, u_last)`` at
    ``t + dt``) is done here with the same step; the input-disturbance estimate is not (acados has none).
    """

    def __init__(self, c, problem: Path, qp: str, warm: str = "shift"):
        self.c, self.qp = c, qp
        solver, *mode = qp.split()
        self.proc = subprocess.Popen([str(ACADOS_ENV), "python", str(ACADOS_PEER), str(problem), "--qp", solver, "--warm", warm,
                                      *(["--hpipm-mode", mode[0]] if mode else []),
                                      "--build", str(problem.parent / f"acados_{qp.lower().replace(' ', '_')}")],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                     env={**os.environ, "OMP_NUM_THREADS": "1"})
        self.u_last = c.u_initial

    def _ask(self, line: str) -> list[str]:
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        answer = self.proc.stdout.readline()
        if not answer:
            raise RuntimeError(f"acados peer ({self.qp}) ended without an answer")
        return answer.split()

    def _p(self, t: float, x: np.ndarray) -> str:
        if self.c.delay:
            t, x = t + self.c.dt, np.asarray(self.c.step(x, self.u_last)).reshape(-1)
        return " ".join(map(_num, self.c.parameters(t, x)))

    def reset(self) -> None:
        """The next step from the gtmodel step's first warm start (``w_initial``, each block's input over its periods)."""
        self.u_last = self.c.u_initial
        w = np.repeat(self.c.w_initial.reshape(self.c.blocks, self.c.nu), self.c.horizon // self.c.blocks, axis=0)
        self.proc.stdin.write("reset " + " ".join(map(_num, w.reshape(-1))) + "\n")

    def __call__(self, t: float, x: np.ndarray) -> tuple[int, np.ndarray]:
        words = self._ask(f"step {self._p(t, x)}")
        self.u_last = np.array([float(v) for v in words[1:]])
        return (0 if words[0] == "0" else 1), self.u_last

    def converged(self, t: float, x: np.ndarray) -> tuple[np.ndarray, bool]:
        """The first input of acados' real-time iterations repeated at ``(t, x)`` (no delay compensation), and whether
        they converged (the whole trajectory's last move within the peer's ``CONVERGE_TOL``, status 0)."""
        self.reset()
        words = self._ask(f"converge {' '.join(map(_num, self.c.parameters(t, x)))}")
        return np.array([float(v) for v in words[3:]]), words[0] == "0" and float(words[2]) <= ACADOS_CONVERGE_TOL

    def step_times(self) -> np.ndarray:
        """The thread CPU times [s] of the steps since the last call."""
        return np.asarray(json.loads(" ".join(self._ask("stats")))["cpu_step_s"])

    def close(self) -> None:
        """End the peer."""
        try:
            self.proc.stdin.write("quit\n")
            self.proc.stdin.close()
        finally:
            self.proc.wait(timeout=60)


def python_step_s(setup, summary) -> float:
    """Median wall time [s] of one MPC step solved in Python by IPOPT (warm-started from the last solution)."""
    c = setup.controller
    solver = c.nlp_solver("ipopt")
    bounds = c.bounds()
    w = np.r_[c.w_initial, np.zeros(c.n_slack)]
    times = []
    for k in np.linspace(0, summary.t.size - 1, PYTHON_STATES).round().astype(int):
        p = c.parameters(summary.t[k], summary.x[k])
        t0 = time.perf_counter()
        sol = solver(x0=w, p=p, **bounds)
        times.append(time.perf_counter() - t0)
        w = np.asarray(sol["x"]).reshape(-1)
    return statistics.median(times)


def acados_available() -> str:
    """Empty when acados' venv is there or can be made (:data:`ACADOS_ENV`), else the reason."""
    try:
        out = subprocess.run([str(ACADOS_ENV)], capture_output=True, text=True, timeout=1800)
    except (OSError, subprocess.TimeoutExpired) as e:
        return f"acados venv: {e}"
    return "" if out.returncode == 0 else (out.stderr.strip().splitlines() or ["acados_env.sh failed"])[-1]


def acados_open(setup, build: Path, rows: bool = True) -> tuple:
    """The acados peers of :data:`ACADOS_QPS` on the horizon problem of :func:`same_nlp` (``rows`` False: without its
    constraint rows), and their runs so far."""
    c = same_nlp(setup.controller) if rows else replace(same_nlp(setup.controller), constraints=None)
    problem = export_problem(c, build / f"{setup.name}_acados{'' if rows else '_without_rows'}")
    peers = {}
    try:
        for qp in ACADOS_QPS:
            peers[qp] = AcadosPeer(c, problem, qp)
    except Exception:
        for peer in peers.values():
            peer.close()
        raise
    return c, peers, {qp: [] for qp in ACADOS_QPS}


def acados_round(setup, peers: dict, runs: dict, repeat: int) -> None:
    """One round: each acados peer runs the file's closed loop ``repeat`` times (its step CPU kept by the peer)."""
    args = (setup.plant_step, setup.plant_x0, setup.t, setup.x_ref)
    kw = dict(setup.loop, plant_p=setup.plant_p, status_names=STATUS_NAMES)
    for qp, peer in peers.items():
        for _ in range(max(repeat, 1)):
            peer.reset()
            runs[qp].append(run_controller_loop(peer, *args, **kw))


def acados_finish(setup, c, peers: dict, runs: dict) -> dict:
    """acados' figures per QP solver after the rounds, and the peers closed.

    Returns, per QP solver of :data:`ACADOS_QPS`, the thread CPU per step (the solve call,
    median, p99, max over all its runs), the tracking RMS of the first run and the largest
    difference of the converged first input from gtmodel's repeated real-time iterations at
    :data:`AGREEMENT_STATES` states of that run, relative to gtmodel's input
    (``first_control_rel_diff``) and over the input range (``first_control_range_diff``; a settled
    state's input near 0 makes the first large), against the line-search SQP's (``sqp_first_control_rel_diff``),
    and at each state against the nearer of the two (``nearest_first_control_rel_diff`` / ``_range_diff``): the
    horizon problem may have several optima, the two iterations may settle in different ones, and gtmodel's HPIPM
    full steps may settle off the optimum (the belt drive's, 3.2e-5 of the input range from IPOPT's, which the SQP
    gives to 1e-10 and acados' configurations to 2.6e-6 of the range).
    """
    out = {}
    try:
        for qp, peer in peers.items():
            cpu = peer.step_times()
            rel, rel_sqp, rel_range, near, near_range, compared, unsolved = 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0
            span = np.where(np.isfinite(c.u_ub - c.u_lb), c.u_ub - c.u_lb, np.nan)
            for k in np.linspace(0, setup.t.size - 1, AGREEMENT_STATES + 2)[1:-1].round().astype(int):
                t, x = runs[qp][0].t[k], runs[qp][0].x[k]
                ua, done = peer.converged(t, x)
                if not done:  # the peer's full-step Gauss-Newton iterations did not settle: no optimum to compare
                    continue
                sg = c.solve(t, x, plugin="hpipm", iterations=AGREEMENT_RTI_ITERATIONS)  # the same iteration as acados'
                ss = c.solve(t, x, plugin="sqpmethod", iterations=40)  # 40: converged to 2e-11 on the L1 (notebook 15)
                ug, us = sg.u, ss.u
                own = [sol.u for sol in (sg, ss) if sol.success]  # gtmodel's inputs whose solver says it converged
                if not own:
                    unsolved += 1
                    continue
                rel = max(rel, float(np.max(np.abs(ua - ug)) / max(np.max(np.abs(ug)), 1e-300)))
                rel_range = max(rel_range, float(np.max(np.abs(ua - ug) / span)))  # NaN without finite bounds
                rel_sqp = max(rel_sqp, float(np.max(np.abs(ua - us)) / max(np.max(np.abs(us)), 1e-300)))
                nearer = min(own, key=lambda u: float(np.max(np.abs(ua - u))))  # the optimum acados' settled in
                near = max(near, float(np.max(np.abs(ua - nearer)) / max(np.max(np.abs(nearer)), 1e-300)))
                near_range = max(near_range, float(np.max(np.abs(ua - nearer) / span)))
                compared += 1
            out[qp] = {"cpu_step_median_s": float(np.median(cpu)), "cpu_step_p99_s": float(np.percentile(cpu, 99)),
                       "cpu_step_max_s": float(np.max(cpu[1:])), "tracking_rms": runs[qp][0].rms_error,
                       "first_control_rel_diff": rel if compared else None,
                       "first_control_range_diff": rel_range if compared and np.isfinite(rel_range) else None,
                       "sqp_first_control_rel_diff": rel_sqp if compared else None, "agreement_states": compared,
                       "agreement_states_unsolved": unsolved,
                       "nearest_first_control_rel_diff": near if compared else None,
                       "nearest_first_control_range_diff": near_range if compared and np.isfinite(near_range) else None,
                       "failed_steps": int(sum(np.count_nonzero(run.status) for run in runs[qp])),
                       "diverged": any(run.diverged for run in runs[qp])}
    finally:
        for peer in peers.values():
            peer.close()
    return out


def acados_failure(figures: dict) -> str:
    """Why an acados configuration's run does not count as converged (empty when it does).

    Parameters
    ----------
    figures : dict
        One QP solver's figures of :func:`acados_finish`.

    Returns
    -------
    str
        ``"3 steps not converged"``, ``"the plant diverged"``, ``"a step time not finite"``, or ``""``.
    """
    if figures.get("failed_steps"):
        return f"{figures['failed_steps']} steps not converged"
    if figures.get("diverged"):
        return "the plant diverged"
    if not np.isfinite(figures["cpu_step_median_s"]) or not np.isfinite(figures["tracking_rms"]):
        return "a step time or the tracking not finite"
    return ""


def _acados_config(qp: str, horizon: int, rows: int = 0) -> str:
    rows_text = f"the {rows} soft constraint rows (a slack per side and stage, as gtmodel's hpipm step)" if rows else "no constraint rows"
    return f"SQP_RTI {qp}, GAUSS_NEWTON, DISCRETE (the same step), N = {horizon}, no blocking, {rows_text}, no disturbance estimate"


def acados_keys(row: dict, acados: dict | str) -> dict:
    """The acados keys of a row: the headline at acados' fastest configuration that converged, its default beside it.

    Parameters
    ----------
    row : dict
        gtmodel's figures of one configuration (``horizon``, ``cpu_step_median_s``, ``cpu_step_p99_s``, ``tracking_rms``).
    acados : dict or str
        Per QP solver of :data:`ACADOS_QPS` its figures (:func:`acados_finish`), or why acados did not run.

    Returns
    -------
    dict
        ``row`` with ``acados_skipped``; or with ``acados_config`` and ``acados_*`` of the fastest
        configuration whose every step converged (no failed status, no divergence; the least median
        CPU per step), ``ratio_to_acados_median``, ``ratio_to_acados_p99`` and
        ``tracking_rms_ratio_to_acados`` against it, ``acados_default_*`` and
        ``ratio_to_acados_default_median`` / ``_p99`` against acados' default QP solver
        (the first of :data:`ACADOS_QPS`) beside it, and ``acados_qps`` (every configuration's figures and
        its ``failure``); issue 65's ``acados_best_config``, ``acados_best_cpu_step_median_s`` / ``_p99_s`` and
        ``acados_best_p99_ratio`` (gtmodel's p99 over it) and ``acados_best_first_control_rel_diff`` / ``_range_diff`` (its
        converged first input against gtmodel's real-time iterations) at the converged configuration of least p99, and
        ``first_control_rel_diff`` / ``first_control_range_diff``: that configuration's converged first input against
        the nearer of gtmodel's two converged ones (:func:`acados_finish`). No configuration converged: the ratios
        (and ``acados_best_*``) None and ``peer_failed`` says why (else ``peer_failed`` None); a failed default has
        no default ratio.
    """
    if isinstance(acados, str):
        return {**row, "acados_skipped": acados}
    failures = {qp: acados_failure(f) for qp, f in acados.items()}
    good = [qp for qp in acados if not failures[qp]]
    head = min(good, key=lambda qp: acados[qp]["cpu_step_median_s"]) if good else None
    best = min(good, key=lambda qp: acados[qp]["cpu_step_p99_s"]) if good else None  # issue 65: the least p99
    # the agreement of the configurations that converged (one whose steps failed or whose plant diverged iterates from
    # elsewhere: the ball screw's SPEED_ABS partial condensing, 1401 failed steps, differed by 2.5e-2)
    first = max((v for qp in good if (v := acados[qp]["first_control_rel_diff"]) is not None), default=None)
    a, default = acados[head or ACADOS_QPS[0]], acados[ACADOS_QPS[0]]
    peer_failed = None if head else ("acados: no configuration converged (" +
                                     "; ".join(f"{qp}: {why}" for qp, why in failures.items()) + "), no ratio")
    default_ok = not failures[ACADOS_QPS[0]]
    ratio = (lambda ours, theirs: ours / theirs) if head else (lambda ours, theirs: None)
    return {**row, "acados_config": _acados_config(head or ACADOS_QPS[0], row["horizon"], row.get("acados_rows", 0)),
            "acados_cpu_step_median_s": a["cpu_step_median_s"], "acados_cpu_step_p99_s": a["cpu_step_p99_s"],
            "acados_cpu_step_max_s": a["cpu_step_max_s"], "acados_tracking_rms": a["tracking_rms"],
            "acados_first_control_rel_diff": first,
            "acados_sqp_first_control_rel_diff": max((v for qp in good if (v := acados[qp]["sqp_first_control_rel_diff"]) is not None),
                                                     default=None),
            "acados_agreement_states": min(f["agreement_states"] for f in acados.values()),
            "ratio_to_acados_median": ratio(row["cpu_step_median_s"], a["cpu_step_median_s"]),
            "ratio_to_acados_p99": ratio(row["cpu_step_p99_s"], a["cpu_step_p99_s"]),
            "tracking_rms_ratio_to_acados": ratio(row["tracking_rms"], a["tracking_rms"]),
            "acados_default_config": _acados_config(ACADOS_QPS[0], row["horizon"], row.get("acados_rows", 0)),
            "acados_default_cpu_step_median_s": default["cpu_step_median_s"], "acados_default_cpu_step_p99_s": default["cpu_step_p99_s"],
            "acados_default_tracking_rms": default["tracking_rms"], "acados_default_failure": failures[ACADOS_QPS[0]] or None,
            "ratio_to_acados_default_median": row["cpu_step_median_s"] / default["cpu_step_median_s"] if default_ok else None,
            "ratio_to_acados_default_p99": row["cpu_step_p99_s"] / default["cpu_step_p99_s"] if default_ok else None,
            "acados_qps": {qp: {**f, "failure": failures[qp] or None} for qp, f in acados.items()},
            "acados_best_config": best and _acados_config(best, row["horizon"], row.get("acados_rows", 0)),
            "acados_best_cpu_step_median_s": best and acados[best]["cpu_step_median_s"],
            "acados_best_cpu_step_p99_s": best and acados[best]["cpu_step_p99_s"],
            "acados_best_p99_ratio": best and row["cpu_step_p99_s"] / acados[best]["cpu_step_p99_s"],
            "acados_best_first_control_rel_diff": best and acados[best]["first_control_rel_diff"],
            "acados_best_first_control_range_diff": best and acados[best]["first_control_range_diff"],
            "first_control_rel_diff": best and acados[best]["nearest_first_control_rel_diff"],
            "first_control_range_diff": best and acados[best]["nearest_first_control_range_diff"],
            "peer_failed": peer_failed}


def same_nlp(c):
    """The MPC on acados' NLP: one input per period, the file's constraint rows with their bounds as declared (no
    back-off), no disturbance estimate, no weight on the input's rate, no measurement filter (acados' step is given
    the state)."""
    return replace(c, blocks=c.horizon, disturbance_gain=0.0, constraint_backoff=False, R_rate=None, state_filter=None)


def prepare(path: Path, build: Path, unblocked: bool = False, solver: str = "") -> tuple:
    """One configuration of an MPC file, generated and compiled (``unblocked``: acados' NLP, :func:`same_nlp`;
    ``solver``: another NLP solver of the step, e.g. ``"hpipm"``)."""
    setup = load_mpc_file(path)
    if unblocked:
        setup = replace(setup, name=setup.name + "_same_nlp" + (f"_{solver}" if solver else ""),
                        controller=replace(same_nlp(setup.controller), solver=solver or setup.controller.solver))
    generated, library = build_mpc(setup, build / setup.name)
    label = ("same NLP" + (f" {solver}" if solver else "")) if unblocked else "shipped"
    return setup, generated, library, label


def cpu_round(prepared: tuple, repeat: int) -> np.ndarray:
    """One round of the generated step in the file's closed loop, ``repeat`` motions: its thread CPU per step (the first apart)."""
    setup, generated, library, _ = prepared
    cpu = closed_loop_check(setup, generated, library, repeat=repeat, clock=time.thread_time)
    return cpu.mpc.step_s[1:], cpu.mpc.bound_violations


def bench(prepared: tuple, cpu: np.ndarray, violations: int) -> dict:
    """All figures of one configuration: the wall-time run here, the CPU per step ``cpu`` pooled over the alternated rounds."""
    setup, generated, library, label = prepared
    wall = closed_loop_check(setup, generated, library, repeat=1, clock=time.perf_counter)  # one motion: wall time, tracking
    st = wall.mpc.step_times()
    py = python_step_s(setup, wall.mpc)
    c = setup.controller
    return {
        "name": setup.name, "configuration": label, "acados_rows": same_nlp(c).constraint_rows, "solver": c.solver, "qpsol": c.qpsol if c.solver == "sqpmethod" else "", "constraint_rows": c.constraint_rows,
        "horizon": c.horizon, "period_s": c.dt, "blocks": c.blocks, "sqp_iterations": c.sqp_iterations,
        "steps": int(wall.mpc.step_s.size), "first_step_s": st["first"],
        "step_median_s": st["median"], "step_p99_s": st["p99"], "step_max_s": st["max"],
        "cpu_steps": int(cpu.size), "cpu_step_median_s": float(np.median(cpu)), "cpu_step_p99_s": float(np.percentile(cpu, 99)),
        "cpu_step_max_s": float(np.max(cpu)),
        "memory_bytes": wall.memory_bytes, "work_bytes": wall.work_bytes,
        "arena_bytes": wall.heap[2] if wall.heap else 0, "arena_peak_bytes": wall.heap[0] if wall.heap else 0,
        "heap_calls": wall.heap[1] if wall.heap else 0,
        "tracking_rms": wall.mpc.rms_error, "feedforward_rms": wall.feedforward.rms_error,
        "tracking_rms_ratio_to_feedforward": wall.ratio_to_feedforward,
        "bound_violations": wall.mpc.bound_violations + violations,
        "status_counts": wall.mpc.status_counts,
        "python_step_median_s": py, "ratio_to_python": py / st["median"],
        "hpipm_libraries": (hpipm_libraries() and os.environ[HPIPM_ENV]) or "casadi wheel" if c.solver == "hpipm" else "",
    }


def _print_row(r: dict) -> None:
    """The figures of one row, the ratio to acados first."""
    if "acados_skipped" in r:
        print(f"{r['name']}: acados skipped ({r['acados_skipped']})")
    else:
        if r["peer_failed"]:
            print(f"{r['name']}: {r['peer_failed']}")
        else:
            print(f"{r['name']}: C step CPU / acados' fastest that converged ({r['acados_config'].split(',')[0]}): "
                  f"median {r['ratio_to_acados_median']:.2f}x, p99 {r['ratio_to_acados_p99']:.2f}x; "
                  f"tracking RMS {r['tracking_rms_ratio_to_acados']:.2f}x acados'")
        if r.get("acados_with_rows_failed"):
            print(f"  acados with the file's constraint rows: no configuration converged ({r['acados_with_rows_failed']}); "
                  "the ratios are to acados without them")
        if r["acados_best_config"]:
            print(f"  issue 65: C step CPU p99 / acados' least p99 that converged ({r['acados_best_config'].split(',')[0]}, "
                  f"{r['acados_best_cpu_step_p99_s'] * 1e6:.1f} us): {r['acados_best_p99_ratio']:.2f}x; its converged first input "
                  + ("n/a" if r["acados_best_first_control_rel_diff"] is None else
                     f"{r['acados_best_first_control_rel_diff']:.1e} relative, "
                     + ("n/a" if r["acados_best_first_control_range_diff"] is None else f"{r['acados_best_first_control_range_diff']:.1e}")
                     + " of the input range off gtmodel's real-time iterations'")
                  + ("" if r["first_control_rel_diff"] is None else
                     f"; {r['first_control_rel_diff']:.1e} relative, "
                     + ("n/a" if r["first_control_range_diff"] is None else f"{r['first_control_range_diff']:.1e}")
                     + " of the range off the nearer of gtmodel's converged inputs (those iterations', its line-search SQP's)"))
        default = r["ratio_to_acados_default_median"]
        print(f"  beside it, acados' default ({r['acados_default_config'].split(',')[0]}): "
              + (f"median {default:.2f}x, p99 {r['ratio_to_acados_default_p99']:.2f}x" if default is not None
                 else f"no ratio ({r['acados_default_failure']})"))
        print(f"  acados {r['acados_config']}: CPU median {r['acados_cpu_step_median_s'] * 1e6:.1f} us, p99 {r['acados_cpu_step_p99_s'] * 1e6:.1f} us, "
              f"max {r['acados_cpu_step_max_s'] * 1e6:.1f} us, tracking RMS {r['acados_tracking_rms']:.4g}; converged first input "
              f"{'n/a' if r['acados_first_control_rel_diff'] is None else format(r['acados_first_control_rel_diff'], '.1e')} "
              f"relative from gtmodel's repeated real-time iterations at the {r['acados_agreement_states']} of "
              f"{AGREEMENT_STATES} states where acados' iterations converged ("
              f"{'n/a' if r['acados_sqp_first_control_rel_diff'] is None else format(r['acados_sqp_first_control_rel_diff'], '.1e')}"
              " from its line-search SQP)")
        for qp, f in r["acados_qps"].items():
            print(f"  acados SQP_RTI {qp}: CPU median {f['cpu_step_median_s'] * 1e6:.1f} us, p99 {f['cpu_step_p99_s'] * 1e6:.1f} us, "
                  f"tracking RMS {f['tracking_rms']:.4g}" + (f"; {f['failure']}" if f["failure"] else "")
                  + ("" if f.get("nearest_first_control_range_diff") is None else
                     f"; converged first input {f['nearest_first_control_range_diff']:.1e} of the range off gtmodel's nearer"))
    print(f"{r['name']}: {r['solver']} {r['qpsol']}, horizon {r['horizon']} x {r['period_s'] * 1e3:g} ms, {r['blocks']} input blocks, "
          f"{r['sqp_iterations']} SQP iteration(s), {r['constraint_rows']} constraint rows, {r['steps']} C steps")
    if r["hpipm_libraries"]:
        print(f"  HPIPM + BLASFEO: {r['hpipm_libraries']}")
    print(f"  C step wall: median {r['step_median_s'] * 1e6:.1f} us, p99 {r['step_p99_s'] * 1e6:.1f} us, "
          f"max {r['step_max_s'] * 1e6:.1f} us (first {r['first_step_s'] * 1e6:.1f} us)")
    print(f"  C step CPU : median {r['cpu_step_median_s'] * 1e6:.1f} us, p99 {r['cpu_step_p99_s'] * 1e6:.1f} us, "
          f"max {r['cpu_step_max_s'] * 1e6:.1f} us")
    print(f"  static memory {r['memory_bytes']} B + stack work {r['work_bytes']} B"
          + (f" + QP arena {r['arena_bytes']} B per thread (peak {r['arena_peak_bytes']} B, {r['heap_calls']} heap calls)" if r["arena_bytes"] else "")
          + f"; statuses {r['status_counts']}")
    print(f"  tracking RMS {r['tracking_rms']:.4g} vs feedforward {r['feedforward_rms']:.4g}: "
          f"ratio {r['tracking_rms_ratio_to_feedforward']:.4g}; bound violations {r['bound_violations']}")
    print(f"  Python (CasADi + IPOPT) per step: median {r['python_step_median_s'] * 1e3:.2f} ms = "
          f"{r['ratio_to_python']:.0f}x the C step")


def main() -> None:
    """Run the benchmark (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path, help="MPC files (default codegen/mpc/*.toml)")
    ap.add_argument("--json", action="store_true", help="end with one JSON line")
    ap.add_argument("--steps", type=int, default=10000, help="at least this many C steps per MPC (default 10000)")
    ap.add_argument("--no-acados", action="store_true", help="without the acados peer")
    ap.add_argument("--rounds", type=int, default=3, help="alternated rounds of the CPU measurement (default 3)")
    args = ap.parse_args()
    logging.getLogger("gtmodel").setLevel(logging.WARNING)
    files = args.files or sorted((ROOT / "codegen" / "mpc").glob("*.toml"))
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_mpc_") as tmp:
        skipped = "--no-acados" if args.no_acados else acados_available()
        for path in files:
            prepared = [prepare(path, Path(tmp), unblocked, solver) for unblocked, solver in CONFIGURATIONS]
            setup = load_mpc_file(path)
            per_round = max(1, -(-args.steps // (setup.t.size * args.rounds)))
            opened = None if skipped else acados_open(setup, Path(tmp))
            cpu = [[] for _ in prepared]
            violations = [0 for _ in prepared]
            try:
                for _ in range(args.rounds):  # alternated: acados, then each configuration, per round
                    if opened:
                        acados_round(setup, opened[1], opened[2], per_round)
                    for i, prep in enumerate(prepared):
                        times, bad = cpu_round(prep, per_round)
                        cpu[i].append(times)
                        violations[i] += bad
            finally:
                acados = skipped or acados_finish(setup, *opened)
            without = None
            if not skipped and opened[0].constraints is not None and all(acados_failure(f) for f in acados.values()):
                # with the file's rows no configuration converged: acados on the NLP without them (less work than
                # gtmodel's steps do), its rounds after gtmodel's (not alternated)
                without = "; ".join(f"{qp}: {acados_failure(f)}" for qp, f in acados.items())
                lighter = acados_open(setup, Path(tmp), rows=False)
                try:
                    for _ in range(args.rounds):
                        acados_round(setup, lighter[1], lighter[2], per_round)
                finally:
                    acados = acados_finish(setup, *lighter)
            for i, prep in enumerate(prepared):
                figures = bench(prep, np.concatenate(cpu[i]), violations[i])
                if without:
                    figures.update(acados_rows=0, acados_with_rows_failed=without)
                r = acados_keys(figures, acados)
                rows.append(r)
                _print_row(r)
    if args.json:
        print(json.dumps({"mpc": rows}))


if __name__ == "__main__":
    main()
