"""The flat model and what it does over time: flattening to a CasADi DAE, simulators,
linearisation and the inverse model.

* :mod:`~gtmodel.modeling.simulation.model`: :class:`Model`, the equation-based model
  (variables, ``der()`` equations, outputs);
* :mod:`~gtmodel.modeling.simulation.flatten`: a model flattened to its semi-explicit
  CasADi DAE (:class:`~gtmodel.modeling.dae.FlatDAE`), ``der()`` solved symbolically;
* :mod:`~gtmodel.modeling.simulation.integration`: the flat DAE integrated on a time grid
  with SUNDIALS (IDAS or CVODES);
* :mod:`~gtmodel.modeling.simulation.event_simulation`: simulation with zero-crossing events;
* :mod:`~gtmodel.modeling.simulation.structured_simulation`: simulation of models that need
  the structural passes (initial equations, aliases, high index);
* :mod:`~gtmodel.modeling.simulation.explicit`: :func:`explicit_ode`, the model as an explicit
  ODE ``xdot = f(x, u, p)`` (algebraic variables eliminated) and its fixed-step integrators;
* :mod:`~gtmodel.modeling.simulation.linear`: :func:`linearize` about an operating point;
* :mod:`~gtmodel.modeling.simulation.inverse`: :func:`inverse_model`, the inputs that
  produce a prescribed motion.
"""

from __future__ import annotations

from gtmodel._lazy import lazy_exports
from gtmodel.modeling.simulation.model import Model
from gtmodel.modeling.simulation.integration import simulate_model
from gtmodel.modeling.simulation.event_simulation import simulate_events
from gtmodel.modeling.simulation.structured_simulation import simulate_structured
from gtmodel.modeling.simulation.linear import Linearization, linearize
from gtmodel.modeling.simulation.explicit import ExplicitODE, explicit_ode

__all__ = [
    "Model",
    "simulate_model",
    "simulate_events",
    "simulate_structured",
    "Linearization",
    "linearize",
    "ExplicitODE",
    "explicit_ode",
    "InverseModel",
    "inverse_model",
]

#: The inverse model, imported on first use (a solve or a simulation does not need it).
__getattr__, __dir__ = lazy_exports(__name__, {"InverseModel": "inverse", "inverse_model": "inverse"})
