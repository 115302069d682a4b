"""The tables of the closed-loop kinds ``tracking`` and ``ilc`` (light: validated before the kinds' solvers are imported).

``[robot]``, ``[structure]`` and ``[sensors]`` of the simulated L1 plant (Dressler (2012),
ch. 6.3 and 7.3); :func:`gtmodel.problems.kinds.closed_loop_common.build_plant` turns them
into a plant.
"""

from __future__ import annotations

from pydantic import Field

from gtmodel.defaults import LOOP_PERIOD_S, STANDARD_GRAVITY
from gtmodel.problems.kinds.schemas.motion import RobotReference
from gtmodel.problems.schema import NonEmptyText, Section, integer, number, vector

__all__ = ["RobotSection", "StructureSection", "SensorsSection", "NYQUIST_HZ"]

#: Nyquist frequency of the 4 ms loop [Hz] (bound of the cut-off fields; the filters check their own loop period).
NYQUIST_HZ = 0.5 / LOOP_PERIOD_S


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
