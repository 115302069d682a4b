"""A model as the user writes it, in an optimisation: its reduction and its symbols.

:class:`~gtmodel.modeling.Optimization` accepts a model that
:meth:`~gtmodel.modeling.Model.flatten` refuses (aliases between states, higher index: a
motor, a gear and a load composed from library components) and reduces it as
:meth:`~gtmodel.modeling.Model.simulate` does (:func:`reduce_written`). The symbols of the
model as written stay usable: :func:`user_substitution` gives each its value in the
reduced model (a state, an algebraic variable, an eliminated alias's expression, the
time derivative of one), and :func:`affine_guess` turns a guess of an output ``a v + b``
into a guess of the variable ``v``.
"""

from __future__ import annotations

import logging
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import ModelError
from gtmodel.modeling.dae import expand_names
from gtmodel.modeling.simulation.model import Model
from gtmodel.modeling.structure.index_reduction import _ident, structural_simplify

__all__ = ["reduce_written", "user_substitution", "affine_guess"]

_log = logging.getLogger("gtmodel")


def reduce_written(model: Model) -> tuple[Model, tuple[ca.SX, ca.SX]]:
    """Reduce a model to index 1 as ``simulate()`` does, with the substitution of its symbols.

    Parameters
    ----------
    model : Model
        A model that :meth:`~gtmodel.modeling.Model.flatten` refuses.

    Returns
    -------
    reduced : Model
        :func:`~gtmodel.modeling.structural_simplify` of ``model`` (the states it chose are
        logged at INFO level).
    substitution : tuple of casadi.SX
        :func:`user_substitution` of the two.

    Raises
    ------
    ModelError
        The model is structurally singular (naming the equations and variables) or cannot
        be reduced.
    """
    reduced = structural_simplify(model)
    _log.info("model %r reduced to index 1 (structural_simplify): states %s", model.name, ", ".join(reduced.flatten().x_names))
    return reduced, user_substitution(model, reduced)


def user_substitution(model: Model, reduced: Model) -> tuple[ca.SX, ca.SX]:
    """The symbols of a model and their values in its reduced model (:func:`~gtmodel.modeling.structural_simplify`).

    Parameters
    ----------
    model : Model
        The model as written.
    reduced : Model
        Its reduced model: every scalar variable of ``model`` is there a state, an
        algebraic variable or an output (an eliminated alias), under its own name or the
        identifier :func:`structural_simplify` made of it (``T[0]`` -> ``T_0``).

    Returns
    -------
    src, dst : casadi.SX
        Column vectors of equal length: ``time``, the parameters, inputs, states (and their
        ``der()``) and algebraic variables of ``model``, and what replaces each.

    Raises
    ------
    ModelError
        A variable of ``model`` has no counterpart in ``reduced`` (should not happen).
    """
    found = {**reduced._outputs, **{n: v.sym for n, v in reduced._vars.items()}}

    def value(nm: str) -> ca.SX:
        for cand in (nm, _ident(nm)):
            if cand in found:
                return found[cand]
        raise ModelError(f"model {model.name!r}: variable {nm!r} has no counterpart in the reduced model")

    src, dst = [model.time], [reduced.time]
    for var in model._vars.values():
        names = expand_names(var.name, var.size)
        for j, nm in enumerate(names):
            src.append(ca.vec(var.sym)[j])
            dst.append(value(nm))
        if var.kind == "state":
            der = ca.vec(model.der(var.sym))
            for j, nm in enumerate(names):
                r = reduced._vars.get(nm) or reduced._vars.get(_ident(nm))
                if r is not None and r.kind == "state":
                    d = reduced.der(r.sym)
                elif f"der({nm})" in found or _ident(f"der({nm})") in found:
                    d = value(f"der({nm})")
                else:  # an eliminated alias: the time derivative of its expression
                    d = _time_derivative(value(nm), reduced, found)
                if d is not None:
                    src.append(der[j])
                    dst.append(d)
    return ca.vertcat(*src), ca.vertcat(*dst)


def _time_derivative(e: ca.SX, reduced: Model, found: dict[str, ca.SX]) -> ca.SX | None:
    """``d e / dt`` by the chain rule over the reduced model's states (``der()``) and algebraics (their dummy
    derivatives ``der_<name>``); None if ``e`` depends on a variable without a derivative (an input)."""
    out = ca.SX(0)
    for nm, v in reduced._vars.items():
        if v.kind in ("parameter",) or not ca.depends_on(e, v.sym):
            continue
        if v.kind == "state":
            d = reduced.der(v.sym)
        elif v.kind == "algebraic" and _ident(f"der({nm})") in found:
            d = found[_ident(f"der({nm})")]
        else:
            return None
        out = out + ca.jtimes(e, v.sym, d)
    return out


def affine_guess(e: ca.SX, values: Any, model: Model, parameters: dict[str, np.ndarray]) -> tuple[ca.SX, Any]:
    """The variable ``v`` of a scalar expression ``e = a v + b`` and the guess of ``v`` from one of ``e``.

    Parameters
    ----------
    e : casadi.SX
        A scalar expression of one variable of ``model`` and its parameters (an output, an
        eliminated alias), or a variable itself (returned as it is).
    values : float, array_like, tuple or callable
        The guess of ``e``, in the forms of :meth:`~gtmodel.modeling.Optimization.set_initial_guess`.
    model : Model
        The (reduced) model.
    parameters : dict of str to numpy.ndarray
        Parameter values set on the problem (else the model's).

    Returns
    -------
    v : casadi.SX
        The variable.
    guess : same form as ``values``
        ``(values - b) / a``.

    Raises
    ------
    ModelError
        ``e`` depends on more than one variable, or not affinely, or not at all.
    """
    if e.is_symbolic():
        return e, values
    declared = model.variables("parameter")
    params = list(declared.values())
    varying = [s for s in ca.symvar(e) if not any(ca.depends_on(s, p) for p in params)]
    if len(varying) != 1 or not ca.is_linear(e, varying[0]):
        raise ModelError(f"set_initial_guess: {e} is not a variable of the model nor affine in one variable")
    v = varying[0]
    # the parameters' values (the problem's, else the model's starts: flatten()'s p_value) without flattening the model
    p_sym = ca.vertcat(*[ca.vec(p) for p in params]) if params else ca.SX(0, 1)
    pv = np.concatenate([np.ravel(np.asarray(parameters[n] if n in parameters else model._vars[n].start, dtype=float))
                         for n in declared]) if params else np.zeros(0)
    a = float(ca.evalf(ca.substitute(ca.jacobian(e, v), p_sym, ca.DM(pv))))
    b = float(ca.evalf(ca.substitute(ca.substitute(e, v, ca.SX(0)), p_sym, ca.DM(pv))))
    if a == 0.0:
        raise ModelError(f"set_initial_guess: {e} does not depend on {v}")
    if callable(values):
        return v, lambda t, f=values: (np.asarray(f(t), dtype=float) - b) / a
    if isinstance(values, tuple):
        return v, (values[0], (np.asarray(values[1], dtype=float) - b) / a)
    return v, (np.asarray(values, dtype=float) - b) / a
