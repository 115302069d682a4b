"""Zero-crossing state events on a :class:`~gtmodel.modeling.Model`: modes, when-clauses, reinit.

A hybrid model in the Modelica sense (Modelica Language Specification 3.6, sections 8.3.5
"when-equations" and 8.5 "Events and synchronization"; Otter, Elmqvist and Mattsson (1999),
"Hybrid modeling in Modelica based on the synchronous data flow principle"):

* a **mode** (:meth:`Model.mode`) is a discrete variable, constant between events; the
  equations may switch on it (``casadi.if_else(mode == 0, ...)``). It is stored as a
  parameter of the flat DAE whose value the simulation changes at events.
* a **when-clause** (:meth:`Model.when`) is a scalar zero-crossing function ``c(t, x, z, u,
  p)`` of the model's variables; an event occurs when ``c`` crosses zero (rising: from
  ``c <= 0`` to ``c > 0``, like Modelica's ``when c > 0``; or falling, or both). At the event
  the clause's actions run: ``reinit`` of states and ``assign`` of modes, their right-hand
  sides evaluated with the values just before the event (Modelica's ``pre()``).
* **event iteration**: after the actions, the algebraic variables are made consistent and
  every condition is evaluated again; a clause whose condition crossed zero through the
  actions (a mode change, a reinit), to beyond a hysteresis of 1e-9, fires at the same instant, until none does (Modelica's
  event iteration until ``pre(m) == m``). This is how a friction state machine goes from
  sliding through stuck to sliding the other way at one instant.

Simulation with events: :mod:`gtmodel.modeling.simulation.event_simulation`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import _as_sx, expand_names

__all__ = [
    "EventRecord",
    "EventSpec",
    "EventsMixin",
    "declare_mode",
    "declare_when",
    "transfer_events",
]


@dataclass
class EventRecord:
    """One state event of a simulation.

    Parameters
    ----------
    t : float
        Event time, s.
    name : str
        Name of the when-clause that fired.
    modes : dict of str to float
        Values of all modes after the event (after the event iteration step of this clause).
    x : dict of str to numpy.ndarray
        States after the event (after its reinit), declared name -> value.
    """

    t: float
    name: str
    modes: dict[str, float] = field(default_factory=dict)
    x: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass
class _When:
    """A declared when-clause (internal record)."""

    name: str
    condition: ca.SX
    direction: int
    reinit: list[tuple[str, list[int], ca.SX]]
    assign: list[tuple[str, ca.SX]]
    initial: bool = False
    assume: dict[str, float] = field(default_factory=dict)  # algebraic name -> value in ``assign``


@dataclass
class EventSpec:
    """The modes and when-clauses declared on one model (held by :class:`Model`).

    Parameters
    ----------
    modes : list of str
        Names of the mode variables (parameters changed at events), in declaration order.
    whens : list
        The when-clauses, in declaration order.
    """

    modes: list[str] = field(default_factory=list)
    whens: list[_When] = field(default_factory=list)


def _spec(model: Any) -> EventSpec:
    if model._events is None:
        model._events = EventSpec()
    return model._events


def declare_mode(model: Any, name: str, start: float = 0.0) -> ca.SX:
    """Declare a discrete mode variable on a model (what :meth:`Model.mode` calls).

    A mode is a scalar that the equations may switch on and that only changes at events,
    by the ``assign`` of a when-clause. It is stored as a parameter of the flat DAE (so
    it can be overridden in ``p=`` of a simulation as its start value).

    Parameters
    ----------
    model : Model
        The model.
    name : str
        Identifier, unique in the model.
    start : float, optional
        Value at the start of a simulation; default 0.

    Returns
    -------
    casadi.SX
        The mode symbol, ``(1, 1)``.

    Raises
    ------
    InputError
        If the name is not an identifier or ``start`` is not one finite number.
    ModelError
        If the name is already declared.
    """
    if np.size(start) != 1:
        raise InputError(f"mode {name!r}: start must be one number, got {start!r}")
    sym = model.parameter(name, start)
    _spec(model).modes.append(name)
    return sym


def _pairs(value: Any, what: str) -> list[tuple[Any, Any]]:
    if value is None:
        return []
    if isinstance(value, Mapping):
        return list(value.items())
    try:
        pairs = [tuple(item) for item in value]
    except TypeError as exc:
        raise InputError(f"{what}: expected a mapping or a sequence of (target, value) pairs") from exc
    if any(len(pr) != 2 for pr in pairs):
        raise InputError(f"{what}: expected a mapping or a sequence of (target, value) pairs")
    return pairs


def _time_varying(model: Any, expr: ca.SX) -> bool:
    """True if ``expr`` depends on time or on a state, algebraic variable, input, der() or mode."""
    syms = [model.time]
    modes = _spec(model).modes
    for var in model._vars.values():
        if var.kind in ("state", "algebraic", "input") or var.name in modes:
            syms.append(var.sym)
        if var.der is not None:
            syms.append(var.der)
    return bool(ca.depends_on(expr, ca.vertcat(*[ca.vec(s) for s in syms])))


def declare_when(
    model: Any,
    condition: Any,
    reinit: Any = None,
    assign: Any = None,
    direction: int = 1,
    name: str | None = None,
    initial: bool = False,
) -> None:
    """Declare a zero-crossing state event on a model (what :meth:`Model.when` calls).

    Modelica ``when c > 0 then reinit(x, ...); m := ...; end when;`` is
    ``model.when(c, reinit={x: ...}, assign={m: ...})``.

    Parameters
    ----------
    model : Model
        The model.
    condition : casadi.SX
        Scalar zero-crossing function of time, states, algebraic variables, inputs,
        ``der()`` (replaced by the ODE right-hand side), parameters and modes.
    reinit : mapping or sequence of pairs, optional
        ``state symbol (or elements of one) -> new value``, evaluated with the values
        just before the event.
    assign : mapping or sequence of pairs, optional
        ``mode symbol -> new value``, evaluated with the values just before the event.
        Clauses firing at the same instant run in declaration order (a later assignment
        of the same mode wins).
    direction : {1, -1, 0}, optional
        1: event when ``condition`` goes from ``<= 0`` to ``> 0`` (default); -1: from
        ``>= 0`` to ``< 0``; 0: either sign change.
    name : str, optional
        Event name in :attr:`SimulationResult.events`; default ``"when<k>"``.
    initial : bool, optional
        Also fire at the start of a simulation if the condition is positive there
        (Modelica ``when {initial(), c > 0}``); default false (edge only).

    Raises
    ------
    InputError
        If the condition is not a scalar SX expression or depends on no time-varying
        variable or mode (it could never cross zero), a reinit/assign value has the wrong size,
        ``direction`` is not 1, -1 or 0, or the name is not a string.
    ModelError
        If the condition or a value contains symbols not declared by the model, a reinit
        target is not a state, an assign target is not a mode, or the name is taken.
    """
    spec = _spec(model)
    label = f"when{len(spec.whens)}" if name is None else name
    if not isinstance(label, str) or not label:
        raise InputError(f"when-clause name must be a non-empty string, got {name!r}")
    if any(w.name == label for w in spec.whens):
        raise ModelError(f"model {model.name!r}: when-clause name {label!r} is already used")
    what = f"when-clause {label!r}"
    if not isinstance(condition, (ca.SX, ca.MX, int, float, np.ndarray, np.number)) or isinstance(condition, bool):
        raise InputError(f"{what}: condition must be a scalar CasADi SX expression, got {type(condition).__name__}")
    cond = _as_sx(condition, f"{what} condition")
    if cond.numel() != 1:
        raise InputError(f"{what}: condition must be a scalar expression, got {cond.numel()} elements")
    model.check_symbols(cond, f"{what} condition")
    if not _time_varying(model, cond):
        raise InputError(
            f"{what}: condition {cond} depends on no time, state, algebraic variable or input, "
            "so it can never cross zero"
        )
    if isinstance(direction, bool) or direction not in (1, -1, 0):
        raise InputError(f"{what}: direction must be 1 (rising), -1 (falling) or 0 (both), got {direction!r}")
    reinits = []
    for target, value in _pairs(reinit, f"{what} reinit"):
        kind, vname, idx = model.locate(target)
        if kind != "state":
            raise ModelError(f"{what}: reinit target {vname!r} is a {kind}, not a state")
        val = _as_sx(value, f"{what} reinit({vname})")
        if val.numel() not in (1, len(idx)):
            raise InputError(f"{what}: reinit({vname}) needs 1 or {len(idx)} values, got {val.numel()}")
        model.check_symbols(val, f"{what} reinit({vname})")
        reinits.append((vname, idx, val))
    assigns = []
    for target, value in _pairs(assign, f"{what} assign"):
        kind, vname, _ = model.locate(target)
        if vname not in spec.modes:
            raise ModelError(f"{what}: assign target {vname!r} is a {kind}, not a mode (declare it with Model.mode)")
        val = _as_sx(value, f"{what} assign({vname})")
        if val.numel() != 1:
            raise InputError(f"{what}: assign({vname}) needs 1 value, got {val.numel()}")
        model.check_symbols(val, f"{what} assign({vname})")
        assigns.append((vname, val))
    spec.whens.append(_When(label, cond, int(direction), reinits, assigns, bool(initial)))


def transfer_events(source: Any, target: Any, old: ca.SX, new: ca.SX, names: Mapping[str, str]) -> None:
    """Declare the modes and when-clauses of ``source`` on ``target`` in ``target``'s symbols.

    Used by :func:`gtmodel.modeling.structure.index_reduction.structural_simplify`: the reduced model
    has new symbols, and its states are a subset of the original ones (the dummy
    derivatives became algebraic).

    Parameters
    ----------
    source : Model
        The model the events were declared on.
    target : Model
        The model receiving them, with the variables, equations and the modes (as
        parameters of the same names) declared.
    old, new : casadi.SX
        Column vectors: the ``source`` symbols (time, parameters, inputs, variables and
        ``der()`` symbols) and the ``target`` expressions replacing them, element by element.
    names : mapping of str to str
        Scalar variable name in ``source`` -> the name of its variable in ``target``.

    Raises
    ------
    ModelError
        If a reinit target is not a state of ``target`` (index reduction made it a dummy
        derivative: reinit needs a state, as in Modelica).
    """
    spec = source._events
    if spec is None:
        return
    tspec = _spec(target)
    tspec.modes.extend(m for m in spec.modes if m not in tspec.modes)

    def sub(e: ca.SX) -> ca.SX:
        return ca.substitute(e, old, new)

    for w in spec.whens:
        reinit = []
        for vname, idx, val in w.reinit:
            scalars = expand_names(vname, len(source._vars[vname].start))
            for k, i in enumerate(idx):
                tname = names.get(scalars[i])
                var = target._vars.get(tname) if tname is not None else None
                if var is None or var.kind != "state":
                    raise ModelError(
                        f"model {source.name!r}: when-clause {w.name!r} reinitialises {scalars[i]!r}, which index "
                        "reduction made a dummy derivative (not a state); a reinit target must stay a state "
                        "(the dummy selection could not keep it)"
                    )
                reinit.append((var.sym, sub(val[k if val.numel() > 1 else 0])))
        assign = [(target._vars[m].sym, sub(val)) for m, val in w.assign]
        declare_when(target, sub(w.condition), reinit, assign, w.direction, w.name, w.initial)


class EventsMixin:
    """The event declarations of :class:`~gtmodel.modeling.Model` (``mode``, ``when``)."""

    def mode(self, name: str, start: float = 0.0) -> ca.SX:
        """Declare a discrete mode variable, constant between events (Modelica ``discrete``).

        See :func:`gtmodel.modeling.structure.events.declare_mode` (it is stored as a parameter,
        changed only by the ``assign`` of a :meth:`when` clause during simulation).

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        start : float, optional
            Value at the start of a simulation; default 0.

        Returns
        -------
        casadi.SX
            Mode symbol, ``(1, 1)``.
        """
        return declare_mode(self, name, start)

    def when(
        self,
        condition: Any,
        reinit: Any = None,
        assign: Any = None,
        direction: int = 1,
        name: str | None = None,
        initial: bool = False,
    ) -> None:
        """Declare a zero-crossing state event (Modelica ``when condition > 0 then ...``).

        See :func:`gtmodel.modeling.structure.events.declare_when` for the semantics and errors.

        Parameters
        ----------
        condition : casadi.SX
            Scalar zero-crossing function of the model's variables.
        reinit : mapping or sequence of pairs, optional
            ``state symbol -> new value`` (Modelica ``reinit``).
        assign : mapping or sequence of pairs, optional
            ``mode symbol -> new value``.
        direction : {1, -1, 0}, optional
            Crossing direction: 1 rising (default), -1 falling, 0 both.
        name : str, optional
            Event name in :attr:`SimulationResult.events`; default ``"when<k>"``.
        initial : bool, optional
            Also fire at the start if the condition is positive there; default false.
        """
        declare_when(self, condition, reinit, assign, direction, name, initial)
