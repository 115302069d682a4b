"""Problem files of kind ``joint_stiffness_calibration``: serial-arm joint stiffnesses, CP vs DPP.

Cvitanic (2021), section 1, eqs. (3)-(5), Tables 1-2: the joint-spring model
``dX = J K_theta^-1 J^T F`` calibrated from (wrench, deflection) pairs by the complete-pose
method with rotation weight 1 (``CP``) and 10 (``CP_rotations_scaled_x10``) and by the
decoupled partial-pose method (``DPP``) of :mod:`gtmodel.calibration.joint_stiffness`::

    name = "kr500_joint_stiffness"
    kind = "joint_stiffness_calibration"

    [arm]
    model = "serial_6r_illustrative"    # shipped DH file or a path (ILLUSTRATIVE geometry)

    [truth]                             # synthetic data on the Table 1 poses
    k_theta = [2.86e6, 2.36e6, 1.67e6, 0.24e6, 0.16e6, 0.14e6]   # N m/rad (default Table 2 DPP)
    scenario = "table_2"                # "none" | "table_2" (unmodelled rotation-only compliance)
    rotation_only_stiffness = 0.3e6     # N m/rad, scenario "table_2" only (default 0.3e6)
    force = 1000.0                      # N per load case
    moment = 200.0                      # N m per load case
    seed = 0

    [noise]                             # optional (defaults: laser tracker, Table 2 notes)
    position_std = 15e-6                # m
    position_std_per_m = 6e-6           # m per m of tracker distance
    rotation_std = 2.6e-4               # rad
    force_relative_std = 0.0

    [calibration]                       # optional
    scaled_rotation_weight = 10.0       # the thesis' "x10"
    bounds = "none"                     # "none" | "positive"

Instead of ``[truth]`` (and ``[noise]``), ``[data] file = "measurements.csv"`` reads
measured rows: a header line ``theta1_deg, ..., theta6_deg, fx_N, fy_N, fz_N, mx_Nm, my_Nm,
mz_Nm, dx_m, dy_m, dz_m, drx_rad, dry_rad, drz_rad`` (:data:`DATA_COLUMNS`), then one
measurement per line (``#`` starts a comment line); an error names the file, the line and
the column. The result folder holds ``summary.json`` (``status``; per method the
identified stiffnesses with standard deviations, the ratio to the truth, residual RMS and
condition numbers; the thesis' Table 2 rows), ``stiffness.csv`` and ``joint_stiffness.png``.
"""

from __future__ import annotations

import csv
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._fields import FieldReader
from gtmodel.errors import GtModelError, InputError, ParameterError, ProblemError

__all__ = [
    "JOINT_STIFFNESS_SCHEMA",
    "DATA_COLUMNS",
    "METHODS",
    "JointStiffnessDeclaration",
    "JointStiffnessOutcome",
    "read_deflection_csv",
    "load_joint_stiffness",
    "solve_joint_stiffness",
    "write_joint_stiffness",
]

_log = logging.getLogger("gtmodel")

#: Allowed fields of a ``joint_stiffness_calibration`` problem file.
JOINT_STIFFNESS_SCHEMA: dict[str, set[str]] = {
    "": {"name", "kind", "description", "arm", "truth", "noise", "calibration", "data"},
    "arm": {"model"},
    "truth": {"k_theta", "scenario", "rotation_only_stiffness", "force", "moment", "seed"},
    "noise": {"position_std", "position_std_per_m", "rotation_std", "force_relative_std"},
    "calibration": {"scaled_rotation_weight", "bounds"},
    "data": {"file"},
}

#: Header of a measured-data CSV (``[data] file``): joint angles [deg], wrench [N, N m],
#: deflection screw [m, rad], base frame.
DATA_COLUMNS = (
    [f"theta{i}_deg" for i in range(1, 7)]
    + ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"]
    + ["dx_m", "dy_m", "dz_m", "drx_rad", "dry_rad", "drz_rad"]
)

#: The calibrations run, named as the rows of Cvitanic (2021), Table 2.
METHODS = ("CP", "CP_rotations_scaled_x10", "DPP")


