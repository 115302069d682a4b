"""The schema of an ``automated_calibration`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.automated_calibration`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import NonEmptyText, ProblemSchema, Section, choice, integer, number, vector

__all__ = ["AutomatedCalibrationFile"]

#: Largest coordinate or length [m] of the set-up (a robot cell).
MAX_COORDINATE_M = 100.0

Rows3 = Annotated[
    list[vector(3, bound=MAX_COORDINATE_M, unit="m")],
    Field(min_length=3, max_length=3, description="three rows, one per arm"),
]


class ParametersSection(Section):
    """``[apriori]`` and ``[truth]``: 3-link kinematic parameters (Dressler (2012), eq. 4.9)."""

    L: vector(3, positive=True, bound=MAX_COORDINATE_M, unit="m", description="link lengths")
    As: Rows3
    v: Rows3


class LimitsSection(Section):
    """``[limits]``: what the workspace search respects."""

    cart_travel: Annotated[list[vector(2, bound=MAX_COORDINATE_M, unit="m")], Field(min_length=3, max_length=3,
                           description="[q_min, q_max] per cart (Table 5.7: +-1 m)")]
    joint_angle_max_deg: number(gt=0, lt=90.0, unit="deg", description="spherical-joint limit (Table 5.7: 30)")
    joint_axes: choice("home", "guideway", description='the joints\' neutral axes: "home" (the link directions with every cart at q = 0) or "guideway"') = "home"
    safety_margin: number(ge=0, le=10.0, unit="m", description="distance kept from the limit of the kinematic workspace (Table 5.7: 0.1)") = 0.1
    search_step: number(gt=0, le=10.0, unit="m", description="grid step of the workspace search (thesis: 0.1)") = 0.1


class ObstacleSection(Section):
    """``[[obstacles]]``: an axis-aligned box and its safety zone."""

    name: NonEmptyText = Field(description="what it is")
    lo: vector(3, bound=MAX_COORDINATE_M, unit="m", description="the box's lower corner")
    hi: vector(3, bound=MAX_COORDINATE_M, unit="m", description="the box's upper corner")
    safety: number(ge=0, le=10.0, unit="m", description="distance kept from the box") = 0.1


class DeviceSection(Section):
    """``[device]``: the measuring device, its noise and the area it measures."""

    type: choice("camera", "laser_tracker", description="a fixed pinhole camera or a laser tracker")
    noise: number(ge=0, le=1.0, unit="m", description="position noise per coordinate (default: camera 1.7e-3, laser tracker 10e-6)") | None = None
    position: vector(3, bound=MAX_COORDINATE_M, unit="m", description="camera centre or tracker position")
    look_at: vector(3, bound=MAX_COORDINATE_M, unit="m", description="camera only: the point on the optical axis") | None = None
    focal_px: number(gt=0, le=1e6, unit="px", description="camera only: focal length") = 1400.0
    image_px: vector(2, positive=True, bound=1e5, unit="px", description="camera only: image width and height") = [1600.0, 1200.0]
    pattern_size: number(gt=0, le=10.0, unit="m", description="camera only: side of the square pattern on the plate, facing the camera") = 0.3
    range: vector(2, nonnegative=True, bound=1e3, unit="m", description="laser tracker only: [min, max] distance") = [1.0, 20.0]


class PosesSection(Section):
    """``[poses]``: how many poses, and their acceptance."""

    desired: integer(8, 5000, description="desired number of poses (thesis: 100)") = 100
    criterion: choice("condition", "noise_amplification", description="reading of eq. 5.14 per arm: cond(J) or sigma_max^2/sigma_min with unit columns") = "condition"
    threshold: number(gt=0, le=1e12, description="C of eq. 5.14 (thesis: 200)") = 200.0
    growth: number(gt=1.0, le=10.0, description="factor on the desired count after a rejected round") = 1.5
    max_rounds: integer(1, 10, description="rounds before giving up") = 4


class SimulationSection(Section):
    """``[simulation]``: the simulated calibration with the device's noise."""

    runs: integer(2, 200, description="simulated calibrations") = 5
    recovery_sigmas: number(gt=0, le=100.0, description="a parameter is recovered when its mean over the runs is within this many standard errors of the truth") = 4.0
    perturbation: number(ge=0, le=1.0, unit="m", description="without [truth]: the truth is the a priori model with every parameter moved by up to this") = 0.01
    seed: integer(0, 2**31 - 1, description="noise seed") = 0


class DataSection(Section):
    """``[data]``: the measurements taken at the poses (the calibration kind's CSV format)."""

    file: NonEmptyText = Field(description="measurement CSV (columns q1, q2, q3, x, y, z; docs/own_data.md), relative to this file")


@fill_doc(**KIND_DOCS)
class AutomatedCalibrationFile(ProblemSchema):
    """An ``automated_calibration`` problem file.

    Parameters
    ----------
    {header_fields}
    apriori : ParametersSection
        ``[apriori]``: the a priori kinematic parameters.
    truth : ParametersSection, optional
        ``[truth]``: the robot of the simulated calibration.
    limits : LimitsSection
        ``[limits]``: travel, joint limit, safety.
    obstacles : list of ObstacleSection
        ``[[obstacles]]``.
    device : DeviceSection
        ``[device]``.
    poses : PosesSection
        ``[poses]``.
    simulation : SimulationSection
        ``[simulation]``.
    data : DataSection, optional
        ``[data]``: measurements taken at the poses (default: synthetic ones of the truth).
    """

    kind: Literal["automated_calibration"]
    apriori: ParametersSection
    truth: ParametersSection | None = None
    limits: LimitsSection
    obstacles: list[ObstacleSection] = Field(default_factory=list, max_length=100)
    device: DeviceSection
    poses: PosesSection = PosesSection()
    simulation: SimulationSection = SimulationSection()
    data: DataSection | None = None
