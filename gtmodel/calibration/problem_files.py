"""Problem files of kind ``calibration``: kinematic calibration from closure equations.

Dressler (2012), ch. 5: measured poses (a CSV file, or synthetic data from a declared
"true" robot), one or several models calibrated on every second pose and evaluated on the
others (eq. 5.5), with identifiability and parameter uncertainties::

    name = "l1_calibration"
    kind = "calibration"

    [data]                          # either a measurement file ...
    # file = "measurements.csv"     #   (format: gtmodel.calibration.measurements)
    # cart_file = "carts.csv"       #   (cart surveys, for piecewise-linear actuator models)

    [truth]                         # ... or synthetic measurements (say so in the file)
    model = "three_link"            # "three_link" | "six_link" | "f1"
    parameters = "L1"               # parameter set of the true robot
    noise = "laser_tracker"         # "laser_tracker" (10 um) | "stereo_vision" (1.7 mm) | "none"
    actuator_errors = "none"        # "none" | "table_4_1" (cyclic error, straightness, backlash)
    grid_step = 0.1153              # m, regular grid in the workspace ...
    # random_poses = 400            # ... or this many random poses
    seed = 0

    [[models]]                      # one table per model to calibrate and compare
    name = "modified"
    type = "three_link"             # "three_link" | "three_link_piecewise" | "six_link"
                                    # | "six_link_piecewise" | "f1"
    parametrisation = "modified"    # three_link only: "ideal" (15) | "modified" (21)
    start = "L1_ideal"              # start parameters: a set name/path, or "truth"
    perturbation = 0.0              # m, random start perturbation of every length/point
    fixed = []                      # parameter names or patterns kept at the start
    ties = []                       # e.g. ["Abj_2b_z = Abj_2a_z"]

    [calibration]                   # optional
    solver = "lm"                   # "lm" | "trf" | "ipopt" | "ipopt-gn"
    max_iter = 200
    align = true                    # move the start model into the measurement frame (5.3)-(5.4)

    [pose_selection]                # optional: choose poses from the candidates by eq. 5.9
    n = 185

The result folder holds ``summary.json`` (``status``, ``mean_error_m``, ``max_error_m``,
``rms_error_m``, ``n_calibration``, ``n_validation``, ``rank``, ``n_parameters``,
``non_identifiable``, ``iterations``, ``solve_time_s`` of the first model, and a ``models``
table for all), ``parameters.toml`` (the first model's calibrated parameters; a 3-link
result is a complete robot parameter set), ``errors.csv`` and ``error_histogram.png``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._fields import FieldReader
from gtmodel.errors import GtModelError, InputError, ParameterError, ProblemError

__all__ = [
    "CALIBRATION_SCHEMA",
    "MODEL_TYPES",
    "CalibrationDeclaration",
    "CalibrationOutcome",
    "load_calibration",
    "solve_calibration",
    "write_calibration",
]

_log = logging.getLogger("gtmodel")

#: Model types a calibration problem can declare.
MODEL_TYPES = ("three_link", "three_link_piecewise", "six_link", "six_link_piecewise", "f1")

#: Allowed fields of a ``calibration`` problem file.
CALIBRATION_SCHEMA: dict[str, set[str]] = {
    "": {"name", "kind", "description", "data", "truth", "models", "calibration", "pose_selection"},
    "data": {"file", "cart_file"},
    "truth": {"model", "parameters", "perturbation", "noise", "actuator_errors", "grid_step", "grid_step_deg", "random_poses", "seed", "rotary_travel_deg", "rotary_step_deg"},
    "calibration": {"solver", "max_iter", "align"},
    "pose_selection": {"n"},
}
_MODEL_KEYS = {"name", "type", "parametrisation", "start", "perturbation", "fixed", "ties"}


@dataclass
class CalibrationDeclaration:
    """A validated calibration problem.

    Parameters
    ----------
    measurements : MeasurementSet
        All poses (before the calibration/validation split).
    cart : CartMeasurements or None
        Cart surveys (piecewise-linear actuator models).
    models : list of dict
        Per model: ``name``, ``type``, ``model`` (start ClosureModel), ``selection``.
    truth : ClosureModel or None
        The true robot of synthetic data (for the noise floor and parameter checks).
    noise_sigma : float or None
        Position noise of synthetic data [m].
    solver, max_iter, align : str, int, bool
        Calibration options.
    source : str
        Where the data come from.
    pose_selection : int or None
        Number of poses to select (eq. 5.9) before splitting.
    truth_exact : bool
        The synthetic data come from ``truth`` exactly (no actuator errors), so its error on
        the data is the noise floor.
    """

    measurements: Any
    cart: Any
    models: list
    truth: Any
    noise_sigma: float | None
    solver: str
    max_iter: int
    align: bool
    source: str
    pose_selection: int | None = None
    truth_exact: bool = True


def _closure_from(kind: str, ref: str, f: FieldReader, field_name: str, parametrisation: str = "modified") -> Any:
    """A ClosureModel of a type from a parameter-set reference."""
    try:
        if kind.startswith("three_link"):
            from gtmodel.robots.closure import ThreeLinkClosure
            from gtmodel.robots.parameters import available_parameter_sets

            path = ref if ref in available_parameter_sets() else str((f.path.parent / ref).resolve())
            return ThreeLinkClosure(path, model=parametrisation)
        if kind.startswith("six_link"):
            from gtmodel.robots.six_link import load_six_link

            return load_six_link(ref if "/" not in ref and not ref.endswith(".toml") else str((f.path.parent / ref).resolve()))
        from gtmodel.robots.f1 import load_f1

        return load_f1(ref if "/" not in ref and not ref.endswith(".toml") else str((f.path.parent / ref).resolve()))
    except (ParameterError, InputError) as exc:
        raise ProblemError(f"{f.path}: field '{field_name}': {exc}") from None


def _perturbed(model: Any, size: float, seed: int, keep: Any = ()) -> Any:
    """Start model with every parameter moved by up to ``size`` (lengths/points) at random.

    Direction-like parameters (guideway ``v`` and quaternions) are perturbed by ``size``
    relative to their unit size, so the start error stays of the order of ``size`` [m].
    Parameters matching a pattern in ``keep`` (fixed ones, tie targets) are not moved:
    a calibration cannot recover a value it holds fixed.
    """
    if size == 0.0:
        return model
    from fnmatch import fnmatchcase

    rng = np.random.default_rng(seed)
    p = model.parameter_vector().copy()
    step = rng.uniform(-size, size, p.size)
    names = model.parameter_names()
    held = [any(fnmatchcase(n, k) or n.startswith(k + "_") for k in keep) for n in names]
    p += np.where(held, 0.0, step)
    return model.with_parameters(p)


def load_calibration(f: FieldReader, name: str) -> CalibrationDeclaration:
    """Validate a ``calibration`` problem file and prepare its data and models.

    Synthetic data are generated here (seeded, so a file always gives the same data).

    Parameters
    ----------
    f : FieldReader
        The problem file.
    name : str
        Problem name.

    Returns
    -------
    CalibrationDeclaration

    Raises
    ------
    ProblemError
        A missing, unknown or invalid field; both or neither of ``[data]`` and
        ``[truth]``; a malformed measurement file (the message names its row); fewer poses
        than the models need.
    """
    from gtmodel.calibration.kinematic import SOLVERS, CalibrationProblem, ParameterSelection
    from gtmodel.calibration.measurements import read_cart_measurements, read_measurements
    from gtmodel.calibration.synthetic import ActuatorErrors, device_noise, synthetic_cart_measurements, synthetic_measurements
    from gtmodel.calibration.poses import grid_poses, random_poses

    f.check_unknown(CALIBRATION_SCHEMA)
    has_data, has_truth = f.has("data"), f.has("truth")
    if has_data == has_truth:
        raise ProblemError(f"{f.path}: declare exactly one of '[data]' (a measurement file) and '[truth]' (synthetic data)")
    models_raw = f.get("", "models")
    if not isinstance(models_raw, list) or not models_raw or not all(isinstance(m, dict) for m in models_raw):
        raise f.fail("models", "one or more [[models]] tables")
    truth = None
    cart = None
    noise_sigma = None
    if has_data:
        rel = f.string("data", "file")
        try:
            data = read_measurements((f.path.parent / rel).resolve())
            if "cart_file" in f.table("data", True):
                cart = read_cart_measurements((f.path.parent / f.string("data", "cart_file")).resolve())
        except InputError as exc:
            raise ProblemError(f"{f.path}: field 'data': {exc}") from None
        source = f"measurements from {rel}"
    else:
        tkind = f.choice("truth", "model", ("three_link", "six_link", "f1"), ...)
        truth = _closure_from(tkind, f.string("truth", "parameters"), f, "truth.parameters")
        # a robot that differs from its parameter set (built tolerances): every parameter moved
        truth = _perturbed(truth, f.number("truth", "perturbation", 0.0, nonnegative=True), 7)
        noise_name = f.choice("truth", "noise", ("laser_tracker", "stereo_vision", "none"), "laser_tracker")
        noise = device_noise(noise_name)
        noise_sigma = noise.position_sigma_m
        errors_name = f.choice("truth", "actuator_errors", ("none", "table_4_1"), "none")
        errors = ActuatorErrors.table_4_1() if errors_name == "table_4_1" else None
        seed = f.integer("truth", "seed", 0, 0, 2**31 - 1)
        rotary = None
        rot_step = None
        if "rotary_travel_deg" in f.table("truth", True):
            rotary = np.deg2rad(np.asarray(f.get("truth", "rotary_travel_deg"), dtype=float))
            rot_step = float(np.deg2rad(f.number("truth", "rotary_step_deg", 10.0, positive=True)))
        try:
            if "grid_step" in f.table("truth", True) and tkind == "f1":
                # the F1's own 6-D workspace grid (position and orientation steps)
                _, _, q = truth.workspace_grid(
                    step_m=f.number("truth", "grid_step", positive=True),
                    step_deg=f.number("truth", "grid_step_deg", 10.0, positive=True),
                    return_q=True,
                )
            elif "grid_step" in f.table("truth", True):
                q = grid_poses(truth, f.number("truth", "grid_step", positive=True), rotary_travel=rotary, rotary_step=rot_step)
            else:
                q = random_poses(truth, f.integer("truth", "random_poses", 400, 2, 10**6), seed=seed, rotary_travel=rotary)
            data = synthetic_measurements(truth, q, noise=noise, actuator_errors=errors, seed=seed)
            if any(str(m.get("type", "")).endswith("_piecewise") for m in models_raw):
                cart = synthetic_cart_measurements(truth, errors, noise=noise, seed=seed + 1)
        except GtModelError as exc:
            raise ProblemError(f"{f.path}: field 'truth': cannot generate the synthetic data: {exc}") from None
        source = f"synthetic: truth {tkind} '{f.string('truth', 'parameters')}', {noise_name} noise, actuator errors {errors_name}, seed {seed}, {data.n_poses} poses"
    models = []
    for k, raw in enumerate(models_raw):
        key = f"models[{k}]"
        unknown = set(raw) - _MODEL_KEYS
        if unknown:
            raise ProblemError(f"{f.path}: unknown field '{key}.{sorted(unknown)[0]}' (allowed here: {', '.join(sorted(_MODEL_KEYS))})")
        mf = FieldReader({"m": raw}, f.path)
        mtype = mf.choice("m", "type", MODEL_TYPES, ...)
        mname = raw.get("name", mtype)
        param = mf.choice("m", "parametrisation", ("ideal", "modified"), "modified")
        start_ref = raw.get("start", "truth")
        if not isinstance(start_ref, str):
            raise f.fail(f"{key}.start", 'a parameter-set name/path or "truth"', start_ref)
        if start_ref == "truth":
            if truth is None:
                raise f.fail(f"{key}.start", 'a parameter set (there is no [truth] with measured data)', start_ref)
            ref = f.string("truth", "parameters")
            base_type = "three_link" if mtype.startswith("three_link") else "six_link" if mtype.startswith("six_link") else "f1"
            start = _closure_from(base_type, ref, f, f"{key}.start", param)
        else:
            base_type = "three_link" if mtype.startswith("three_link") else "six_link" if mtype.startswith("six_link") else "f1"
            start = _closure_from(base_type, start_ref, f, f"{key}.start", param)
        pert = float(raw.get("perturbation", 0.0))
        held = [*raw.get("fixed", []), *(t.split("=")[0].strip() for t in raw.get("ties", []) if isinstance(t, str))]
        start = _perturbed(start, pert, 1000 + k, keep=held)
        if mtype.endswith("_piecewise"):
            if cart is None:
                raise f.fail("data.cart_file", f"cart surveys for the piecewise-linear model '{mname}'")
            from gtmodel.robots.actuator import PiecewiseActuatorClosure

            try:
                start = PiecewiseActuatorClosure.from_model(start, cart, extrapolate=True)
            except GtModelError as exc:
                raise ProblemError(f"{f.path}: field '{key}': {exc}") from None
        for lst in ("fixed", "ties"):
            val = raw.get(lst, [])
            if not isinstance(val, list) or not all(isinstance(x, str) for x in val):
                raise f.fail(f"{key}.{lst}", "a list of strings", val)
        try:
            selection = ParameterSelection(fixed=tuple(raw.get("fixed", [])), ties=tuple(raw.get("ties", [])))
            CalibrationProblem(start, selection)  # resolves names and ties (errors name them)
        except InputError as exc:
            raise ProblemError(f"{f.path}: field '{key}': {exc}") from None
        if start.n_q != data.n_q:
            raise f.fail(f"{key}.type", f"a model with {data.n_q} actuator values per pose (the data's)", mtype)
        models.append({"name": str(mname), "type": mtype, "model": start, "selection": selection})
    solver = f.choice("calibration", "solver", SOLVERS, "lm")
    max_iter = f.integer("calibration", "max_iter", 200, 1, 10**6)
    align = f.boolean("calibration", "align", True)
    n_sel = f.integer("pose_selection", "n", None, 2, 10**6) if f.has("pose_selection") else None
    if n_sel is not None and n_sel >= data.n_poses:
        raise f.fail("pose_selection.n", f"fewer poses than the {data.n_poses} candidates", n_sel)
    exact = truth is not None and not (has_truth and f.get("truth", "actuator_errors", "none") != "none")
    return CalibrationDeclaration(data, cart, models, truth, noise_sigma, solver, max_iter, align, source, n_sel, exact)


@dataclass
class CalibrationOutcome:
    """Results of a calibration problem: one calibration and evaluation per model.

    Parameters
    ----------
    declaration : CalibrationDeclaration
        The problem.
    calibration, validation : MeasurementSet
        The poses used to calibrate and to evaluate.
    results : list
        Per model: ``(name, CalibrationResult or None, AccuracyReport or None, message)``.
    noise_floor : AccuracyReport or None
        The true robot's errors on the validation poses (synthetic data only): what a
        perfect model achieves on the same noise.
    selected : numpy.ndarray or None
        Indices of the selected poses (pose selection).
    solve_time : float
        Total wall time [s].
    extra : dict
        Further figures for reports.
    """

    declaration: CalibrationDeclaration
    calibration: Any
    validation: Any
    results: list
    noise_floor: Any = None
    selected: Any = None
    solve_time: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def status(self) -> str:
        """Worst status over the models (``error`` if a model could not be calibrated)."""
        from gtmodel.status import Status

        return Status.worst(res.status if res is not None else ("optimal" if rep is not None else "error") for _, res, rep, _ in self.results)

    @property
    def success(self) -> bool:
        """True when every model calibrated to an optimal solution."""
        return self.status == "optimal"


def solve_calibration(decl: CalibrationDeclaration, verbose: bool = False) -> CalibrationOutcome:
    """Calibrate every declared model on every second pose and evaluate on the others.

    Parameters
    ----------
    decl : CalibrationDeclaration
        The problem.
    verbose : bool, optional
        Log progress per model.

    Returns
    -------
    CalibrationOutcome
        Never None; a model whose calibration failed has ``None`` results and a message.

    Raises
    ------
    ProblemError
        Too few poses for a model's free parameters, or an unidentifiable request (the
        message lists the offending parameters and what they depend on).
    """
    from gtmodel.calibration.kinematic import CalibrationProblem
    from gtmodel.calibration.evaluation import evaluate

    t0 = time.perf_counter()
    data = decl.measurements
    selected = None
    if decl.pose_selection is not None:
        from gtmodel.calibration.pose_selection import select_poses

        first = decl.models[0]
        sel = select_poses(first["model"], data.q, decl.pose_selection, T=data.T, quat=data.quat, selection=first["selection"])
        selected = np.asarray(sel.indices)
        data = data.subset(np.sort(selected))
    cal, val = data.split_alternate()
    results = []
    starts: dict[str, Any] = {}
    for spec in decl.models:
        _log.info("calibrating %s (%s) on %d poses ...", spec["name"], spec["type"], cal.n_poses)
        try:
            res = CalibrationProblem(spec["model"], spec["selection"]).solve(
                cal, solver=decl.solver, align=decl.align, max_iter=decl.max_iter
            )
        except (InputError, GtModelError) as exc:
            raise ProblemError(f"model '{spec['name']}': {exc}") from None
        try:
            report = evaluate(res.model, val, label=spec["name"]) if res.success else None
            msg = res.message
        except GtModelError as exc:
            report, msg = None, f"evaluation failed: {exc}"
        start_report = _start_report(spec["model"].transformed(res.rotation, res.translation), val)
        results.append((spec["name"], res, report, msg))
        starts[spec["name"]] = start_report
    floor = None
    if decl.truth is not None:
        try:
            floor = evaluate(decl.truth, val, label="true robot (noise floor)")
        except GtModelError:
            floor = None
    return CalibrationOutcome(decl, cal, val, results, floor, selected, time.perf_counter() - t0, {"start_reports": starts})


def _start_report(model: Any, val: Any) -> Any:
    """The uncalibrated start on the validation poses; poses where it cannot assemble are skipped."""
    from gtmodel.calibration.evaluation import evaluate

    try:
        return evaluate(model, val, label="start")
    except GtModelError:
        pass
    reps = []
    for k in range(val.n_poses):
        try:
            reps.append(evaluate(model, val.subset([k]), label="start"))
        except GtModelError:
            continue
    if not reps:
        return None
    from gtmodel.calibration.evaluation import AccuracyReport

    rep = AccuracyReport(np.vstack([r.error_vectors for r in reps]), label="start")
    rep.skipped = val.n_poses - len(reps)
    return rep


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


def write_calibration(decl: CalibrationDeclaration, outcome: CalibrationOutcome, out: Path, plots: bool, title: str) -> tuple[dict[str, Any], list[str]]:
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
        Plot title.

    Returns
    -------
    summary : dict
        The required figures of the first model and a ``models`` table of all.
    files : list of str
        Files written besides ``summary.json``.
    """
    from gtmodel.report.calibration import plot_error_histogram

    rows = []
    for name, res, rep, msg in outcome.results:
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
            check = _within_3_std(res, decl.truth)
            if check is not None:
                row["parameters_vs_truth"] = check
        if rep is not None:
            row.update(rep.to_dict())
        start = outcome.extra.get("start_reports", {}).get(name)
        if start is not None:
            row["start_mean_error_m"] = start.mean_error
            row["start_max_error_m"] = start.max_error
            row["start_poses_without_assembly"] = int(getattr(start, "skipped", 0))
            if start.angle_errors is not None:
                row["start_max_angle_error_deg"] = float(np.rad2deg(start.angle_errors.max()))
        rows.append(row)
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
    if outcome.selected is not None:
        summary["selected_poses"] = int(outcome.selected.size)
    files: list[str] = []
    reports = {name: rep for name, _, rep, _ in outcome.results if rep is not None}
    res0 = outcome.results[0][1]
    if res0 is not None and res0.success:
        _write_parameters(res0, out / "parameters.toml", decl, title)
        files.append("parameters.toml")
    if reports:
        cols = {"pose": np.arange(outcome.validation.n_poses)}
        for name, rep in reports.items():
            cols[f"error_m[{name}]"] = rep.errors
        header = ",".join(cols)
        np.savetxt(out / "errors.csv", np.column_stack(list(cols.values())), delimiter=",", header=header, comments="", fmt="%.9g")
        files.append("errors.csv")
        if plots:
            plot_error_histogram(reports, out / "error_histogram.png", title=f"{title}: TCP error on {outcome.validation.n_poses} validation poses")
            files.append("error_histogram.png")
    return summary, files


