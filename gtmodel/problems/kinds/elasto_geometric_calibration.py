"""Kind ``elasto_geometric_calibration``: compliant robot, two models compared.

Dressler (2012), ch. 5.3 (the next step named there) and ch. 6.3: synthetic measurements of a
compliant Gantry-Tau, ``T_m = FK(q) + K_x^-1 F_g + noise`` (:mod:`gtmodel.robots.stiffness`,
:mod:`gtmodel.calibration.elasto_geometric`), calibrated on every second grid pose with the
geometric-only 3-link model and with the elasto-geometric model, both evaluated on the other
poses (eq. 5.5) against the true model's error on the same poses (the noise floor)::

    name = "l1_elasto_geometric"
    kind = "elasto_geometric_calibration"

    [truth]                         # synthetic data (the only source for now)
    parameters = "L1"               # robot parameter set of the true robot
    stiffness = "stiffness"         # stated stiffness values: shipped file or a path
    payloads_kg = [0.0, 40.0]       # every pose measured with each payload (one value: one load)
    noise = "laser_tracker"         # "laser_tracker" | "stereo_vision" | "none"
    grid_step = 0.1153              # m, regular workspace grid
    seed = 0

    [start]
    parameters = "L1_ideal"         # start geometry (set name or path)
    parametrisation = "modified"    # "ideal" (15) | "modified" (21)
    compliance = "zero"             # start compliances: "zero" | "stated"

    [calibration]                   # optional
    solver = "lm"
    max_iter = 200
    align = true
    free_compliance = ["c_l*", "c_a*"]
    compare_single_load = true      # also calibrate on one load (the largest payload)

    [stiffness_map]                 # optional: stiffness map of the true robot on a yz section
    step = 0.05                     # m
    # x = -0.1                      # m, section (default: the workspace median)

The pose grid and the stiffness-map section are bounded up front (their point counts are
computed from the workspace box and the steps before anything is built).

The result folder holds ``summary.json`` (``status``; validation mean/max errors of both
models and of the true model; the improvement; identifiability of the compliances with the
geometry: rank, condition number, non-identifiable parameters with dependencies and
explanations; calibrated compliances vs the truth; the stiffness map ranges vs the D1's
measured 2-4 N/um), ``parameters.toml``, ``errors.csv``, ``calibration_measurements.csv`` and
``validation_measurements.csv`` (the synthetic poses in the measurement-file format of
:mod:`gtmodel.calibration.measurements`; with several payloads each pose's plate load in the
columns ``F_x_N, F_y_N, F_z_N``), ``error_histogram.png`` and ``stiffness_map.png``.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._escape import toml_comment, toml_string
from gtmodel.calibration import grid_poses
from gtmodel.report.calibration import plot_error_histogram
from gtmodel.calibration.elasto_geometric import compliance_selection
from gtmodel.calibration.elasto_geometric_declared import ElastoGeometricDeclaration, ElastoGeometricOutcome
from gtmodel.errors import GtModelError
from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS, ProblemFile, ProblemKind, Written
from gtmodel.calibration.grid_count import axis_count
from gtmodel.problems.kinds.calibration import MAX_GRID_CANDIDATES, calibration_columns
from gtmodel.problems.kinds.calibration_results import calibrated_tables
from gtmodel.problems.kinds.schemas.elasto_geometric_calibration import MAX_PAYLOAD_KG, ElastoGeometricFile
from gtmodel.problems.references import robot_parameters
from gtmodel.robots import GantryTau3Kinematics, GantryTau3Stiffness, load_stiffness
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.report.stiffness import plot_stiffness_map

__all__ = [
    "ElastoGeometricKind",
    "ElastoGeometricFile",
    "ElastoGeometricDeclaration",
    "ElastoGeometricOutcome",
    "MAX_PAYLOAD_KG",
    "MAX_MAP_POINTS",
]

_log = logging.getLogger("gtmodel")

#: Largest number of points of the stiffness-map section examined (one statics solve each).
MAX_MAP_POINTS = 20_000
#: Shipped stiffness files.
_STIFFNESS_SETS = ("stiffness", "default")


class ElastoGeometricKind(ProblemKind):
    """Geometric-only vs elasto-geometric calibration of a compliant robot (Dressler (2012), ch. 5.3, 6.3)."""

    name = "elasto_geometric_calibration"
    schema = ElastoGeometricFile
    title = "compliant robot: geometric-only vs elasto-geometric calibration (Dressler (2012), ch. 5.3, 6.3)"
    file_descriptions = {
        "parameters.toml": "the elasto-geometric calibrated parameters, loadable as a robot file",
        "errors.csv": "TCP error of every validation pose, geometric-only and elasto-geometric [m]",
        "calibration_measurements.csv": "the simulated measurements the calibration used",
        "validation_measurements.csv": "the simulated measurements of the validation poses",
        "error_histogram.png": "histogram of the validation TCP errors of both calibrations",
        "stiffness_map.png": "TCP compliance over the workspace",
    }
    columns = calibration_columns()
    extra_empty_fields = ("geometric_mean_error_m", "geometric_max_error_m", "elasto_geometric_mean_error_m",
                    "elasto_geometric_max_error_m", "noise_floor_mean_error_m", "noise_floor_max_error_m", "n_calibration",
                    "n_validation", "iterations")

    @fill_doc(**KIND_DOCS)
    def load(self, doc: ElastoGeometricFile, file: ProblemFile, name: str) -> ElastoGeometricDeclaration:
        """Resolve the parameter sets, check the compliance patterns and build the pose grid.

        Parameters
        ----------
        {load_args}

        Returns
        -------
        ElastoGeometricDeclaration

        Raises
        ------
        ProblemError
            A bad parameter set or stiffness file, an unknown compliance pattern, a grid
            or stiffness-map section with too many points, a grid too coarse to hold enough
            poses, a section outside the workspace; the message names the file and the field.
        """
        t, s, c, m = doc.truth, doc.start, doc.calibration, doc.stiffness_map
        robot = robot_parameters(file, "truth.parameters", t.parameters)
        target = file.reference("truth.stiffness", t.stiffness, _STIFFNESS_SETS)
        try:
            stiff = load_stiffness(target)
        except GtModelError as exc:
            raise file.wrap("truth.stiffness", exc) from None
        loads = np.array(t.payloads_kg, dtype=float)
        truth = GantryTau3Stiffness(robot, stiff, float(loads.max()))
        start_set = robot_parameters(file, "start.parameters", s.parameters)
        start = ThreeLinkClosure(start_set, model=s.parametrisation)
        try:
            compliance_selection(c.free_compliance)
        except GtModelError as exc:
            raise file.wrap("calibration.free_compliance", exc) from None
        box = GantryTau3Kinematics(robot).workspace_bounds()
        cap = MAX_GRID_CANDIDATES["three_link"]
        count = math.prod(axis_count(lo, hi, t.grid_step) for lo, hi in box)
        if count > cap:
            raise file.fail("truth.grid_step", f"a grid step giving at most {cap} grid poses (this one gives {count:.3g})", t.grid_step)
        points = axis_count(*box[1], m.step) * axis_count(*box[2], m.step)
        if points > MAX_MAP_POINTS:
            raise file.fail("stiffness_map.step", f"a step giving at most {MAX_MAP_POINTS} section points (this one gives {points:.3g})", m.step)
        if m.x is not None and not box[0, 0] <= m.x <= box[0, 1]:
            raise file.fail("stiffness_map.x", f"a section within the workspace box x in [{box[0, 0]:.4g}, {box[0, 1]:.4g}] m", m.x)
        try:
            q = grid_poses(ThreeLinkClosure(robot), t.grid_step)
        except GtModelError as exc:
            raise file.wrap("truth.grid_step", exc) from None
        n_par = start.n_parameters + len(c.free_compliance) * 2
        if q.shape[0] // 2 * loads.size * 3 < 2 * n_par or q.shape[0] < 8:
            raise file.fail("truth.grid_step", f"a grid with enough poses for {n_par} parameters (got {q.shape[0]} poses)", t.grid_step)
        source = (
            f"synthetic compliant {robot.name}: {q.shape[0]} grid poses x payloads {loads.tolist()} kg, "
            f"{t.noise} noise, seed {t.seed}; {stiff.describe()}"
        )
        return ElastoGeometricDeclaration(
            truth, start, q, loads, t.noise, t.seed, s.compliance, tuple(c.free_compliance), c.solver, c.max_iter, c.align,
            c.compare_single_load, m.step, m.x, source,
        )

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: ElastoGeometricDeclaration, solution: ElastoGeometricOutcome, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, parameters, errors, the synthetic measurements and plots.

        ``parameters.toml`` is written only for a converged elasto-geometric calibration (a
        stopped one's last iterate is not a parameter set to hand to a controller).

        Parameters
        ----------
        declaration : ElastoGeometricDeclaration
            The problem.
        solution : ElastoGeometricOutcome
            Its results.
        {write_args}

        Returns
        -------
        Written
        """
        return _write(declaration, solution, out, plots, name)


