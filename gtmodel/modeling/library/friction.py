"""Friction with stiction and hard stops, named as ``Modelica.Mechanics.Translational``.

The friction state machine of the Modelica Standard Library (MSL 4.0,
``Translational.Interfaces.PartialFriction`` / ``PartialFrictionWithStop``; Otter, Elmqvist
and Mattsson (1999), "Hybrid modeling in Modelica based on the synchronous data flow
principle"), written with the events of :mod:`gtmodel.modeling.structure.events`:

* modes ``1`` forward sliding (``v_rel > 0``), ``0`` stuck, ``-1`` backward sliding;
* sliding: ``f = F_prop v_rel + mode (F_Coulomb + F_Stribeck exp(-fexp |v_rel|))``
  (``f`` positive when it opposes a positive ``v_rel``; MSL ``MassWithStopAndFriction``);
* stuck: ``der(v_rel) = 0`` (the relative acceleration of the ODE, ``substitute_der``),
  which determines ``f`` like the MSL's "locked" equation;
* sliding -> stuck when ``v_rel`` crosses zero; stuck -> sliding when ``|f|`` exceeds the
  maximum static friction ``f0_max = peak (F_Coulomb + F_Stribeck)`` (``peak`` as in the
  MSL's ``SupportFriction``; 1 in ``MassWithStopAndFriction``), in the direction of ``f``.
  An event iteration (stuck, then at once sliding the other way) gives the MSL's
  ``startForward``/``startBackward``.

Deviations from the MSL, documented: the breakaway threshold is ``f0_max`` itself (the
MSL's 0.1 % margin ``f0_max = 1.001 f0`` exists to keep its event iteration from
chattering; events here are located by root finding); the friction force is continuous
at breakaway only when ``peak = 1`` (as in the MSL); the MSL's friction table ``f_pos``
of ``SupportFriction`` is replaced by the Stribeck curve of ``MassWithStopAndFriction``.

Hard stops (:class:`MassWithStopAndFriction`): an impact at ``smin``/``smax`` reverses the velocity
with a coefficient of restitution ``e`` (Newton's impact law ``v+ = -e v-``). With
``e = 0`` (the MSL) the mass stops at the stop and stays stuck (friction mode ``0``)
until the force pulls it away from the stop.

:class:`MassWithStopAndFriction` is a component on the translational flanges of
:mod:`gtmodel.modeling.library.translational` (its mode, friction law and when-clauses reach the
flattened model through :meth:`~gtmodel.modeling.components.component.Component.model_call`);
:func:`add_friction` declares the same state machine on a plain
:class:`~gtmodel.modeling.Model` for any relative velocity.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.components.component import Parameter, State, Variable
from gtmodel.modeling.library.translational import PartialTwoFlanges
from gtmodel.modeling.simulation.model import Model

__all__ = ["Stribeck", "FrictionSymbols", "stribeck_force", "add_friction", "MassWithStopAndFriction"]


@dataclass(frozen=True)
class Stribeck:
    """Friction characteristic of MSL ``MassWithStopAndFriction`` plus ``peak`` of ``SupportFriction``.

    ``f(v) = F_prop v + sign(v) (F_Coulomb + F_Stribeck exp(-fexp |v|))`` while sliding;
    stuck while ``|f| <= peak (F_Coulomb + F_Stribeck)``.

    Parameters
    ----------
    F_prop : float, optional
        Velocity-dependent (viscous) friction, N s/m, ``>= 0``; default 1 (MSL start value).
    F_Coulomb : float, optional
        Coulomb friction force, N, ``>= 0``; default 5.
    F_Stribeck : float, optional
        Stribeck effect (extra force at zero speed), N, ``>= 0``; default 10.
    fexp : float, optional
        Exponential decay of the Stribeck effect, s/m, ``>= 0``; default 2.
    peak : float, optional
        Maximum static friction over ``F_Coulomb + F_Stribeck``, ``>= 1``; default 1.

    Raises
    ------
    InputError
        If a value is not finite, negative, or ``peak < 1``.
    """

    F_prop: float = 1.0
    F_Coulomb: float = 5.0
    F_Stribeck: float = 10.0
    fexp: float = 2.0
    peak: float = 1.0

    def __post_init__(self) -> None:
        for name in ("F_prop", "F_Coulomb", "F_Stribeck", "fexp", "peak"):
            val = getattr(self, name)
            if isinstance(val, bool) or not isinstance(val, (int, float, np.number)) or not np.isfinite(val) or val < 0:
                raise InputError(f"Stribeck.{name} must be a finite number >= 0, got {val!r}")
        if self.peak < 1.0:
            raise InputError(f"Stribeck.peak must be >= 1 (static friction >= sliding friction at v = 0), got {self.peak!r}")

    @property
    def f0_max(self) -> float:
        """Maximum static friction force ``peak (F_Coulomb + F_Stribeck)``, N."""
        return self.peak * (self.F_Coulomb + self.F_Stribeck)

    def sliding(self, v: Any, direction: Any) -> Any:
        """Sliding friction force, N (opposing ``v`` when ``direction = sign(v)``).

        Parameters
        ----------
        v : casadi.SX or float
            Relative velocity, m/s.
        direction : casadi.SX or float
            Sliding direction (the friction mode), ``1`` or ``-1``.

        Returns
        -------
        casadi.SX or float
            ``F_prop v + direction (F_Coulomb + F_Stribeck exp(-fexp |v|))``.
        """
        return stribeck_force(v, direction, self.F_prop, self.F_Coulomb, self.F_Stribeck, self.fexp)


def stribeck_force(v: Any, direction: Any, F_prop: Any, F_Coulomb: Any, F_Stribeck: Any, fexp: Any) -> Any:
    """Sliding friction force of MSL ``MassWithStopAndFriction``, N.

    ``F_prop v + direction (F_Coulomb + F_Stribeck exp(-fexp |v|))``.

    Parameters
    ----------
    v : casadi.SX or float
        Relative velocity, m/s.
    direction : casadi.SX or float
        Sliding direction (the friction mode), ``1`` or ``-1``.
    F_prop, F_Coulomb, F_Stribeck, fexp : casadi.SX or float
        Viscous coefficient [N s/m], Coulomb force [N], Stribeck force [N], decay [s/m].

    Returns
    -------
    casadi.SX or float
        The force, positive when it opposes a positive ``v``.
    """
    return F_prop * v + direction * (F_Coulomb + F_Stribeck * ca.exp(-fexp * ca.fabs(v)))


@dataclass
class FrictionSymbols:
    """Symbols declared by :func:`add_friction` / :func:`mass_with_stop_and_friction`.

    Parameters
    ----------
    mode : casadi.SX
        Friction mode (``1`` forward, ``0`` stuck, ``-1`` backward).
    f : casadi.SX
        Friction force, N (positive when opposing a positive relative velocity).
    """

    mode: ca.SX
    f: ca.SX


def _state_machine(
    declare: Any, prefix: str, mode_name: str, v: ca.SX, acc: ca.SX, f: ca.SX,
    sliding: Any, f0_max: Any, can_start: Any, mode_start: float,
) -> ca.SX:
    """Mode, friction law and the four when-clauses of the MSL friction state machine (module docstring).

    ``declare(method, *args, **kwargs)`` calls a :class:`Model` method (directly, or through
    :meth:`Component.model_call`).
    """
    fwd, bwd = (1.0, 1.0) if can_start is None else can_start
    mode = declare("mode", mode_name, float(mode_start))
    declare("equation", ca.if_else(mode == 0, acc, f - sliding(v, mode)), 0.0, name=f"{prefix}law", substitute_der=True)
    declare("when", ca.if_else(mode == 1, -v, -1.0), assign=[(mode, 0.0)], name=f"{prefix}stuck_forward")
    declare("when", ca.if_else(mode == -1, v, -1.0), assign=[(mode, 0.0)], name=f"{prefix}stuck_backward")
    start_fwd = ca.if_else(ca.logic_and(mode == 0, fwd > 0), f - f0_max, -1.0)
    start_bwd = ca.if_else(ca.logic_and(mode == 0, bwd > 0), -f - f0_max, -1.0)
    declare("when", start_fwd, assign=[(mode, 1.0)], name=f"{prefix}start_forward", initial=True)
    declare("when", start_bwd, assign=[(mode, -1.0)], name=f"{prefix}start_backward", initial=True)
    return mode


def add_friction(
    model: Model,
    v_rel: Any,
    f: Any,
    friction: Stribeck,
    name: str = "friction",
    a_rel: Any = None,
    mode_start: float = 0.0,
) -> FrictionSymbols:
    """Declare the MSL friction state machine for a relative velocity on a plain model.

    Adds the mode ``<name>_mode``, the friction equation ``<name>.law`` (sliding law or,
    stuck, ``a_rel = 0`` with ``der()`` replaced by the ODE right-hand side) and the
    when-clauses ``<name>.stuck_forward``, ``<name>.stuck_backward``,
    ``<name>.start_forward``, ``<name>.start_backward`` (module docstring).

    Parameters
    ----------
    model : Model
        The model; ``f`` must be one of its algebraic variables, with no other equation.
    v_rel : casadi.SX
        Relative velocity of the friction surfaces, m/s (scalar expression).
    f : casadi.SX
        Algebraic variable: friction force, N, positive when opposing a positive ``v_rel``.
    friction : Stribeck
        The friction characteristic.
    name : str, optional
        Prefix of the declared mode and clauses; default ``"friction"``.
    a_rel : casadi.SX, optional
        Relative acceleration, an expression with ``der()``; default ``der(v_rel)`` (then
        ``v_rel`` must be a state).
    mode_start : {0, 1, -1}, optional
        Mode at the start of a simulation; default 0 (stuck; it starts sliding at once,
        by an initial event, if the force exceeds the static friction).

    Returns
    -------
    FrictionSymbols
        The mode and the force.

    Raises
    ------
    InputError
        If ``friction`` is not a :class:`Stribeck`, ``mode_start`` not -1, 0 or 1, or
        ``v_rel``/``a_rel`` are not scalar SX expressions.
    ModelError
        If ``f`` is not an algebraic variable of the model, or ``a_rel`` is omitted and
        ``v_rel`` is not a state.
    """
    if not isinstance(friction, Stribeck):
        raise InputError(f"{name}: friction must be a Stribeck, got {type(friction).__name__}")
    if isinstance(mode_start, bool) or mode_start not in (-1, 0, 1):
        raise InputError(f"{name}: mode_start must be -1, 0 or 1, got {mode_start!r}")
    kind, fname, _ = model.locate(f)
    if kind != "algebraic" or ca.SX(f).numel() != 1:
        raise ModelError(f"{name}: the friction force must be a scalar algebraic variable, got {kind} {fname!r}")
    if not isinstance(v_rel, ca.SX) or v_rel.numel() != 1:
        raise InputError(f"{name}: v_rel must be a scalar SX expression, got {v_rel!r}")
    acc = model.der(v_rel) if a_rel is None else a_rel
    if not isinstance(acc, ca.SX) or acc.numel() != 1:
        raise InputError(f"{name}: a_rel must be a scalar SX expression, got {a_rel!r}")

    def declare(method: str, *args: Any, **kwargs: Any) -> Any:
        return getattr(model, method)(*args, **kwargs)

    mode = _state_machine(
        declare, f"{name}.", f"{name}_mode", v_rel, acc, ca.SX(f), friction.sliding, friction.f0_max, None, mode_start
    )
    return FrictionSymbols(mode=mode, f=ca.SX(f))


class MassWithStopAndFriction(PartialTwoFlanges):
    """Sliding mass with hard stops and Stribeck friction (MSL ``Translational.Components.MassWithStopAndFriction``).

    ``flange_a.s = s - L/2``, ``flange_b.s = s + L/2``, ``v = der(s)``, ``a = der(v)``,
    ``m a = flange_a.f + flange_b.f - f`` (the velocity is the component's own, as in the
    MSL: the flanges carry position and force only)
    with the friction force ``f`` of the MSL
    state machine on ``v_rel = v - v_support`` (module docstring); hard stops at
    ``smin + L/2 <= s <= smax - L/2`` with Newton's impact law ``v+ = -e v-``. Declared
    mode ``<path>.mode``, when-clauses ``<path>.stuck_forward``, ``<path>.stuck_backward``,
    ``<path>.start_forward``, ``<path>.start_backward``, ``<path>.stop_max``,
    ``<path>.stop_min``. Additions to the MSL, documented: ``peak`` (static over sliding
    friction at rest, from the MSL's ``SupportFriction``), ``e`` (the MSL stops the mass:
    ``e = 0``) and ``v_support`` (velocity of the surface, e.g. a belt; the MSL's is 0).
    With ``e = 0`` the support is assumed at rest at the stops. The initial friction mode
    follows the start value of ``v`` (the ``v`` modifier), not an ``x0`` of the simulation.
    Rigidly coupled to another mass (a model of higher index), ``Model.simulate`` reduces
    the model keeping ``s`` and ``v`` of this component as states (they are reinit targets);
    two of them rigidly coupled are refused (ModelError).

    Parameters
    ----------
    m : float, optional
        Mass [kg], > 0 (default 1).
    L : float, optional
        Length [m], >= 0 (default 0).
    smax, smin : float, optional
        Right and left stop [m] (default 25 and -25, MSL start values).
    F_prop : float, optional
        Velocity-dependent friction [N s/m], >= 0 (default 1).
    F_Coulomb : float, optional
        Coulomb friction force [N], >= 0 (default 5).
    F_Stribeck : float, optional
        Stribeck effect [N], >= 0 (default 10).
    fexp : float, optional
        Exponential decay [s/m], >= 0 (default 2).
    peak : float, optional
        Maximum static friction over ``F_Coulomb + F_Stribeck``, >= 1 (default 1).
    e : float, optional
        Coefficient of restitution at the stops, in [0, 1] (default 0).
    v_support : float, optional
        Velocity of the friction surface [m/s] (default 0).
    **modifiers
        Further modifiers (start values of the states ``s``, ``v``), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    m = Parameter(1.0, unit="kg", description="mass of the sliding mass", lb=1e-300)
    L = Parameter(0.0, unit="m", description="length of the component, flange_a to flange_b", lb=0.0)
    smax = Parameter(25.0, unit="m", description="right stop for (right end of) sliding mass")
    smin = Parameter(-25.0, unit="m", description="left stop for (left end of) sliding mass")
    F_prop = Parameter(1.0, unit="N.s/m", description="velocity dependent friction", lb=0.0)
    F_Coulomb = Parameter(5.0, unit="N", description="constant friction: Coulomb force", lb=0.0)
    F_Stribeck = Parameter(10.0, unit="N", description="Stribeck effect", lb=0.0)
    fexp = Parameter(2.0, unit="s/m", description="exponential decay", lb=0.0)
    peak = Parameter(1.0, unit="1", description="maximum static friction / (F_Coulomb + F_Stribeck)", lb=1.0)
    e = Parameter(0.0, unit="1", description="coefficient of restitution at the stops", lb=0.0, ub=1.0)
    v_support = Parameter(0.0, unit="m/s", description="velocity of the friction surface (belt)")
    s = State(unit="m", description="absolute position of the centre of the component")
    v = State(unit="m/s", description="absolute velocity of the component")
    a = Variable(unit="m/s2", description="absolute acceleration of the component")
    f = Variable(unit="N", description="friction force, positive if opposing a positive relative velocity")

    def equations(self) -> None:
        """Rigid flanges, Newton's law with friction, the friction state machine and the stops."""
        self.equation(self.flange_a.s, self.s - self.L / 2, name="s_a")
        self.equation(self.flange_b.s, self.s + self.L / 2, name="s_b")
        self.equation(self.der(self.s), self.v, name="velocity")
        self.equation(self.der(self.v), self.a, name="acceleration")
        self.equation(self.m * self.a, self.flange_a.f + self.flange_b.f - self.f, name="newton")
        lo, hi = float(self._values["smin"][0] + self._values["L"][0] / 2), float(self._values["smax"][0] - self._values["L"][0] / 2)
        if lo > hi:
            raise InputError(f"the stops leave no room: smin + L/2 = {lo} > smax - L/2 = {hi}")
        start = self._attributes["s"]["start"]
        s0 = 0.0 if start is None else float(start[0])
        if not lo <= s0 <= hi:
            raise InputError(f"the start position s = {s0} is outside the stops [{lo}, {hi}]")
        vstart = self._attributes["v"]["start"]
        v_rel0 = (0.0 if vstart is None else float(vstart[0])) - float(self._values["v_support"][0])
        pre = f"{self.path}." if self.path else ""

        def sliding(v: ca.SX, direction: ca.SX) -> ca.SX:
            return stribeck_force(v, direction, self.F_prop, self.F_Coulomb, self.F_Stribeck, self.fexp)

        s_lo, s_hi = self.smin + self.L / 2, self.smax - self.L / 2
        f0_max = self.peak * (self.F_Coulomb + self.F_Stribeck)
        v_rel = self.v - self.v_support
        mode = _state_machine(
            self.model_call, pre, f"{pre}mode", v_rel, self.a, self.f, sliding, f0_max,
            (s_hi - self.s, self.s - s_lo), float(np.sign(v_rel0)),
        )
        v_post = -self.e * self.v
        after = ca.sign(v_post - self.v_support)  # e = 0, support at rest: 0, stuck at the stop
        for name, cond, stop in (("stop_max", self.s - s_hi, s_hi), ("stop_min", s_lo - self.s, s_lo)):
            reinit = [(self.s, stop), (self.v, v_post)]
            self.model_call("when", cond, reinit=reinit, assign=[(mode, after)], name=f"{pre}{name}")
