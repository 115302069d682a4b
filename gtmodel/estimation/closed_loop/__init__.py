"""Closed-loop simulation: the L1 tracking plant and real-time pose-offset corrections.

* :mod:`~gtmodel.estimation.closed_loop.plant`: the closed-loop tracking plant of the L1
  Gantry-Tau at 4 ms (actuators, kinematics, structure, sensors), Dressler (2012), ch. 7;
* :mod:`~gtmodel.estimation.closed_loop.correction`: the response of a serial arm to
  real-time pose-offset commands, Cvitanic (2021), eqs. (30)-(33);
* :mod:`~gtmodel.estimation.closed_loop.correction_loop`: the closed-loop stability of
  those corrections, Cvitanic (2021), section 5.
"""

from __future__ import annotations

from gtmodel.estimation.closed_loop.plant import SensorModel, ToolStructure, TrackingPlant, TrackingResponse
from gtmodel.estimation.closed_loop.correction import OffsetResponseModel, equivalent_force, fit_offset_response, truth_model
from gtmodel.estimation.closed_loop.correction_loop import (
    CorrectionStudy,
    GainScan,
    LoopSimulation,
    correction_study,
    critical_gain,
    largest_stable_gain,
    simulate_loop,
)

__all__ = [
    "ToolStructure",
    "SensorModel",
    "TrackingPlant",
    "TrackingResponse",
    "equivalent_force",
    "OffsetResponseModel",
    "truth_model",
    "fit_offset_response",
    "LoopSimulation",
    "GainScan",
    "CorrectionStudy",
    "simulate_loop",
    "largest_stable_gain",
    "critical_gain",
    "correction_study",
]
