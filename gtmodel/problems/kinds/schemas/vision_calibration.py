"""The schema of a ``vision_calibration`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.vision_calibration`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field
from pydantic_core import PydanticCustomError

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import MAX_LENGTH_M, NonEmptyText, ProblemSchema, Section, choice, integer, matrix, number, vector

__all__ = ["VisionCalibrationFile", "MAX_IMAGE_PX", "MAX_DISTORTION"]

#: Largest image side [px].
MAX_IMAGE_PX = 100_000
#: Largest absolute distortion coefficient accepted.
MAX_DISTORTION = 10.0


class TruthSection(Section):
    """``[truth]``: synthetic images and tracker data of a declared true robot."""

    parameters: NonEmptyText = Field(default="L1", description="parameter set of the true 3-link robot: a shipped name or a TOML path relative to the problem file")
    actuator_errors: choice("none", "table_4_1", description="actuator errors of the true robot (Table 4.1), seen by camera and tracker") = "none"
    grid_step: number(gt=0, le=MAX_LENGTH_M, unit="m", description="spacing of the cart grid of commanded poses") = 0.14
    tracker_noise: choice("laser_tracker", "none", description="the laser tracker measuring the same poses") = "laser_tracker"
    seed: integer(0, 2**31 - 1, description="seed of pixel and tracker noise") = 0


class DataSection(Section):
    """``[data]``: detected corners of a real rig."""

    file: NonEmptyText = Field(description="corner CSV (pose, corner, q1_m..q3_m, u1_px, v1_px, u2_px, v2_px; docs/own_data.md), relative to the problem file")
    tracker_file: NonEmptyText | None = Field(default=None, description="optional tracker measurements of the same poses (measurement CSV, matched by the cart positions)")


class CameraSection(Section):
    """``[[cameras]]``: one of the two cameras (intrinsics calibrated beforehand)."""

    name: NonEmptyText | None = Field(default=None, description="label (default: camera 1, camera 2)")
    image_size: vector(2, positive=True, bound=MAX_IMAGE_PX, description="width, height [px]")
    focal_px: vector(2, positive=True, bound=1e6, description="fx, fy [px]")
    principal_point_px: vector(2, nonnegative=True, bound=MAX_IMAGE_PX, description="cx, cy [px], inside the image")
    distortion: vector(5, bound=MAX_DISTORTION, description="k1, k2, p1, p2, k3 (OpenCV order) the reconstruction assumes") = [0.0] * 5
    true_distortion: vector(5, bound=MAX_DISTORTION, description="[truth] only: the lens' true coefficients (default: distortion)") | None = None
    position: vector(3, bound=MAX_LENGTH_M, unit="m", description="camera centre in the robot (tracker) frame: the truth of synthetic images; plots only for [data]")
    look_at: vector(3, bound=MAX_LENGTH_M, unit="m", description="a point on the optical axis (robot frame)")
    up: vector(3, bound=MAX_LENGTH_M, description="direction that appears upwards in the image") = [0.0, 0.0, 1.0]


def _two_cameras(v: Any) -> Any:
    if not isinstance(v, list) or len(v) != 2 or not all(isinstance(c, dict) for c in v):
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": "exactly two [[cameras]] tables (a stereo rig)"})
    return v


class PatternSection(Section):
    """``[pattern]``: the calibration pattern on the end-effector plate."""

    type: choice("five_squares", "corners", description="five squares in a quincunx, 20 corners (Dressler (2012), Figure 5.14), or any planar pattern given by its corners") = "five_squares"
    side: number(gt=0, le=10.0, unit="m", description="five_squares: side of each square (declared size: the reconstruction's unit)") = 0.06
    pitch: number(gt=0, le=10.0, unit="m", description="five_squares: distance between the squares' centres along x and y (> side)") = 0.1
    corners: matrix(2, bound=10.0, unit="m", description="corners: the pattern's corners (x, y) in its plane, in the order of the corner file's numbers (at least 4, not collinear)") | None = None
    normal: vector(3, bound=MAX_LENGTH_M, description="pattern normal in the plate frame (towards the cameras)") = [0.0, 1.0, 0.0]
    x_axis: vector(3, bound=MAX_LENGTH_M, description="pattern x direction in the plate frame") = [1.0, 0.0, 0.0]
    offset: vector(3, bound=10.0, unit="m", description="pattern centre from the TCP in the plate frame") = [0.0, 0.0, 0.0]


class MeasurementSection(Section):
    """``[measurement]``: the detector and the reconstruction."""

    pixel_sigma: number(gt=0, le=100.0, unit="px", description="corner noise per pixel coordinate (synthetic noise and the covariance)")
    max_obliquity_deg: number(gt=0, le=90.0, unit="deg", description="[truth] only: largest angle between plate normal and line of sight that is detected") = 60.0
    transmission: number(gt=0, le=10.0, description="TCP travel per cart travel for the metric scale (default: mean |v_i| of the start model)") | None = None


class CalibrationSection(Section):
    """``[calibration]``: the kinematic calibration on the reconstructed TCPs."""

    start: NonEmptyText = Field(default="L1_ideal", description="start parameters: a shipped name or a TOML path")
    parametrisation: choice("ideal", "modified", description="ideal (15) or modified (21 parameters) 3-link model") = "modified"
    solver: choice("lm", "trf", "ipopt", "ipopt-gn", description="least-squares solver") = "lm"
    max_iter: integer(1, 10**6, description="iteration limit") = 200


@fill_doc(**KIND_DOCS)
class VisionCalibrationFile(ProblemSchema):
    """A ``vision_calibration`` problem file: exactly one of ``[truth]`` and ``[data]``.

    Parameters
    ----------
    {header_fields}
    truth : TruthSection, optional
        ``[truth]``: synthetic images and tracker data.
    data : DataSection, optional
        ``[data]``: detected corners (and tracker data) of a real rig.
    cameras : list of CameraSection
        ``[[cameras]]``: exactly two.
    pattern : PatternSection
        ``[pattern]``: the calibration pattern.
    measurement : MeasurementSection
        ``[measurement]``: corner noise, detection, scale.
    calibration : CalibrationSection
        ``[calibration]``: start model, parametrisation, solver.
    """

    kind: Literal["vision_calibration"]
    truth: TruthSection | None = None
    data: DataSection | None = None
    cameras: Annotated[list[CameraSection], BeforeValidator(_two_cameras)]
    pattern: PatternSection = PatternSection()
    measurement: MeasurementSection
    calibration: CalibrationSection = CalibrationSection()
