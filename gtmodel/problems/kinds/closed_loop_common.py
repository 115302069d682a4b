"""Tables shared by the closed-loop kinds ``tracking`` and ``ilc``: the simulated L1 plant.

Dressler (2012), ch. 6.3 and 7.3: ``[robot]`` (kinematics and the closed-loop actuator
models (6.11)), ``[structure]`` (one mode per direction x, y of the tool structure, physical
form (6.14)) and ``[sensors]`` (tool accelerometer and position gauge). :func:`build_plant`
turns them into a :class:`~gtmodel.estimation.TrackingPlant`.
"""

from __future__ import annotations

from pydantic import Field

from gtmodel.errors import GtModelError, ParameterError
from gtmodel.estimation import SensorModel, ToolStructure, TrackingPlant
from gtmodel.estimation.closed_loop.plant import DT, STANDARD_GRAVITY
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.kinds.motion_common import RobotReference
from gtmodel.problems.references import robot_parameters
from gtmodel.problems.schema import NonEmptyText, Section, integer, number, vector
from gtmodel.robots import GantryTau3Kinematics
from gtmodel.robots.actuator_dynamics import DynamicsModels, actuator_models, load_dynamics_models, loop_period

__all__ = ["RobotSection", "StructureSection", "SensorsSection", "build_plant", "NYQUIST_HZ", "SHIPPED_DYNAMICS"]

#: Nyquist frequency of the 4 ms loop [Hz] (bound of the cut-off fields; the filters check their own loop period).
NYQUIST_HZ = 0.5 / DT
#: Shipped dynamics-models files.
SHIPPED_DYNAMICS = ("L1_dynamics_models",)
#: Tolerance on the loop period against the actuator models' sample time [s].
_DT_TOLERANCE = 1e-9


class RobotSection(RobotReference):
    """``[robot]``: parameter set, IK configuration and the closed-loop actuator models.

    Parameters
    ----------
    parameters : str
        Shipped parameter set name or a TOML path relative to the problem file.
    configuration : int
        IK configuration, 0..7.
    dynamics_models : str
        Closed-loop actuator models (6.11): a shipped dynamics-models file or a TOML path.
    loop_period : float, optional
        Period of the controller loop [s]; omitted: the actuator models' sample time (the
        robot's data file; 4 ms on the L1). Given, it must equal that sample time.
    """

    dynamics_models: NonEmptyText = Field(default="L1_dynamics_models", description="closed-loop actuator models (6.11): shipped name or a TOML path relative to this file")
    loop_period: number(gt=0, le=1.0, unit="s", description="period of the controller loop; omitted: the actuator models' sample time "
                                                             "from the robot's data file (L1: 4 ms)") | None = None


class StructureSection(Section):
    """``[structure]``: one mode per direction x, y (Dressler (2012), eq. 6.14; defaults: the ILC operating point).

    Parameters
    ----------
    frequencies_hz : list of float, shape (2,)
        Resonances in x and y [Hz].
    stiffness : list of float, shape (2,)
        Static TCP stiffness in x and y [N/m].
    damping : list of float, shape (2,)
        Damping ratios in x and y.
    mass : float
        Inertial load ``m_acc`` [kg].
    """

    frequencies_hz: vector(2, positive=True, bound=1e4, unit="Hz", description="resonance in x, y (thesis, Table 6.4, with wrist: 7.4, 11.5)") = [7.4, 11.5]
    stiffness: vector(2, positive=True, bound=1e12, unit="N/m", description="static TCP stiffness in x, y (thesis: 2-4 N/um, stiffer in x)") = [4.0e6, 2.0e6]
    damping: vector(2, positive=True, bound=0.999, description="damping ratios in x, y (below 1)") = [0.05, 0.05]
    mass: number(gt=0, le=1e5, unit="kg", description="inertial load m_acc (thesis: m_p + sum m_a/2 = 22.38 kg)") = 22.38


class SensorsSection(Section):
    """``[sensors]``: tool accelerometer and position gauge (Dressler (2012), ch. 7.3).

    Parameters
    ----------
    accelerometer_noise : float
        Accelerometer noise (std) [m/s^2].
    accelerometer_range : float
        Measuring range, readings clipped [m/s^2].
    gauge_noise : float
        Position gauge noise (std) [m].
    seed : int
        Noise seed.
    """

    accelerometer_noise: number(ge=0, le=1e3, unit="m/s^2", description="standard deviation of the accelerometer noise") = 0.07
    accelerometer_range: number(gt=0, le=1e4, unit="m/s^2", description="measuring range (clipped), default 1.5 g") = 1.5 * STANDARD_GRAVITY
    gauge_noise: number(ge=0, le=1.0, unit="m", description="standard deviation of the position gauge noise") = 1e-6
    seed: integer(0, 2**31 - 1, description="seed of the sensor noise") = 0


def build_plant(robot: RobotSection, structure: StructureSection, sensors: SensorsSection, file: ProblemFile) -> TrackingPlant:
    """The closed-loop L1 plant of Dressler (2012), ch. 7.3, from validated tables.

    Parameters
    ----------
    robot : RobotSection
        ``[robot]``.
    structure : StructureSection
        ``[structure]``.
    sensors : SensorsSection
        ``[sensors]``.
    file : ProblemFile
        The problem file (references, messages).

    Returns
    -------
    TrackingPlant

    Raises
    ------
    ProblemError
        An unknown parameter set or dynamics-models file, not 3 actuator models, a loop period
        other than their sample time, or a plant the models reject (the message names the field).
    """
    params = robot_parameters(file, "robot.parameters", robot.parameters)
    ref = file.reference("robot.dynamics_models", robot.dynamics_models, SHIPPED_DYNAMICS)
    try:
        models: DynamicsModels = load_dynamics_models(ref)
    except ParameterError as exc:
        raise file.wrap("robot.dynamics_models", exc) from None
    if models.actuators.a.size != 3:
        raise file.fail("robot.dynamics_models", "3 actuator models", f"{models.actuators.a.size}")
    period = loop_period(models)
    if robot.loop_period is not None and abs(robot.loop_period - period) > _DT_TOLERANCE:
        raise file.fail("robot.loop_period", f"the sample time of the actuator models in robot.dynamics_models ({period:g} s)",
                        robot.loop_period)
    try:
        tool = ToolStructure(tuple(structure.frequencies_hz), tuple(structure.stiffness), tuple(structure.damping), structure.mass)
        sensor_model = SensorModel(sensors.accelerometer_noise, sensors.accelerometer_range, sensors.gauge_noise, sensors.seed)
        return TrackingPlant(GantryTau3Kinematics(params), actuator_models(models), tool, sensor_model, period, robot.configuration)
    except GtModelError as exc:
        raise file.wrap("structure", exc) from None
