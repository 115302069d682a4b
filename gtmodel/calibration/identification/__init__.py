"""Identification: masses and friction from servo logs, excitation design, system identification.

Dressler (2012), ch. 6.2-6.3. The inverse dynamics (6.7) with the cart friction (6.8) is
linear in the parameters ``theta = (m_p, m_c, m_a, f_c, f_v)``::

    tau = Y(T, T_dot, T_ddot) theta + tau_0

One module per job:

=================  =====================================================================
``variants``       the Table 6.3 model variants (which parameters are estimated) and the
                   thesis' Table 6.3
``regressor``      ``Y = d tau / d theta`` from the symbolic inverse dynamics by CasADi
                   (:class:`DynamicRegressor`; compiled to C on many samples, cached)
``signals``        motion logs (:class:`MotionLog`, CSV), zero-phase filtering and
                   differentiation (:func:`preprocess_log`)
``identify``       weighted least squares, standard deviations, base parameters
                   (:func:`identify_dynamics`, :class:`DynamicIdentificationResult`)
``friction``       the constant-velocity friction experiment, eq. 6.9, Table 6.1
``simulation``     synthetic servo logs and constant-velocity runs
``excitation``     optimal excitation trajectories (finite Fourier series, IPOPT)
``system``         actuator and structural models from input/output data (ch. 6.3):
                   PRBS, first-order actuator lags, ARX + ERA state space, physical form
=================  =====================================================================
"""

from gtmodel.calibration.identification.excitation import (
    ExcitationDesign,
    FourierTrajectory,
    design_excitation,
    regressor_condition,
)
from gtmodel.calibration.identification.friction import (
    SPEED_MATCH_TOLERANCE,
    ConstantVelocityData,
    FrictionFit,
    accumulated_gravity_forces,
    fit_friction,
    subtract_gravity,
    two_direction_friction,
)
from gtmodel.calibration.identification.identify import (
    SPEED_BINS,
    DynamicIdentificationResult,
    column_dependency,
    identify_dynamics,
)
from gtmodel.calibration.identification.regressor import DynamicRegressor
from gtmodel.calibration.identification.signals import (
    MIN_SAMPLES,
    SAMPLING_TOLERANCE,
    DynamicSamples,
    MotionLog,
    preprocess_log,
    read_motion_log,
)
from gtmodel.calibration.identification.simulation import StribeckTerm, simulate_constant_velocity, simulate_log
from gtmodel.calibration.identification.system import (
    MIN_ROWS,
    ActuatorIdentification,
    StateSpaceIdentification,
    discrete_to_continuous,
    identify_actuator,
    identify_state_space,
    physical_from_state_space,
    prbs,
)
from gtmodel.calibration.identification.variants import (
    TABLE_6_3_COLUMNS,
    THESIS_TABLE_6_3,
    VARIANTS,
    ModelVariant,
    get_variant,
)

__all__ = [
    "VARIANTS",
    "TABLE_6_3_COLUMNS",
    "THESIS_TABLE_6_3",
    "ModelVariant",
    "get_variant",
    "DynamicRegressor",
    "MotionLog",
    "read_motion_log",
    "DynamicSamples",
    "preprocess_log",
    "MIN_SAMPLES",
    "SAMPLING_TOLERANCE",
    "DynamicIdentificationResult",
    "identify_dynamics",
    "column_dependency",
    "SPEED_BINS",
    "StribeckTerm",
    "simulate_log",
    "simulate_constant_velocity",
    "ConstantVelocityData",
    "FrictionFit",
    "accumulated_gravity_forces",
    "subtract_gravity",
    "fit_friction",
    "two_direction_friction",
    "SPEED_MATCH_TOLERANCE",
    "FourierTrajectory",
    "ExcitationDesign",
    "design_excitation",
    "regressor_condition",
    "ActuatorIdentification",
    "StateSpaceIdentification",
    "identify_actuator",
    "identify_state_space",
    "discrete_to_continuous",
    "physical_from_state_space",
    "prbs",
    "MIN_ROWS",
]
