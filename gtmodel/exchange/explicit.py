"""A gtmodel model as the explicit ODE an FMU carries: ``xdot, y = F(t, x, u, p)``.

Both FMU writers (:mod:`gtmodel.exchange.fmu_export`) start from the model's
:class:`~gtmodel.modeling.ExplicitODE` (``ExplicitModel`` here, the same class):
the model is flattened (:meth:`gtmodel.modeling.Model.flatten`), after alias elimination
and index reduction (:func:`gtmodel.modeling.structural_simplify`) when it needs them, and
its algebraic variables ``z`` are eliminated as for every explicit model
(:func:`gtmodel.modeling.explicit_ode`: symbolically in block-triangular order where the
blocks are affine in their variables, the common case of a composed component; otherwise
by a bounded Newton iteration inside the graph, started from the variables' start values). Units and descriptions come from the model (``Model.units``) and,
for a :class:`~gtmodel.modeling.Component`, from its declarations
(:meth:`~gtmodel.modeling.Component.describe`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import casadi as ca

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Component, ExplicitODE, Model, explicit_ode
from gtmodel.modeling.dae import casadi_name

__all__ = ["ExplicitModel", "explicit_model", "fmi_identifier"]

def fmi_identifier(name: str) -> str:
    """A C identifier for the FMU's ``modelIdentifier`` and CasADi's Function names.

    Parameters
    ----------
    name : str
        Model name.

    Returns
    -------
    str
        :func:`gtmodel.modeling.dae.casadi_name` of ``name`` (``my-model`` -> ``my_model``,
        ``cart__pole`` -> ``cart_pole``, ``2dof`` -> ``m_2dof``), or ``"model"`` for a name
        it refuses (an imported FMU's ``modelName`` may be anything).
    """
    try:
        return casadi_name(name)
    except InputError:
        return "model"


#: The explicit model of an FMU is the modelling layer's :class:`~gtmodel.modeling.ExplicitODE`
#: (one class: ``f(x, u, p)``, steps and the loop's Functions, plus descriptions and events for
#: an FMU; :attr:`~gtmodel.modeling.ExplicitODE.rhs` is ``f(t, x, u, p) -> (xdot, y)``); the
#: former name is kept.
ExplicitModel = ExplicitODE


def _metadata(source: Any, model_units: dict[str, str]) -> tuple[dict[str, str], dict[str, str]]:
    """Units and descriptions by scalar name, from a component's declarations and the model."""
    units: dict[str, str] = {}
    descriptions: dict[str, str] = {}
    if isinstance(source, Component):
        table = source.describe()
        for row in table.itertuples(index=False):
            if row.unit:
                units[row.name] = str(row.unit)
            if row.description:
                descriptions[row.name] = str(row.description)
    for name, (unit, text) in getattr(source, "exchange_metadata", {}).items():  # a Modelica model's (modelica.py)
        if unit:
            units.setdefault(name, unit)
        if text:
            descriptions.setdefault(name, text)
    for name, unit in model_units.items():
        units.setdefault(name, unit)
    return units, descriptions


def _expand(meta: dict[str, str], names: list[str]) -> dict[str, str]:
    """Give element names ``v[i]`` the entry of their declared name ``v``."""
    out = dict(meta)
    for n in names:
        base = n.split("[", 1)[0]
        if n not in out and base in meta:
            out[n] = meta[base]
    return out


def _add_events(em: ExplicitModel, dae: Any, whens: list) -> None:
    """Event indicators and the jump map of the when-clauses (reinit only) of a flat model."""
    t, x, u, p = dae.t, dae.x, dae.u, dae.p
    fire = ca.SX.sym("fire", len(whens))
    x_new = x
    for k, w in enumerate(whens):
        target = x
        for name, idx, expr in w.reinit:
            sl = dae.x_vars[name]
            for j, i in enumerate(idx):
                target = ca.vertcat(target[: sl.start + i], expr[j] if expr.numel() > 1 else expr, target[sl.start + i + 1:])
        x_new = x_new + fire[k] * (target - x)
    em.indicators = ca.Function("ind", [t, x, u, p], [ca.vertcat(*[w.condition for w in whens])], ["t", "x", "u", "p"], ["c"])
    em.jump = ca.Function("jump", [t, x, u, p, fire], [x_new], ["t", "x", "u", "p", "fire"], ["x_new"])
    em.directions = [int(w.direction) for w in whens]
    em.event_names = [w.name for w in whens]


def explicit_model(model: Any, name: str | None = None) -> ExplicitModel:
    """Reduce a model to the explicit ODE of an FMU (algebraic variables solved inside).

    Parameters
    ----------
    model : Model or Component
        A gtmodel model, or a component (flattened with :meth:`Component.to_model`).
    name : str, optional
        Model name in the FMU; default the model's.

    Returns
    -------
    ExplicitODE
        The model's explicit ODE (:func:`~gtmodel.modeling.explicit_ode`; ``rhs(t, x, u, p) ->
        (xdot, y)``) with the FMU's metadata: units, descriptions, events.

    Raises
    ------
    InputError
        ``model`` is neither a Model nor a Component.
    ModelError
        The model has modes (``Model.mode``, ``assign`` of a when-clause) or when-clauses
        together with algebraic variables, index reduction or initial equations (not
        exported yet), no state, or does not reduce to index 1.
    """
    if isinstance(model, Component):
        source, m = model, model.to_model(name)
    elif isinstance(model, Model):
        source, m = model, model
    else:
        raise InputError(f"model: expected a gtmodel Model or Component, got {type(model).__name__}")
    whens = list(m._events.whens) if m._events is not None else []
    if m._events is not None and (m._events.modes or any(w.assign or w.initial for w in whens)):
        raise ModelError(f"model {m.name!r}: modes and assign/initial when-clauses are not exported to an FMU yet "
                         "(when-clauses with reinit are)")
    if whens and (not m._flattens() or m._initial_equations):
        raise ModelError(f"model {m.name!r}: when-clauses are exported for models that flatten as they are "
                         "(no index reduction, no initial equations)")
    ode = explicit_ode(m)
    dae = ode.dae
    units, descriptions = _metadata(source, ode.units)
    names = dae.x_names + dae.u_names + dae.p_names + dae.output_names
    em = dataclasses.replace(ode, name=name or m.name, units=_expand(units, names), descriptions=_expand(descriptions, names))
    if whens:
        if dae.nz:
            raise ModelError(f"model {m.name!r}: when-clauses are exported for models without algebraic variables")
        _add_events(em, dae, whens)
    return em
