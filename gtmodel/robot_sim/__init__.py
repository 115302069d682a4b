"""Robot-side simulators of KUKA RSI and ABB EGM: the project's plant models behind the protocols.

The simulators play the ROBOT: from their own 4 ms clock they send the robot's packet to a
sensor side (gtmodel's runtime, or any client), take the replies back, apply them through
a plant model as the real controller would, stream the tracker on the sensor port, inject
faults on the robot's side of the link and record what happened.

- :mod:`~gtmodel.robot_sim.rsi`, :mod:`~gtmodel.robot_sim.egm`: the two wire formats (compose
  the robot's message, parse the sensor's reply from untrusted bytes);
- :mod:`~gtmodel.robot_sim.state`: what a robot sends and takes back, protocol-free;
- :mod:`~gtmodel.robot_sim.plants`: the KR 500 correction plant (Cvitanic (2021), sec. 5)
  and the L1 servo plant (Dressler (2012), eq. 6.11);
- :mod:`~gtmodel.robot_sim.faults`: the seeded fault schedule and its text syntax;
- :mod:`~gtmodel.robot_sim.run`: :func:`~gtmodel.robot_sim.run.simulate`, the clock, the
  rules (late replies, RSI's stop), the record;
- :mod:`~gtmodel.robot_sim.cli`: ``gtmodel robot-sim``.

The names below are imported on first use (:mod:`gtmodel._lazy`), so ``gtmodel robot-sim``
and ``import gtmodel.robot_sim.cli`` stay light.
"""

from gtmodel._lazy import lazy_exports

__all__ = ["simulate", "SimResult", "FaultRule", "FaultSchedule", "parse_faults", "SimPlant", "KR500CorrectionPlant", "L1ServoPlant",
           "make_plant", "RobotState", "Command"]

__getattr__, __dir__ = lazy_exports(__name__, {
    "simulate": "run", "SimResult": "run", "FaultRule": "faults", "FaultSchedule": "faults", "parse_faults": "faults",
    "SimPlant": "plants", "KR500CorrectionPlant": "plants", "L1ServoPlant": "plants", "make_plant": "plants",
    "RobotState": "state", "Command": "state",
})
