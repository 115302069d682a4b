"""The schema of a ``replay`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.replay` (formerly ``tracking``: a file with
``kind = "tracking"`` is read as ``replay`` with a deprecation warning); the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.closed_loop import RobotSection, SensorsSection, StructureSection
from gtmodel.problems.schema import NonEmptyText, ProblemSchema, Section, number

__all__ = ["ReplayFile", "MAX_SETTLE_S"]

#: Longest accepted settling time [s].
MAX_SETTLE_S = 60.0


class TrajectorySection(Section):
    """``[trajectory]``: what is replayed (exactly one of ``problem`` and ``file``)."""

    problem: NonEmptyText | None = Field(default=None, description="a point_to_point or path_constrained problem file (relative to this file), solved first; its trajectory.csv is replayed")
    file: NonEmptyText | None = Field(default=None, description="a trajectory.csv written by point_to_point or path_constrained (relative to this file)")
    settle_time: number(ge=0, le=MAX_SETTLE_S, unit="s", description="the reference is held at its last value this long after the motion") = 1.0


@fill_doc(**KIND_DOCS)
class ReplayFile(ProblemSchema):
    """A ``replay`` problem file.

    Parameters
    ----------
    {header_fields}
    trajectory : TrajectorySection
        ``[trajectory]``: the replayed trajectory and the settling time.
    robot : RobotSection
        ``[robot]``: parameter set, IK configuration, actuator models.
    structure : StructureSection
        ``[structure]``: the structural modes.
    sensors : SensorsSection
        ``[sensors]``: noise and range.
    """

    kind: Literal["replay"]
    trajectory: TrajectorySection
    robot: RobotSection
    structure: StructureSection = StructureSection()
    sensors: SensorsSection = SensorsSection()
