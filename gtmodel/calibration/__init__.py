"""Calibration: measurement data, synthetic measurements, kinematic calibration as NLPs.

Dressler (2012), ch. 5: measured poses (:class:`MeasurementSet`, read from CSV files by
:func:`read_measurements`), cart surveys for the piecewise-linear actuator model
(:class:`CartMeasurements`), and synthetic data of a "true" robot with actuator errors and
device noise for studies and tests (:mod:`gtmodel.calibration.synthetic`); calibration
from closure equations (:mod:`gtmodel.calibration.kinematic`), identifiability
(:mod:`gtmodel.calibration.identifiability`), pose selection
(:mod:`gtmodel.calibration.pose_selection`) and accuracy reports
(:mod:`gtmodel.calibration.evaluation`); worst-case pose accuracy from actuator tolerances
(:mod:`gtmodel.calibration.accuracy`, Appendix A) and the automated calibration of ch. 5.6
(:mod:`gtmodel.calibration.automated`).
"""

from gtmodel.calibration.accuracy import Tolerances, largest_tolerances, monte_carlo, parallelepiped, worst_case
from gtmodel.calibration.automated import CalibrationWorkspace, rapid_module
from gtmodel.calibration.kinematic import (
    CalibrationProblem,
    CalibrationResult,
    ParameterSelection,
    analyze_identifiability,
    calibrate,
)
from gtmodel.calibration.elasto_geometric import (
    calibrate_elasto_geometric,
    compliant_measurements,
    elasto_geometric_study,
)
from gtmodel.calibration.identification import (
    DynamicIdentificationResult,
    DynamicRegressor,
    MotionLog,
    identify_dynamics,
    preprocess_log,
    read_motion_log,
    simulate_log,
)
from gtmodel.calibration.evaluation import AccuracyReport, evaluate, parameter_sensitivity, tcp_errors
from gtmodel.calibration.identification import FourierTrajectory, design_excitation
from gtmodel.calibration.identifiability import IdentifiabilityReport, analyze_jacobian

from gtmodel.calibration.measurements import (
    CartMeasurements,
    MeasurementSet,
    measurement_columns,
    read_cart_measurements,
    read_measurements,
)
from gtmodel.calibration.pose_selection import select_poses, simulate_calibration
from gtmodel.calibration.poses import grid_poses, random_poses
from gtmodel.calibration.synthetic import (
    LASER_TRACKER,
    NO_NOISE,
    STEREO_VISION,
    ActuatorErrors,
    DeviceNoise,
    device_noise,
    synthetic_cart_measurements,
    synthetic_measurements,
)
from gtmodel.calibration.identification import (
    ActuatorIdentification,
    StateSpaceIdentification,
    identify_actuator,
    identify_state_space,
    physical_from_state_space,
    prbs,
)
from gtmodel.calibration.joint_stiffness import (
    DeflectionData,
    DeflectionNoise,
    JointStiffnessResult,
    calibrate_cp,
    calibrate_dpp,
    synthetic_deflections,
    table_2_scenario,
    cp_dpp_study,
)

__all__ = [
    "Tolerances",
    "parallelepiped",
    "worst_case",
    "monte_carlo",
    "largest_tolerances",
    "CalibrationWorkspace",
    "rapid_module",
    "calibrate",
    "CalibrationProblem",
    "CalibrationResult",
    "ParameterSelection",
    "analyze_identifiability",
    "IdentifiabilityReport",
    "analyze_jacobian",
    "select_poses",
    "simulate_calibration",
    "AccuracyReport",
    "evaluate",
    "parameter_sensitivity",
    "tcp_errors",
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
    "grid_poses",
    "random_poses",
    "synthetic_measurements",
    "synthetic_cart_measurements",
    "ActuatorIdentification",
    "StateSpaceIdentification",
    "identify_actuator",
    "identify_state_space",
    "physical_from_state_space",
    "prbs",
    "calibrate_elasto_geometric",
    "compliant_measurements",
    "elasto_geometric_study",
    "DynamicRegressor",
    "DynamicIdentificationResult",
    "MotionLog",
    "identify_dynamics",
    "preprocess_log",
    "read_motion_log",
    "simulate_log",
    "FourierTrajectory",
    "design_excitation",
    "DeflectionData",
    "DeflectionNoise",
    "JointStiffnessResult",
    "calibrate_cp",
    "calibrate_dpp",
    "synthetic_deflections",
    "table_2_scenario",
    "cp_dpp_study",
]
