"""Kind ``pose_accuracy``: worst-case TCP errors from actuator tolerances over a workspace section.

Dressler (2012), ch. 4.3 (Table 4.2, Figs. 4.8-4.10) and Appendix A, on the 3-link closure
model::

    name = "d1_pose_accuracy"
    kind = "pose_accuracy"

    [robot]
    parameters = "D1"

    [section]                     # the yz section x = x0, gridded
    x = -1.6
    y = [-5.8, -2.8]
    z = [-1.4, 1.6]
    step = 0.02
    max_link_angle_deg = 65.0     # optional (default: the set's joint limit)

    [[cases]]                     # one table per tolerance case
    name = "case_1"
    semi_axes_um = [[32, 32, 32], [77, 77, 77], [54, 54, 54]]
    link_um = [0, 0, 0]
    reference_range_um = [140, 230]

    [exact]                       # the NLP and Monte-Carlo at the check poses
    corner_starts = 2
    random_starts = 2
    samples = 20000

    [inverse]                     # optional: the inverse question
    tcp_error_um = 100
    case = "case_1"

The result folder holds ``summary.json`` (per case the map range by the geometric method
(A.2) and the parallelepiped (A.4, equal to the exact NLP to nanometres), the check poses
with the three methods compared (geometric, parallelepiped, exact NLP, Monte-Carlo max,
mean and 95 % quantile), the gaps, the published range and its relative deviation; the
inverse answer), ``map_<case>.csv``, ``checks.csv`` and the plots ``map_<case>.png`` (Figs.
4.8/4.10), ``faces_<case>.png`` (Fig. 4.9) and ``error_set_<case>.png``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel._tables import write_table
from gtmodel.calibration.accuracy import (
    AccuracyCase,
    CaseResult,
    PoseAccuracyDeclaration,
    PoseAccuracyResult,
    Section,
    Tolerances,
)
from gtmodel.calibration.accuracy.section import MAX_SECTION_POINTS, section_poses
from gtmodel.errors import GtModelError
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.schemas.pose_accuracy import PoseAccuracyFile
from gtmodel.report.accuracy import plot_accuracy_map, plot_error_set, plot_face_areas
from gtmodel.robots import available_parameter_sets
from gtmodel.robots.kinematics import GantryTau3Kinematics

__all__ = ["PoseAccuracyKind", "PoseAccuracyFile"]

UM = 1e-6
#: Grid lines per axis of the load-time check that the section meets the workspace.
_CHECK_LINES = 50


class PoseAccuracyKind(ProblemKind):
    """Worst-case pose accuracy: geometric method, exact NLP and Monte-Carlo compared (Dressler (2012), App. A)."""

    name = "pose_accuracy"
    schema = PoseAccuracyFile
    title = "worst-case TCP error from actuator tolerances: geometric method, exact NLP, Monte-Carlo, inverse (Dressler (2012), ch. 4.3, App. A)"
    file_descriptions = {
        "map_*.csv": "a case's worst-case TCP error over the workspace grid: geometric, parallelepiped, face areas [m]",
        "map_*.png": "a case's accuracy map over the workspace",
        "faces_*.png": "a case's parallelepiped face areas along a line",
        "error_set_*.png": "a case's TCP error set at a pose",
        "checks.csv": "the geometric method checked against the exact NLP and Monte-Carlo at chosen poses",
    }
    columns = (
        Column("max_error_m", "largest worst case [m]", "{:.4e}"),
        Column("min_error_m", "smallest worst case [m]", "{:.4e}"),
        Column("parallelepiped_gap_m", "parallelepiped - exact [m]", "{:.2e}"),
    )
    extra_empty_fields = ("cases",)

    @fill_doc(**KIND_DOCS)
    def load(self, doc: PoseAccuracyFile, file: ProblemFile, name: str) -> PoseAccuracyDeclaration:
        """The model, the section (bounded, not empty), the tolerances and the check poses.

        Parameters
        ----------
        {load_args}

        Returns
        -------
        PoseAccuracyDeclaration

        Raises
        ------
        ProblemError
            A bad parameter set; a section range that is not increasing, too fine or without
            a workspace point (checked on a grid of about 50 x 50 points); repeated case names; an inverse case that is not declared; a
            check pose outside the workspace.
        """
        ref = file.reference("robot.parameters", doc.robot.parameters, available_parameter_sets())
        try:
            kin = GantryTau3Kinematics(str(ref))
        except GtModelError as exc:
            raise file.wrap("robot.parameters", exc) from None
        s = doc.section
        for key in ("y", "z"):
            lo, hi = getattr(s, key)
            if not hi > lo:
                raise file.fail(f"section.{key}", "an increasing range [min, max]", [lo, hi])
        angle = None if s.max_link_angle_deg is None else float(np.radians(s.max_link_angle_deg))
        section = Section(s.x, tuple(s.y), tuple(s.z), s.step, angle)
        ys, zs = section.axes()
        if ys.size * zs.size > MAX_SECTION_POINTS:
            raise file.fail("section.step", f"a step giving at most {MAX_SECTION_POINTS} grid points", s.step)
        # the load-time check on a grid of at most ~50 x 50 points (the map is the solve's job)
        coarse = max(s.step, (s.y[1] - s.y[0]) / _CHECK_LINES, (s.z[1] - s.z[0]) / _CHECK_LINES)
        _, _, inside = section_poses(kin, Section(s.x, tuple(s.y), tuple(s.z), coarse, angle))
        if not inside.any():
            raise file.fail("section", "a section with grid points in the workspace (none of its points is reachable within the limits)",
                            {"x": s.x, "y": s.y, "z": s.z})
        names = [c.name for c in doc.cases]
        if len(set(names)) != len(names):
            raise file.fail("cases", "distinct case names", names)
        cases = []
        for k, c in enumerate(doc.cases):
            try:
                tol = Tolerances(np.asarray(c.semi_axes_um) * UM, link=np.asarray(c.link_um) * UM)
            except GtModelError as exc:
                raise file.wrap(f"cases[{k}].semi_axes_um", exc) from None
            ref_range = None
            if c.reference_range_um is not None:
                if not c.reference_range_um[1] > c.reference_range_um[0]:
                    raise file.fail(f"cases[{k}].reference_range_um", "an increasing range [min, max]", c.reference_range_um)
                ref_range = (c.reference_range_um[0] * UM, c.reference_range_um[1] * UM)
            cases.append(AccuracyCase(c.name, tol, ref_range))
        poses = np.zeros((0, 3)) if doc.exact.poses is None else np.asarray(doc.exact.poses, dtype=float)
        for k, T in enumerate(poses):
            try:
                ok = kin.in_workspace(T, doc.robot.configuration)
            except GtModelError as exc:
                raise file.wrap(f"exact.poses[{k}]", exc) from None
            if not ok:
                raise file.fail(f"exact.poses[{k}]", f"a pose in the workspace of {kin.parameters.name}", T.tolist())
        inverse_case = 0
        tcp_error = None
        if doc.inverse is not None:
            if doc.inverse.case not in names:
                raise file.fail("inverse.case", f"one of the cases ({', '.join(names)})", doc.inverse.case)
            inverse_case = names.index(doc.inverse.case)
            tcp_error = doc.inverse.tcp_error_um * UM
        e = doc.exact
        return PoseAccuracyDeclaration(kin, section, tuple(cases), poses, e.corner_starts, e.random_starts, e.samples, e.seed,
                                       tcp_error, inverse_case)

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: PoseAccuracyDeclaration, solution: PoseAccuracyResult, out: Path, plots: bool, name: str) -> Written:
        """Summary fields, ``map_<case>.csv``, ``checks.csv`` and the plots.

        Parameters
        ----------
        declaration : PoseAccuracyDeclaration
            The problem.
        solution : PoseAccuracyResult
            Its result.
        {write_args}

        Returns
        -------
        Written
        """
        cases = {c.case.name: _case_fields(c) for c in solution.cases}
        fields: dict[str, Any] = {
            "status": solution.status,
            "message": solution.message,
            "robot": declaration.kinematics.parameters.name,
            "section_x_m": declaration.section.x,
            "actuators_yz_m": solution.actuators.tolist() if solution.actuators is not None else None,
            "max_error_m": max((v["map_parallelepiped_m"][1] for v in cases.values()), default=None),
            "min_error_m": min((v["map_parallelepiped_m"][0] for v in cases.values()), default=None),
            "parallelepiped_gap_m": max((v["max_parallelepiped_gap_m"] for v in cases.values()), default=None),
            "cases": cases,
        }
        if solution.inverse is not None:
            inv = solution.inverse
            fields["inverse"] = {
                "tcp_error_m": inv.tcp_error,
                "case": declaration.cases[declaration.inverse_case].name,
                "factors": inv.factors.tolist(),
                "semi_axes_m": inv.tolerances.semi_axes.tolist(),
                "link_m": inv.tolerances.link.tolist(),
                "uniform_factor": inv.uniform_factor,
                "exact_worst_m": inv.exact_worst,
                "tightest_pose_m": inv.tightest_pose.tolist(),
                "status": inv.status,
            }
        written = Written(fields)
        rows = []
        for ci, c in enumerate(solution.cases):
            m = c.map
            Y, Z = np.meshgrid(m.ys, m.zs, indexing="ij")
            data = np.column_stack([Y[m.inside], Z[m.inside], m.geometric[m.inside], m.parallelepiped[m.inside], m.face_areas[m.inside]])
            write_table(out / f"map_{c.case.name}.csv", ["y_m", "z_m", "geometric_m", "parallelepiped_m", "face_1_m2", "face_2_m2", "face_3_m2"],
                        data, comments=[f"{name}: worst-case TCP error over the section x = {declaration.section.x} m, case {c.case.name}"])
            written.files.append(f"map_{c.case.name}.csv")
            for k, ch in enumerate(c.checks):
                rows.append([ci, k, *ch.T, ch.geometric, ch.parallelepiped, ch.exact.error, ch.monte_carlo.max, ch.monte_carlo.mean,
                             ch.monte_carlo.quantile(0.95)])
            if plots:
                line = float(c.checks[2].T[2])
                plot_accuracy_map(c, solution.actuators, out / f"map_{c.case.name}.png", f"{name}: ", line_z=line)
                plot_face_areas(c, line, out / f"faces_{c.case.name}.png", f"{name}: ")
                plot_error_set(c, 2, out / f"error_set_{c.case.name}.png", f"{name}: ")
                written.files += [f"map_{c.case.name}.png", f"faces_{c.case.name}.png", f"error_set_{c.case.name}.png"]
        if rows:
            write_table(out / "checks.csv", ["case", "check", "x_m", "y_m", "z_m", "geometric_m", "parallelepiped_m", "exact_m", "monte_carlo_max_m",
                                             "monte_carlo_mean_m", "monte_carlo_p95_m"], rows,
                        comments=[f"{name}: cases {', '.join(c.case.name for c in solution.cases)}; checks min, max, centre, then declared poses"],
                        integer_columns=(0, 1))
            written.files.append("checks.csv")
        return written


def _case_fields(c: CaseResult) -> dict[str, Any]:
    """The summary of one case: map ranges, the check poses, the gaps, the published range."""
    par = c.map.parallelepiped[c.map.inside]
    out: dict[str, Any] = {
        "map_geometric_m": list(c.range),
        "map_parallelepiped_m": [float(par.min()), float(par.max())],
        "grid_points": int(c.map.inside.sum()),
        "max_parallelepiped_gap_m": c.max_parallelepiped_gap,
        "max_geometric_gap_m": c.max_geometric_gap,
        "monte_carlo_within_exact": c.monte_carlo_within_exact,
        "checks": {
            ch.label: {
                "T_m": ch.T.tolist(),
                "geometric_m": ch.geometric,
                "parallelepiped_m": ch.parallelepiped,
                "exact_m": ch.exact.error,
                "exact_direction": (ch.exact.deviation / ch.exact.error).tolist(),
                "exact_status": ch.exact.status,
                "exact_starts": ch.exact.starts,
                "monte_carlo_max_m": ch.monte_carlo.max,
                "monte_carlo_mean_m": ch.monte_carlo.mean,
                "monte_carlo_p95_m": ch.monte_carlo.quantile(0.95),
                "face_areas_m2": ch.face_areas.tolist(),
            }
            for ch in c.checks
        },
    }
    if c.case.reference_range is not None:
        lo, hi = c.case.reference_range
        out["reference_range_m"] = [lo, hi]
        for key in ("map_parallelepiped_m", "map_geometric_m"):
            got = out[key]
            out[f"{key[:-2]}_deviation_from_reference"] = [got[0] / lo - 1.0, got[1] / hi - 1.0]
    return out