@dataclass
class JointStiffnessDeclaration:
    """A validated joint-stiffness calibration problem.

    Parameters
    ----------
    arm : SerialArm
        Nominal arm (Jacobian source; also generates synthetic data).
    data : DeflectionData
        Measurements (synthetic or read from a file).
    k_true : numpy.ndarray or None, shape (6,)
        True joint stiffnesses of synthetic data [N m/rad] (None for measured data).
    scaled_rotation_weight : float
        CP rotation weight of the scaled variant [m/rad] (the thesis' 10).
    bounds : str
        ``"none"`` or ``"positive"``.
    source : str
        Description of the data.
    """

    arm: Any
    data: Any
    k_true: np.ndarray | None
    scaled_rotation_weight: float
    bounds: str
    source: str


@dataclass
class JointStiffnessOutcome:
    """Results of a joint-stiffness calibration problem.

    Parameters
    ----------
    results : dict of str to JointStiffnessResult
        One result per name of :data:`METHODS`.
    solve_time : float
        Wall time [s].
    """

    results: dict[str, Any]
    solve_time: float

    @property
    def status(self) -> str:
        """Worst status of the calibrations."""
        from gtmodel.status import Status

        return Status.worst(r.status for r in self.results.values())


def read_deflection_csv(path: Path) -> Any:
    """Read measured (pose, wrench, deflection) rows, strictly validated.

    Cvitanic (2021), eq. (3) data: the header must be :data:`DATA_COLUMNS` (in that order);
    each further non-empty line that does not start with ``#`` is one measurement of 18
    finite numbers. Joint angles are converted from degrees to rad.

    Parameters
    ----------
    path : pathlib.Path
        The CSV file.

    Returns
    -------
    DeflectionData
        The measurements.

    Raises
    ------
    ProblemError
        Unreadable file, wrong header, wrong number of columns or a non-number; the message
        names the file, the line and the column; fewer than 2 measurements.
    """
    from gtmodel.calibration.joint_stiffness import DeflectionData

    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ProblemError(f"{path}: cannot read the data file ({exc.strerror})") from None
    rows: list[list[float]] = []
    header_seen = False
    for lineno, fields in enumerate(csv.reader(text.splitlines()), start=1):
        if not fields or not "".join(fields).strip() or fields[0].lstrip().startswith("#"):
            continue
        cells = [c.strip() for c in fields]
        if not header_seen:
            if cells != DATA_COLUMNS:
                raise ProblemError(f"{path}: line {lineno}: expected the header {','.join(DATA_COLUMNS)}, got {','.join(cells)}")
            header_seen = True
            continue
        if len(cells) != len(DATA_COLUMNS):
            raise ProblemError(f"{path}: line {lineno}: expected {len(DATA_COLUMNS)} columns, got {len(cells)}")
        row = []
        for col, (name, cell) in enumerate(zip(DATA_COLUMNS, cells), start=1):
            try:
                v = float(cell)
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise ProblemError(f"{path}: line {lineno}, column {col} ({name}): expected a finite number, got {cell!r}")
            row.append(v)
        rows.append(row)
    if not header_seen:
        raise ProblemError(f"{path}: expected the header {','.join(DATA_COLUMNS)}, the file is empty")
    if len(rows) < 2:
        raise ProblemError(f"{path}: expected at least 2 measurement lines, got {len(rows)}")
    a = np.array(rows)
    try:
        return DeflectionData(np.radians(a[:, :6]), a[:, 6:12], a[:, 12:], f"measured: {path.name}, {len(rows)} rows")
    except InputError as exc:
        raise ProblemError(f"{path}: {exc}") from None


