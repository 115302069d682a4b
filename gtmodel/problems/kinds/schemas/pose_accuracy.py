"""The schema of a ``pose_accuracy`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.pose_accuracy`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import FileName, NonEmptyText, ProblemSchema, Section, integer, matrix, number, vector

__all__ = ["PoseAccuracyFile", "MAX_TOLERANCE_UM"]

#: Largest tolerance [um] (the analysis assumes L >> r, Appendix A.4): 5 cm.
MAX_TOLERANCE_UM = 5.0e4


def _range(description: str) -> Any:
    return vector(2, bound=100.0, unit="m", description=description)


class RobotSection(Section):
    """``[robot]``: the 3-link parameter set analysed."""

    parameters: NonEmptyText = Field(default="D1", description="shipped 3-link parameter set (D1, L1, L1_ideal) or a TOML path relative to this file")
    configuration: integer(0, 7, description="IK configuration (0: the nominal assembly)") = 0


class SectionSection(Section):
    """``[section]``: the yz workspace section ``x = x0`` that is mapped."""

    x: number(ge=-100.0, le=100.0, unit="m", description="the section's x")
    y: _range("[min, max] of the grid in y")
    z: _range("[min, max] of the grid in z")
    step: number(gt=0, le=10.0, unit="m", description="grid spacing")
    max_link_angle_deg: number(gt=0, lt=90.0, unit="deg", description="largest link-guideway angle of a grid point (default: the parameter set's joint limit)") | None = None


Tolerance3 = Annotated[
    list[vector(3, positive=True, bound=MAX_TOLERANCE_UM, unit="um")],
    Field(min_length=3, max_length=3, description="row i: the semi-axes of arm i's joint-point error ellipsoid along x, y, z, positive [um]"),
]


class CaseSection(Section):
    """``[[cases]]``: one tolerance case (a column of Table 4.2)."""

    name: FileName = Field(description="case name (file and column names)")
    semi_axes_um: Tolerance3
    link_um: vector(3, nonnegative=True, bound=MAX_TOLERANCE_UM, unit="um", description="link-length tolerances l_i (Appendix A.3)") = [0.0, 0.0, 0.0]
    reference_range_um: vector(2, positive=True, bound=1e6, unit="um", description="the published [min, max] of the map, compared in the result") | None = None


class ExactSection(Section):
    """``[exact]``: the exact worst-case NLP and the Monte-Carlo estimate at the check poses."""

    corner_starts: integer(1, 8, description="IPOPT starts from the best corners of the geometric method") = 2
    random_starts: integer(0, 50, description="further IPOPT starts, uniform in the tolerances") = 2
    samples: integer(100, 1_000_000, description="Monte-Carlo samples per check pose") = 20000
    seed: integer(0, 2**31 - 1, description="random seed") = 0
    poses: matrix(3, bound=100.0, unit="m", description="further check poses [x, y, z] (the map's min, max and centre are always checked)") | None = None


class InverseSection(Section):
    """``[inverse]``: the largest tolerances keeping the worst case under a TCP error bound."""

    tcp_error_um: number(gt=0, le=1e6, unit="um", description="the TCP error bound over the section")
    case: NonEmptyText = Field(description="the case whose tolerance shape is scaled")


@fill_doc(**KIND_DOCS)
class PoseAccuracyFile(ProblemSchema):
    """A ``pose_accuracy`` problem file.

    Parameters
    ----------
    {header_fields}
    robot : RobotSection
        ``[robot]``: the parameter set.
    section : SectionSection
        ``[section]``: the mapped section.
    cases : list of CaseSection
        ``[[cases]]``: the tolerance cases.
    exact : ExactSection
        ``[exact]``: NLP and Monte-Carlo settings.
    inverse : InverseSection, optional
        ``[inverse]``: the inverse question.
    """

    kind: Literal["pose_accuracy"]
    robot: RobotSection = RobotSection()
    section: SectionSection
    cases: list[CaseSection] = Field(min_length=1, max_length=10)
    exact: ExactSection = ExactSection()
    inverse: InverseSection | None = None
