"""``sign()`` in a model's equations as an event-switched mode, with Filippov sliding.

Exact Coulomb friction ``m v' = F - F_c sign(v)`` cannot be integrated as it stands: at
``v = 0`` the right-hand side jumps, the step size collapses and IDAS stops with
``IDA_TOO_MUCH_WORK``. :func:`sign_modes` rewrites a model so that it can:

* every distinct argument ``a`` of ``sign(a)`` gets a mode ``sign_<k>`` (``1``, ``-1`` or
  ``0``), and when-clauses of :mod:`gtmodel.modeling.structure.events` switch it where ``a`` crosses
  zero, so the integrator never steps over the jump;
* if ``a`` depends on time, states and parameters only, the switching surface ``a = 0``
  may be **sliding** (Filippov (1988), *Differential equations with discontinuous
  righthand sides*, ch. 2): when ``a`` reaches zero and the vector field on the other
  side points back (``da/dt > 0`` there with ``sign = -1``, or ``< 0`` with ``+1``), the
  mode becomes ``0`` and ``sign(a)`` is replaced by an algebraic variable
  ``sign_<k>_value`` in ``[-1, 1]`` determined by ``da/dt = 0`` (the Filippov convex
  combination; for friction: the force that keeps the body stuck). It leaves the surface
  when that value reaches ``+1`` or ``-1`` (the force exceeds the friction);
* otherwise (``a`` depends on algebraic variables or inputs, or the integrator is
  CVODES, which takes no algebraic variables) the sign only switches at crossings; a
  chattering surface then stops at ``max_events`` with a message.

Modelica's ``sign()`` is ``noEvent`` and its relations generate events; here ``sign`` is
the discontinuity, because it is how Coulomb friction is written. The rewrite applies to
simulation (:meth:`Model.simulate`); optimisation and the collocation transcriptions see
the model as written.
"""

from __future__ import annotations

import copy
from typing import Any

import casadi as ca

from gtmodel.modeling.structure.events import EventSpec, _When, declare_mode

__all__ = ["sign_modes"]


def _rewrite(exprs: list[ca.SX], inputs: list[ca.SX]) -> tuple[list[ca.SX], list[ca.SX], list[ca.SX]]:
    """Re-evaluate ``exprs`` with each ``sign(a)`` replaced by a placeholder symbol.

    Returns ``(new expressions, distinct arguments a_k, placeholders)``.
    """
    if not exprs:
        return [], [], []
    fn = ca.Function("signs", inputs, exprs)
    ins = [ca.vec(i) for i in inputs]
    outs = [ca.SX.zeros(e.numel(), 1) for e in exprs]
    work: dict[int, ca.SX] = {}
    args: list[ca.SX] = []
    holders: list[ca.SX] = []
    for k in range(fn.n_instructions()):
        op, i_in, i_out = fn.instruction_id(k), fn.instruction_input(k), fn.instruction_output(k)
        if op == ca.OP_CONST:
            work[i_out[0]] = ca.SX(fn.instruction_constant(k))
        elif op == ca.OP_INPUT:
            work[i_out[0]] = ins[i_in[0]][i_in[1]]
        elif op == ca.OP_OUTPUT:
            outs[i_out[0]][i_out[1]] = work[i_in[0]]
        elif op == ca.OP_SIGN:
            a = work[i_in[0]]
            j = next((j for j, b in enumerate(args) if ca.is_equal(a, b, 1000)), None)
            if j is None:
                args.append(a)
                holders.append(ca.SX.sym(f"sign_placeholder{len(args)}"))
                j = len(args) - 1
            work[i_out[0]] = holders[j]
        elif len(i_in) == 1:
            work[i_out[0]] = ca.SX.unary(op, work[i_in[0]])
        else:
            work[i_out[0]] = ca.SX.binary(op, work[i_in[0]], work[i_in[1]])
    return [ca.reshape(o, e.size1(), e.size2()) for o, e in zip(outs, exprs)], args, holders


