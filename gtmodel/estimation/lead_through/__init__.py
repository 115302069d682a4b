"""Lead-through programming with tool force feedback (Dressler (2012), ch. 8).

* :mod:`~gtmodel.estimation.lead_through.law`: the two-sensor control law (eqs. 8.3-8.11)
  as one CasADi step Function;
* :mod:`~gtmodel.estimation.lead_through.contact`: the workpieces (a compliant surface, a
  peg and a misaligned hole);
* :mod:`~gtmodel.estimation.lead_through.simulation`: the closed loop with a velocity
  servo, sensors and an operator;
* :mod:`~gtmodel.estimation.lead_through.stability`: the contact loop linearised (poles,
  oscillation frequency, largest stable force gain);
* :mod:`~gtmodel.estimation.lead_through.experiments`: the experiments of ch. 8.4.
"""

from gtmodel.estimation.lead_through.contact import CARDBOARD, METAL_PLATE, PegHole, Surface, surface_of
from gtmodel.estimation.lead_through.law import TASKS, LeadThroughLaw, LeadThroughStep, unit_normal
from gtmodel.estimation.lead_through.simulation import LeadThroughRun, Operator, Servo, simulate

__all__ = ["TASKS", "LeadThroughLaw", "LeadThroughStep", "unit_normal", "Surface", "PegHole", "CARDBOARD",
           "METAL_PLATE", "surface_of", "Servo", "Operator", "LeadThroughRun", "simulate"]
