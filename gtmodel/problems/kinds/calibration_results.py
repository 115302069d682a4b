"""Result files of the kinematic calibration kinds: summary rows, ``errors.csv``, ``parameters.toml``.

With synthetic data, the summary also compares the first model with its true robot (the
Monte-Carlo study's input, :mod:`gtmodel.problems.study.analyses.calibration_monte_carlo`):
``parameters`` (per parameter: ``estimate``, ``truth``, predicted ``std`` and its
``role``) and ``truth_mean_error_m``/``truth_max_error_m`` (TCP error against the
noise-free true robot on all candidate poses). The frame: synthetic measurements are
taken in the true robot's frame, and the calibration identifies the parameters in the
measurement frame (the alignment of eqs. 5.3-5.4 only moves the start), so estimate and
truth are compared as they are; quaternion parameters are compared with the sign of the
truth (``q`` and ``-q`` are the same rotation).

``parameters.toml`` of a 3-link result is a complete robot parameter set (Dressler (2012),
Table 5.1 layout); other models get ``[calibrated]`` and ``[standard_deviation]`` tables
(:func:`calibrated_tables`, shared with the elasto-geometric kind).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from gtmodel._escape import toml_comment, toml_string
from gtmodel._geometry import rotation_to_zyz
from gtmodel.calibration import tcp_errors
from gtmodel.errors import GtModelError
from gtmodel.report.calibration import plot_error_histogram
from gtmodel.problems.base import Written
from gtmodel.robots.closure import ThreeLinkClosure

__all__ = ["write_calibration", "calibrated_tables", "parameters_vs_truth", "measured_orientation_range_deg"]


def _within_3_std(res: Any, truth: Any) -> dict[str, Any] | None:
    """How many calibrated parameters lie within 3 reported standard deviations of the truth."""
    if truth is None or type(truth) is not type(res.model) or tuple(truth.parameter_names()) != tuple(res.model.parameter_names()):
        return None
    true = dict(zip(truth.parameter_names(), truth.parameter_vector()))
    n_free = n_in = 0
    worst = 0.0
    for k, v in res.parameters.items():
        s = res.std.get(k, 0.0)
        if s and np.isfinite(s) and s > 0:
            n_free += 1
            z = abs(v - true[k]) / s
            worst = max(worst, z)
            n_in += int(z <= 3.0)
    return {"n_free": n_free, "n_within_3_std": n_in, "max_z": worst}


def parameters_vs_truth(res: Any, truth: Any, ties: Any = ()) -> dict[str, dict[str, Any]] | None:
    """Per parameter of a calibration: estimate, truth, predicted standard deviation, role.

    Parameters
    ----------
    res : CalibrationResult
        The calibration (parameters in the measurement frame).
    truth : ClosureModel or None
        The true robot of synthetic data (its frame is the measurement frame).
    ties : sequence of (str, str), optional
        ``(target, source)`` ties of the parameter selection.

    Returns
    -------
    dict or None
        Name -> ``{"estimate", "truth", "std", "role"}`` with ``role`` one of ``"free"``,
        ``"fixed"`` (std 0), ``"tied"`` (a tie target) and ``"non_identifiable"`` (std
        not finite); None without a truth of the same model type and parameter names.
    """
    if truth is None or type(truth) is not type(res.model) or tuple(truth.parameter_names()) != tuple(res.model.parameter_names()):
        return None
    names = list(truth.parameter_names())
    true = np.asarray(truth.parameter_vector(), dtype=float)
    est = np.array([res.parameters[n] for n in names])
    for qi in res.model.quaternion_indices():  # q and -q: the same rotation
        if float(est[list(qi)] @ true[list(qi)]) < 0:
            est[list(qi)] *= -1.0
    targets = {t for t, _ in ties}
    out = {}
    for n, e, t in zip(names, est, true):
        s = float(res.std.get(n, np.nan))
        role = "fixed" if s == 0 else "non_identifiable" if not np.isfinite(s) else "tied" if n in targets else "free"
        out[n] = {"estimate": float(e), "truth": float(t), "std": s, "role": role}
    return out


def _truth_errors(res: Any, decl: Any) -> dict[str, float]:
    """TCP error of a calibrated model against the noise-free truth on all candidate poses."""
    if decl.truth is None or not decl.truth_exact or res is None or not res.success:
        return {}
    q = decl.measurements.q
    try:
        e = tcp_errors(res.model, q, np.atleast_2d(decl.truth.fk(q)[0]))
    except GtModelError:
        return {}
    return {"truth_mean_error_m": float(e.mean()), "truth_max_error_m": float(e.max())}


def _closure_figures(res: Any) -> dict[str, Any]:
    """Per-link RMS closure residual, the conditioning and the least determined parameter of a calibration.

    The RMS of ``||A - B||^2 - L^2`` over the calibration poses [m^2] is ``sqrt(V_j / N)`` of the
    thesis' final cost per link (Dressler (2012), Tables 5.8-5.9); divided by ``2 L`` it is the
    length error along the link [m].
    """
    r = np.asarray(res.residuals, dtype=float)
    names = [n for arm in getattr(res.model, "links", ()) for n in arm]
    ident = res.identifiability
    finite = {k: v for k, v in res.std.items() if v and np.isfinite(v)}
    worst = max(finite, key=finite.get) if finite else None
    out: dict[str, Any] = {
        "cost_per_arm": [float(c) for c in res.cost_per_arm],
        "link_residual_rms_m2": np.sqrt(np.mean(r**2, axis=0)).tolist() if r.size else [],
        "condition_number": float(ident.condition_number),
    }
    if len(names) == r.shape[-1]:
        out["links"] = names
    if worst is not None:
        out["least_determined"] = {"name": worst, "std": float(finite[worst])}
    return out


def measured_orientation_range_deg(data: Any) -> list[float] | None:
    """Range (max - min) of the measured plate orientation's ZYZ Euler angles over all poses.

    The figure of Dressler (2012), Fig. 4.7 (D1: 0.1 deg in alpha to 0.5 deg in beta).

    Parameters
    ----------
    data : MeasurementSet
        Measured poses (``quat`` (N, 4) ``(w, x, y, z)`` or None).

    Returns
    -------
    list of float or None
        ``[alpha, beta, gamma]`` ranges [deg]; None without orientations.
    """
    quat = getattr(data, "quat", None)
    if quat is None:
        return None
    R = Rotation.from_quat(np.asarray(quat, dtype=float)[:, [1, 2, 3, 0]]).as_matrix()
    e = np.unwrap(rotation_to_zyz(R), axis=0)
    return np.degrees(e.max(axis=0) - e.min(axis=0)).tolist()


def _model_row(name: str, res: Any, rep: Any, msg: str, decl: Any, start: Any) -> dict[str, Any]:
    row: dict[str, Any] = {"name": name, "status": res.status if res else ("optimal" if rep is not None else "error"), "message": msg}
    if res is not None:
        ident = res.identifiability
        row.update(
            rank=int(ident.rank),
            n_parameters=int(ident.n_parameters),
            non_identifiable=sorted(ident.non_identifiable),
            iterations=int(res.iterations),
            solve_time_s=float(res.solve_time),
            cost=float(res.cost),
            quaternion_norms=res.quaternion_norms,
        )
        row.update(_closure_figures(res))
        check = _within_3_std(res, decl.truth)
        if check is not None:
            row["parameters_vs_truth"] = check
    if rep is not None:
        row.update(rep.to_dict())
    if start is not None:
        row["start_mean_error_m"] = start.mean_error
        row["start_max_error_m"] = start.max_error
        row["start_poses_without_assembly"] = int(getattr(start, "skipped", 0))
        if start.angle_errors is not None:
            row["start_max_angle_error_deg"] = float(np.rad2deg(start.angle_errors.max()))
    return row


def write_calibration(decl: Any, outcome: Any, out: Path, plots: bool, title: str) -> Written:
    """Summary fields, ``parameters.toml``, ``errors.csv`` and the histogram of a calibration.

    Parameters
    ----------
    decl : CalibrationDeclaration
        The problem.
    outcome : CalibrationOutcome
        Its results.
    out : pathlib.Path
        Result folder (exists).
    plots : bool
        Write the PNG histogram.
    title : str
        Problem name (titles, the name of the calibrated parameter set).

    Returns
    -------
    Written
        The required figures of the first model and a ``models`` table of all; the files.
    """
    starts = outcome.extra.get("start_reports", {})
    rows = [_model_row(name, res, rep, msg, decl, starts.get(name)) for name, res, rep, msg in outcome.results]
    first = rows[0]
    summary: dict[str, Any] = {
        "status": outcome.status,
        "message": first.get("message", ""),
        "source": decl.source,
        "mean_error_m": first.get("mean_error_m"),
        "max_error_m": first.get("max_error_m"),
        "rms_error_m": first.get("rms_error_m"),
        "n_calibration": outcome.calibration.n_poses,
        "n_validation": outcome.validation.n_poses,
        "rank": first.get("rank"),
        "n_parameters": first.get("n_parameters"),
        "non_identifiable": first.get("non_identifiable"),
        "iterations": first.get("iterations"),
        "solve_time_s": outcome.solve_time,
        "solver": decl.solver,
        "models": rows,
    }
    if outcome.noise_floor is not None:
        # the true robot on the same noisy poses: the noise floor when the data come from it
        # exactly; with actuator errors, what the linear-actuator truth misses
        key = "noise_floor" if decl.truth_exact else "truth_without_actuator_errors"
        summary[f"{key}_mean_error_m"] = outcome.noise_floor.mean_error
        summary[f"{key}_max_error_m"] = outcome.noise_floor.max_error
    orient = measured_orientation_range_deg(decl.measurements)
    if orient is not None:
        summary["measured_orientation_range_deg"] = orient
    if outcome.selected is not None:
        summary["selected_poses"] = int(outcome.selected.size)
    summary.update(outcome.extra.get("pose_choice", {}))
    res0 = outcome.results[0][1]
    if res0 is not None:
        summary.update(_truth_errors(res0, decl))
        table = parameters_vs_truth(res0, decl.truth, decl.models[0]["selection"].ties)
        if table is not None:
            summary["parameters"] = table
    written = Written(summary)
    reports = {name: rep for name, _, rep, _ in outcome.results if rep is not None}
    if res0 is not None and res0.success:
        _write_parameters(res0, out / "parameters.toml", decl, title)
        written.files.append("parameters.toml")
    if reports:
        cols = {"pose": np.arange(outcome.validation.n_poses)}
        for name, rep in reports.items():
            head = f"error_m[{name}]"
            cols['"' + head.replace('"', '""') + '"' if any(c in head for c in ',"') else head] = rep.errors  # RFC 4180 quoting
        np.savetxt(out / "errors.csv", np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="", fmt="%.9g")
        written.files.append("errors.csv")
        if plots:
            plot_error_histogram(reports, out / "error_histogram.png", title=f"{title}: TCP error on {outcome.validation.n_poses} validation poses")
            written.files.append("error_histogram.png")
    return written


def _write_parameters(res: Any, path: Path, decl: Any, title: str) -> None:
    """Calibrated parameters as TOML; a 3-link result is a complete robot parameter set."""
    model = res.model
    lines = [
        "# " + toml_comment(f"Calibrated by gtmodel ({title}), {decl.solver}, {res.n_poses} poses; {decl.source}"),
        "# Frame: the measurement frame (Dressler (2012), eqs. 5.3-5.4). SI units.",
    ]
    if isinstance(model, ThreeLinkClosure):
        k = model.kinematics
        robot = model.robot
        lines += [
            f"name = {toml_string(f'{title}_calibrated')}",
            f"description = {toml_string(f'calibrated {model.model} 3-link model')}",
            "",
            "[kinematics]",
            f"source = {toml_string(f'gtmodel calibration {title}')}",
            f"model = {toml_string(model.model)}",
            f"L = {np.array2string(k.L, separator=', ', precision=10, max_line_width=200)}",
            f"As = {np.array2string(k.As, separator=', ', precision=10, max_line_width=400)}".replace("\n", ""),
            f"v = {np.array2string(k.v, separator=', ', precision=10, max_line_width=400)}".replace("\n", ""),
        ]
        if robot is not None:
            d, lim = robot.dynamics, robot.limits
            lines += [
                "",
                "[dynamics]",
                f"source = {toml_string(f'copied from the start parameter set {robot.name}')}",
                f"m_p = {d.m_p!r}",
                f"m_c = {list(map(float, d.m_c))}",
                f"m_a = {list(map(float, d.m_a))}",
                f"f_c = {list(map(float, d.f_c))}",
                f"f_v = {list(map(float, d.f_v))}",
                f"g = {d.g!r}",
                "",
                "[limits]",
                f"source = {toml_string(f'copied from the start parameter set {robot.name}')}",
                f"cart_travel = {lim.cart_travel.tolist()}",
                f"joint_angle_max_deg = {float(np.rad2deg(lim.joint_angle_max))!r}",
            ]
        # the parameter-set schema has no table for them: comments
        lines += ["", "# standard deviations (from the Jacobian and the residual variance):"]
        lines += ["# " + toml_comment(f"  {n} = {float(s):.3e}") for n, s in res.std.items()]
    else:
        lines += [f"model = {toml_string(model.name)}", ""]
        lines += calibrated_tables(res.parameters, res.std, "  # name = value [m, rad, 1]", "  # from the Jacobian and the residual variance")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def calibrated_tables(parameters: dict[str, float], std: dict[str, float], comment: str = "", std_comment: str = "") -> list[str]:
    """TOML lines of the ``[calibrated]`` values and their ``[standard_deviation]``.

    Shared by the result files (``parameters.toml``) of the calibration kinds.

    Parameters
    ----------
    parameters : dict of str to float
        Calibrated values by name.
    std : dict of str to float
        Standard deviations by name (``nan`` when not finite).
    comment : str, optional
        Text after the ``[calibrated]`` header.
    std_comment : str, optional
        Text after the ``[standard_deviation]`` header.

    Returns
    -------
    list of str
        The lines, without newlines.
    """
    return (
        [f"[calibrated]{comment}"]
        + [f'"{n}" = {v!r}' for n, v in parameters.items()]
        + ["", f"[standard_deviation]{std_comment}"]
        + [f'"{n}" = {float(s)!r}' if np.isfinite(s) else f'"{n}" = nan' for n, s in std.items()]
    )