def load_joint_stiffness(f: FieldReader, name: str) -> JointStiffnessDeclaration:
    """Validate a ``joint_stiffness_calibration`` problem file and prepare the data.

    Cvitanic (2021), Tables 1-2: synthetic data on the Table 1 poses
    (:func:`~gtmodel.calibration.joint_stiffness.synthetic_deflections`) or a measured CSV.

    Parameters
    ----------
    f : FieldReader
        The problem file.
    name : str
        Problem name.

    Returns
    -------
    JointStiffnessDeclaration
        The validated problem.

    Raises
    ------
    ProblemError
        A missing, unknown or invalid field (non-positive stiffness, wrong vector length,
        unknown scenario, both or neither of ``[truth]`` and ``[data]``, a bad data file);
        the message names the file and the field (and line and column of a data file).
    """
    from gtmodel.calibration.joint_stiffness import (
        TABLE_1_POSES_DEG,
        TABLE_2_K_THETA,
        TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS,
        DeflectionNoise,
        axis_wrenches,
        synthetic_deflections,
    )
    from gtmodel.robots.serial import load_serial_arm

    f.check_unknown(JOINT_STIFFNESS_SCHEMA)
    model = f.string("arm", "model", "serial_6r_illustrative")
    try:
        arm = load_serial_arm(model if "/" not in model and not model.endswith(".toml") else (f.path.parent / model).resolve())
    except ParameterError as exc:
        raise ProblemError(f"{f.path}: field 'arm.model': {exc}") from None
    w10 = f.number("calibration", "scaled_rotation_weight", 10.0, positive=True)
    bounds = f.choice("calibration", "bounds", ("none", "positive"), "none")
    has_truth, has_data = f.has("truth"), f.has("data")
    if has_truth == has_data:
        raise ProblemError(f"{f.path}: expected exactly one of the tables [truth] (synthetic data) and [data] (measured CSV)")
    if has_data:
        if f.has("noise"):
            raise ProblemError(f"{f.path}: field 'noise': only for synthetic data ([truth]), not with [data]")
        ref = f.string("data", "file")
        try:
            data = read_deflection_csv((f.path.parent / ref).resolve())
        except GtModelError as exc:
            raise ProblemError(f"{f.path}: field 'data.file': {exc}") from None
        return JointStiffnessDeclaration(arm, data, None, w10, bounds, data.description)
    k = f.vector("truth", "k_theta", 6, TABLE_2_K_THETA["DPP"].tolist(), positive=True)
    scenario = f.choice("truth", "scenario", ("none", "table_2"), "table_2")
    k_r = f.number("truth", "rotation_only_stiffness", TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS, positive=True)
    if scenario == "none" and "rotation_only_stiffness" in f.table("truth", False):
        raise f.fail("truth.rotation_only_stiffness", "no value with scenario = \"none\" (the joint-spring model is exact)")
    force = f.number("truth", "force", 1000.0, positive=True)
    moment = f.number("truth", "moment", 200.0, positive=True)
    seed = f.integer("truth", "seed", 0, 0, 2**31 - 1)
    noise = DeflectionNoise(
        f.number("noise", "position_std", 15e-6, nonnegative=True),
        f.number("noise", "position_std_per_m", 6e-6, nonnegative=True),
        f.number("noise", "rotation_std", 2.6e-4, nonnegative=True),
        f.number("noise", "force_relative_std", 0.0, nonnegative=True),
    )
    idx, F = axis_wrenches(len(TABLE_1_POSES_DEG), force, moment)
    data = synthetic_deflections(
        arm, np.radians(TABLE_1_POSES_DEG)[idx], F, k, noise=noise,
        rotation_only_stiffness=k_r if scenario == "table_2" else None, seed=seed,
    )
    source = f"synthetic on the Table 1 poses ({arm.name}, scenario {scenario!r}): {data.description}"
    return JointStiffnessDeclaration(arm, data, k, w10, bounds, source)


def solve_joint_stiffness(decl: JointStiffnessDeclaration, verbose: bool = False) -> JointStiffnessOutcome:
    """Run the CP (weight 1), CP (scaled rotation weight) and DPP calibrations.

    Cvitanic (2021), eqs. (3)-(5) and Table 2
    (:func:`~gtmodel.calibration.joint_stiffness.calibrate_cp`,
    :func:`~gtmodel.calibration.joint_stiffness.calibrate_dpp`).

    Parameters
    ----------
    decl : JointStiffnessDeclaration
        The problem.
    verbose : bool, optional
        Log the identified stiffnesses.

    Returns
    -------
    JointStiffnessOutcome
        One result per method (each with its status).

    Raises
    ------
    ProblemError
        A calibration that cannot be posed (e.g. an arm without a spherical wrist for DPP).
    """
    from gtmodel.calibration.joint_stiffness import calibrate_cp, calibrate_dpp

    t0 = time.perf_counter()
    try:
        results = {
            "CP": calibrate_cp(decl.arm, decl.data, 1.0, decl.bounds),
            "CP_rotations_scaled_x10": calibrate_cp(decl.arm, decl.data, decl.scaled_rotation_weight, decl.bounds),
            "DPP": calibrate_dpp(decl.arm, decl.data, decl.bounds),
        }
    except GtModelError as exc:
        raise ProblemError(str(exc)) from None
    if verbose:
        for m, r in results.items():
            _log.info("joint stiffness %s: k = %s MN m/rad (%s)", m, np.round(r.k_theta / 1e6, 3).tolist(), r.status)
    return JointStiffnessOutcome(results, time.perf_counter() - t0)