def _study_fields(st: Any) -> dict[str, Any]:
    g, e, n = st.geometric_report, st.elasto_report, st.noise_floor
    ident = st.identifiability
    return {
        "geometric_mean_error_m": g.mean_error,
        "geometric_max_error_m": g.max_error,
        "elasto_geometric_mean_error_m": e.mean_error,
        "elasto_geometric_max_error_m": e.max_error,
        "noise_floor_mean_error_m": n.mean_error,
        "noise_floor_max_error_m": n.max_error,
        "improvement_mean_error_m": g.mean_error - e.mean_error,
        "improvement_ratio": g.mean_error / e.mean_error if e.mean_error > 0 else None,
        "gravity_deflection_mean_m": float(st.deflection.mean()),
        "gravity_deflection_max_m": float(st.deflection.max()),
        "n_calibration": st.calibration.n_poses,
        "n_validation": st.validation.n_poses,
        "status_geometric": st.geometric.status,
        "status_elasto_geometric": st.elasto.status,
        "iterations": int(st.geometric.iterations + st.elasto.iterations),
        "identifiability": {
            "rank": int(ident.rank),
            "n_parameters": int(ident.n_parameters),
            "condition_number": float(ident.condition_number),
            "non_identifiable": sorted(ident.non_identifiable),
            "compliance_std_m_per_N": {k: float(v) for k, v in st.elasto.std.items() if k.startswith("c_")},
        },
        "load_identifiability": {
            "rank": int(st.load_identifiability.rank),
            "n_parameters": int(st.load_identifiability.n_parameters),
            "non_identifiable": {k: v.get("depends_on", {}) for k, v in st.load_identifiability.non_identifiable.items()},
            "explanations": list(st.explanations),
        },
        "compliances": st.compliance_table(),
    }


