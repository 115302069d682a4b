"""The schema of an ``elasto_geometric_calibration`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.elasto_geometric_calibration`; the field
reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.calibration import LSQ_SOLVERS, StringList
from gtmodel.problems.schema import MAX_LENGTH_M, Flag, NonEmptyText, ProblemSchema, Section, choice, integer, number, vector

__all__ = ["ElastoGeometricFile", "MAX_PAYLOAD_KG", "MAX_PAYLOADS", "COMPLIANCE_NAME_LIST"]

#: The compliance names, those of :data:`gtmodel.calibration.elasto_geometric.COMPLIANCE_NAMES`
#: (equal, checked by the tests; here so that a file is validated without the calibration).
COMPLIANCE_NAME_LIST = ("c_l1", "c_l2", "c_l3", "c_a1", "c_a2", "c_a3")
#: Largest payload [kg] (the Gantry-Tau robots carry tens of kilograms).
MAX_PAYLOAD_KG = 1.0e3
#: Largest number of payloads (each multiplies the measured poses).
MAX_PAYLOADS = 10
class TruthSection(Section):
    """``[truth]``: the compliant true robot and its synthetic measurements."""

    parameters: NonEmptyText = Field(description="robot parameter set of the true robot: a shipped name or a TOML path")
    stiffness: NonEmptyText = Field(default="stiffness", description='stated stiffness values: "stiffness" (shipped) or a TOML path')
    payloads_kg: vector(None, nonnegative=True, bound=MAX_PAYLOAD_KG, max_length=MAX_PAYLOADS, unit="kg",
                        description="every pose is measured with each payload") = [40.0]
    noise: choice("laser_tracker", "stereo_vision", "none", description="measurement device (noise)") = "laser_tracker"
    grid_step: number(gt=0, le=MAX_LENGTH_M, unit="m", description="spacing of the regular workspace grid")
    seed: integer(0, 2**31 - 1, description="noise seed") = 0


class StartSection(Section):
    """``[start]``: the start model."""

    parameters: NonEmptyText = Field(description="start geometry: a shipped name or a TOML path")
    parametrisation: choice("ideal", "modified", description="ideal (15) or modified (21 parameters)") = "modified"
    compliance: choice("zero", "stated", description="start compliances") = "zero"


class CalibrationSection(Section):
    """``[calibration]``: solver options and the free compliances."""

    solver: choice(*LSQ_SOLVERS, description="least-squares solver") = "lm"
    max_iter: integer(1, 10**6, description="iteration limit") = 200
    align: Flag = Field(default=True, description="move the start model into the measurement frame")
    free_compliance: StringList = Field(default_factory=lambda: list(COMPLIANCE_NAME_LIST), description="compliance names or patterns estimated")
    compare_single_load: Flag = Field(default=False, description="also calibrate on one load (the largest payload)")


class StiffnessMapSection(Section):
    """``[stiffness_map]``: stiffness map of the true robot on a yz section."""

    step: number(gt=0, le=MAX_LENGTH_M, unit="m", description="grid spacing in y and z") = 0.05
    x: number(ge=-MAX_LENGTH_M, le=MAX_LENGTH_M, unit="m", description="section coordinate (default: the workspace median)") | None = None


@fill_doc(**KIND_DOCS)
class ElastoGeometricFile(ProblemSchema):
    """An ``elasto_geometric_calibration`` problem file.

    Parameters
    ----------
    {header_fields}
    truth : TruthSection
        ``[truth]``: the true robot, stiffness, payloads and noise.
    start : StartSection
        ``[start]``: the model calibrated and its starting compliances.
    calibration : CalibrationSection, optional
        ``[calibration]``: solver settings and free compliances.
    stiffness_map : StiffnessMapSection, optional
        ``[stiffness_map]``: the stiffness map written with the result.
    """

    kind: Literal["elasto_geometric_calibration"]
    truth: TruthSection
    start: StartSection
    calibration: CalibrationSection = CalibrationSection()
    stiffness_map: StiffnessMapSection = StiffnessMapSection()
