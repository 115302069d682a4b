"""Calibration: measurement data, synthetic measurements, kinematic calibration as NLPs.

Dressler (2012), ch. 5: measured poses (:class:`MeasurementSet`, read from CSV files by
:func:`read_measurements`), cart surveys for the piecewise-linear actuator model
(:class:`CartMeasurements`), and synthetic data of a "true" robot with actuator errors and
device noise for studies and tests (:mod:`gtmodel.calibration.synthetic`).
"""

from gtmodel.calibration.measurements import (
    CartMeasurements,
    MeasurementSet,
    measurement_columns,
    read_cart_measurements,
    read_measurements,
)
from gtmodel.calibration.synthetic import (
    LASER_TRACKER,
    NO_NOISE,
    STEREO_VISION,
    ActuatorErrors,
    DeviatedClosure,
    DeviceNoise,
    device_noise,
    grid_poses,
    random_poses,
    synthetic_cart_measurements,
    synthetic_measurements,
)

__all__ = [
    "MeasurementSet",
    "CartMeasurements",
    "read_measurements",
    "read_cart_measurements",
    "measurement_columns",
    "DeviceNoise",
    "LASER_TRACKER",
    "STEREO_VISION",
    "NO_NOISE",
    "device_noise",
    "ActuatorErrors",
    "DeviatedClosure",
    "grid_poses",
    "random_poses",
    "synthetic_measurements",
    "synthetic_cart_measurements",
]