def _write(decl: ElastoGeometricDeclaration, solution: ElastoGeometricOutcome, out: Path, plots: bool, name: str) -> Written:
    st = solution.study
    smap = solution.stiffness_map
    stiffness = decl.truth.stiffness
    summary: dict[str, Any] = {
        "status": solution.status,
        "message": f"geometric: {st.geometric.message}; elasto-geometric: {st.elasto.message}",
        "source": decl.source,
        "mean_error_m": st.elasto_report.mean_error,
        "max_error_m": st.elasto_report.max_error,
        **_study_fields(st),
        "payloads_kg": decl.payloads_kg.tolist(),
        "plate_mass_without_payload_kg": float(decl.truth.plate_mass - decl.truth.payload_kg),
        "solve_time_s": solution.solve_time,
        "solver": decl.solver,
        "stiffness_values": {
            "k_joint_N_per_m": stiffness.k_joint,
            "link_E_Pa": stiffness.E,
            "link_tube_diameters_m": [stiffness.outer_diameter, stiffness.inner_diameter],
            "links_per_arm": stiffness.links_per_arm.tolist(),
            "k_actuator_N_per_m": stiffness.k_actuator.tolist(),
            "sources": dict(stiffness.sources),
        },
        "stiffness_map": smap.summary(),
    }
    if solution.single_load is not None:
        s1 = _study_fields(solution.single_load)
        summary["single_load"] = {k: s1[k] for k in (
            "geometric_mean_error_m", "geometric_max_error_m", "elasto_geometric_mean_error_m",
            "elasto_geometric_max_error_m", "noise_floor_mean_error_m", "noise_floor_max_error_m",
            "improvement_mean_error_m", "gravity_deflection_mean_m", "identifiability", "load_identifiability",
        )}
        summary["single_load"]["payload_kg"] = float(decl.truth.payload_kg)
    written = Written(summary)
    if st.elasto.success:
        _write_parameters(out / "parameters.toml", decl, st, name)
        written.files.append("parameters.toml")
    cols = np.column_stack([np.arange(st.validation.n_poses), st.geometric_report.errors, st.elasto_report.errors, st.noise_floor.errors])
    np.savetxt(out / "errors.csv", cols, delimiter=",", header="pose,error_m[geometric],error_m[elasto_geometric],error_m[true_model]",
               comments="", fmt="%.9g")
    written.files.append("errors.csv")
    # the synthetic data (with the per-pose plate load), readable by read_measurements
    for label, data in (("calibration", st.calibration), ("validation", st.validation)):
        data.to_csv(out / f"{label}_measurements.csv")
        written.files.append(f"{label}_measurements.csv")
    if plots:
        reports = {"geometric only": st.geometric_report, "elasto-geometric": st.elasto_report, "true model": st.noise_floor}
        plot_error_histogram(reports, out / "error_histogram.png", title=f"{name}: TCP error on {st.validation.n_poses} validation poses")
        plot_stiffness_map(smap, out / "stiffness_map.png", title=decl.truth.parameters.name)
        written.files += ["error_histogram.png", "stiffness_map.png"]
    return written


def _write_parameters(path: Path, decl: ElastoGeometricDeclaration, st: Any, name: str) -> None:
    """``parameters.toml``: the calibrated geometric and compliance parameters with std."""
    lines = [
        "# " + toml_comment(f"Elasto-geometric calibration ({name}), {decl.solver}, {st.calibration.n_poses} poses; {decl.source}"),
        "# Frame: the measurement frame (Dressler (2012), eqs. 5.3-5.4). SI units: m, m/N, N.",
        f"model = {toml_string(st.elasto.model.name)}",
        "",
    ] + calibrated_tables(st.elasto.parameters, st.elasto.std)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
