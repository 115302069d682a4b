"""Kind ``replay`` (formerly ``tracking``, still read with a deprecation warning): replay a planned trajectory through the closed-loop L1 at 4 ms.

Dressler (2012), ch. 7.3, with the plant of :mod:`gtmodel.estimation.closed_loop.plant` (actuators
(6.11), fk, structure (6.14) at the ILC operating point: 7.4 Hz in x, 11.5 Hz in y,
sensors). The trajectory is a ``trajectory.csv`` of kind ``point_to_point`` or
``path_constrained`` (columns ``t, x, y, z, q1, q2, q3``, 4 ms samples), given either as

- ``[trajectory] problem = "l1_time_optimal.toml"``: that problem file is loaded (on
  load), solved (on solve) with its own kind and written into a temporary folder, and its
  ``trajectory.csv`` is read, so the replayed file is exactly what
  ``gtmodel solve l1_time_optimal.toml`` writes; or
- ``[trajectory] file = "results/l1_time_optimal/trajectory.csv"``: a file already written.

The samples must be one loop period (``dt`` = 4 ms) apart (within 1e-9 s); the last step may be shorter
(the final time of a ``point_to_point`` trajectory, where the motion is at rest): that
last row is the rest position, placed on the next 4 ms sample. After the motion the
reference is held for ``settle_time``. The actuator references are the columns
``q1..q3``; the tool reference is ``fk(q_ref)``, checked against the file's ``x, y, z``
(within 1 um: a trajectory of another robot is refused). The field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel._tables import read_table
from gtmodel._toml import read_toml
from gtmodel.errors import GtModelError, InputError, ProblemError
from gtmodel.estimation import TrackingPlant
from gtmodel.estimation.closed_loop.plant import DT
from gtmodel.estimation.closed_loop.replay import TrackingSolution, replay
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.closed_loop_common import build_plant
from gtmodel.problems.kinds.path_constrained import PathConstrainedKind
from gtmodel.problems.kinds.schemas.replay import ReplayFile
from gtmodel.problems.kinds.point_to_point import PointToPointKind
from gtmodel.problems.schema import validate_document
from gtmodel.report.tracking import plot_actuator_error, plot_deflection, plot_tool_error, plot_tool_path

__all__ = ["ReplayFile", "ReplayDeclaration", "TrackingSolution", "ReplayKind", "read_trajectory", "REQUIRED_COLUMNS"]

#: Columns a replayed trajectory must have.
REQUIRED_COLUMNS = ("t", "x", "y", "z", "q1", "q2", "q3")
#: Tolerance on every sample step [s].
DT_TOLERANCE = 1e-9
#: Largest accepted ``|fk(q) - (x, y, z)|`` of a trajectory file [m].
FK_TOLERANCE = 1e-6
#: Most samples of a replayed trajectory (one hour at 4 ms).
MAX_SAMPLES = 900_000
#: Largest trajectory file [bytes] (checked before reading): 900,000 rows of 7 columns at ~20 characters each.
MAX_BYTES = 130_000_000
#: Kinds whose ``trajectory.csv`` can be replayed.
SOURCE_KINDS = {"point_to_point": PointToPointKind(), "path_constrained": PathConstrainedKind()}


@dataclass(frozen=True)
class ReplayDeclaration:
    """A validated ``replay`` problem.

    Parameters
    ----------
    plant : TrackingPlant
        The closed-loop plant.
    settle_time : float
        Hold after the motion [s].
    source : pathlib.Path
        The referenced problem file or trajectory file.
    columns : dict or None
        The trajectory's columns (``file``), or None (``problem``: read after solving).
    source_problem : tuple or None
        ``(kind, declaration, name)`` of a referenced problem, or None.
    origin : ProblemFile
        The replay problem file (for error messages at solve time).
    """

    plant: TrackingPlant
    settle_time: float
    source: Path
    columns: dict[str, np.ndarray] | None
    source_problem: tuple[Any, Any, str] | None
    origin: ProblemFile


def read_trajectory(path: Path, origin: ProblemFile, field_name: str, dt: float = DT) -> dict[str, np.ndarray]:
    """Read and check a ``trajectory.csv`` (a CSV table of :mod:`gtmodel._tables`, 4 ms samples).

    Parameters
    ----------
    path : pathlib.Path
        The CSV file.
    origin : ProblemFile
        The problem file (named in errors).
    field_name : str
        The field that names the trajectory (named in errors).
    dt : float, optional
        Required sample time [s] (default the loop period).

    Returns
    -------
    dict of str to numpy.ndarray
        Every column, each (K,).

    Raises
    ------
    ProblemError
        Unreadable file or a malformed table (:func:`gtmodel._tables.read_table`: the line and
        column named), missing columns (named), fewer than 2 or more than
        :data:`MAX_SAMPLES` rows or :data:`MAX_BYTES` bytes, a sample step other than ``dt``
        (within :data:`DT_TOLERANCE`; the last step may be shorter), decreasing times.
    """
    where = f"the trajectory file {path}"
    try:
        table = read_table(path, "the trajectory file", max_rows=MAX_SAMPLES, max_bytes=MAX_BYTES)
    except InputError as exc:
        raise origin.fail(field_name, f"a readable CSV table ({exc})") from None
    header, data = table.columns, table.data
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise origin.fail(field_name, f"the columns {', '.join(REQUIRED_COLUMNS)} ({where} lacks {', '.join(missing)})")
    if not 2 <= data.shape[0] <= MAX_SAMPLES:
        raise origin.fail(field_name, f"2 to {MAX_SAMPLES} samples ({where} has {data.shape[0]})")
    cols = {name: data[:, k] for k, name in enumerate(header)}
    steps = np.diff(cols["t"])
    body, last = steps[:-1], steps[-1]
    bad = np.nonzero(np.abs(body - dt) > DT_TOLERANCE)[0]
    if bad.size or not 0 < last <= dt + DT_TOLERANCE:
        k = int(bad[0]) if bad.size else steps.size - 1
        raise origin.fail(field_name, f"samples dt = {dt} s apart, column t ({where}: step {steps[k]:.9g} s after row {k + 1})")
    return cols


class ReplayKind(ProblemKind):
    """Replay of a planned trajectory through the closed-loop L1 (:class:`~gtmodel.estimation.TrackingPlant`)."""

    name = "replay"
    schema = ReplayFile
    title = "replay of a planned trajectory through the closed-loop L1 at 4 ms: actuators, structure, sensors (Dressler (2012), ch. 7.3)"
    file_descriptions = {
        "tracking.csv": "the closed-loop run every 4 ms: actuator and TCP references, actual, kinematic and measured positions, accelerations",
        "actuator_error.png": "actuator tracking errors against time",
        "tool_error.png": "tool (TCP) tracking errors against time",
        "deflection.png": "structural deflections against time",
        "tool_path.png": "reference and simulated tool path",
    }
    columns = (
        Column("actuator_error_max_abs_m", "max |q - q_ref| [m]", "{:.3e}"),
        Column("tool_error_max_abs_m", "max |z - T_ref| [m]", "{:.3e}"),
        Column("deflection_max_abs_m", "max |d| [m]", "{:.3e}"),
    )

    @fill_doc(**KIND_DOCS)
    def load(self, doc: ReplayFile, file: ProblemFile, name: str) -> ReplayDeclaration:
        """Build the plant and read (or load the problem of) the trajectory (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        ReplayDeclaration

        Raises
        ------
        ProblemError
            Neither or both of ``trajectory.problem`` and ``trajectory.file``; a missing or
            unreadable file; a referenced problem of another kind or invalid itself; a
            trajectory without the required columns, with another sample time, or not of
            this robot; actuator models of another sample time.
        """
        tr = doc.trajectory
        if (tr.problem is None) == (tr.file is None):
            raise file.fail("trajectory", "exactly one of trajectory.problem (a problem file) and trajectory.file (a trajectory.csv)")
        plant = build_plant(doc.robot, doc.structure, doc.sensors, file)
        if tr.file is not None:
            source = file.data_file("trajectory.file", tr.file)
            columns = read_trajectory(source, file, "trajectory.file", plant.dt)
            self._check_robot(plant, columns, file, "trajectory.file")
            return ReplayDeclaration(plant, tr.settle_time, source, columns, None, file)
        source = file.data_file("trajectory.problem", tr.problem)
        try:
            data = read_toml(source, ProblemError, "problem file")
        except ProblemError as exc:
            raise file.wrap("trajectory.problem", exc) from None
        named = data.get("kind")  # type-checked here: a list or table is not a kind (it was an unhashable key)
        kind = SOURCE_KINDS.get(named) if isinstance(named, str) else None
        if kind is None:
            shown = repr(named) if isinstance(named, str) and len(named) <= 40 else f"a {type(named).__name__}, not a kind name"
            raise file.fail("trajectory.problem", f"a problem file of kind {' or '.join(SOURCE_KINDS)} ({source} is of kind {shown})")
        try:
            sdoc = validate_document(kind.schema, data, source)
            sname = sdoc.name or source.stem
            declaration = kind.load(sdoc, ProblemFile(source), sname)
        except GtModelError as exc:
            raise file.wrap("trajectory.problem", exc) from None
        return ReplayDeclaration(plant, tr.settle_time, source, None, (kind, declaration, sname), file)

    @staticmethod
    def _check_robot(plant: TrackingPlant, cols: dict[str, np.ndarray], file: ProblemFile, field_name: str) -> None:
        q = np.column_stack([cols[f"q{i}"] for i in (1, 2, 3)])
        T = np.column_stack([cols[c] for c in "xyz"])
        try:
            dev = np.linalg.norm(plant.kinematics.fk(q, plant.solution) - T, axis=1)
        except GtModelError as exc:
            raise file.wrap(field_name, exc) from None
        if dev.max() > FK_TOLERANCE:
            k = int(np.argmax(dev))
            raise file.fail(field_name, f"x, y, z = fk(q1, q2, q3) of robot.parameters within {FK_TOLERANCE} m (row {k + 1} is {dev[k]:.3g} m off: another robot?)")

    def solve(self, declaration: ReplayDeclaration, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> TrackingSolution:
        """Solve the referenced problem (if any), then simulate the replay.

        Parameters
        ----------
        declaration : ReplayDeclaration
            From :meth:`load`.
        verbose : bool, optional
            Solver progress of the referenced problem.
        previous : Any, optional
            Unused.
        warm_start : bool, optional
            Unused.

        Returns
        -------
        TrackingSolution
            Status ``"completed"`` with the response, or the referenced problem's status.

        Raises
        ------
        ProblemError
            The referenced problem's trajectory fails the checks of :func:`read_trajectory`.
        """
        d = declaration
        cols, source_status = d.columns, "file"
        if d.source_problem is not None:
            kind, sdecl, sname = d.source_problem
            ssol = kind.solve(sdecl, verbose=verbose)
            source_status = str(kind.status(ssol))
            if source_status not in ("optimal", "acceptable"):
                return TrackingSolution(status=kind.status(ssol), message=f"the referenced problem {d.source} ended with status {source_status}: {ssol.message}", source_status=source_status)
            with tempfile.TemporaryDirectory(prefix="gtmodel-tracking-") as tmp:
                kind.write(sdecl, ssol, Path(tmp), False, sname)
                cols = read_trajectory(Path(tmp) / "trajectory.csv", d.origin, "trajectory.problem", d.plant.dt)
            self._check_robot(d.plant, cols, d.origin, "trajectory.problem")
        q = np.column_stack([cols[f"q{i}"] for i in (1, 2, 3)])
        return replay(d.plant, q, d.settle_time, d.source.name, source_status)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: ReplayDeclaration, solution: TrackingSolution, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, ``tracking.csv`` and plots of a replay.

        Parameters
        ----------
        declaration : ReplayDeclaration
            The declaration.
        solution : TrackingSolution
            Its solution.
        {write_args}

        Returns
        -------
        Written
            Status; max and RMS actuator error per actuator and tool error per direction
            [m] (over the motion and the settling hold), final errors, largest deflection,
            the structure's modes, accelerometer clipping.
        """
        d = declaration
        plant = d.plant
        modes = plant.structure.modes()
        fields: dict[str, Any] = {
            "status": solution.status,
            "message": solution.message,
            "trajectory_source": str(d.source),
            "source_status": solution.source_status,
            "sample_time_s": d.plant.dt,
            "settle_time_s": d.settle_time,
            "structure_modes_hz": modes.natural_frequencies_hz.tolist(),
            "structure_damping": modes.damping_ratios.tolist(),
            "static_deflection_m_per_m_s2": plant.structure.static_deflection().tolist(),
            "actuator_dc_gains": [float(np.squeeze(g.dcgain())) for g in plant.actuators],
        }
        written = Written(fields)
        r = solution.response
        if r is None:
            fields.update({k: None for k in self.empty_fields})
            return written
        e_q, e_T = r.actuator_error, r.tool_error
        n = solution.motion_samples
        end_time = float(r.t[n - 1])
        fields.update({
            "samples": int(r.t.size),
            "motion_samples": n,
            "duration_s": float(r.t[-1]),
            "motion_end_s": end_time,
            "actuator_error_max_m": np.abs(e_q).max(axis=0).tolist(),
            "actuator_error_rms_m": np.sqrt(np.mean(e_q**2, axis=0)).tolist(),
            "actuator_error_final_m": e_q[-1].tolist(),
            "tool_error_max_m": np.abs(e_T).max(axis=0).tolist(),
            "tool_error_rms_m": np.sqrt(np.mean(e_T**2, axis=0)).tolist(),
            "tool_error_final_m": e_T[-1].tolist(),
            "deflection_max_m": np.abs(r.d[:, :2]).max(axis=0).tolist(),
            "tool_acceleration_max_m_s2": np.abs(r.a).max(axis=0).tolist(),
            "accelerometer_clipped_samples": int(np.sum(np.any(np.abs(r.a_m) >= plant.sensors.accelerometer_range, axis=1))),
            "actuator_error_max_abs_m": float(np.abs(e_q).max()),
            "tool_error_max_abs_m": float(np.abs(e_T).max()),
            "deflection_max_abs_m": float(np.abs(r.d).max()),
        })
        table = {"t": r.t}
        for key, prefix in (("q_ref", "q_ref"), ("q", "q")):
            for i in range(3):
                table[f"{prefix}{i + 1}"] = getattr(r, key)[:, i]
        for key, suffix in (("T_ref", "_ref"), ("T_kin", "_kin"), ("d", "_d"), ("z", ""), ("a_kin", "_acc_kin"), ("a", "_acc"), ("a_m", "_acc_m"), ("z_m", "_m")):
            for i, c in enumerate("xyz"):
                table[f"{c}{suffix}"] = getattr(r, key)[:, i]
        written.fields["units"] = {c: "s" if c == "t" else "m/s^2" if "_acc" in c else "m" for c in table}  # the report's axes
        np.savetxt(out / "tracking.csv", np.column_stack(list(table.values())), delimiter=",", header=",".join(table), comments="", fmt="%.10g")
        written.files.append("tracking.csv")
        if plots:
            plot_actuator_error(r.t, e_q, out / "actuator_error.png", title=name, end_time=end_time)
            plot_tool_error(r.t, e_T, out / "tool_error.png", title=name, end_time=end_time)
            plot_deflection(r.t, r.d, out / "deflection.png", title=name, end_time=end_time)
            plot_tool_path(r.T_ref, r.z, out / "tool_path.png", title=name)
            written.files += ["actuator_error.png", "tool_error.png", "deflection.png", "tool_path.png"]
        return written
