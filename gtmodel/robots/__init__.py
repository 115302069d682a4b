"""Concrete robot models: Gantry-Tau parameter sets, kinematics, dynamics, modelling-layer models."""

from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.f1 import F1Closure, load_f1
from gtmodel.robots.friction import FRICTION_FORMS, friction_force
from gtmodel.robots.kinematics import GantryTau3Kinematics, configuration_signs
from gtmodel.robots.model import gantry_tau_model
from gtmodel.robots.parameters import RobotParameters, available_parameter_sets, load_parameters
from gtmodel.robots.six_link import SixLinkClosure, load_six_link
from gtmodel.robots.actuator_dynamics import actuator_models, load_dynamics_models
from gtmodel.robots.structural import PhysicalModel
from gtmodel.robots.stiffness import GantryTau3Stiffness, StiffnessParameters, load_stiffness
from gtmodel.robots.serial import SerialArm, load_serial_arm
from gtmodel.robots.wrapped import WrappedClosure, guideway_frame
from gtmodel.robots.deviated import DeviatedClosure, guideway_axes
from gtmodel.robots.elasto_geometric import ElastoGeometricClosure
from gtmodel.robots.dynamic_stiffness import DynamicStiffnessGP, fit_single_mode, simulate_single_mode, single_mode_frf

__all__ = [
    "F1Closure",
    "load_f1",
    "GantryTau3Dynamics",
    "GantryTau3Kinematics",
    "FRICTION_FORMS",
    "RobotParameters",
    "SixLinkClosure",
    "available_parameter_sets",
    "configuration_signs",
    "friction_force",
    "gantry_tau_model",
    "load_parameters",
    "load_six_link",
    "actuator_models",
    "load_dynamics_models",
    "PhysicalModel",
    "GantryTau3Stiffness",
    "StiffnessParameters",
    "load_stiffness",
    "SerialArm",
    "load_serial_arm",
    "DynamicStiffnessGP",
    "fit_single_mode",
    "simulate_single_mode",
    "single_mode_frf",
    "WrappedClosure",
    "guideway_frame",
    "DeviatedClosure",
    "guideway_axes",
    "ElastoGeometricClosure",
]