def _fresh(model: Any, base: str) -> str:
    name = base
    while name in model._vars or name in model._outputs:
        name = "_" + name
    return name


def sign_modes(model: Any, sliding: bool = True) -> Any | None:
    """A copy of ``model`` with every ``sign()`` of its equations switched by events (module docstring).

    Parameters
    ----------
    model : Model
        The model; it is not changed.
    sliding : bool, optional
        Allow sliding modes (they add algebraic variables, so not with CVODES); default
        true. Without, every sign only switches at crossings.

    Returns
    -------
    Model or None
        The rewritten copy (modes ``sign_<k>``, algebraic variables ``sign_<k>_value`` for
        sliding surfaces, when-clauses ``sign_<k>.down``, ``.up``, ``.leave_up``,
        ``.leave_down``), or ``None`` if no equation or output contains ``sign()``.
    """
    labels = [label for label, _ in model._equations]
    exprs = [r for _, r in model._equations] + list(model._outputs.values())
    inputs = model._known_symbols()
    new_exprs, args, holders = _rewrite(exprs, inputs)
    if not args:
        return None
    new = copy.copy(model)
    for key, value in vars(model).items():  # the copy's declarations must not reach the model
        if isinstance(value, (list, dict, set)):
            setattr(new, key, copy.copy(value))
    spec = model._events
    new._events = EventSpec(list(spec.modes), list(spec.whens)) if spec else None
    new._equations = list(zip(labels, new_exprs[: len(labels)]))
    states = [v for v in model._vars.values() if v.kind == "state"]
    x = ca.vertcat(*[v.sym for v in states]) if states else ca.SX(0, 1)
    xdot = ca.vertcat(*[v.der for v in states]) if states else ca.SX(0, 1)
    others = [v.sym for v in model._vars.values() if v.kind in ("algebraic", "input")]
    fast = ca.vertcat(*[ca.vec(s) for s in others + [xdot]])
    repl = []
    for k, a in enumerate(args):
        name = _fresh(new, f"sign_{k}")
        sigma = declare_mode(new, name, 1.0)
        down, up = ca.if_else(sigma == 1, -a, -1.0), ca.if_else(sigma == -1, a, -1.0)
        if not sliding or (fast.numel() and ca.depends_on(a, fast)):  # switching only
            repl.append(sigma)
            new._events.whens += [
                _When(f"{name}.down", down, 1, [], [(name, ca.SX(-1.0))], initial=True),
                _When(f"{name}.up", up, 1, [], [(name, ca.SX(1.0))], initial=True),
            ]
            continue
        lam_name = _fresh(new, f"{name}_value")
        lam = new.algebraic(lam_name, start=1.0)
        adot = (ca.jtimes(a, x, xdot) if states else 0.0) + ca.jacobian(a, model.time)
        new.equation(ca.if_else(sigma == 0, adot, lam - sigma), name=f"{name}.law", substitute_der=True)
        repl.append(lam)
        new._events.whens += [
            _When(f"{name}.down", down, 1, [], [(name, ca.if_else(adot > 0, 0.0, -1.0))], True, {lam_name: -1.0}),
            _When(f"{name}.up", up, 1, [], [(name, ca.if_else(adot < 0, 0.0, 1.0))], True, {lam_name: 1.0}),
            _When(f"{name}.leave_up", ca.if_else(sigma == 0, lam - 1.0, -1.0), 1, [], [(name, ca.SX(1.0))], True),
            _When(f"{name}.leave_down", ca.if_else(sigma == 0, -lam - 1.0, -1.0), 1, [], [(name, ca.SX(-1.0))], True),
        ]
    hold = ca.vertcat(*holders)
    rep = ca.vertcat(*repl)
    eqs = [(label, ca.substitute(r, hold, rep)) for label, r in new._equations[: len(labels)]]
    new._equations = eqs + new._equations[len(labels):]
    new._outputs = {n: ca.substitute(e, hold, rep) for n, e in zip(model._outputs, new_exprs[len(labels):])}
    return new
