"""Kind ``joint_stiffness_calibration``: serial-arm joint stiffnesses, CP vs DPP.

Cvitanic (2021), section 1, eqs. (3)-(5), Tables 1-2: the joint-spring model
``dX = J K_theta^-1 J^T F`` calibrated from (wrench, deflection) pairs by the complete-pose
method with rotation weight 1 (``CP``) and 10 (``CP_rotations_scaled_x10``) and by the
decoupled partial-pose method (``DPP``) of :mod:`gtmodel.calibration.joint_stiffness`.
The data are synthetic (``[truth]``, ``[noise]``: the Table 1 poses, six load cases each)
or measured (``[data] file``, a CSV with the header :data:`DATA_COLUMNS`, one measurement
per line, ``#`` starts a comment line; an error names the file, the line and the column).

The result folder holds ``summary.json`` (``status``; per method the identified
stiffnesses with standard deviations, the ratio to the truth, residual RMS and condition
numbers; the thesis' Table 2 rows), ``stiffness.csv`` and ``joint_stiffness.png``. The
field reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._escape import csv_field
from gtmodel.calibration import DeflectionData, DeflectionNoise, synthetic_deflections
from gtmodel.calibration.joint_stiffness import (
    TABLE_1_POSES_DEG,
    TABLE_2_K_THETA,
    TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS,
    axis_wrenches,
)
from gtmodel.calibration.joint_stiffness_thesis import gravity_pulley_wrenches, three_target_rotation_std
from gtmodel.calibration.joint_stiffness_declared import JointStiffnessDeclaration, JointStiffnessOutcome
from gtmodel.errors import GtModelError, InputError, ParameterError, ProblemError
from gtmodel._docstrings import fill_doc
from gtmodel._tables import read_table
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.schemas.joint_stiffness_calibration import MAX_JOINT_STIFFNESS, MAX_MOMENT_NM, JointStiffnessFile, NoiseSection
from gtmodel.report.stiffness_calibration import plot_joint_stiffness
from gtmodel.robots import load_serial_arm

__all__ = [
    "JointStiffnessKind",
    "JointStiffnessFile",
    "JointStiffnessDeclaration",
    "JointStiffnessOutcome",
    "DATA_COLUMNS",
    "METHODS",
    "SHIPPED_ARMS",
    "MAX_MOMENT_NM",
    "MAX_JOINT_STIFFNESS",
    "read_deflection_csv",
]

_log = logging.getLogger("gtmodel")

#: Header of a measured-data CSV (``[data] file``): joint angles [deg], wrench [N, N m],
#: deflection screw [m, rad], base frame.
DATA_COLUMNS = (
    [f"theta{i}_deg" for i in range(1, 7)]
    + ["fx_N", "fy_N", "fz_N", "mx_Nm", "my_Nm", "mz_Nm"]
    + ["dx_m", "dy_m", "dz_m", "drx_rad", "dry_rad", "drz_rad"]
)

#: The calibrations run, named as the rows of Cvitanic (2021), Table 2.
METHODS = ("CP", "CP_rotations_scaled_x10", "DPP")

#: Serial-arm geometries shipped in ``gtmodel/robots/data`` (``[arm] model`` by name).
SHIPPED_ARMS = ("serial_6r_illustrative",)

#: Most measurement lines of a data CSV (each is 18 numbers; the fit is 6 parameters).
MAX_MEASUREMENTS = 100_000
#: Largest data CSV read [bytes].
MAX_DATA_BYTES = 50_000_000



def read_deflection_csv(path: Path) -> DeflectionData:
    """Read measured (pose, wrench, deflection) rows, strictly validated.

    Cvitanic (2021), eq. (3) data in the CSV table format of :mod:`gtmodel._tables`: the
    header must be :data:`DATA_COLUMNS` (in that order); each further line that does not
    start with ``#`` is one measurement of 18 finite decimal numbers. Joint angles are
    converted from degrees to rad.

    Parameters
    ----------
    path : pathlib.Path
        The CSV file (UTF-8, at most :data:`MAX_DATA_BYTES` bytes and
        :data:`MAX_MEASUREMENTS` measurements).

    Returns
    -------
    DeflectionData
        The measurements.

    Raises
    ------
    ProblemError
        Unreadable, too large or non-UTF-8 file, wrong header, wrong number of columns or
        a non-number (the message names the file, the line and the column); fewer than 2
        or more than :data:`MAX_MEASUREMENTS` measurements; a line identical to an earlier one.
    """
    try:
        table = read_table(path, "the data file", header=DATA_COLUMNS, max_rows=MAX_MEASUREMENTS, max_bytes=MAX_DATA_BYTES)
    except InputError as exc:
        raise ProblemError(str(exc)) from None
    if table.n_rows < 2:
        raise ProblemError(f"{path}: expected at least 2 measurement lines, got {table.n_rows}")
    try:
        table.check_unique_rows()  # a copy-paste slip, as in the other data formats
    except InputError as exc:
        raise ProblemError(str(exc)) from None
    rows, a = table.n_rows, table.data
    try:
        return DeflectionData(np.radians(a[:, :6]), a[:, 6:12], a[:, 12:], f"measured: {path.name}, {rows} rows")
    except InputError as exc:
        raise ProblemError(f"{path}: {exc}") from None


def _finite(a: np.ndarray) -> list[float | None]:
    return [float(x) if np.isfinite(x) else None for x in a]


class JointStiffnessKind(ProblemKind):
    """Joint stiffnesses of a serial arm by CP, CP with scaled rotations and DPP (Cvitanic (2021))."""

    name = "joint_stiffness_calibration"
    schema = JointStiffnessFile
    title = "serial-arm joint stiffnesses by CP, CP x10 and DPP (Cvitanic (2021), eqs. (3)-(5), Table 2)"
    file_descriptions = {
        "stiffness.csv": "identified joint stiffnesses per method and joint with their spread, ratio to the truth and the thesis' Table 2 [N m/rad]",
        "joint_stiffness.png": "the identified joint stiffnesses per method against the true ones",
    }
    columns = (
        Column("n_measurements", "measurements", "{}"),
        Column("solve_time_s", "solve time [s]", "{:.3f}"),
    )

    @fill_doc(**KIND_DOCS)
    def load(self, doc: JointStiffnessFile, file: ProblemFile, name: str) -> JointStiffnessDeclaration:
        """Load the arm, and read or synthesise the data (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        JointStiffnessDeclaration

        Raises
        ------
        ProblemError
            Both or neither of ``[truth]`` and ``[data]``, ``[noise]`` with ``[data]``, a
            rotation-only stiffness with scenario "none", ``noise.rotation_std`` beside
            ``noise.target_radius``, an unknown arm, a bad data file (its line and column named).
        """
        ref = file.reference("arm.model", doc.arm.model, SHIPPED_ARMS)
        try:
            arm = load_serial_arm(ref)
        except ParameterError as exc:
            raise file.wrap("arm.model", exc) from None
        cal = doc.calibration
        if (doc.truth is None) == (doc.data is None):
            raise ProblemError(f"{file.path}: expected exactly one of the tables [truth] (synthetic data) and [data] (measured CSV)")
        if doc.data is not None:
            if doc.noise is not None:
                raise ProblemError(f"{file.path}: field 'noise': only for synthetic data ([truth]), not with [data]")
            path = file.data_file("data.file", doc.data.file)
            try:
                data = read_deflection_csv(path)
            except GtModelError as exc:
                raise file.wrap("data.file", exc) from None
            return JointStiffnessDeclaration(arm, data, None, cal.scaled_rotation_weight, cal.bounds, data.description, cal.rotation_weight,
                                             cal.dpp_step2)
        tr = doc.truth
        if tr.scenario == "none" and tr.rotation_only_stiffness is not None:
            raise file.fail("truth.rotation_only_stiffness", "no value with scenario = \"none\" (the joint-spring model is exact)")
        k_r = tr.rotation_only_stiffness if tr.rotation_only_stiffness is not None else TABLE_2_SCENARIO_ROTATION_ONLY_STIFFNESS
        nz = doc.noise or NoiseSection()
        if nz.target_radius is not None and "rotation_std" in nz.model_fields_set:
            raise file.fail("noise.rotation_std", "no value with noise.target_radius (the three targets give the rotation noise)")
        rot_std = nz.rotation_std if nz.target_radius is None else three_target_rotation_std(nz.position_std, nz.target_radius)
        noise = DeflectionNoise(nz.position_std, nz.position_std_per_m, rot_std, nz.force_relative_std)
        k = np.array(tr.k_theta)
        n = len(TABLE_1_POSES_DEG)
        idx, F = gravity_pulley_wrenches(n, tr.force) if tr.load_cases == "gravity_pulley" else axis_wrenches(n, tr.force, tr.moment)
        theta = np.radians(TABLE_1_POSES_DEG)[idx]
        k_only = k_r if tr.scenario == "table_2" else None

        def data_for_seed(offset: int) -> DeflectionData:
            return synthetic_deflections(arm, theta, F, k, noise=noise, rotation_only_stiffness=k_only, seed=tr.seed + offset)

        try:
            data = data_for_seed(0)
        except InputError as exc:
            raise file.wrap("truth", exc) from None
        source = f"synthetic on the Table 1 poses ({arm.name}, scenario {tr.scenario!r}, loads {tr.load_cases!r}): {data.description}"
        return JointStiffnessDeclaration(arm, data, k, cal.scaled_rotation_weight, cal.bounds, source, cal.rotation_weight, cal.dpp_step2,
                                         data_for_seed, tr.seeds)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: JointStiffnessDeclaration, solution: JointStiffnessOutcome, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, ``stiffness.csv`` and ``joint_stiffness.png`` (Cvitanic (2021), Table 2).

        Parameters
        ----------
        declaration : JointStiffnessDeclaration
            The problem.
        solution : JointStiffnessOutcome
            Its results.
        {write_args}

        Returns
        -------
        Written
            ``status``, per method the stiffnesses [N m/rad] with std, ratio to the truth,
            residual RMS, condition numbers; the truth and the thesis' Table 2 rows; with
            ``[truth] seeds > 1``, ``monte_carlo`` (the methods against the truth and Table 2's
            pattern over the seeds). The
            files are written only when every method succeeded.
        """
        decl = declaration
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
                **{k: (v if isinstance(v, str) else float(v)) for k, v in r.extra.items()},
            }
            for j in range(6):
                cells = [csv_field(m), str(j + 1), f"{r.k_theta[j]:.9g}", f"{r.std_k_theta[j]:.9g}",
                         f"{ratio[j]:.9g}" if ratio is not None else "", f"{TABLE_2_K_THETA[m][j]:.9g}"]
                lines.append(",".join(cells))
        fields: dict[str, Any] = {
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
        if solution.monte_carlo is not None:
            fields["monte_carlo"] = solution.monte_carlo
        written = Written(fields)
        if not solution.status.success:
            return written
        (out / "stiffness.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
        written.files.append("stiffness.csv")
        if plots:
            plot_joint_stiffness(solution.results, METHODS, decl.k_true, out / "joint_stiffness.png", f"{name}: identified joint stiffnesses")
            written.files.append("joint_stiffness.png")
        return written