def _write_parameters(res: Any, path: Path, decl: CalibrationDeclaration, title: str) -> None:
    """Calibrated parameters as TOML; a 3-link result is a complete robot parameter set."""
    from gtmodel.robots.closure import ThreeLinkClosure

    model = res.model
    lines = [
        f"# Calibrated by gtmodel ({title}), {decl.solver}, {res.n_poses} poses; {decl.source}",
        "# Frame: the measurement frame (Dressler (2012), eqs. 5.3-5.4). SI units.",
    ]
    if isinstance(model, ThreeLinkClosure):
        k = model.kinematics
        robot = model.robot
        lines += [
            f'name = "{title}_calibrated"',
            f'description = "calibrated {model.model} 3-link model"',
            "",
            "[kinematics]",
            f'source = "gtmodel calibration {title}"',
            f'model = "{model.model}"',
            f"L = {np.array2string(k.L, separator=', ', precision=10, max_line_width=200)}",
            f"As = {np.array2string(k.As, separator=', ', precision=10, max_line_width=400)}".replace("\n", ""),
            f"v = {np.array2string(k.v, separator=', ', precision=10, max_line_width=400)}".replace("\n", ""),
        ]
        if robot is not None:
            d, lim = robot.dynamics, robot.limits
            lines += [
                "",
                "[dynamics]",
                f'source = "copied from the start parameter set {robot.name}"',
                f"m_p = {d.m_p!r}",
                f"m_c = {list(map(float, d.m_c))}",
                f"m_a = {list(map(float, d.m_a))}",
                f"f_c = {list(map(float, d.f_c))}",
                f"f_v = {list(map(float, d.f_v))}",
                f"g = {d.g!r}",
                "",
                "[limits]",
                f'source = "copied from the start parameter set {robot.name}"',
                f"cart_travel = {lim.cart_travel.tolist()}",
                f"joint_angle_max_deg = {float(np.rad2deg(lim.joint_angle_max))!r}",
            ]
    else:
        lines += [f'model = "{model.name}"', ""]
        lines += _calibrated_tables(res.parameters, res.std, "  # name = value [m, rad, 1]", "  # from the Jacobian and the residual variance")
    if isinstance(model, ThreeLinkClosure):  # the parameter-set schema has no such table: comments
        lines += ["", "# standard deviations (from the Jacobian and the residual variance):"]
        lines += [f"#   {n} = {float(s):.3e}" for n, s in res.std.items()]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _calibrated_tables(parameters: dict[str, float], std: dict[str, float], comment: str = "", std_comment: str = "") -> list[str]:
    """TOML lines of the ``[calibrated]`` values and their ``[standard_deviation]`` (``nan`` if not finite).

    Shared by the result files of the calibration kinds (``parameters.toml``).
    """
    return (
        [f"[calibrated]{comment}"]
        + [f'"{n}" = {v!r}' for n, v in parameters.items()]
        + ["", f"[standard_deviation]{std_comment}"]
        + [f'"{n}" = {float(s)!r}' if np.isfinite(s) else f'"{n}" = nan' for n, s in std.items()]
    )
