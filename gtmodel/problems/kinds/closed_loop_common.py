"""Tables shared by the closed-loop kinds ``tracking`` and ``ilc``: the simulated L1 plant.

Dressler (2012), ch. 6.3 and 7.3: ``[robot]`` (kinematics and the closed-loop actuator
models (6.11)), ``[structure]`` (one mode per direction x, y of the tool structure, physical
form (6.14)) and ``[sensors]`` (tool accelerometer and position gauge). :func:`build_plant`
turns them into a :class:`~gtmodel.estimation.TrackingPlant`. The tables are defined in the
light :mod:`gtmodel.problems.kinds.schemas.closed_loop` and re-exported here.
"""

from __future__ import annotations

from gtmodel.errors import GtModelError, ParameterError
from gtmodel.estimation import SensorModel, ToolStructure, TrackingPlant
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.kinds.schemas.closed_loop import NYQUIST_HZ, RobotSection, SensorsSection, StructureSection
from gtmodel.problems.references import robot_parameters
from gtmodel.robots import GantryTau3Kinematics
from gtmodel.robots.actuator_dynamics import DynamicsModels, actuator_models, load_dynamics_models, loop_period

__all__ = ["RobotSection", "StructureSection", "SensorsSection", "build_plant", "NYQUIST_HZ", "SHIPPED_DYNAMICS"]

#: Shipped dynamics-models files.
SHIPPED_DYNAMICS = ("L1_dynamics_models",)
#: Tolerance on the loop period against the actuator models' sample time [s].
_DT_TOLERANCE = 1e-9


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
