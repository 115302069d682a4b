"""Automated kinematic calibration for non-experts, Dressler (2012), ch. 5.6 (Fig. 5.21).

The calibration workspace from *a priori* parameters (:mod:`.workspace`), evenly spread
poses accepted by eq. 5.14 and a simulated calibration (:mod:`.declared`), and the
measurement program for the controller (:mod:`.program`).
"""

from gtmodel.calibration.automated.declared import AutomatedCalibrationDeclaration, AutomatedCalibrationResult, Round
from gtmodel.calibration.automated.program import rapid_module, write_pose_csv
from gtmodel.calibration.automated.workspace import (
    CalibrationWorkspace,
    Obstacle,
    PinholeCamera,
    Tracker,
    grid_constant,
    home_joint_axes,
)

__all__ = [
    "AutomatedCalibrationDeclaration",
    "AutomatedCalibrationResult",
    "Round",
    "CalibrationWorkspace",
    "Obstacle",
    "PinholeCamera",
    "Tracker",
    "grid_constant",
    "home_joint_axes",
    "rapid_module",
    "write_pose_csv",
]
