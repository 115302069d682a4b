"""Filters, learning control and closed-loop simulation of the 4 ms loop.

Dressler (2012), ch. 7: tool-position estimators (complementary filter, stationary Kalman
filter), iterative learning control with its lifted-system stability checks, the
closed-loop tracking simulation of the L1 at 4 ms and the ILC experiment of section 7.3.

Cvitanic (2021), ch. 4-5: the 19-D end-effector state model of the laser tracker + IMU
fusion, the KF/EKF (one CasADi step), the UKF and particle filter, the Table 7 sensors and
sine paths, the simulation study, and the stability of real-time pose-offset corrections.

Rooms by job (lower rooms never import higher ones; an import-linter contract checks it):

* :mod:`~gtmodel.estimation.filters`: complementary, Kalman (stationary, KF, EKF),
  unscented and particle filters, and the end-effector state model they run on;
* :mod:`~gtmodel.estimation.closed_loop`: the L1 tracking plant at 4 ms and the
  pose-offset correction loop;
* :mod:`~gtmodel.estimation.ilc`: iterative learning control, its lifted-system stability
  and the ILC experiment (uses ``filters`` and ``closed_loop``);
* :mod:`~gtmodel.estimation.fusion`: the tracker + IMU sensors, sine paths and the fusion
  study (uses ``filters``).

The loop's controllers (tracking, MPC, their references and the plant bounds) live in
:mod:`gtmodel.control` (import them from there).

Lower layers only: control, robots, modeling and the base modules.
"""

from gtmodel.estimation.filters.complementary import THESIS_CUTOFFS_HZ, ComplementaryFilter
from gtmodel.estimation.ilc.iteration import ILCResult, error_measure, ilc_correction_function, next_correction, run_ilc
from gtmodel.estimation.filters.kalman import ExtendedKalmanFilter, KalmanFilter, StationaryKalman, tune_position_noise
from gtmodel.estimation.filters.end_effector import IMU_ROTATION, IMU_TRANSLATION_M, EndEffectorModel, constant_acceleration
from gtmodel.estimation.filters.gaussian import FilterRun
from gtmodel.estimation.ilc.lifted import ILCStability, LearningFilter, QFilter, lifted_matrix, stability, time_window
from gtmodel.estimation.filters.particle import ParticleFilter, ParticleRun
from gtmodel.estimation.filters.unscented import UnscentedKalmanFilter
from gtmodel.estimation.fusion.tracker_imu import SensorSpec, measure, four_point_velocity
from gtmodel.estimation.fusion.sine_path import SinePath, Truth
from gtmodel.estimation.fusion.runs import FusionRun, nees_test
from gtmodel.estimation.fusion.study import FusionStudy, FusionStudyResult
from gtmodel.estimation.closed_loop.plant import SensorModel, ToolStructure, TrackingPlant, TrackingResponse
from gtmodel.estimation.closed_loop.correction import OffsetResponseModel, equivalent_force, fit_offset_response, truth_model
from gtmodel.estimation.closed_loop.correction_loop import CorrectionStudy, GainScan, LoopSimulation, correction_study, largest_stable_gain, simulate_loop
from gtmodel.estimation.ilc.experiment import REQUIREMENTS, SIGNALS, ILCCase, ILCCaseResult, ILCExperiment, ILCReference

__all__: list[str] = []
__all__ += ["lifted_matrix", "time_window", "QFilter", "LearningFilter", "ILCStability", "stability"]
__all__ += ["error_measure", "ILCResult", "run_ilc", "next_correction", "ilc_correction_function"]
__all__ += ["ToolStructure", "SensorModel", "TrackingPlant", "TrackingResponse"]
__all__ += ["ComplementaryFilter", "THESIS_CUTOFFS_HZ"]
__all__ += ["StationaryKalman", "tune_position_noise"]
__all__ += ["EndEffectorModel", "constant_acceleration", "IMU_TRANSLATION_M", "IMU_ROTATION"]
__all__ += ["FilterRun", "KalmanFilter", "ExtendedKalmanFilter"]
__all__ += ["UnscentedKalmanFilter", "ParticleFilter", "ParticleRun"]
__all__ += ["SensorSpec", "SinePath", "Truth", "measure", "four_point_velocity", "FusionRun", "nees_test", "FusionStudy", "FusionStudyResult"]
__all__ += ["SIGNALS", "REQUIREMENTS", "ILCCase", "ILCReference", "ILCCaseResult", "ILCExperiment"]
__all__ += ["equivalent_force", "OffsetResponseModel", "truth_model", "fit_offset_response"]
__all__ += ["LoopSimulation", "GainScan", "CorrectionStudy", "simulate_loop", "largest_stable_gain", "correction_study"]
