"""The structural passes over a model's equations, and its events.

* :mod:`~gtmodel.modeling.structure.analysis`: scalar view, incidence, matching,
  Dulmage-Mendelsohn, the structural check and alias elimination;
* :mod:`~gtmodel.modeling.structure.index_reduction`: Pantelides' algorithm, dummy
  derivatives and :func:`structural_simplify`;
* :mod:`~gtmodel.modeling.structure.initialization`: the initial equations (start/fixed)
  solved at the start time;
* :mod:`~gtmodel.modeling.structure.events`: zero-crossing events (modes, when-clauses,
  reinit) declared on a model;
* :mod:`~gtmodel.modeling.structure.discontinuities`: ``sign()`` as an event-switched mode.

``gtmodel.modeling.structure.scalarize`` and ``.eliminate_aliases`` (paths the docs show)
are the functions of :mod:`~gtmodel.modeling.structure.analysis`.
"""

from __future__ import annotations

from gtmodel.modeling.structure.analysis import (
    Incidence,
    ScalarDAE,
    check_structure,
    dulmage_mendelsohn,
    eliminate_aliases,
    incidence,
    matching,
    scalarize,
)
from gtmodel.modeling.structure.discontinuities import sign_modes
from gtmodel.modeling.structure.events import EventRecord, EventSpec, EventsMixin, declare_mode, declare_when
from gtmodel.modeling.structure.index_reduction import AugmentedDAE, pantelides, structural_simplify
from gtmodel.modeling.structure.initialization import solve_initial

__all__ = [
    "ScalarDAE",
    "Incidence",
    "scalarize",
    "incidence",
    "matching",
    "dulmage_mendelsohn",
    "check_structure",
    "eliminate_aliases",
    "AugmentedDAE",
    "pantelides",
    "structural_simplify",
    "solve_initial",
    "EventRecord",
    "EventSpec",
    "EventsMixin",
    "declare_mode",
    "declare_when",
    "sign_modes",
]
