"""Estimators of the tool or end-effector state, run at the loop rate.

* :mod:`~gtmodel.estimation.filters.complementary`: the complementary filter of the tool
  position (Dressler (2012), eq. 7.17);
* :mod:`~gtmodel.estimation.filters.kalman`: the Kalman filters: the stationary Kalman
  filter of the tool position (Dressler (2012), eqs. 7.19-7.22), and the Kalman and extended
  Kalman filters of the end-effector state (Cvitanic (2021), section 4.1);
* :mod:`~gtmodel.estimation.filters.model_kalman`: the thesis' form of the tool-position
  Kalman filter, model (7.21) with the kinematic position as input (Dressler (2012), eqs. 7.19-7.22);
* :mod:`~gtmodel.estimation.filters.gaussian`: the one CasADi predict-update step the
  Kalman and extended Kalman filters share, the record of a filter run
  (:class:`FilterRun`, NEES) and the Cholesky pivots;
* :mod:`~gtmodel.estimation.filters.unscented` and :mod:`~gtmodel.estimation.filters.particle`:
  the sampling filters, the unscented Kalman filter and the particle filter (Cvitanic (2021),
  section 4.1);
* :mod:`~gtmodel.estimation.filters.end_effector`: the 19-D end-effector state model of the
  laser tracker + IMU fusion the filters run on (Cvitanic (2021), eqs. (21)-(29)).

``gtmodel.estimation.filters.KalmanFilter`` (and the other names of the former module
``gtmodel.estimation.filters``) stay importable from here.
"""

from __future__ import annotations

from gtmodel.estimation.filters.complementary import THESIS_CUTOFFS_HZ, ComplementaryFilter
from gtmodel.estimation.filters.end_effector import IMU_ROTATION, IMU_TRANSLATION_M, EndEffectorModel, constant_acceleration
from gtmodel.estimation.filters.gaussian import FilterRun, cholesky_pivots
from gtmodel.estimation.filters.kalman import ExtendedKalmanFilter, KalmanFilter, StationaryKalman, tune_position_noise
from gtmodel.estimation.filters.model_kalman import ModelKalman
from gtmodel.estimation.filters.particle import ParticleFilter, ParticleRun
from gtmodel.estimation.filters.unscented import UnscentedKalmanFilter

__all__ = [
    "ComplementaryFilter",
    "THESIS_CUTOFFS_HZ",
    "StationaryKalman",
    "tune_position_noise",
    "ModelKalman",
    "FilterRun",
    "KalmanFilter",
    "ExtendedKalmanFilter",
    "cholesky_pivots",
    "UnscentedKalmanFilter",
    "ParticleFilter",
    "ParticleRun",
    "EndEffectorModel",
    "constant_acceleration",
    "IMU_TRANSLATION_M",
    "IMU_ROTATION",
]
