"""The laser tracker + IMU fusion study of Cvitanic (2021), ch. 4.

* :mod:`~gtmodel.estimation.fusion.sine_path`: the sine paths of section 4.2 and their
  closed-form true state;
* :mod:`~gtmodel.estimation.fusion.tracker_imu`: the simulated sensors of Table 7, the
  measurements and the sensor-only estimates;
* :mod:`~gtmodel.estimation.fusion.runs`: one case of the study (:class:`FusionRun`) and the
  NEES consistency test;
* :mod:`~gtmodel.estimation.fusion.study`: the study of sections 4.2-4.3 (Tables 8-10, the
  filter comparison).
"""

from __future__ import annotations

from gtmodel.estimation.fusion.sine_path import SinePath, Truth
from gtmodel.estimation.fusion.tracker_imu import SensorSpec, four_point_velocity, measure
from gtmodel.estimation.fusion.runs import FusionRun, nees_test
from gtmodel.estimation.fusion.study import FusionStudy, FusionStudyResult

__all__ = [
    "SinePath",
    "Truth",
    "SensorSpec",
    "measure",
    "four_point_velocity",
    "FusionRun",
    "nees_test",
    "FusionStudy",
    "FusionStudyResult",
]
