"""Kind ``lead_through``: lead-through programming with tool force feedback, simulated in contact.

Dressler (2012), ch. 8: the two-sensor control law (eqs. 8.3-8.11,
:mod:`gtmodel.estimation.lead_through.law`) acting on a velocity-controlled robot, a
workpiece and an operator (:mod:`gtmodel.estimation.lead_through.simulation`); the
experiments of ch. 8.4 (surface tracking with and without tool force control, Figure 8.4;
the normal-vector correction range on a stiff surface, Figure 8.5; peg-in-hole with a
misaligned hole, Figure 8.6) and the contact loop linearised (poles, oscillation
frequency, largest stable force gain per stiffness). Each experiment is judged against the
structure the thesis reports (:data:`~gtmodel.estimation.lead_through.declared.CHECKS`):
status ``completed`` when every check holds, ``check_failed`` otherwise.

The result folder holds ``summary.json``, ``surface_tracking.csv`` (the run with tool force
control: every controller input and output per 4 ms sample, the record the generated C is
checked on), ``correction_ranges.csv``, ``stability.csv``, ``peg_in_hole.csv``, the plots,
and ``controller.json`` with the controller step for ``gtmodel codegen --controller
controller.json``. The field reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel.codegen.controller import EstimatorILCBundle
from gtmodel.codegen.controller_file import save_controller
from gtmodel.errors import InputError
from gtmodel.estimation.lead_through.contact import PegHole, Surface
from gtmodel.estimation.lead_through.declared import CHECKS, LeadThroughDeclaration, LeadThroughSolution
from gtmodel.estimation.lead_through.experiments import tangent
from gtmodel.estimation.lead_through.law import LeadThroughLaw
from gtmodel.estimation.lead_through.simulation import LeadThroughRun, Servo
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.schemas.lead_through import LeadThroughFile
from gtmodel.report.lead_through import plot_peg, plot_position_force, plot_stable_gain, plot_surface_path

__all__ = ["LeadThroughKind", "LeadThroughFile", "run_table"]

#: Controller fields -> law arguments.
_LAW_FIELDS = {"task": "task", "mass": "M", "damping": "D", "force_gain": "K", "force_reference": "force_reference",
               "correction_range_deg": "correction_range_deg", "nominal_normal": "nominal_normal",
               "contact_force": "contact_force", "release_force": "release_force", "max_speed": "max_speed",
               "max_angular_speed": "max_angular_speed", "loop_period": "dt"}


#: Units of :func:`run_table`'s columns (``summary.json``'s ``units``: the report's axes): positions
#: [m], forces [N] and torques [N m] (``*_r*``), the handle velocity ``xs0..xs5`` and ``V_tool``
#: [m/s, rad/s], the flags and unit normals dimensionless.
RUN_UNITS: dict[str, str] = {
    "t": "s", **{c: "m" for c in "xyz"},
    **{f"{f}_{a}": ("N m" if a.startswith("r") else "N") for f in ("fc", "ft", "fh") for a in ("x", "y", "z", "rx", "ry", "rz")},
    **{f"{f}_{a}": "1" for f in ("nn", "n") for a in "xyz"},
    **{f"xs{i}": ("m/s" if i < 3 else "rad/s" if i < 6 else "1") for i in range(8)},
    **{f"v_{a}": ("rad/s" if a.startswith("r") else "m/s") for a in ("x", "y", "z", "rx", "ry", "rz")},
    "contact": "1",
}


def run_table(run: LeadThroughRun) -> dict[str, np.ndarray]:
    """The columns of a run's CSV: time, TCP position, wrenches, controller state and outputs.

    Parameters
    ----------
    run : LeadThroughRun
        The record.

    Returns
    -------
    dict of str to numpy.ndarray
        ``t``; ``x, y, z`` [m]; ``fc_*`` the true contact wrench; ``ft_*``, ``fh_*`` the
        measured tool and handle wrenches (the step's inputs ``F_t``, ``F_h``); ``nn_*`` the
        nominal normal; ``xs0..xs7`` the controller state before the step; ``v_*`` the
        applied ``V_tool``; ``n_*`` the normal used; ``contact`` (0/1). Each (N,).
    """
    axes6 = ("x", "y", "z", "rx", "ry", "rz")
    cols: dict[str, np.ndarray] = {"t": run.t}
    cols.update({c: run.p[:, i] for i, c in enumerate("xyz")})
    for prefix, data in (("fc", run.F_contact), ("ft", run.F_t), ("fh", run.F_h)):
        cols.update({f"{prefix}_{a}": data[:, i] for i, a in enumerate(axes6)})
    cols.update({f"nn_{a}": np.full(run.t.size, run.n_n[i]) for i, a in enumerate("xyz")})
    cols.update({f"xs{i}": run.x[:-1, i] for i in range(run.x.shape[1])})
    cols.update({f"v_{a}": run.V_tool[:, i] for i, a in enumerate(axes6)})
    cols.update({f"n_{a}": run.n[:, i] for i, a in enumerate("xyz")})
    cols["contact"] = run.contact.astype(float)
    return cols


def _expected(exc: Exception) -> str:
    """The part of an ``InputError`` ("<arg>: expected X, got Y") that follows "expected", for ``ProblemFile.fail``."""
    text = str(exc).split(": ", 1)[-1]
    return text[len("expected "):] if text.startswith("expected ") else text


def _write_csv(path: Path, cols: dict[str, Any]) -> None:
    np.savetxt(path, np.column_stack([np.asarray(v, dtype=float) for v in cols.values()]), delimiter=",",
               header=",".join(cols), comments="", fmt="%.17g")


class LeadThroughKind(ProblemKind):
    """Lead-through programming with tool force feedback, simulated (Dressler (2012), ch. 8)."""

    name = "lead_through"
    schema = LeadThroughFile
    title = "lead-through programming with tool force feedback: surface tracking, peg-in-hole, contact stability (Dressler (2012), ch. 8)"
    file_descriptions = {
        "controller.json": "the lead-through step function (gtmodel codegen --controller controller.json)",
        "surface_tracking.csv": "the surface-tracking run: positions, forces and corrections every sample",
        "correction_ranges.csv": "measures of the surface-tracking runs over the correction ranges",
        "stability.csv": "the contact loop's stability figures",
        "peg_in_hole.csv": "the peg-in-hole run: positions, forces and corrections every sample",
        "surface_tracking.png": "position and force while tracking the surface (Figure 8.4)",
        "surface_path.png": "the tool path over the surface, contact marked",
        "correction_ranges.png": "position and force over the correction ranges",
        "stability.png": "the contact loop's stability margin against the used gain",
        "peg_in_hole.png": "insertion depth and forces of the peg-in-hole runs",
    }
    columns = (
        Column("force_error_n", "max |f - f_ref| [N]", "{:.3f}"),
        Column("peg_max_insertion_m", "peg depth [m]", "{:.4f}"),
    )

    @fill_doc(**KIND_DOCS)
    def load(self, doc: LeadThroughFile, file: ProblemFile, name: str) -> LeadThroughDeclaration:
        """Build the controller, robot and workpieces (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        LeadThroughDeclaration

        Raises
        ------
        ProblemError
            A singular mass matrix, a zero normal, a release force not above the contact
            force (each naming its ``controller`` field); a task without its workpiece
            (``surface`` for surface tracking, ``peg`` for peg-in-hole); correction ranges
            without ``stiff_surface``; a hole narrower than the peg.
        """
        c = doc.controller
        args = {law_name: getattr(c, field) for field, law_name in _LAW_FIELDS.items()}
        try:
            law = LeadThroughLaw(**args)
        except InputError as exc:
            arg = str(exc).split(":", 1)[0]
            field = next((f for f, a in _LAW_FIELDS.items() if a == arg), "controller")
            raise file.fail(f"controller.{field}" if field != "controller" else field, _expected(exc)) from None
        ex = doc.experiment
        surface = stiff = hole = None
        if c.task == "surface_tracking":
            if doc.surface is None:
                raise file.fail("surface", "a [surface] table (stiffness, damping) for controller.task = surface_tracking")
            surface = Surface(doc.surface.stiffness, doc.surface.damping, normal=law.nominal_normal)
            if ex.correction_ranges_deg:
                if doc.stiff_surface is None:
                    raise file.fail("stiff_surface", "a [stiff_surface] table for experiment.correction_ranges_deg")
                stiff = Surface(doc.stiff_surface.stiffness, doc.stiff_surface.damping, normal=law.nominal_normal)
        else:
            if doc.peg is None:
                raise file.fail("peg", "a [peg] table for controller.task = peg_in_hole")
            p = doc.peg
            try:
                hole = PegHole(p.peg_radius, p.hole_radius, p.depth, p.misalignment_deg, stiffness=p.stiffness)
            except InputError as exc:
                raise file.fail(f"peg.{str(exc).split(':', 1)[0]}", _expected(exc)) from None
        return LeadThroughDeclaration(
            law=law, servo=Servo(doc.servo.bandwidth_hz, doc.servo.delay_samples), surface=surface, stiff_surface=stiff,
            hole=hole, duration=ex.duration, seed=ex.seed, tool_noise=doc.sensors.tool_noise,
            handle_noise=doc.sensors.handle_noise, operator_noise=ex.operator_noise,
            compare_without_force_control=ex.compare_without_force_control,
            correction_ranges_deg=tuple(ex.correction_ranges_deg),
            zero_clearance=bool(doc.peg.zero_clearance) if doc.peg is not None else False,
            stability_stiffness=tuple(ex.stability_stiffness))

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: LeadThroughDeclaration, solution: LeadThroughSolution, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, the runs' CSV files, plots and ``controller.json``.

        Parameters
        ----------
        declaration : LeadThroughDeclaration
            The declaration.
        solution : LeadThroughSolution
            Its runs.
        {write_args}

        Returns
        -------
        Written
            Status and message, the checks (with what each asserts), per experiment its
            measures, the assumptions (servo, operator), the controller file.
        """
        d, s = declaration, solution
        fields: dict[str, Any] = {
            "status": s.status, "message": s.message,
            "checks": {k: {"passed": v, "asserts": CHECKS[k]} for k, v in s.checks.items()},
            "task": d.law.task, "sample_time_s": d.law.dt,
            "servo": {"bandwidth_hz": d.servo.bandwidth_hz, "delay_samples": d.servo.delay_samples,
                      "assumed": "first-order velocity servo; the thesis gives no figure for the IRB 140"},
            "force_error_n": None, "peg_max_insertion_m": None, "units": dict(RUN_UNITS),
        }
        written = Written(fields)
        n = d.law.nominal_normal
        runs = []
        for label, r in (("with tool force control", s.tracking), ("without tool force control", s.without_control)):
            if r is None:
                continue
            key = "surface_tracking" if r is s.tracking else "without_force_control"
            fields[key] = {"first_contact_s": r.first_contact_s, "lost_contact_fraction": r.lost_contact_fraction,
                           "force_min_n": r.force_min, "force_max_n": r.force_max, "peak_force_n": r.peak_force,
                           "force_error_n": r.force_error, "released": r.released}
            runs.append((label, r.run.t, -d.surface.penetration(r.run.p), r.run.normal_force(n)))
        if s.tracking is not None:
            fields["force_error_n"] = s.tracking.force_error
            _write_csv(out / "surface_tracking.csv", run_table(s.tracking.run))
            written.files.append("surface_tracking.csv")
        if s.correction_ranges:
            rows = s.correction_ranges
            fields["correction_ranges"] = [r.measures() for r in rows]
            _write_csv(out / "correction_ranges.csv", {k: [r.measures()[k] for r in rows] for k in rows[0].measures()})
            written.files.append("correction_ranges.csv")
        if s.stability:
            fields["stability"] = [vars(r) for r in s.stability]
            _write_csv(out / "stability.csv", {k: [getattr(r, k) for r in s.stability] for k in vars(s.stability[0])})
            written.files.append("stability.csv")
        pegs = [(label, p) for label, p in (("4 mm hole" if d.hole is None else f"clearance {1e3 * (d.hole.hole_radius - d.hole.peg_radius):.2g} mm", s.peg),
                                            ("zero clearance", s.peg_zero_clearance)) if p is not None]
        for label, p in pegs:
            key = "peg_in_hole" if p is s.peg else "peg_zero_clearance"
            fields[key] = {"max_insertion_m": p.max_insertion, "final_insertion_m": p.final_insertion, "max_force_n": p.max_force,
                           "angle_start_deg": p.angle_start_deg, "angle_end_deg": p.angle_end_deg, "inserted": p.inserted}
        if s.peg is not None:
            fields["peg_max_insertion_m"] = s.peg.max_insertion
            _write_csv(out / "peg_in_hole.csv", run_table(s.peg.run))
            written.files.append("peg_in_hole.csv")
        save_controller(out / "controller.json", EstimatorILCBundle(lead_through_step=d.law.step_function(), dt=d.law.dt),
                        description=f"{name}: lead-through step ({d.law.task}); gtmodel codegen --controller controller.json")
        written.files.append("controller.json")
        fields["controller"] = {"file": "controller.json", "function": "lead_through_step"}
        if plots:
            if runs:
                plot_position_force(runs, out / "surface_tracking.png", force_reference=d.law.force_reference, title=f"{name}: Figure 8.4")
                t = tangent(n)
                b = np.cross(n, t)
                r = s.tracking.run
                plot_surface_path(r.p @ t, r.p @ b, r.contact, out / "surface_path.png", title=f"{name}: tool path")
                written.files += ["surface_tracking.png", "surface_path.png"]
            if s.correction_ranges:
                stiff = d.stiff_surface
                ranges = [(f"phi_L = {r.correction_range_deg:g} deg", r.run.t, -stiff.penetration(r.run.p), r.run.normal_force(n))
                          for r in s.correction_ranges]
                plot_position_force(ranges, out / "correction_ranges.png", force_reference=d.law.force_reference,
                                    title=f"{name}: Figure 8.5 (stiff surface)")
                written.files.append("correction_ranges.png")
            if s.stability:
                st = s.stability
                plot_stable_gain([r.stiffness for r in st], [r.largest_stable_gain for r in st], [r.frequency_hz for r in st],
                                 out / "stability.png", used_gain=float(n @ d.law.K[:3, :3] @ n), title=f"{name}: contact loop")
                written.files.append("stability.png")
            if pegs:
                peg_runs = []
                for label, p in pegs:
                    angle = np.degrees(np.arccos(np.clip(-(p.run.R[:, :, 2] @ p.hole.axis), -1.0, 1.0)))
                    peg_runs.append((label, p.run.t, p.hole.insertion(p.run.p), np.linalg.norm(p.run.F_contact[:, :3], axis=1), angle))
                plot_peg(peg_runs, out / "peg_in_hole.png", depth=d.hole.depth, title=f"{name}: peg-in-hole")
                written.files.append("peg_in_hole.png")
        return written
