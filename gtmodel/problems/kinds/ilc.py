"""Kind ``ilc``: the ILC experiment of Dressler (2012), section 7.3, on the simulated L1.

The reference is a square in the xy plane (``[reference]``: first corner, side, nominal
speed, acceleration limit) planned by gtmodel's own path-constrained solver (a
:class:`~gtmodel.trajectory.Polyline` through the corners, which it traverses with zero
velocity at each corner, under a TCP speed and per-axis acceleration limit), sampled at
4 ms, mapped to actuator references by IK and framed by a lead-in and a lead-out at rest.
The plant is the closed-loop L1 (``[robot]``, ``[structure]``, ``[sensors]``, see
:mod:`gtmodel.problems.kinds.closed_loop_common`); the learning law is
``u_{k+1} = Q (u_k + L eps_k)`` (7.2) with ``L = gamma q^delta`` and Q a zero-phase
Butterworth low-pass with the Tukey time window (``[ilc]``); the cases (``[[cases]]``)
choose the learning signal (:data:`~gtmodel.estimation.SIGNALS`) and Q's cut-off, and may
require the lifted check (7.15)/(7.16) to hold before they run: a design that fails it is
an input error naming the case (exit 2), raised at solve time before any trial (the check
decomposes the lifted matrices: seconds to a minute, too slow for loading the file).

The result folder holds ``summary.json`` (per case ``rho`` and ``sigma_max`` per channel,
the error measure (7.25) per iteration on the actuator and the tool side, the Table 7.2
figures), ``table_7_2.md``/``.csv`` (mean of iterations 5-10 relative to iteration 0),
``ilc_iterations.csv``, ``controller.json`` (the stationary Kalman step and the learned
actuator correction of the first case when it learns on the actuators, for
``gtmodel codegen --controller``) and the plots ``ilc_actuator_errors.png``, ``ilc_tool_errors.png``
(Figs. 7.7-7.10) and ``ilc_tool_path_case_<name>.png`` (Fig. 7.11). The field reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from gtmodel._escape import csv_field
from gtmodel._docstrings import fill_doc
from gtmodel.errors import GtModelError, UnreachablePoseError
from gtmodel.estimation import (
    ComplementaryFilter,
    ILCCase,
    ILCExperiment,
    ILCReference,
    LearningFilter,
    QFilter,
    StationaryKalman,
    time_window,
)
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.codegen import EstimatorILCBundle, save_controller
from gtmodel.estimation import ilc_correction_function
from gtmodel.estimation.filters.model_kalman import ModelKalman
from gtmodel.estimation.ilc.iteration import error_measure
from gtmodel.problems.kinds.closed_loop_common import build_plant
from gtmodel.problems.kinds.schemas.ilc import ILCFile
from gtmodel.report.ilc import plot_convergence, plot_error_measure, plot_tool_path
from gtmodel.estimation.ilc.cases import ILCDeclaration, ILCOutcome
from gtmodel.estimation.ilc.thesis import thesis_table_7_2
from gtmodel.trajectory.square import plan_square

__all__ = [
    "ILCFile",
    "ILCKind",
]

_log = logging.getLogger("gtmodel")

#: Most samples of a reference (lead-in, motion and lead-out); bounds the lifted matrices.
MAX_SAMPLES = 4000


def _channels(checks: dict[str, Any]) -> dict[str, dict[str, float | bool]]:
    return {ch: {"rho": float(c.rho), "sigma_max": float(c.sigma_max), "stable": bool(c.stable), "monotone": bool(c.monotone)}
            for ch, c in checks.items()}


class ILCKind(ProblemKind):
    """The ILC experiment of Dressler (2012), section 7.3: four learning signals on the simulated L1."""

    name = "ilc"
    schema = ILCFile
    title = "iterative learning control on the simulated L1 (Dressler (2012), section 7.3, eqs. 7.2-7.25, Table 7.2)"
    file_descriptions = {
        "table_7_2.md": "Table 7.2: mean error of iterations 5-10 relative to iteration 0, per case (Markdown)",
        "table_7_2.csv": "Table 7.2 as CSV",
        "ilc_iterations.csv": "error measure (7.25) per case and iteration, actuator and tool side [m]",
        "controller.json": "the stationary Kalman step and the learned actuator correction (gtmodel codegen --controller)",
        "ilc_lifted.npz": "the lifted system matrices of the monotone-convergence check (7.15)/(7.16)",
        "ilc_estimators.npz": "the estimators' matrices (Kalman gains, observers) used for the learning signals",
        "ilc_signals_case_*.npz": "a case's reference, learned input u and learning signal eps per iteration",
        "ilc_actuator_errors.png": "actuator-side error measure per iteration and case (Figs. 7.7-7.10)",
        "ilc_tool_errors.png": "tool-side error measure per iteration and case (Figs. 7.7-7.10)",
        "ilc_convergence.png": "monotone-convergence picture per case: |Q^-1|, loop gain and their product (7.16)",
        "ilc_tool_path_case_*.png": "a case's tool path over the iterations against the reference square (Fig. 7.11)",
    }
    columns = (
        Column("worst_sigma_max", "worst sigma_max", "{:.3f}"),
        Column("solve_time_s", "solve time [s]", "{:.2f}"),
    )

    @fill_doc(**KIND_DOCS)
    def load(self, doc: ILCFile, file: ProblemFile, name: str) -> ILCDeclaration:
        """Plan the square, build the plant and estimators, check each case's fields (cheap checks only).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        ILCDeclaration

        Raises
        ------
        ProblemError
            The square leaves the workspace (``reference.corner``), the planner fails, two
            cases share a name, the window is longer than the reference, or a case's Q
            cut-off is not below the Nyquist frequency of the loop period. A case's design
            that fails the lifted check it requires (``cases[i].require``) is reported by
            the solve, before any trial (:meth:`ILCDeclaration.check_requirements`).
        """
        with threadpool_limits(limits=1, user_api="blas"):  # (N, N) products and decompositions: threads cost 10-20x CPU on a busy machine
            return self._load(doc, file)

    def _load(self, doc: ILCFile, file: ProblemFile) -> ILCDeclaration:
        plant = build_plant(doc.robot, doc.structure, doc.sensors, file)
        dt = plant.dt  # the loop period: [robot] loop_period, else the actuator models' sample time
        ref = doc.reference
        try:
            T, q, final_time = plan_square(plant.kinematics, ref.corner, ref.side, ref.speed, ref.acceleration, ref.lead,
                                           ref.grid, doc.robot.configuration, plant.dt, ref.rounds)
        except UnreachablePoseError as exc:
            raise file.fail("reference.corner", "a square inside the workspace", f"{ref.corner} ({exc})") from None
        except GtModelError as exc:
            raise file.wrap("reference", exc) from None
        n = len(T)
        if n > MAX_SAMPLES:
            raise file.fail("reference", f"a reference of at most {MAX_SAMPLES} samples (lead-in, square, lead-out)", f"{n} samples")
        il = doc.ilc
        try:
            window = time_window(n, lead=ref.lead, tukey_points=il.tukey_points, alpha=il.tukey_alpha)
        except GtModelError as exc:
            raise file.wrap("ilc.tukey_points", exc) from None
        est = doc.estimators
        try:
            complementary = ComplementaryFilter(est.complementary_cutoff_hz, dt=dt, reading=est.cutoff_reading)
        except GtModelError as exc:
            raise file.wrap("estimators.complementary_cutoff_hz", exc) from None
        try:
            kalman = StationaryKalman(dt=dt, accelerometer_noise=max(doc.sensors.accelerometer_noise, 1e-6),
                                      position_noise=tuple(est.kalman_position_noise), jerk_noise=tuple(est.kalman_jerk_noise), d=2)
        except (GtModelError, ValueError, np.linalg.LinAlgError) as exc:  # a Riccati equation without a stabilising solution
            raise file.fail("estimators", "Kalman noise figures with a stationary solution of the Riccati equation", str(exc)) from None
        comparison, model_kalman = _compare_estimators(plant, q, window, complementary, kalman)
        estimators = {"complementary": complementary, "kalman": model_kalman if est.kalman_form == "model" else kalman,
                      "kalman_triple_integrator": kalman, "kalman_model": model_kalman}
        comparison["kalman_form"] = est.kalman_form
        kin = plant.kinematics
        configuration = doc.robot.configuration
        experiment = ILCExperiment(
            plant, ILCReference(np.arange(n) * dt, T, q, window), LearningFilter(il.gamma, il.delta), il.iterations,
            estimators, lambda X: kin.ik(X, configuration), ref.corner, coupled=il.coupled_check,
        )
        cases: list[ILCCase] = []
        names: set[str] = set()
        for i, c in enumerate(doc.cases):  # the cheap checks; the lifted ones (seconds to minutes) run at solve time
            if c.name in names:
                raise file.fail(f"cases[{i}].name", "a name not used by an earlier case", c.name)
            names.add(c.name)
            if c.q_design == "robust" and c.q_cutoff_hz is None:
                raise file.fail(f"cases[{i}].q_cutoff_hz", "a cut-off for the robust Q design (the thesis: 30 Hz)", None)
            try:
                QFilter(c.q_cutoff_hz, dt=dt, order=c.q_order)  # the cut-off against this loop period's Nyquist frequency
            except GtModelError as exc:
                raise file.wrap(f"cases[{i}].q_cutoff_hz", exc) from None
            cases.append(ILCCase(c.name, c.signal, c.q_cutoff_hz, c.q_order, c.require, c.q_design, c.q_margin))
        return ILCDeclaration(experiment, cases, final_time, estimator_comparison=comparison, rounds=ref.rounds, fail=file.fail)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: ILCDeclaration, solution: ILCOutcome, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, ``table_7_2.md``/``.csv``, ``ilc_iterations.csv``, ``controller.json`` (the stationary Kalman step and the learned
actuator correction of the first case when it learns on the actuators, for
``gtmodel codegen --controller``) and the plots.

        Dressler (2012), Table 7.2 (mean of iterations 5-10 relative to iteration 0) and
        Figs. 7.7-7.11.

        Parameters
        ----------
        declaration : ILCDeclaration
            The experiment.
        solution : ILCOutcome
            Its results.
        {write_args}

        Returns
        -------
        Written
            ``status``; per case the checks per channel, the error measures per iteration
            [m] and the Table 7.2 figures; the thesis' figures beside them. The tables,
            plots and ``controller.json`` are written only when every case converged.
        """
        cases: dict[str, Any] = {}
        rows = []
        for case in declaration.cases:
            r = solution.results[case.name]
            entry: dict[str, Any] = {
                "status": r.status, "message": r.message, "signal": case.signal, "q_cutoff_hz": case.q_cutoff_hz,
                "q_order": case.q_order, "require": case.require, "checks": _channels(r.stability),
                "actuator_error_m": r.actuator_error.tolist(), "tool_error_m": r.tool_error.tolist(),
                "solve_time_s": r.solve_time, "q_design": case.q_design,
            }
            if r.deflection is not None:
                entry["deflection_rms_m"] = np.asarray(r.deflection).tolist()
            if case.q_design == "robust":
                entry["q_margin"] = case.q_margin
            if r.coupled is not None:
                entry["coupled_check"] = {"rho": r.coupled.rho, "sigma_max": r.coupled.sigma_max, "stable": r.coupled.stable,
                                          "monotone": r.coupled.monotone}
            if r.learning_error is not None:
                entry["learning_error"] = np.asarray(r.learning_error).tolist()
            if len(r.actuator_error) > 1:
                act, tool = r.relative("actuator"), r.relative("tool")
                entry["table_7_2"] = {"actuator": act.tolist(), "tool_x": float(tool[0]), "tool_y": float(tool[1])}
                rows.append((case, r, act, tool))
            cases[case.name] = entry
        worst = max((c.sigma_max for r in solution.results.values() for c in r.stability.values()), default=float("nan"))
        fields: dict[str, Any] = {
            "status": solution.status,
            "message": "; ".join(r.message for r in solution.results.values()),
            "sample_time_s": declaration.experiment.plant.dt,
            "samples": declaration.experiment.reference.n,
            "square_final_time_s": declaration.final_time,
            "reference_rounds": declaration.rounds,
            "iterations": declaration.experiment.iterations,
            "error_measure": "RMS of the error over the fully corrected samples (time window 1), eq. 7.25",
            "table_7_2_definition": "mean of the error measure over iterations 5-10 relative to iteration 0",
            "cases": cases,
            "worst_sigma_max": float(worst),
            "estimators": _estimator_figures(declaration),
            "thesis": thesis_table_7_2(),  # Dressler (2012), Table 7.2, from the package data (estimation/ilc/data)
            "solve_time_s": solution.solve_time,
        }
        written = Written(fields)
        if not rows or not solution.status.success:
            return written  # a diverged case: the summary (errors per iteration) only, no table that looks like a result
        header = ["case", "signal", "actuator_1", "actuator_2", "actuator_3", "tool_x", "tool_y", "sigma_max_worst", "rho_worst"]
        lines = [",".join(header)]
        md = ["| case | signal | actuator 1 | actuator 2 | actuator 3 | tool x | tool y | worst sigma_max | worst rho | thesis |",
              "|---|---|---|---|---|---|---|---|---|---|"]
        for case, r, act, tool in rows:
            smax = max(c.sigma_max for c in r.stability.values())
            rho = max(c.rho for c in r.stability.values())
            cells = [f"{v:.4f}" for v in (*act, tool[0], tool[1])]
            lines.append(",".join([csv_field(case.name), csv_field(case.signal), *cells, f"{smax:.4f}", f"{rho:.4f}"]))
            th = fields["thesis"].get(case.name)
            thesis = (f"tool x {th['tool_x']:.3f}, y {th['tool_y']:.3f}; sigma_max {', '.join(f'{v:.2f}' for v in th['sigma_max'])}"
                      + (f"; actuator about {th['actuator_relative_error']:.0%} at k = 5" if "actuator_relative_error" in th else "")
                      if th else "not in the thesis")
            md.append(f"| {case.name} | {case.signal} | " + " | ".join(cells) + f" | {smax:.3f} | {rho:.3f} | {thesis} |")
        (out / "table_7_2.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
        (out / "table_7_2.md").write_text(
            f"# {name}: Table 7.2 layout (Dressler (2012))\n\nError measure (7.25), mean of iterations 5-10 relative to "
            "iteration 0 (1 = no improvement).\n\n" + "\n".join(md) + "\n", encoding="utf-8")
        it = ["case,iteration,actuator_1_m,actuator_2_m,actuator_3_m,tool_x_m,tool_y_m,tool_z_m"]
        for case, r, _, _ in rows:
            for k, (a, t) in enumerate(zip(r.actuator_error, r.tool_error)):
                it.append(",".join([csv_field(case.name), str(k), *(f"{v:.9g}" for v in (*a, *t))]))
        (out / "ilc_iterations.csv").write_text("\n".join(it) + "\n", encoding="utf-8")
        written.files += ["table_7_2.md", "table_7_2.csv", "ilc_iterations.csv"]
        written.files += _exports(declaration, solution, out)
        first = rows[0][1]
        if first.success and first.case.signal == "actuator":
            table = np.asarray(first.correction)
            kalman = declaration.experiment.estimators["kalman_triple_integrator"]  # the one CasADi step of the generated C
            save_controller(out / "controller.json",
                            EstimatorILCBundle(kalman_step=kalman.step_function(), ilc_correction=ilc_correction_function(table), ilc_table=table,
                                       dt=declaration.experiment.plant.dt),
                            description=f"{name}: stationary Kalman step (x, y) and the learned actuator correction of case "
                                        f"{first.case.name}; gtmodel codegen --robot L1 --controller controller.json")
            written.files.append("controller.json")
            fields["controller"] = {"file": "controller.json", "ilc_case": first.case.name, "ilc_table_samples": int(table.shape[0])}
        if plots:
            signals = {c.name: c.signal for c, _, _, _ in rows}  # panel titles "Case 1: actuator positions" (Table 7.2)
            plot_error_measure({c.name: r.actuator_error for c, r, _, _ in rows}, out / "ilc_actuator_errors.png",
                               labels=["actuator 1", "actuator 2", "actuator 3"], signals=signals,
                               title=f"{name}: actuator-side error measure (7.25) per iteration")
            plot_error_measure({c.name: r.tool_error[:, :2] for c, r, _, _ in rows}, out / "ilc_tool_errors.png",
                               labels=["x", "y"], signals=signals, title=f"{name}: tool-side error measure (7.25) per iteration")
            written.files += ["ilc_actuator_errors.png", "ilc_tool_errors.png"]
            plot_convergence(_convergence(declaration, solution), out / "ilc_convergence.png",
                             title=f"{name}: |Q^-1| and the loop gain (Figs. 7.14, 7.17); lifted sigma_max (7.16)")
            written.files.append("ilc_convergence.png")
            ref_T = declaration.experiment.reference.T
            for c, r, _, _ in rows:
                paths = {f"iteration {k}": z for k, z in sorted(r.tool_paths.items())}
                plot_tool_path(ref_T, paths, out / f"ilc_tool_path_case_{c.name}.png",
                               title=f"{name}, case {c.name} ({c.signal}): tool path")
                written.files.append(f"ilc_tool_path_case_{c.name}.png")
        return written


#: Look-ahead of the thesis-form Kalman filter's input: the simulated deflection at t uses z_kin(t + 1)
#: (central second difference), so the model (6.13) is strictly proper in z_kin(t + 2).
MODEL_KALMAN_LOOKAHEAD = 2


def _compare_estimators(plant: Any, q_ref: np.ndarray, window: np.ndarray, complementary: ComplementaryFilter,
                        kalman: StationaryKalman) -> tuple[dict[str, Any], ModelKalman]:
    """The thesis-form Kalman filter tuned on the uncorrected trial, and every estimator's error on it.

    Dressler (2012), eqs. 7.17-7.22 and Fig. 7.1 (the estimation errors of the kinematic
    position, the complementary filter and the Kalman filter against the gauges): the
    uncorrected trial (the reference, trial 0's noise) is simulated; the model (6.13) is the
    plant's own structure (:meth:`~gtmodel.estimation.ToolStructure.kinematic_model`, a
    perfectly identified model); :meth:`ModelKalman.tuned` sets ``R2`` and ``r``; the RMS of
    ``z - z_hat`` over the fully corrected samples is reported per estimator and direction.
    """
    resp = plant.simulate(q_ref, trial=0)
    z_kin, a_m, z = np.asarray(resp.T_kin)[:, :2], np.asarray(resp.a_m)[:, :2], np.asarray(resp.z)[:, :2]
    mask = window >= 1.0 - 1e-12
    model, tuning = ModelKalman.tuned(plant.structure.kinematic_model(plant.dt), plant.dt, z_kin, a_m, z,
                                      lookahead=MODEL_KALMAN_LOOKAHEAD, mask=mask)
    estimates = {"kinematic": z_kin, "complementary": complementary.estimate(z_kin, a_m),
                 "kalman_triple_integrator": kalman.estimate(z_kin, a_m), "kalman_model": model.estimate(z_kin, a_m)}
    rms = {k: error_measure(z - v, mask).tolist() for k, v in estimates.items()}
    closest = min(rms, key=lambda k: float(np.sum(rms[k])))
    return {"estimation_error_rms_m": rms, "closest_to_truth": closest, "kalman_model_tuning": tuning,
            "kalman_model_gain": [k.tolist() for k in model.K], "kalman_model_lookahead": MODEL_KALMAN_LOOKAHEAD,
            "deflection_rms_m": error_measure(z - z_kin, mask).tolist()}, model


def _estimator_figures(declaration: ILCDeclaration) -> dict[str, Any]:
    """The estimators' printed figures: the complementary filter's reading and crossover, the Kalman gain."""
    comp, kal = declaration.experiment.estimators["complementary"], declaration.experiment.estimators["kalman_triple_integrator"]
    # LP and HP = 1 - LP cross where the zero-phase magnitude |H(f)|^2 is 1/2: at the Butterworth design frequency
    return {"complementary_reading": comp.reading, "complementary_cutoff_hz": comp.cutoff_hz.tolist(),
            "complementary_crossover_hz": comp.design_hz.tolist(), "kalman_measurement_gain": np.asarray(kal.M).tolist(),
            **(declaration.estimator_comparison or {})}


def _convergence(declaration: ILCDeclaration, solution: ILCOutcome) -> dict[str, Any]:
    """Per case the data of :func:`~gtmodel.report.ilc.plot_convergence`."""
    e = declaration.experiment
    out: dict[str, Any] = {}
    for case in declaration.cases:
        r = solution.results[case.name]
        f, g = e.loop_gain(case)
        out[case.name] = {"signal": case.signal, "freqs_hz": f, "loop_gain": g, "q": e.q_filter(case).magnitude(f),
                          "sigma": {ch: c.sigma_max for ch, c in r.stability.items()},
                          "coupled": None if r.coupled is None else r.coupled.sigma_max}
    return out


def _exports(declaration: ILCDeclaration, solution: ILCOutcome, out: Path) -> list[str]:
    """The data of an independent check (Dressler (2012), eqs. 7.2-7.22).

    ``ilc_lifted.npz``: ``t``, ``window``, ``gamma``, ``delta``, ``L`` (N, N) and the plant's
    impulse responses linearised at the operating point (``h_actuator`` (N, 3); ``h_kin``,
    ``h_acc``, ``h_tool_position`` (N, 3, 3), ``[k, l, j]`` the response in direction ``l`` to an
    impulse of the tool reference in ``j``); per case ``Q_<case>`` (N, N). ``ilc_estimators.npz``:
    the estimators' lifted matrices ``F_kin_<estimator>``, ``F_acc_<estimator>`` (2, N, N), the
    complementary filter's ``complementary_cutoff_hz``, ``complementary_design_hz``,
    ``complementary_sos`` (2, sections, 6), the Kalman filter's ``kalman_A``, ``kalman_C``,
    ``kalman_Q``, ``kalman_R``, ``kalman_P``, ``kalman_L``, ``kalman_M`` (the triple integrator), the
    thesis-form filter's (7.21)-(7.22) ``kalman_model_{Abar,Bbar,Cbar,P,K}_{x,y}``, ``kalman_model_R2``,
    ``kalman_model_r``, the form Case 2B used (``kalman_form``) and the sensor noise
    covariances ``accelerometer_covariance``, ``gauge_covariance``. ``ilc_signals_case_<case>.npz``:
    the reference ``T_ref``, ``q_ref`` (N, 3) and per trial the correction ``u`` and the learning
    error ``eps`` (K+1, N, 3).
    """
    e = declaration.experiment
    n = e.reference.n
    h = e._impulses()
    lifted: dict[str, Any] = {"t": e.reference.t, "window": e.reference.window, "gamma": e.learning.gamma, "delta": e.learning.delta,
                              "L": e.learning.lifted(n), "h_actuator": h["actuator"], "h_kin": h["kin_full"], "h_acc": h["acc_full"],
                              "h_tool_position": h["tool_position_full"]}
    for case in declaration.cases:
        lifted[f"Q_{case.name}"] = e.q_filter(case).lifted(n)
    np.savez(out / "ilc_lifted.npz", **lifted)
    comp, kal, model = e.estimators["complementary"], e.estimators["kalman_triple_integrator"], e.estimators["kalman_model"]
    est: dict[str, Any] = {"complementary_cutoff_hz": comp.cutoff_hz, "complementary_design_hz": comp.design_hz,
                           "complementary_sos": np.asarray(comp.sos), "complementary_reading": comp.reading}
    for key in ("complementary", "kalman"):
        if any(c.signal == key for c in declaration.cases):
            F_kin, F_acc = e.estimator_matrices(key)
            est[f"F_kin_{key}"], est[f"F_acc_{key}"] = np.asarray(F_kin), np.asarray(F_acc)
    for k in ("A", "C", "Q", "R", "P", "L", "M"):
        est[f"kalman_{k}"] = getattr(kal, k)
    est["kalman_form"] = "model" if e.estimators["kalman"] is model else "triple_integrator"
    est["kalman_model_R2"], est["kalman_model_r"] = model.R2, model.process_noise
    for j, axis in enumerate("xy"):
        for k in ("Abar", "Bbar", "Cbar", "P", "K"):
            est[f"kalman_model_{k}_{axis}"] = getattr(model, k)[j]
    sensors = e.plant.sensors
    est["accelerometer_covariance"] = np.eye(3) * sensors.accelerometer_noise**2
    est["gauge_covariance"] = np.eye(2) * sensors.gauge_noise**2
    np.savez(out / "ilc_estimators.npz", **est)
    files = ["ilc_lifted.npz", "ilc_estimators.npz"]
    for case in declaration.cases:
        r = solution.results[case.name]
        if r.u is None:
            continue
        np.savez_compressed(out / f"ilc_signals_case_{case.name}.npz", T_ref=e.reference.T, q_ref=e.reference.q, u=r.u, eps=r.eps)
        files.append(f"ilc_signals_case_{case.name}.npz")
    return files
