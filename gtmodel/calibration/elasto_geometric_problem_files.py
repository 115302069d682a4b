"""Problem files of kind ``elasto_geometric_calibration``: compliant robot, two models compared.

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
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._fields import FieldReader
from gtmodel.errors import GtModelError, InputError, ParameterError, ProblemError

__all__ = [
    "ELASTO_GEOMETRIC_SCHEMA",
    "ElastoGeometricDeclaration",
    "ElastoGeometricOutcome",
    "load_elasto_geometric",
    "solve_elasto_geometric",
    "write_elasto_geometric",
]

_log = logging.getLogger("gtmodel")

#: Allowed fields of an ``elasto_geometric_calibration`` problem file.
ELASTO_GEOMETRIC_SCHEMA: dict[str, set[str]] = {
    "": {"name", "kind", "description", "truth", "start", "calibration", "stiffness_map"},
    "truth": {"parameters", "stiffness", "payloads_kg", "noise", "grid_step", "seed"},
    "start": {"parameters", "parametrisation", "compliance"},
    "calibration": {"solver", "max_iter", "align", "free_compliance", "compare_single_load"},
    "stiffness_map": {"step", "x"},
}


@dataclass
class ElastoGeometricDeclaration:
    """A validated elasto-geometric calibration problem.

    Parameters
    ----------
    truth : GantryTau3Stiffness
        The true robot (geometry, stated stiffness values; ``payload_kg`` = the largest payload).
    start : ThreeLinkClosure
        Start geometry.
    q : numpy.ndarray, shape (N, 3)
        Grid poses (cart positions) [m].
    payloads_kg : numpy.ndarray, shape (n_loads,)
        Payloads every pose is measured with [kg].
    noise : str
        Device name.
    seed : int
        Noise seed.
    start_compliance : str
        ``"zero"`` or ``"stated"``.
    free_compliance : tuple of str
        Compliance names/patterns estimated.
    solver : str
        Calibration solver.
    max_iter : int
        Iteration limit.
    align : bool
        Frame alignment.
    compare_single_load : bool
        Also calibrate on single-load data.
    map_step : float
        Grid step of the stiffness map [m].
    map_x : float or None
        Section coordinate of the stiffness map [m].
    source : str
        Description of the data.
    """

    truth: Any
    start: Any
    q: np.ndarray
    payloads_kg: np.ndarray
    noise: str
    seed: int
    start_compliance: str
    free_compliance: tuple
    solver: str
    max_iter: int
    align: bool
    compare_single_load: bool
    map_step: float
    map_x: float | None
    source: str


@dataclass
class ElastoGeometricOutcome:
    """Results of an elasto-geometric calibration problem.

    Parameters
    ----------
    study : ElastoGeometricStudy
        The comparison on the declared loads.
    single_load : ElastoGeometricStudy or None
        The same on single-load data (``compare_single_load``).
    stiffness_map : StiffnessMap
        Stiffness of the true robot on a yz section.
    solve_time : float
        Wall time [s].
    """

    study: Any
    single_load: Any
    stiffness_map: Any
    solve_time: float

    @property
    def status(self) -> str:
        """Worst status of the calibrations."""
        from gtmodel.calibration.calibrate import _worst_status

        return _worst_status([self.study.status] + ([self.single_load.status] if self.single_load is not None else []))


def _parameter_set(f: FieldReader, table: str, key: str) -> Any:
    from gtmodel.robots.parameters import available_parameter_sets, load_parameters

    ref = f.string(table, key)
    try:
        return load_parameters(ref if ref in available_parameter_sets() else (f.path.parent / ref).resolve())
    except ParameterError as exc:
        raise ProblemError(f"{f.path}: field '{table}.{key}': {exc}") from None


def load_elasto_geometric(f: FieldReader, name: str) -> ElastoGeometricDeclaration:
    """Validate an ``elasto_geometric_calibration`` problem file and prepare the poses.

    Parameters
    ----------
    f : FieldReader
        The problem file.
    name : str
        Problem name.

    Returns
    -------
    ElastoGeometricDeclaration

    Raises
    ------
    ProblemError
        A missing, unknown or invalid field (negative payload, bad stiffness file, unknown
        compliance pattern, unknown device or solver, a grid too coarse to hold enough
        poses); the message names the file and the field.
    """
    from gtmodel.calibration.calibrate import SOLVERS
    from gtmodel.calibration.elasto_geometric import COMPLIANCE_NAMES, compliance_selection
    from gtmodel.calibration.synthetic import grid_poses
    from gtmodel.robots.closure import ThreeLinkClosure
    from gtmodel.robots.stiffness import GantryTau3Stiffness, load_stiffness

    f.check_unknown(ELASTO_GEOMETRIC_SCHEMA)
    robot = _parameter_set(f, "truth", "parameters")
    sref = f.string("truth", "stiffness", "stiffness")
    try:
        stiff = load_stiffness(sref if sref in ("stiffness", "default") else (f.path.parent / sref).resolve())
    except ParameterError as exc:
        raise ProblemError(f"{f.path}: field 'truth.stiffness': {exc}") from None
    loads = f.vector("truth", "payloads_kg", None, [40.0])
    if np.any(loads < 0):
        raise f.fail("truth.payloads_kg", "non-negative masses [kg]", loads.tolist())
    noise = f.choice("truth", "noise", ("laser_tracker", "stereo_vision", "none"), "laser_tracker")
    step = f.number("truth", "grid_step", positive=True)
    seed = f.integer("truth", "seed", 0, 0, 2**31 - 1)
    truth = GantryTau3Stiffness(robot, stiff, float(loads.max()))
    start_set = _parameter_set(f, "start", "parameters")
    param = f.choice("start", "parametrisation", ("ideal", "modified"), "modified")
    start = ThreeLinkClosure(start_set, model=param)
    start_c = f.choice("start", "compliance", ("zero", "stated"), "zero")
    solver = f.choice("calibration", "solver", SOLVERS, "lm")
    max_iter = f.integer("calibration", "max_iter", 200, 1, 10**6)
    align = f.boolean("calibration", "align", True)
    free = f.get("calibration", "free_compliance", list(COMPLIANCE_NAMES))
    if not isinstance(free, list) or not all(isinstance(x, str) for x in free):
        raise f.fail("calibration.free_compliance", "a list of compliance names or patterns", free)
    try:
        compliance_selection(free)
    except InputError as exc:
        raise ProblemError(f"{f.path}: field 'calibration.free_compliance': {exc}") from None
    single = f.boolean("calibration", "compare_single_load", False)
    map_step = f.number("stiffness_map", "step", 0.05, positive=True)
    map_x = f.number("stiffness_map", "x") if "x" in f.table("stiffness_map", False) else None
    try:
        q = grid_poses(ThreeLinkClosure(robot), step)
    except GtModelError as exc:
        raise ProblemError(f"{f.path}: field 'truth.grid_step': {exc}") from None
    n_par = start.n_parameters + len(free) * 2
    if q.shape[0] // 2 * loads.size * 3 < 2 * n_par or q.shape[0] < 8:
        raise f.fail("truth.grid_step", f"a grid with enough poses for {n_par} parameters (got {q.shape[0]} poses)", step)
    source = (
        f"synthetic compliant {robot.name}: {q.shape[0]} grid poses x payloads {loads.tolist()} kg, "
        f"{noise} noise, seed {seed}; {stiff.describe()}"
    )
    return ElastoGeometricDeclaration(
        truth, start, q, loads, noise, seed, start_c, tuple(free), solver, max_iter, align, single, map_step, map_x, source
    )


def solve_elasto_geometric(decl: ElastoGeometricDeclaration, verbose: bool = False) -> ElastoGeometricOutcome:
    """Run the comparison (and the single-load one), and the stiffness map of the truth.

    Parameters
    ----------
    decl : ElastoGeometricDeclaration
        The problem.
    verbose : bool, optional
        Log progress.

    Returns
    -------
    ElastoGeometricOutcome

    Raises
    ------
    ProblemError
        A calibration that cannot be posed (too few poses, a singular problem naming the
        non-identifiable parameters), or a stiffness-map section outside the workspace.
    """
    from gtmodel.calibration.elasto_geometric import elasto_geometric_study

    t0 = time.perf_counter()
    opts = dict(
        noise=decl.noise, seed=decl.seed, start_compliance=decl.start_compliance, free_compliance=decl.free_compliance,
        solver=decl.solver, align=decl.align, max_iter=decl.max_iter,
    )
    try:
        study = elasto_geometric_study(decl.truth, decl.start, decl.q, payloads_kg=decl.payloads_kg, **opts)
        if verbose:
            _log.info("elasto-geometric study: %s / %s", study.geometric.summary(), study.elasto.summary())
        single = None
        if decl.compare_single_load:
            single = elasto_geometric_study(decl.truth, decl.start, decl.q, payloads_kg=None, **opts)
        T = decl.truth.section_grid(decl.map_x, decl.map_step)
        smap = decl.truth.stiffness_map(T)
    except GtModelError as exc:
        raise ProblemError(str(exc)) from None
    return ElastoGeometricOutcome(study, single, smap, time.perf_counter() - t0)


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


def write_elasto_geometric(
    decl: ElastoGeometricDeclaration, solution: ElastoGeometricOutcome, out: Path, plots: bool, name: str
) -> tuple[dict[str, Any], list[str]]:
    """Summary fields, parameters, errors and plots of an elasto-geometric calibration.

    Parameters
    ----------
    decl : ElastoGeometricDeclaration
        The problem.
    solution : ElastoGeometricOutcome
        Its results.
    out : pathlib.Path
        Result folder (exists).
    plots : bool
        Write PNG plots.
    name : str
        Problem name (titles).

    Returns
    -------
    summary : dict
        ``status``, both models' validation errors, noise floor, improvement,
        identifiability, compliances, stiffness map ranges.
    files : list of str
        Files written besides ``summary.json``.
    """
    from gtmodel.calibration.evaluation import plot_error_histogram
    from gtmodel.report.stiffness import plot_stiffness_map

    st = solution.study
    fields = _study_fields(st)
    smap = solution.stiffness_map
    summary: dict[str, Any] = {
        "status": solution.status,
        "message": f"geometric: {st.geometric.message}; elasto-geometric: {st.elasto.message}",
        "source": decl.source,
        "mean_error_m": st.elasto_report.mean_error,
        "max_error_m": st.elasto_report.max_error,
        **fields,
        "payloads_kg": decl.payloads_kg.tolist(),
        "plate_mass_without_payload_kg": float(decl.truth.plate_mass - decl.truth.payload_kg),
        "solve_time_s": solution.solve_time,
        "solver": decl.solver,
        "stiffness_values": {
            "k_joint_N_per_m": decl.truth.stiffness.k_joint,
            "link_E_Pa": decl.truth.stiffness.E,
            "link_tube_diameters_m": [decl.truth.stiffness.outer_diameter, decl.truth.stiffness.inner_diameter],
            "links_per_arm": decl.truth.stiffness.links_per_arm.tolist(),
            "k_actuator_N_per_m": decl.truth.stiffness.k_actuator.tolist(),
            "sources": dict(decl.truth.stiffness.sources),
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
    files: list[str] = []
    # calibrated parameters with standard deviations: only for a converged calibration (a
    # stopped one's last iterate is not a parameter set to hand to a controller)
    if st.elasto.success:
        _write_parameters(out / "parameters.toml", decl, st, name)
        files.append("parameters.toml")
    cols = np.column_stack([np.arange(st.validation.n_poses), st.geometric_report.errors, st.elasto_report.errors, st.noise_floor.errors])
    np.savetxt(out / "errors.csv", cols, delimiter=",", header="pose,error_m[geometric],error_m[elasto_geometric],error_m[true_model]",
               comments="", fmt="%.9g")
    files.append("errors.csv")
    # the synthetic data (with the per-pose plate load), readable by read_measurements
    for label, data in (("calibration", st.calibration), ("validation", st.validation)):
        data.to_csv(out / f"{label}_measurements.csv")
        files.append(f"{label}_measurements.csv")
    if plots:
        reports = {"geometric only": st.geometric_report, "elasto-geometric": st.elasto_report, "true model": st.noise_floor}
        plot_error_histogram(reports, out / "error_histogram.png", title=f"{name}: TCP error on {st.validation.n_poses} validation poses")
        files.append("error_histogram.png")
        plot_stiffness_map(smap, out / "stiffness_map.png", title=decl.truth.parameters.name)
        files.append("stiffness_map.png")
    return summary, files


def _write_parameters(path: Path, decl: Any, st: Any, name: str) -> None:
    """``parameters.toml``: the calibrated geometric and compliance parameters with std."""
    from gtmodel.calibration.problem_files import _calibrated_tables

    lines = [
        f"# Elasto-geometric calibration ({name}), {decl.solver}, {st.calibration.n_poses} poses; {decl.source}",
        "# Frame: the measurement frame (Dressler (2012), eqs. 5.3-5.4). SI units: m, m/N, N.",
        f'model = "{st.elasto.model.name}"',
        "",
    ] + _calibrated_tables(st.elasto.parameters, st.elasto.std)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