def _finite(a: np.ndarray) -> list[float | None]:
    return [float(x) if np.isfinite(x) else None for x in a]


def _plot(decl: JointStiffnessDeclaration, solution: JointStiffnessOutcome, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    joints = np.arange(1, 7)
    width = 0.8 / len(METHODS)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for i, m in enumerate(METHODS):
        r = solution.results[m]
        k = np.where(np.isfinite(r.k_theta), r.k_theta, np.nan) / 1e6
        std = np.where(np.isfinite(r.std_k_theta), r.std_k_theta, 0.0) / 1e6
        ax.bar(joints + (i - 1) * width, k, width, yerr=std, capsize=2, label=m if m != "CP" else "CP (w = 1)")
    if decl.k_true is not None:
        ax.scatter(joints, decl.k_true / 1e6, marker="_", s=400, color="k", zorder=3, label="truth")
    ax.set_yscale("log")
    ax.set_xticks(joints)
    ax.set_xlabel("joint")
    ax.set_ylabel("k_theta [MN m/rad]")
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_joint_stiffness(
    decl: JointStiffnessDeclaration, solution: JointStiffnessOutcome, out: Path, plots: bool, name: str
) -> tuple[dict[str, Any], list[str]]:
    """Summary fields, the stiffness table and the bar plot of a joint-stiffness calibration.

    Cvitanic (2021), Table 2 (its rows are reported next to the identified values).

    Parameters
    ----------
    decl : JointStiffnessDeclaration
        The problem.
    solution : JointStiffnessOutcome
        Its results.
    out : pathlib.Path
        Result folder (exists).
    plots : bool
        Write the PNG plot.
    name : str
        Problem name (title).

    Returns
    -------
    summary : dict
        ``status``, per method the stiffnesses [N m/rad] with std, ratio to the truth,
        residual RMS, condition numbers; the truth and the thesis' Table 2 rows.
    files : list of str
        Files written besides ``summary.json``.
    """
    from gtmodel.calibration.joint_stiffness import TABLE_2_K_THETA

    methods: dict[str, Any] = {}
    lines = ["method,joint,k_theta_Nm_per_rad,std_Nm_per_rad,ratio_to_truth,thesis_table_2_Nm_per_rad"]
    for m in METHODS:
        r = solution.results[m]
        ratio = r.k_theta / decl.k_true if decl.k_true is not None else None
        methods[m] = {
            "status": r.status,
            "message": r.message,
            "rotation_weight": r.rotation_weight,
            "k_theta_Nm_per_rad": _finite(r.k_theta),
            "std_k_theta_Nm_per_rad": _finite(r.std_k_theta),
            "ratio_to_truth": _finite(ratio) if ratio is not None else None,
            "rms_translation_m": r.rms_translation,
            "rms_rotation_rad": r.rms_rotation,
            "condition_number": r.condition,
            **{k: float(v) for k, v in r.extra.items()},
        }
        for j in range(6):
            cells = [m, str(j + 1), f"{r.k_theta[j]:.9g}", f"{r.std_k_theta[j]:.9g}",
                     f"{ratio[j]:.9g}" if ratio is not None else "", f"{TABLE_2_K_THETA[m][j]:.9g}"]
            lines.append(",".join(cells))
    summary: dict[str, Any] = {
        "status": solution.status,
        "message": "; ".join(f"{m}: {solution.results[m].message.removeprefix(solution.results[m].method + ': ')}" for m in METHODS),
        "source": decl.source,
        "arm": decl.arm.name,
        "n_measurements": int(decl.data.n),
        "bounds": decl.bounds,
        "k_theta_true_Nm_per_rad": decl.k_true.tolist() if decl.k_true is not None else None,
        "methods": methods,
        "thesis_table_2_Nm_per_rad": {m: TABLE_2_K_THETA[m].tolist() for m in METHODS},
        "solve_time_s": solution.solve_time,
    }
    (out / "stiffness.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    files = ["stiffness.csv"]
    if plots:
        _plot(decl, solution, out / "joint_stiffness.png", f"{name}: identified joint stiffnesses")
        files.append("joint_stiffness.png")
    return summary, files
