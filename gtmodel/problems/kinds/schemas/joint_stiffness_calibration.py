"""The schema of a ``joint_stiffness_calibration`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.joint_stiffness_calibration`; the field
reference is ``docs/problem_files.md``.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, Field
from pydantic_core import PydanticCustomError

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import MAX_FORCE_N, NonEmptyText, ProblemSchema, Section, choice, integer, number, vector

__all__ = [
    "JointStiffnessFile",
    "MAX_MOMENT_NM",
    "MIN_JOINT_STIFFNESS",
    "MAX_JOINT_STIFFNESS",
    "TABLE_2_DPP_K_THETA",
    "TABLE_2_ROTATION_ONLY_STIFFNESS",
]

#: Defaults of ``[truth]``, those of :mod:`gtmodel.calibration.joint_stiffness` (equal,
#: checked by the tests; here so that a file is validated without the calibration): the
#: DPP joint stiffnesses of Cvitanic (2021), Table 2 [N m/rad], and the stiffness of the
#: rotation-only compliance of its scenario [N m/rad].
TABLE_2_DPP_K_THETA = (2.86e6, 2.36e6, 1.67e6, 2.4e5, 1.6e5, 1.4e5)
TABLE_2_ROTATION_ONLY_STIFFNESS = 3.0e5
#: Largest load-case moment [N m] (a moment of 1e308 made LAPACK hang on inf deflections).
MAX_MOMENT_NM = 1.0e7
#: Joint (and rotation-only) stiffness range [N m/rad]: from a very soft joint to a rigid one.
MIN_JOINT_STIFFNESS = 1.0
MAX_JOINT_STIFFNESS = 1.0e12
def _stiffness(description: str) -> Any:
    return number(ge=MIN_JOINT_STIFFNESS, le=MAX_JOINT_STIFFNESS, unit="N m/rad", description=description,
                  what=f"a stiffness in {MIN_JOINT_STIFFNESS:g}..{MAX_JOINT_STIFFNESS:g} N m/rad")


def _at_least_min_stiffness(v: list[float]) -> list[float]:
    if any(x < MIN_JOINT_STIFFNESS for x in v):
        raise PydanticCustomError("gtmodel", "expected {expected}",
                                  {"expected": f"stiffnesses in {MIN_JOINT_STIFFNESS:g}..{MAX_JOINT_STIFFNESS:g} N m/rad"})
    return v


#: Six joint stiffnesses [N m/rad] in the physical range.
JointStiffnesses = Annotated[
    vector(6, positive=True, bound=MAX_JOINT_STIFFNESS, unit="N m/rad", description="true joint stiffnesses (default: Table 2 DPP)"),
    AfterValidator(_at_least_min_stiffness),
]


class ArmSection(Section):
    """``[arm]``: the serial arm (Jacobian source)."""

    model: NonEmptyText = Field(default="serial_6r_illustrative",
                                description="shipped DH file (serial_6r_illustrative, ILLUSTRATIVE geometry) or a TOML path relative to the problem file")


class TruthSection(Section):
    """``[truth]``: synthetic data on the Table 1 poses."""

    k_theta: JointStiffnesses = Field(default_factory=lambda: list(TABLE_2_DPP_K_THETA))
    scenario: choice("none", "table_2", description='"none": exact joint-spring model; "table_2": unmodelled rotation-only compliance') = "table_2"
    rotation_only_stiffness: _stiffness("stiffness of the unmodelled rotation-only compliance, scenario table_2 only "
                                        f"(default {TABLE_2_ROTATION_ONLY_STIFFNESS:g})") | None = None
    load_cases: choice("axis", "gravity_pulley", description='"axis": forces along +x, +y, -z and moments about x, y, z per pose; '
                       '"gravity_pulley": the thesis\' force-only loads, gravity (-z) and a pulley along +x and +y per pose') = "axis"
    force: number(gt=0, le=MAX_FORCE_N, unit="N", description="force of each force load case") = 1000.0
    moment: number(gt=0, le=MAX_MOMENT_NM, unit="N m", description="moment of each moment load case") = 200.0
    seed: integer(0, 2**31 - 1, description="noise seed") = 0
    seeds: integer(1, 10_000, description="Monte-Carlo seeds seed .. seed + seeds - 1 judged against the truth and Table 2's pattern (1: none)") = 1


class NoiseSection(Section):
    """``[noise]``: laser-tracker noise of synthetic data (Table 2 notes)."""

    position_std: number(ge=0, le=1.0, unit="m", description="position noise (std)") = 15e-6
    position_std_per_m: number(ge=0, le=1.0, unit="m/m", description="position noise per m of tracker distance") = 6e-6
    rotation_std: number(ge=0, le=math.pi, unit="rad", description="rotation noise (std) per axis") = 2.6e-4
    force_relative_std: number(ge=0, le=1.0, description="relative wrench noise (std)") = 0.0
    target_radius: number(gt=0, le=10.0, unit="m", description="three tracker targets on this radius measure the rotation: "
                          "rotation_std = position_std / (radius sqrt(3/2)), replacing rotation_std") | None = None


class CalibrationSection(Section):
    """``[calibration]``: method options."""

    scaled_rotation_weight: number(gt=0, le=1e6, unit="m/rad", description="rotation weight of the scaled CP variant (the thesis' x10)") = 10.0
    bounds: choice("none", "positive", description='"positive": compliances c = 1/k >= 0') = "none"
    rotation_weight: number(gt=0, le=1e6, unit="m/rad", description="rotation weight of CP (1: residual in m and rad; 1e-3: in mm and rad)") = 1.0
    dpp_step2: choice("rotation", "tcp_translation", description='data of DPP step 2: the rotation, or the TCP translation as eq. (5) is written') = "rotation"


class DataSection(Section):
    """``[data]``: measured deflections."""

    file: NonEmptyText = Field(description="CSV of measurements (header DATA_COLUMNS), relative to the problem file")


@fill_doc(**KIND_DOCS)
class JointStiffnessFile(ProblemSchema):
    """A ``joint_stiffness_calibration`` problem file: exactly one of ``[truth]`` and ``[data]``.

    Parameters
    ----------
    {header_fields}
    arm : ArmSection, optional
        ``[arm]``: the serial arm.
    truth : TruthSection, optional
        ``[truth]``: synthetic data on the Table 1 poses.
    noise : NoiseSection, optional
        ``[noise]``: noise of synthetic data.
    calibration : CalibrationSection, optional
        ``[calibration]``: method options.
    data : DataSection, optional
        ``[data]``: measured deflections.
    """

    kind: Literal["joint_stiffness_calibration"]
    arm: ArmSection = ArmSection()
    truth: TruthSection | None = None
    noise: NoiseSection | None = None
    calibration: CalibrationSection = CalibrationSection()
    data: DataSection | None = None
