"""Filters, learning control and closed-loop simulation of the 4 ms loop.

Dressler (2012), ch. 7: tool-position estimators (complementary filter, stationary Kalman
filter), iterative learning control with its lifted-system stability checks, the
closed-loop tracking simulation of the L1 at 4 ms and the ILC experiment of section 7.3.

Cvitanic (2021), ch. 4-5: the 19-D end-effector state model of the laser tracker + IMU
fusion (``end_effector``), the KF/EKF (one CasADi step, ``filters``), the UKF and particle
filter (``sampling_filters``), the Table 7 sensors and sine paths (``tracker_imu``,
``sine_path``), the simulation study (``fusion_study``, ``fusion_runs``), and the stability
of real-time pose-offset corrections (``correction``, ``correction_loop``).

Lower layers only: robots, modeling and the base modules.
"""

from gtmodel.estimation.complementary import THESIS_CUTOFFS_HZ, ComplementaryFilter
from gtmodel.estimation.ilc import ILCResult, error_measure, ilc_correction_function, run_ilc
from gtmodel.estimation.kalman import StationaryKalman, tune_position_noise
from gtmodel.estimation.end_effector import IMU_ROTATION, IMU_TRANSLATION_M, EndEffectorModel, constant_acceleration
from gtmodel.estimation.filters import ExtendedKalmanFilter, FilterRun, KalmanFilter
from gtmodel.estimation.lifted import ILCStability, LearningFilter, QFilter, lifted_matrix, stability, time_window
from gtmodel.estimation.sampling_filters import ParticleFilter, ParticleRun, UnscentedKalmanFilter
from gtmodel.estimation.tracker_imu import SensorSpec, measure, four_point_velocity
from gtmodel.estimation.sine_path import SinePath, Truth
from gtmodel.estimation.fusion_runs import FusionRun, nees_test
from gtmodel.estimation.fusion_study import FusionStudy, FusionStudyResult
from gtmodel.estimation.plant import SensorModel, ToolStructure, TrackingPlant, TrackingResponse
from gtmodel.estimation.correction import OffsetResponseModel, equivalent_force, fit_offset_response, truth_model
from gtmodel.estimation.correction_loop import CorrectionStudy, GainScan, LoopSimulation, correction_study, largest_stable_gain, simulate_loop
from gtmodel.estimation.experiment import REQUIREMENTS, SIGNALS, ILCCase, ILCCaseResult, ILCExperiment, ILCReference

__all__: list[str] = []
__all__ += ["lifted_matrix", "time_window", "QFilter", "LearningFilter", "ILCStability", "stability"]
__all__ += ["error_measure", "ILCResult", "run_ilc", "ilc_correction_function"]
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
