"""Problem files of kind ``dynamic_identification``: masses and friction from a servo log.

Dressler (2012), ch. 6.2 and Table 6.3: a logged motion (a CSV file, or synthetic data
from a declared true robot along an optimised excitation trajectory) is filtered and
differentiated, and one or several model variants are identified by least squares::

    name = "l1_dynamic_identification"
    kind = "dynamic_identification"

    [robot]
    parameters = "L1"               # kinematics, gravity and the Table 6.1 friction
    configuration = 0

    [data]                          # either a log ...
    # file = "log.csv"              #   (format: gtmodel.calibration.dynamic_identification.read_motion_log)

    [truth]                         # ... or synthetic data (say so in the file)
    parameters = "L1"               # the true robot (L1: Table 6.3 model 2)
    duration = 30.0                 # s
    sample_time = 0.004             # s
    force_noise = 5.0               # N, Gaussian
    position_noise = 1e-6           # m, Gaussian
    position_resolution = 1e-6      # m, encoder quantisation
    stribeck_amplitude = [40.0, 40.0, 40.0]   # N, f_s - f_c: not in the model; [] for none
    stribeck_velocity = 0.02        # m/s
    seed = 1

    [excitation]                    # synthetic data only: the motion, designed for the
                                    # first variant's regressor (model_2 for models 3/4)
    optimize = true                 # IPOPT design (gtmodel.calibration.excitation)
    harmonics = 4
    period = 10.0                   # s
    n_grid = 60
    max_velocity = 0.5              # m/s
    max_acceleration = 3.0          # m/s^2
    T_center = [0.0, 2.9, -0.5]     # m
    seed = 0
    max_iter = 150

    [filter]
    method = "butter"               # "butter" (filtfilt) | "savgol"
    cutoff = 10.0                   # Hz
    order = 4
    # decimate = 25                 # default round(fs / cutoff)
    # trim = 50                     # default 2 fs / cutoff

    [identification]
    variants = ["model_2", "model_1", "model_3", "model_4", "full"]
    weighting = "actuator"          # "actuator" | "none"
    min_speed = 0.05                # m/s

The result folder holds ``summary.json`` (``status``, the first variant's parameters
with standard deviations and, for synthetic data, the truth and ``|error| / std``,
residual RMS per actuator and per speed bin, condition numbers, the excitation design
and a ``variants`` table with the Table 6.3 rows next to the thesis'),
``parameters.toml`` (the first variant's ``[dynamics]`` table), ``identification.csv``
(every variant's parameters) and ``residuals.png``.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._fields import FieldReader
from gtmodel.errors import GtModelError, ProblemError

__all__ = [
    "DYNAMIC_IDENTIFICATION_SCHEMA",
    "DynamicIdentificationDeclaration",
    "DynamicIdentificationOutcome",
    "load_dynamic_identification",
    "solve_dynamic_identification",
    "write_dynamic_identification",
]

_log = logging.getLogger("gtmodel")

#: Allowed fields of a ``dynamic_identification`` problem file.
DYNAMIC_IDENTIFICATION_SCHEMA: dict[str, set[str]] = {
    "": {"name", "kind", "description", "robot", "data", "truth", "excitation", "filter", "identification"},
    "robot": {"parameters", "configuration"},
    "data": {"file"},
    "truth": {"parameters", "duration", "sample_time", "force_noise", "position_noise", "position_resolution",
              "stribeck_amplitude", "stribeck_velocity", "seed"},
    "excitation": {"optimize", "harmonics", "period", "n_grid", "max_velocity", "max_acceleration", "T_center", "seed", "max_iter"},
    "filter": {"method", "cutoff", "order", "decimate", "trim"},
    "identification": {"variants", "weighting", "min_speed"},
}


@dataclass
class DynamicIdentificationDeclaration:
    """A validated dynamic-identification problem.

    Parameters
    ----------
    robot : RobotParameters
        The model's parameter set (kinematics, gravity, Table 6.1 friction).
    configuration : int
        IK configuration.
    log : MotionLog or None
        The measured log (``[data]``), or None for synthetic data.
    truth : dict or None
        Synthetic-data settings (``[truth]``), with the true parameter set under ``robot``.
    excitation : dict
        Excitation settings (synthetic data).
    filter : dict
        :func:`~gtmodel.calibration.dynamic_identification.preprocess_log` options.
    variants : list of str
        Variants to identify (the first is the main result).
    weighting : str
        Row weighting.
    min_speed : float
        Rows below this cart speed are not fitted [m/s].
    source : str
        Where the data come from.
    """

    robot: Any
    configuration: int
    log: Any
    truth: dict | None
    excitation: dict
    filter: dict
    variants: list
    weighting: str
    min_speed: float
    source: str


def load_dynamic_identification(f: FieldReader, name: str) -> DynamicIdentificationDeclaration:
    """Validate a ``dynamic_identification`` problem file (the log file is read here).

    Parameters
    ----------
    f : FieldReader
        The problem file.
    name : str
        Problem name.

    Returns
    -------
    DynamicIdentificationDeclaration

    Raises
    ------
    ProblemError
        A missing, unknown or invalid field, both or neither of ``[data]`` and
        ``[truth]``, ``[excitation]`` with ``[data]``, or a malformed log file (the message
        names the file and the line).
    """
    from gtmodel.calibration.identification import VARIANTS, read_motion_log
    from gtmodel.robots.parameters import load_parameters

    f.check_unknown(DYNAMIC_IDENTIFICATION_SCHEMA)
    has_data, has_truth = f.has("data"), f.has("truth")
    if has_data == has_truth:
        raise ProblemError(f"{f.path}: declare exactly one of '[data]' (a motion log) and '[truth]' (synthetic data)")
    if has_data and f.has("excitation"):
        raise ProblemError(f"{f.path}: '[excitation]' is for synthetic data ('[truth]'); a log file brings its own motion")

    def params(table: str) -> Any:
        ref = f.string(table, "parameters", "L1")
        target = str(f.path.parent / ref) if ref.endswith(".toml") and not Path(ref).is_absolute() else ref
        try:
            return load_parameters(target)
        except GtModelError as exc:
            raise f.fail(f"{table}.parameters", "a parameter set name or file", ref) from exc

    robot = params("robot")
    configuration = f.integer("robot", "configuration", 0, 0, 7)
    log = None
    truth = None
    excitation: dict[str, Any] = {}
    if has_data:
        file = f.string("data", "file")
        path = Path(file) if Path(file).is_absolute() else f.path.parent / file
        try:
            log = read_motion_log(path)
        except GtModelError as exc:
            raise ProblemError(f"{f.path}: field 'data.file': {exc}") from None
        source = f"measured log {path}"
    else:
        strib = f.get("truth", "stribeck_amplitude", [40.0, 40.0, 40.0])
        if strib == []:
            strib_amp = None
        else:
            strib_amp = f.vector("truth", "stribeck_amplitude", 3, [40.0, 40.0, 40.0])
        truth = {
            "robot": params("truth"),
            "duration": f.number("truth", "duration", 30.0, positive=True),
            "sample_time": f.number("truth", "sample_time", 0.004, positive=True),
            "force_noise": f.number("truth", "force_noise", 5.0, nonnegative=True),
            "position_noise": f.number("truth", "position_noise", 1e-6, nonnegative=True),
            "position_resolution": f.number("truth", "position_resolution", 1e-6, nonnegative=True),
            "stribeck_amplitude": strib_amp,
            "stribeck_velocity": f.number("truth", "stribeck_velocity", 0.02, positive=True),
            "seed": f.integer("truth", "seed", 0, 0, 2**31 - 1),
        }
        if truth["duration"] / truth["sample_time"] > 2e6:
            raise f.fail("truth.duration", "at most 2e6 samples (duration / sample_time)", truth["duration"])
        excitation = {
            "optimize": f.boolean("excitation", "optimize", True),
            "harmonics": f.integer("excitation", "harmonics", 4, 1, 20),
            "period": f.number("excitation", "period", 10.0, positive=True),
            "n_grid": f.integer("excitation", "n_grid", 60, 8, 1000),
            "max_velocity": f.number("excitation", "max_velocity", 0.5, positive=True),
            "max_acceleration": f.number("excitation", "max_acceleration", 3.0, positive=True),
            "T_center": f.vector("excitation", "T_center", 3, [0.0, 2.9, -0.5]),
            "seed": f.integer("excitation", "seed", 0, 0, 2**31 - 1),
            "max_iter": f.integer("excitation", "max_iter", 150, 1, 10000),
        }
        from gtmodel.robots.kinematics import GantryTau3Kinematics

        try:
            GantryTau3Kinematics(robot).require_in_workspace(excitation["T_center"], configuration)
        except GtModelError as exc:
            raise f.fail("excitation.T_center", f"a TCP position [m] inside the workspace of {robot.name} ({exc})",
                         [float(x) for x in excitation["T_center"]]) from None
        if excitation["n_grid"] < 4 * excitation["harmonics"]:
            raise f.fail("excitation.n_grid", f"at least 4 points per period of the highest harmonic ({4 * excitation['harmonics']})", excitation["n_grid"])
        source = (f"SYNTHETIC: true robot {truth['robot'].name} ({truth['robot'].dynamics.source}), force noise {truth['force_noise']} N, "
                  f"{'Stribeck term ' + str([float(x) for x in strib_amp]) + ' N' if strib_amp is not None else 'no Stribeck term'}")
    filt = {
        "method": f.choice("filter", "method", ("butter", "savgol"), "butter"),
        "cutoff": f.number("filter", "cutoff", 10.0, positive=True),
        "order": f.integer("filter", "order", 4, 1, 10),
        "decimate": f.integer("filter", "decimate", ..., 1, 10000) if "decimate" in f.table("filter", False) else None,
        "trim": f.integer("filter", "trim", ..., 0, 10**6) if "trim" in f.table("filter", False) else None,
    }
    if filt["method"] == "savgol" and filt["order"] < 2:
        raise f.fail("filter.order", "an integer >= 2 for method 'savgol'", filt["order"])
    variants = f.get("identification", "variants", ["model_2"])
    if not isinstance(variants, list) or not variants or not all(isinstance(v, str) and v in VARIANTS for v in variants) or len(set(variants)) != len(variants):
        raise f.fail("identification.variants", f"a non-empty list of distinct names from {', '.join(VARIANTS)}", variants)
    for v in variants:
        if VARIANTS[v].asymmetric and robot.dynamics.asymmetric is None:
            raise f.fail("identification.variants", f"variants the parameter set {robot.name} supports (it has no Table 6.1 friction for {v})", variants)
    weighting = f.choice("identification", "weighting", ("actuator", "none"), "actuator")
    min_speed = f.number("identification", "min_speed", 0.05, nonnegative=True)
    return DynamicIdentificationDeclaration(robot, configuration, log, truth, excitation, filt, list(variants), weighting, min_speed, source)


@dataclass
class DynamicIdentificationOutcome:
    """Results of a dynamic-identification problem.

    Parameters
    ----------
    declaration : DynamicIdentificationDeclaration
        The problem.
    results : list
        Per variant: ``(name, DynamicIdentificationResult or None, message)``.
    samples : DynamicSamples
        The filtered data.
    log : MotionLog
        The raw log.
    design : ExcitationDesign or None
        The optimised excitation (synthetic data with ``optimize = true``).
    truth_theta : dict
        Per variant the true parameter vector (synthetic data; models 1, 3, 4 differ from
        the truth in structure, so only the shared parameters are compared).
    solve_time : float
        Total wall time [s].
    """

    declaration: DynamicIdentificationDeclaration
    results: list
    samples: Any
    log: Any
    design: Any = None
    truth_theta: dict = field(default_factory=dict)
    solve_time: float = 0.0

    @property
    def status(self) -> str:
        """``optimal`` if every variant was identified, else ``error``."""
        return "optimal" if all(r is not None and r.success for _, r, _ in self.results) else "error"

    @property
    def success(self) -> bool:
        """True when every variant was identified."""
        return self.status == "optimal"


def solve_dynamic_identification(decl: DynamicIdentificationDeclaration, verbose: bool = False) -> DynamicIdentificationOutcome:
    """Design the excitation and simulate (synthetic data), filter, identify every variant.

    Parameters
    ----------
    decl : DynamicIdentificationDeclaration
        The problem.
    verbose : bool, optional
        Log progress.

    Returns
    -------
    DynamicIdentificationOutcome
        Never None; a variant that failed has ``None`` and the message.

    Raises
    ------
    ProblemError
        The data cannot be filtered (too short, non-uniform sampling, cut-off above
        Nyquist) or the motion leaves the workspace.
    """
    from gtmodel.calibration.identification import (
        DynamicRegressor,
        StribeckTerm,
        identify_dynamics,
        preprocess_log,
        simulate_log,
    )
    from gtmodel.calibration.identification import FourierTrajectory, design_excitation

    t0 = time.perf_counter()
    design = None
    truth_theta: dict[str, Any] = {}
    try:
        if decl.log is None:
            tr, ex = decl.truth, decl.excitation
            if ex["optimize"]:
                design = design_excitation(decl.robot, decl.variants[0] if decl.variants[0] in ("model_1", "model_2", "full") else "model_2",
                                           harmonics=ex["harmonics"], period=ex["period"], n_grid=ex["n_grid"],
                                           T_center=ex["T_center"], max_velocity=ex["max_velocity"], max_acceleration=ex["max_acceleration"],
                                           configuration=decl.configuration, seed=ex["seed"], max_iter=ex["max_iter"])
                trajectory = design.trajectory
                if verbose:
                    _log.info("excitation: %s, cond %.3g -> %.3g", design.message, design.condition_before, design.condition_after)
            else:
                rng = np.random.default_rng(ex["seed"])
                from gtmodel.robots.kinematics import GantryTau3Kinematics

                q0 = GantryTau3Kinematics(decl.robot).require_in_workspace(ex["T_center"], decl.configuration)
                K = ex["harmonics"]
                trajectory = FourierTrajectory(q0, 0.06 * rng.standard_normal((3, K)), 0.06 * rng.standard_normal((3, K)), ex["period"])
            strib = StribeckTerm(np.asarray(tr["stribeck_amplitude"]), tr["stribeck_velocity"]) if tr["stribeck_amplitude"] is not None else None
            log, _ = simulate_log(trajectory, tr["duration"], tr["robot"], tr["sample_time"], tr["force_noise"], tr["position_noise"],
                                  tr["position_resolution"], strib, tr["seed"], decl.configuration)
        else:
            log = decl.log
        samples = preprocess_log(log, **decl.filter)
    except GtModelError as exc:
        raise ProblemError(f"dynamic identification: {exc}") from None
    results = []
    for v in decl.variants:
        try:
            reg = DynamicRegressor(decl.robot, v, decl.configuration)
            res = identify_dynamics(samples, variant=v, weighting=decl.weighting, min_speed=decl.min_speed, rank_deficient="base", regressor=reg)
            results.append((v, res, res.message))
            if decl.truth is not None:
                truth_theta[v] = reg.theta_of(decl.truth["robot"].dynamics)
        except GtModelError as exc:
            results.append((v, None, str(exc)))
        if verbose:
            _log.info("variant %s: %s", v, results[-1][2])
    return DynamicIdentificationOutcome(decl, results, samples, log, design, truth_theta, time.perf_counter() - t0)


def _parameter_rows(name: str, res: Any, truth: np.ndarray | None, same_structure: bool) -> list[dict[str, Any]]:
    rows = []
    for k, (n, v, s) in enumerate(zip(res.names, res.theta, res.std)):
        row: dict[str, Any] = {"variant": name, "parameter": n, "estimate": float(v), "std": float(s), "unit": _unit(n)}
        if truth is not None:
            row["truth"] = float(truth[k])
            row["z"] = float(abs(v - truth[k]) / s) if same_structure and np.isfinite(s) and s > 0 else math.nan
        rows.append(row)
    return rows


def _unit(n: str) -> str:
    return "kg" if n.startswith("m_") else ("N s/m" if n.startswith("f_v") else "N")


def write_dynamic_identification(decl: DynamicIdentificationDeclaration, solution: DynamicIdentificationOutcome, out: Path, plots: bool, name: str) -> tuple[dict[str, Any], list[str]]:
    """Summary fields, ``parameters.toml``, ``identification.csv`` and ``residuals.png``.

    Parameters
    ----------
    decl : DynamicIdentificationDeclaration
        The problem.
    solution : DynamicIdentificationOutcome
        Its results.
    out : pathlib.Path
        Result folder (exists).
    plots : bool
        Write the PNG plot.
    name : str
        Problem name (titles).

    Returns
    -------
    summary : dict
        ``status``, ``message``, the first variant's figures and a ``variants`` table.
    files : list of str
        Files written besides ``summary.json``.
    """
    from gtmodel.calibration.identification import THESIS_TABLE_6_3, VARIANTS

    # a variant "has the truth's structure" when the simulated data come from it exactly:
    # simulate_log uses symmetric friction and the truth's masses, so "full" always and
    # "model_2" when the truth has no link masses (the L1 set: Table 6.3 model 2)
    exact = {"full"}
    if decl.truth is not None and not np.any(np.asarray(decl.truth["robot"].dynamics.m_a) != 0):
        exact.add("model_2")
    table = []
    csv_rows: list[dict[str, Any]] = []
    for v, res, msg in solution.results:
        row: dict[str, Any] = {"variant": v, "description": VARIANTS[v].description, "status": "optimal" if res is not None else "error", "message": msg}
        if res is not None:
            truth = solution.truth_theta.get(v)
            same = v in exact
            prow = _parameter_rows(v, res, truth, same)
            csv_rows += prow
            row.update(
                parameters={r["parameter"]: {k: r[k] for k in ("estimate", "std", "unit", "truth", "z") if k in r} for r in prow},
                residual_rms_N=res.residual_rms.tolist(),
                residual_ss_N2=res.residual_ss.tolist(),
                condition_number=res.condition_number,
                condition_number_raw=res.condition_number_raw,
                rank=int(res.identifiability.rank),
                n_parameters=len(res.names),
                n_rows=res.n_rows,
                table_6_3_row=res.table_6_3_row().tolist(),
            )
            if v in THESIS_TABLE_6_3:
                row["thesis_table_6_3_row"] = list(THESIS_TABLE_6_3[v]["row"])
                row["thesis_residual_1e7"] = list(THESIS_TABLE_6_3[v]["residual"])
            if v == "full":
                row["near_dependencies"] = res.near_dependencies
            if truth is not None and same:
                z = np.array([r["z"] for r in prow])
                row["max_z"] = float(np.nanmax(z))
                row["n_within_3_std"] = int(np.sum(z <= 3.0))
        table.append(row)
    first_v, first, first_msg = solution.results[0]
    summary: dict[str, Any] = {
        "status": solution.status,
        "message": first_msg if first is not None else f"variant {first_v}: {first_msg}",
        "source": decl.source,
        "variant": first_v,
        "solve_time_s": solution.solve_time,
        "n_samples_log": solution.log.n_samples,
        "n_samples_used": solution.samples.n_samples,
        "filter": solution.samples.info,
    }
    if first is not None:
        summary.update(table[0])
        low = next(b for b in first.residual_by_speed if b["v_min"] == 0.02)
        high = [b for b in first.residual_by_speed if b["v_min"] >= 0.2]
        summary["residual_rms_low_speed_N"] = low["rms"]
        summary["residual_rms_high_speed_N"] = [float(np.sqrt(np.nanmean([b["rms"][i] ** 2 for b in high]))) for i in range(3)]
        summary["residual_by_speed"] = first.residual_by_speed
        summary["status"] = solution.status
    if solution.design is not None:
        d = solution.design
        summary["excitation"] = {"status": d.status, "message": d.message, "condition_before": d.condition_before,
                                 "condition_after": d.condition_after, "iterations": d.iterations, "solve_time_s": d.solve_time,
                                 "max_violation": d.max_violation, **d.info}
    summary["variants"] = table
    files: list[str] = []
    if first is not None:
        _write_parameters(out / "parameters.toml", decl, first_v, first, name)
        files.append("parameters.toml")
    if csv_rows:
        cols = ["variant", "parameter", "estimate", "std", "unit", "truth", "z"]
        lines = [",".join(cols)]
        for r in csv_rows:
            lines.append(",".join(str(r.get(c, "")) if not isinstance(r.get(c), float) else repr(r[c]) for c in cols))
        (out / "identification.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
        files.append("identification.csv")
    if plots and first is not None:
        _plot_residuals(solution, first_v, out / "residuals.png", f"{name}: {first_v}")
        files.append("residuals.png")
    return summary, files


def _write_parameters(path: Path, decl: DynamicIdentificationDeclaration, variant: str, res: Any, name: str) -> None:
    """A complete robot parameter set (loadable by ``load_parameters``) with the identified dynamics."""
    p = res.parameters
    robot = decl.robot
    d, k, lim = robot.dynamics, robot.kinematics, robot.limits

    def vec(prefix: str, default: Any) -> list[float]:
        return [float(p.get(f"{prefix}{i + 1}", default[i])) for i in range(3)]

    def arr(x: Any) -> str:
        return str(np.asarray(x, dtype=float).tolist())

    sym = not _variant_asymmetric(variant)
    lines = [
        f"# Identified by gtmodel ({name}), variant {variant}; {decl.source}",
        "# Dressler (2012), eqs. 6.7-6.8, Table 6.3. SI units. Kinematics, limits and the parameters the",
        f"# variant does not estimate are copied from the parameter set {robot.name} (link masses 0 unless estimated).",
        f'name = "{robot.name}_identified"',
        f'description = "{robot.name} with dynamics identified by gtmodel ({variant})"',
        f'frame = "{robot.frame}"',
        "",
        "[kinematics]",
        f'source = "copied from {robot.name}"',
        f'model = "{k.model}"',
        f"L = {arr(k.L)}",
        f"As = {arr(k.As)}",
        f"v = {arr(k.v[0]) if k.model == 'ideal' else arr(k.v)}",
        "",
        "[dynamics]",
        f'source = "gtmodel dynamic identification {name}, variant {variant}"',
        f"m_p = {float(p.get('m_p', d.m_p))!r}",
        f"m_c = {vec('m_c', d.m_c)}",
        f"m_a = {vec('m_a', np.zeros(3))}",
        f"f_c = {vec('f_c', d.f_c) if sym else arr(d.f_c)}",
        f"f_v = {vec('f_v', np.zeros(3) if variant == 'model_1' else d.f_v) if sym else arr(d.f_v)}",
        f"g = {float(d.g)!r}",
    ]
    a = d.asymmetric
    if a is not None:
        lines += ["", "[dynamics.asymmetric_friction]", f'source = "copied from {robot.name}"' if sym else f'source = "gtmodel dynamic identification {name}, variant {variant}"']
        for key in ("f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus"):
            default = getattr(a, key)
            if variant == "model_4" and key.startswith("f_c"):
                vals = vec("f_c", default)
            elif sym:
                vals = list(map(float, default))
            else:
                vals = vec(key, default)
            lines.append(f"{key} = {vals}")
    lines += [
        "",
        "[limits]",
        f'source = "copied from {robot.name}"',
        f"cart_travel = {arr(lim.cart_travel)}",
        f"joint_angle_max_deg = {float(np.rad2deg(lim.joint_angle_max))!r}",
        "",
        "# standard deviations of the estimated parameters (least squares):",
    ]
    lines += [f"#   {n} = {float(s):.6g}" for n, s in zip(res.names, res.std)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _variant_asymmetric(variant: str) -> bool:
    from gtmodel.calibration.identification import VARIANTS

    return VARIANTS[variant].asymmetric


def _plot_residuals(solution: DynamicIdentificationOutcome, variant: str, path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gtmodel.calibration.identification import DynamicRegressor

    res = next(r for v, r, _ in solution.results if v == variant)
    s = solution.samples
    reg = DynamicRegressor(solution.declaration.robot, variant, solution.declaration.configuration)
    Y, tau0, q_dot = reg.evaluate(s.x, s.x_dot, s.x_ddot, s.coordinates)
    tau_hat = Y @ res.theta + tau0
    if s.smoother is not None:  # the forces went through this filter; so does the model (parallel filtering)
        tau_hat = s.smoother(tau_hat)
    fig, ax = plt.subplots(2, 3, figsize=(13, 6.5), sharex="row")
    for i in range(3):
        ax[0, i].plot(s.t, s.tau[:, i], lw=0.8, label="measured (filtered)")
        ax[0, i].plot(s.t, tau_hat[:, i], lw=0.8, ls="--", label="model (same filter)")
        ax[0, i].set_title(f"actuator {i + 1}")
        ax[0, i].set_xlabel("t [s]")
        ax[1, i].plot(q_dot[:, i], s.tau[:, i] - tau_hat[:, i], ".", ms=2)
        ax[1, i].axvspan(-res.info["min_speed"], res.info["min_speed"], color="0.9", label="not fitted")
        ax[1, i].set_xlabel("cart velocity [m/s]")
    ax[0, 0].set_ylabel("force [N]")
    ax[1, 0].set_ylabel("residual [N]")
    ax[0, 0].legend(fontsize=8)
    ax[1, 0].legend(fontsize=8)
    fig.suptitle(f"{title}: residual RMS {np.round(res.residual_rms, 2).tolist()} N")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
