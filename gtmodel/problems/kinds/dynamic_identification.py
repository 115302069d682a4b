"""Kind ``dynamic_identification``: masses and friction from a servo log.

Dressler (2012), ch. 6.2 and Table 6.3: a logged motion (``[data] file``, a CSV read by
:func:`gtmodel.calibration.read_motion_log`, or synthetic data from a declared true robot,
``[truth]``, along an optimised excitation trajectory, ``[excitation]``) is filtered and
differentiated (``[filter]``), and one or several model variants are identified by least
squares (``[identification]``); the first variant is the main result.

The result folder holds ``summary.json`` (``status``, the first variant's parameters
with standard deviations and, for synthetic data, the truth and ``|error| / std``,
residual RMS per actuator and per speed bin, condition numbers, the excitation design
and a ``variants`` table with the Table 6.3 rows next to the thesis'),
``parameters.toml`` (a loadable parameter set with the first variant's ``[dynamics]``),
``identification.csv`` (every variant's parameters) and ``residuals.png``. The field
reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._escape import csv_field, toml_comment, toml_string
from gtmodel.calibration import read_motion_log
from gtmodel.calibration.identification import THESIS_TABLE_6_3, VARIANTS
from gtmodel.calibration.identification.declared import DynamicIdentificationDeclaration, DynamicIdentificationOutcome
from gtmodel.errors import GtModelError, ProblemError
from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.schemas.dynamic_identification import DynamicIdentificationFile, ExcitationSection
from gtmodel.problems.references import robot_parameters
from gtmodel.report.identification import plot_identification_residuals
from gtmodel.robots import GantryTau3Kinematics

__all__ = [
    "DynamicIdentificationKind",
    "DynamicIdentificationFile",
    "MAX_SAMPLES",
    "MAX_LOG_BYTES",
]

_log = logging.getLogger("gtmodel")

#: Most samples of a log (synthetic: ``duration / sample_time``): 13 times the shipped
#: 30 s at 4 ms; a few seconds of simulation, filtering and identification, about 250 MB
#: (300 000 samples took 11 s of CPU and 670 MB).
MAX_SAMPLES = 100_000
#: Largest log file read [bytes] (100 000 rows of full-precision numbers).
MAX_LOG_BYTES = 10_000_000
#: Header and comment lines allowed in a log beyond :data:`MAX_SAMPLES` rows.
MAX_LOG_COMMENT_LINES = 1000


def _read_log(file: ProblemFile, ref: str) -> tuple[Any, Path]:
    path = file.data_file("data.file", ref)
    size = path.stat().st_size
    if size > MAX_LOG_BYTES:
        raise file.fail("data.file", f"a log file of at most {MAX_LOG_BYTES} bytes", f"{ref} ({size} bytes)")
    try:
        lines = path.read_bytes().count(b"\n")
    except OSError as exc:
        raise file.fail("data.file", f"a readable log file ({exc.strerror})", ref) from None
    if lines > MAX_SAMPLES + MAX_LOG_COMMENT_LINES:  # counted before parsing, which is slow
        raise file.fail("data.file", f"a log of at most {MAX_SAMPLES} samples", f"{ref} ({lines} lines)")
    try:
        log = read_motion_log(path)
    except GtModelError as exc:
        raise file.wrap("data.file", exc) from None
    except UnicodeDecodeError as exc:
        raise file.fail("data.file", f"a UTF-8 text file (byte {exc.start} is not)", ref) from None
    if log.n_samples > MAX_SAMPLES:
        raise file.fail("data.file", f"a log of at most {MAX_SAMPLES} samples", f"{ref} ({log.n_samples} samples)")
    return log, path


class DynamicIdentificationKind(ProblemKind):
    """Masses and friction from a servo log, Table 6.3 variants (Dressler (2012), ch. 6.2)."""

    name = "dynamic_identification"
    schema = DynamicIdentificationFile
    title = "masses and friction from a servo log, Table 6.3 model variants (Dressler (2012), ch. 6.2)"
    file_descriptions = {
        "parameters.toml": "identified masses and friction of the first model variant",
        "identification.csv": "every model variant's parameter estimates with their standard deviation, unit and the truth (Table 6.3)",
        "residuals.png": "measured against predicted actuator forces and their residuals",
    }
    columns = (
        Column("max_z", "max |error|/std", "{:.3g}"),
        Column("condition_number", "condition", "{:.4g}"),
        Column("n_samples_used", "samples", "{}"),
        Column("solve_time_s", "solve time [s]", "{:.3f}"),
    )
    extra_empty_fields = ("n_samples_log",)

    @fill_doc(**KIND_DOCS)
    def load(self, doc: DynamicIdentificationFile, file: ProblemFile, name: str) -> DynamicIdentificationDeclaration:
        """Resolve the parameter sets, read the log or check the synthetic setup (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        DynamicIdentificationDeclaration

        Raises
        ------
        ProblemError
            Both or neither of ``[data]`` and ``[truth]``, ``[excitation]`` with ``[data]``,
            too many samples, a motion centre outside the workspace, a too coarse design
            grid, variants the parameter set cannot support, a malformed log file (the
            message names the file and the line).
        """
        if (doc.data is None) == (doc.truth is None):
            raise ProblemError(f"{file.path}: declare exactly one of '[data]' (a motion log) and '[truth]' (synthetic data)")
        if doc.data is not None and doc.excitation is not None:
            raise ProblemError(f"{file.path}: '[excitation]' is for synthetic data ('[truth]'); a log file brings its own motion")
        robot = robot_parameters(file, "robot.parameters", doc.robot.parameters)
        configuration = doc.robot.configuration
        log = None
        truth = None
        excitation: dict[str, Any] = {}
        if doc.data is not None:
            log, path = _read_log(file, doc.data.file)
            source = f"measured log {path}"
        else:
            tr = doc.truth
            if tr.duration / tr.sample_time > MAX_SAMPLES:
                raise file.fail("truth.sample_time", f"at most {MAX_SAMPLES} samples (duration / sample_time = {tr.duration:g} / sample_time)", tr.sample_time)
            truth = {
                "robot": robot_parameters(file, "truth.parameters", tr.parameters),
                "duration": tr.duration,
                "sample_time": tr.sample_time,
                "force_noise": tr.force_noise,
                "position_noise": tr.position_noise,
                "position_resolution": tr.position_resolution,
                "stribeck_amplitude": None if tr.stribeck_amplitude is None else np.array(tr.stribeck_amplitude),
                "stribeck_velocity": tr.stribeck_velocity,
                "seed": tr.seed,
            }
            ex = doc.excitation or ExcitationSection()
            excitation = {k: getattr(ex, k) for k in ExcitationSection.model_fields}
            excitation["T_center"] = np.array(ex.T_center)
            try:
                GantryTau3Kinematics(robot).require_in_workspace(excitation["T_center"], configuration)
            except GtModelError as exc:
                raise file.fail("excitation.T_center", f"a TCP position [m] inside the workspace of {robot.name} ({exc})", list(ex.T_center)) from None
            if ex.n_grid < 4 * ex.harmonics:
                raise file.fail("excitation.n_grid", f"at least 4 points per period of the highest harmonic ({4 * ex.harmonics})", ex.n_grid)
            strib = truth["stribeck_amplitude"]
            source = (f"SYNTHETIC: true robot {truth['robot'].name} ({truth['robot'].dynamics.source}), force noise {truth['force_noise']} N, "
                      f"{'Stribeck term ' + str([float(x) for x in strib]) + ' N' if strib is not None else 'no Stribeck term'}")
        fs = doc.filter
        if fs.method == "savgol" and fs.order < 2:
            raise file.fail("filter.order", "an integer >= 2 for method 'savgol'", fs.order)
        filt = {"method": fs.method, "cutoff": fs.cutoff, "order": fs.order, "decimate": fs.decimate, "trim": fs.trim}
        ident = doc.identification
        for v in ident.variants:
            if VARIANTS[v].asymmetric and robot.dynamics.asymmetric is None:
                raise file.fail("identification.variants", f"variants the parameter set {robot.name} supports (it has no Table 6.1 friction for {v})",
                                ident.variants)
        return DynamicIdentificationDeclaration(robot, configuration, log, truth, excitation, filt, list(ident.variants), ident.weighting,
                                                ident.min_speed, source)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: DynamicIdentificationDeclaration, solution: DynamicIdentificationOutcome, out: Path, plots: bool,
              name: str) -> Written:
        """Summary fields, ``parameters.toml``, ``identification.csv`` and ``residuals.png``.

        The files are written only when every variant was identified (status
        ``optimal``); a failed run has its summary alone.

        Parameters
        ----------
        declaration : DynamicIdentificationDeclaration
            The problem.
        solution : DynamicIdentificationOutcome
            Its results.
        {write_args}

        Returns
        -------
        Written
            ``status``, ``message``, the first variant's figures and a ``variants`` table.
        """
        decl = declaration
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
        fields: dict[str, Any] = {
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
            fields.update(table[0])
            low = next(b for b in first.residual_by_speed if b["v_min"] == 0.02)
            high = [b for b in first.residual_by_speed if b["v_min"] >= 0.2]
            fields["residual_rms_low_speed_N"] = low["rms"]
            fields["residual_rms_high_speed_N"] = [_rms_of_bins([b["rms"][i] for b in high]) for i in range(3)]
            fields["residual_by_speed"] = first.residual_by_speed
            fields["status"] = solution.status
        if solution.design is not None:
            d = solution.design
            fields["excitation"] = {"status": d.status, "message": d.message, "condition_before": d.condition_before,
                                    "condition_after": d.condition_after, "iterations": d.iterations, "solve_time_s": d.solve_time,
                                    "max_violation": d.max_violation, **d.info}
        fields["variants"] = table
        written = Written(fields)
        if not solution.status.success:  # a failed variant: no file that could look like a result
            return written
        if first is not None:
            _write_parameters(out / "parameters.toml", decl, first_v, first, name)
            written.files.append("parameters.toml")
        if csv_rows:
            cols = ["variant", "parameter", "estimate", "std", "unit", "truth", "z"]
            lines = [",".join(cols)]
            for r in csv_rows:
                lines.append(",".join(csv_field(r.get(c, "")) if not isinstance(r.get(c), float) else repr(r[c]) for c in cols))
            (out / "identification.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
            written.files.append("identification.csv")
        if plots and first is not None:
            plot_identification_residuals(decl.robot, decl.configuration, first_v, solution.samples, first, out / "residuals.png", f"{name}: {first_v}")
            written.files.append("residuals.png")
        return written


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


def _write_parameters(path: Path, decl: DynamicIdentificationDeclaration, variant: str, res: Any, name: str) -> None:
    """A complete robot parameter set (loadable by ``load_parameters``) with the identified dynamics."""
    p = res.parameters
    robot = decl.robot
    d, k, lim = robot.dynamics, robot.kinematics, robot.limits

    def vec(prefix: str, default: Any) -> list[float]:
        return [float(p.get(f"{prefix}{i + 1}", default[i])) for i in range(3)]

    def arr(x: Any) -> str:
        return str(np.asarray(x, dtype=float).tolist())

    sym = not VARIANTS[variant].asymmetric
    lines = [
        "# " + toml_comment(f"Identified by gtmodel ({name}), variant {variant}; {decl.source}"),
        "# Dressler (2012), eqs. 6.7-6.8, Table 6.3. SI units. Kinematics, limits and the parameters the",
        "# " + toml_comment(f"variant does not estimate are copied from the parameter set {robot.name} (link masses 0 unless estimated)."),
        f"name = {toml_string(f'{robot.name}_identified')}",
        f"description = {toml_string(f'{robot.name} with dynamics identified by gtmodel ({variant})')}",
        f"frame = {toml_string(robot.frame)}",
        "",
        "[kinematics]",
        f"source = {toml_string(f'copied from {robot.name}')}",
        f"model = {toml_string(k.model)}",
        f"L = {arr(k.L)}",
        f"As = {arr(k.As)}",
        f"v = {arr(k.v[0]) if k.model == 'ideal' else arr(k.v)}",
        "",
        "[dynamics]",
        f"source = {toml_string(f'gtmodel dynamic identification {name}, variant {variant}')}",
        f"m_p = {float(p.get('m_p', d.m_p))!r}",
        f"m_c = {vec('m_c', d.m_c)}",
        f"m_a = {vec('m_a', np.zeros(3))}",
        f"f_c = {vec('f_c', d.f_c) if sym else arr(d.f_c)}",
        f"f_v = {vec('f_v', np.zeros(3) if variant == 'model_1' else d.f_v) if sym else arr(d.f_v)}",
        f"g = {float(d.g)!r}",
    ]
    a = d.asymmetric
    if a is not None:
        lines += ["", "[dynamics.asymmetric_friction]", f"source = {toml_string(f'copied from {robot.name}')}" if sym else f"source = {toml_string(f'gtmodel dynamic identification {name}, variant {variant}')}"]
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
        f"source = {toml_string(f'copied from {robot.name}')}",
        f"cart_travel = {arr(lim.cart_travel)}",
        f"joint_angle_max_deg = {float(np.rad2deg(lim.joint_angle_max))!r}",
        "",
        "# standard deviations of the estimated parameters (least squares):",
    ]
    lines += ["# " + toml_comment(f"  {n} = {float(s):.6g}") for n, s in zip(res.names, res.std)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _rms_of_bins(rms: list[float]) -> float | None:
    """The RMS over speed bins of their RMS values; None when no bin holds samples (a slow log: no warning)."""
    finite = [float(r) ** 2 for r in rms if r is not None and np.isfinite(r)]
    return float(np.sqrt(np.mean(finite))) if finite else None
