"""Acausal components, Modelica style: the room where a model is composed from parts.

* :mod:`~gtmodel.modeling.components.component`: :class:`Component` and :func:`connect`;
* :mod:`~gtmodel.modeling.components.connectors`: connectors with potential and flow
  variables (:class:`Connector`, :class:`Potential`, :class:`Flow`, the 3-D frame);
* :mod:`~gtmodel.modeling.components.declarations`: parameters and variables declared as
  class attributes (:class:`Parameter`, :class:`Variable`, :class:`State`, :class:`Input`,
  :class:`Structural`), with modifiers and ``extends``;
* :mod:`~gtmodel.modeling.components.flattening`: a component tree flattened into a
  :class:`~gtmodel.modeling.Model` (internal).
"""

from __future__ import annotations

from gtmodel.modeling.components.component import Component, Input, Parameter, State, Structural, Variable, connect
from gtmodel.modeling.components.connectors import Connector, Flow, Frame, Frame_a, Frame_b, Potential

__all__ = [
    "Component",
    "connect",
    "Parameter",
    "Variable",
    "State",
    "Input",
    "Structural",
    "Connector",
    "Potential",
    "Flow",
    "Frame",
    "Frame_a",
    "Frame_b",
]
