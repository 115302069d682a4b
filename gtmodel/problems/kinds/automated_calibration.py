"""Kind ``automated_calibration``: one command from *a priori* parameters to accepted poses, a program and a calibration.

Dressler (2012), ch. 5.6 (Fig. 5.21, eq. 5.14, Table 5.7, Figs. 5.22-5.26)::

    name = "l1_automated_calibration"
    kind = "automated_calibration"

    [apriori]                       # e.g. measured with a tape (Table 5.7)
    L  = [2.05, 1.82, 1.81]
    As = [[0.04, 0.0, 1.44], [0.25, -1.31, 1.46], [0.0, 0.0, 0.0]]
    v  = [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]

    [truth]                         # optional: the robot of the simulated calibration
    L = ...                         # (default: a priori moved by simulation.perturbation)

    [limits]
    cart_travel = [[-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0]]
    joint_angle_max_deg = 30.0
    safety_margin = 0.1

    [[obstacles]]                   # boxes, each with its safety zone
    name = "table"
    lo = [...]
    hi = [...]
    safety = 0.1

    [device]                        # what measures, and what it sees
    type = "camera"                 # or "laser_tracker" (position, range)
    position = [1.5, 3.5, 0.55]
    look_at = [1.5, -0.7, 0.55]

    [poses]
    desired = 100
    threshold = 200.0               # C of eq. 5.14

    [data]                          # optional: the measurements taken at the poses
    file = "measured.csv"           # (default: synthetic measurements of the truth)

The result folder holds ``summary.json`` (workspace ratio and points removed per step, per
round the desired count, grid constant, poses, eq. 5.14 per arm and the simulated
calibration; per arm the identifiability report), ``poses.csv`` (the joint positions of the
poses, the program a controller runs), ``calibration_poses.mod`` (the same as a RAPID module
with ``MoveAbsJ``), ``simulated_parameters.csv`` (truth, a priori, calibrated mean, spread and
predicted std per parameter), the calibration from the measurements (``parameters.toml``: the calibrated
kinematics; ``errors.csv``: the validation poses' errors, eq. 5.5) and ``workspace.png``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._escape import toml_comment, toml_string
from gtmodel._docstrings import fill_doc
from gtmodel.calibration.automated import (
    AutomatedCalibrationDeclaration,
    AutomatedCalibrationResult,
    CalibrationWorkspace,
    Obstacle,
    PinholeCamera,
    Tracker,
    home_joint_axes,
    rapid_module,
    write_pose_csv,
)
from gtmodel.calibration.comparison import perturbed_model
from gtmodel.calibration.measurements import read_measurements
from gtmodel.calibration.synthetic import device_noise
from gtmodel.errors import GtModelError
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.schemas.automated_calibration import AutomatedCalibrationFile, ParametersSection
from gtmodel.report.automated import plot_calibration_workspace
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import KinematicParameters

__all__ = ["AutomatedCalibrationKind", "AutomatedCalibrationFile"]

#: Grid step of the load-time check that something remains (coarse: the load stays fast).
_CHECK_STEP_M = 0.2
#: Default device noise per coordinate [m].
_NOISE = {"camera": "stereo_vision", "laser_tracker": "laser_tracker"}


def _parameters(section: ParametersSection, file: ProblemFile, key: str) -> KinematicParameters:
    v = np.asarray(section.v, dtype=float)
    norms = np.linalg.norm(v, axis=1)
    if np.any((norms < 0.5) | (norms > 2.0)):
        raise file.fail(f"{key}.v", "guideway directions of norm about 1 (0.5 < |v_i| < 2)", section.v)
    return KinematicParameters(L=np.asarray(section.L, dtype=float), As=np.asarray(section.As, dtype=float), v=v, model="modified",
                               source=f"{file.path} [{key}]")


def _camera(d: Any, file: ProblemFile) -> PinholeCamera:
    if d.look_at is None:
        raise file.fail("device.look_at", "the point the camera looks at (type = \"camera\")")
    c = np.asarray(d.position, dtype=float)
    z = np.asarray(d.look_at, dtype=float) - c
    if np.linalg.norm(z) < 1e-6:
        raise file.fail("device.look_at", "a point different from device.position", d.look_at)
    z /= np.linalg.norm(z)
    up = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
    x = np.cross(z, up)  # image x to the right of the optical axis, y downwards
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    s = d.pattern_size / 2
    pattern = np.array([sx * s * x + sy * s * y for sx in (-1, 1) for sy in (-1, 1)])
    return PinholeCamera(c, np.column_stack([x, y, z]), d.focal_px, (int(d.image_px[0]), int(d.image_px[1])), pattern)


class AutomatedCalibrationKind(ProblemKind):
    """Automated calibration: workspace, evenly spread poses, eq. 5.14 and a simulated calibration, a program (Dressler (2012), ch. 5.6)."""

    name = "automated_calibration"
    schema = AutomatedCalibrationFile
    title = "automated calibration: workspace, evenly spread poses accepted by eq. 5.14 and a simulated calibration, CSV/RAPID program (Dressler (2012), ch. 5.6)"
    file_descriptions = {
        "poses.csv": "the planned calibration poses: carts [m] and TCP [m]",
        "calibration_poses.mod": "the poses as an ABB RAPID program module",
        "simulated_parameters.csv": "per parameter: truth, a-priori value, calibrated mean, spread and predicted standard deviation of the simulated calibrations",
        "parameters.toml": "the calibrated parameters from the simulated measurements",
        "errors.csv": "TCP error of every validation pose (eq. 5.5) [m]",
        "workspace.png": "the workspace and the accepted poses",
    }
    columns = (
        Column("n_poses", "poses", "{:d}"),
        Column("workspace_ratio", "workspace ratio", "{:.3f}"),
        Column("max_acceptance", "eq. 5.14 (max over arms)", "{:.4g}"),
    )
    extra_empty_fields = ("grid_constant_m", "rounds", "arms")

    @fill_doc(**KIND_DOCS)
    def load(self, doc: AutomatedCalibrationFile, file: ProblemFile, name: str) -> AutomatedCalibrationDeclaration:
        """The a priori model, the workspace tests, the device, and a coarse check that something remains.

        Parameters
        ----------
        {load_args}

        Returns
        -------
        AutomatedCalibrationDeclaration

        Raises
        ------
        ProblemError
            Bad parameters or travel rows; no pose at the home cart positions; an obstacle
            with ``lo >= hi``; a camera without ``look_at``; a coarse grid (0.2 m) on which
            the limits leave no workspace (``limits``), the obstacles swallow all of it (names
            the obstacle) or the device sees none of it (``device``).
        """
        apriori = _parameters(doc.apriori, file, "apriori")
        kin = GantryTau3Kinematics(apriori)
        travel = np.asarray(doc.limits.cart_travel, dtype=float)
        for i, row in enumerate(travel):
            if not row[1] > row[0]:
                raise file.fail(f"limits.cart_travel[{i}]", "[q_min, q_max] with q_min < q_max", row.tolist())
        axes = None
        if doc.limits.joint_axes == "home":
            try:
                axes = home_joint_axes(kin)
            except GtModelError as exc:
                raise file.wrap("limits.joint_axes", exc) from None
        obstacles = []
        for k, o in enumerate(doc.obstacles):
            lo, hi = np.asarray(o.lo), np.asarray(o.hi)
            if not np.all(hi > lo):
                raise file.fail(f"obstacles[{k}].hi", "an upper corner above obstacles[{k}].lo in every coordinate".format(k=k), o.hi)
            obstacles.append(Obstacle(lo, hi, o.safety, o.name))
        d = doc.device
        if d.type == "camera":
            device: Any = _camera(d, file)
        else:
            if not d.range[1] > d.range[0]:
                raise file.fail("device.range", "[min, max] with min < max", d.range)
            device = Tracker(np.asarray(d.position, dtype=float), d.range[0], d.range[1])
        noise = d.noise if d.noise is not None else device_noise(_NOISE[d.type]).position_sigma_m
        ws = CalibrationWorkspace(kin, travel, float(np.radians(doc.limits.joint_angle_max_deg)), doc.limits.safety_margin,
                                  tuple(obstacles), device, axes)
        _check_remaining(ws, file)
        if doc.truth is not None:
            truth = ThreeLinkClosure(_parameters(doc.truth, file, "truth"))
        else:
            truth = perturbed_model(ThreeLinkClosure(apriori), doc.simulation.perturbation, doc.simulation.seed + 7)
        measured = None
        if doc.data is not None:
            try:
                measured = read_measurements(file.data_file("data.file", doc.data.file))
            except GtModelError as exc:
                raise file.wrap("data.file", exc) from None
            if measured.q.shape[1] != 3 or measured.n_poses < 16:
                raise file.fail("data.file", "measurements of a 3-link robot (q1..q3) at 16 poses or more", f"{measured.n_poses} poses")
        p, s = doc.poses, doc.simulation
        return AutomatedCalibrationDeclaration(ws, ThreeLinkClosure(apriori), truth, doc.limits.search_step, p.desired, p.threshold,
                                               float(noise), s.runs, s.recovery_sigmas, p.growth, p.max_rounds, s.seed, p.criterion,
                                               measured)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: AutomatedCalibrationDeclaration, solution: AutomatedCalibrationResult, out: Path, plots: bool,
              name: str) -> Written:
        """Summary fields, ``poses.csv``, ``calibration_poses.mod``, ``simulated_parameters.csv`` and ``workspace.png``.

        Parameters
        ----------
        declaration : AutomatedCalibrationDeclaration
            The problem.
        solution : AutomatedCalibrationResult
            Its result.
        {write_args}

        Returns
        -------
        Written
        """
        r = solution
        fields: dict[str, Any] = {
            "status": r.status,
            "message": r.message,
            "kinematic_points": r.kinematic_points,
            "remaining_points": r.remaining_points,
            "workspace_ratio": r.workspace_ratio,
            "removed_points": r.removed,
            "search_step_m": r.search_step,
            "estimated_volume_m3": r.remaining_points * r.search_step**3,
            "noise_m": declaration.noise_sigma,
            "criterion": declaration.criterion,
            "threshold": declaration.threshold,
        }
        written = Written(fields)
        if not r.rounds:
            return written
        f = r.final
        fields.update({
            "n_poses": int(f.T.shape[0]),
            "desired": f.desired,
            "grid_constant_m": f.grid_constant,
            "max_acceptance": max(f.acceptance),
            "rounds": [_round_fields(x) for x in r.rounds],
            "arms": [
                {
                    "acceptance": f.acceptance[i],
                    "noise_amplification": f.noise_amplification[i],
                    "singular_values_min_max": list(f.singular_values[i]),
                    "rank": rep.rank,
                    "n_parameters": rep.n_parameters,
                    "condition_number_scaled": rep.condition_number,
                    "identifiable": list(rep.identifiable),
                    "non_identifiable": sorted(rep.non_identifiable),
                }
                for i, rep in enumerate(r.identifiability)
            ],
        })
        write_pose_csv(out / "poses.csv", f.q, f.T, f"{name}: {f.T.shape[0]} calibration poses, carts [m] and planned TCP [m] of the a priori model")
        (out / "calibration_poses.mod").write_text(rapid_module(f.q), encoding="utf-8")
        written.files += ["poses.csv", "calibration_poses.mod"]
        if f.simulation is not None:
            sim = f.simulation
            start = declaration.apriori.parameter_vector()
            lines = ["parameter,truth,apriori,calibrated_mean,spread,predicted_std"]
            for k, n in enumerate(sim.names):
                row = (sim.true_parameters[k], start[k], sim.true_parameters[k] + sim.parameter_bias[k], sim.parameter_std[k], sim.predicted_std[k])
                lines.append(n + "," + ",".join(repr(float(x)) for x in row))
            (out / "simulated_parameters.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
            written.files.append("simulated_parameters.csv")
        if r.calibrated is not None:
            written.files += _write_calibrated(r, out, name, fields)
        if plots:
            kin = declaration.workspace.kinematics
            ends = np.array([[kin.As[i] + declaration.workspace.cart_travel[i, k] * kin.v[i] for k in range(2)] for i in range(3)])
            plot_calibration_workspace(r, declaration.workspace.obstacles, declaration.workspace.search_box(), ends,
                                       out / "workspace.png", f"{name}: {f.T.shape[0]} poses, workspace ratio {r.workspace_ratio:.2f}")
            written.files.append("workspace.png")
        return written


def _write_calibrated(r: AutomatedCalibrationResult, out: Path, name: str, fields: dict[str, Any]) -> list[str]:
    """The calibration from the measurements: summary fields, ``parameters.toml``, ``errors.csv``."""
    c = r.calibrated
    res = c.result
    fields["calibration"] = {
        "source": c.source,
        "status": str(res.status),
        "n_calibration": int(res.n_poses),
        "n_validation": int(c.validation_errors.size),
        "validation_error_mean_m": float(c.validation_errors.mean()),
        "validation_error_max_m": float(c.validation_errors.max()),
        "true_error_mean_m": None if c.true_errors is None else float(c.true_errors.mean()),
        "true_error_max_m": None if c.true_errors is None else float(c.true_errors.max()),
        "max_parameter_error": None if c.parameter_errors is None else max(abs(v) for v in c.parameter_errors.values()),
    }
    k = res.model.kinematics
    fmt = lambda a: np.array2string(np.asarray(a), separator=", ", precision=10, max_line_width=400).replace("\n", "")  # noqa: E731
    lines = ["# " + toml_comment(f"Calibrated by gtmodel ({name}, automated calibration) from {c.source}, {res.n_poses} poses; SI units"),
             "# Kinematics only: add [dynamics] and [limits] for a complete parameter set.",
             "[kinematics]", f"source = {toml_string(f'gtmodel automated calibration {name}')}", 'model = "modified"',
             f"L = {fmt(k.L)}", f"As = {fmt(k.As)}", f"v = {fmt(k.v)}", "", "# standard deviations:"]
    lines += ["# " + toml_comment(f"  {n} = {float(v):.3e}") for n, v in res.std.items()]
    (out / "parameters.toml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    errors = [f"{e!r}" for e in c.validation_errors]
    (out / "errors.csv").write_text("# validation poses (every second measured pose), eq. 5.5\nerror_m\n" + "\n".join(errors) + "\n", encoding="utf-8")
    return ["parameters.toml", "errors.csv"]


def _round_fields(x: Any) -> dict[str, Any]:
    out = {
        "desired": x.desired,
        "grid_constant_m": x.grid_constant,
        "n_poses": int(x.T.shape[0]),
        "acceptance": x.acceptance,
        "noise_amplification": x.noise_amplification,
        "accepted_5_14": x.accepted_5_14,
        "recovered": x.recovered,
        "worst_bias_standard_errors": x.worst_recovery,
    }
    if x.simulation is not None:
        out["tcp_error_mean_m"] = float(np.mean(x.simulation.tcp_error_mean))
        out["tcp_error_max_m"] = float(np.max(x.simulation.tcp_error_max))
        out["simulation_statuses"] = list(x.simulation.statuses)
    return out


def _check_remaining(ws: CalibrationWorkspace, file: ProblemFile) -> None:
    """On a coarse grid: the limits leave points, the obstacles do not cover them all, the device sees some."""
    P = ws.grid(_CHECK_STEP_M)
    ok = ws.kinematic(P)
    if not ok.any():
        raise file.fail("limits", f"limits that leave a kinematic workspace (none on a {_CHECK_STEP_M} m grid)")
    P = P[ok]
    left = np.ones(P.shape[0], dtype=bool)
    for k, o in enumerate(ws.obstacles):
        left &= ~o.contains(P)
        if not left.any():
            raise file.fail(f"obstacles[{k}]", f"an obstacle that leaves part of the workspace (with the obstacles before it, '{o.name}' "
                            f"and its safety zone cover all {P.shape[0]} workspace points of a {_CHECK_STEP_M} m grid)")
    if ws.device is not None and not ws.device.sees(P[left]).any():
        raise file.fail("device", f"a device that measures part of the workspace (it sees none of its {int(left.sum())} points on a {_CHECK_STEP_M} m grid)")
