"""Friction with stiction and hard stops, named as ``Modelica.Mechanics.Translational``.

The friction state machine of the Modelica Standard Library (MSL 4.0,
``Translational.Interfaces.PartialFriction`` / ``PartialFrictionWithStop``; Otter, Elmqvist
and Mattsson (1999), "Hybrid modeling in Modelica based on the synchronous data flow
principle"), written with the events of :mod:`gtmodel.modeling.events`:

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

Hard stops (:func:`mass_with_stop_and_friction`): an impact at ``smin``/``smax`` reverses the velocity
with a coefficient of restitution ``e`` (Newton's impact law ``v+ = -e v-``). With
``e = 0`` (the MSL) the mass stops at the stop and stays stuck (friction mode ``0``)
until the force pulls it away from the stop.

The translational components of the library (``Mass``, ``Spring``, ...) are components of
:mod:`gtmodel.modeling.components`; the friction here is declared on a
:class:`~gtmodel.modeling.Model` (:func:`add_friction`, :func:`mass_with_stop_and_friction`)
because modes and when-clauses are model-level declarations.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.model import Model

__all__ = ["Stribeck", "FrictionSymbols", "add_friction", "mass_with_stop_and_friction"]


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
        return self.F_prop * v + direction * (self.F_Coulomb + self.F_Stribeck * ca.exp(-self.fexp * ca.fabs(v)))


@dataclass
class FrictionSymbols:
    """Symbols declared by :func:`add_friction` / :func:`mass_with_stop_and_friction`.

    Parameters
    ----------
    mode : casadi.SX
        Friction mode (``1`` forward, ``0`` stuck, ``-1`` backward).
    f : casadi.SX
        Friction force, N (positive when opposing a positive relative velocity).
    s, v : casadi.SX or None
        Position [m] and velocity [m/s] of the sliding mass (``None`` for :func:`add_friction`).
    """

    mode: ca.SX
    f: ca.SX
    s: ca.SX | None = None
    v: ca.SX | None = None


def add_friction(
    model: Model,
    v_rel: Any,
    f: Any,
    friction: Stribeck,
    name: str = "friction",
    a_rel: Any = None,
    mode_start: float = 0.0,
    can_start: Any = None,
) -> FrictionSymbols:
    """Declare the MSL friction state machine for a relative velocity on a model.

    Adds the mode ``<name>_mode``, the friction equation (sliding law or, stuck,
    ``a_rel = 0`` with ``der()`` replaced by the ODE right-hand side) and the four
    when-clauses ``<name>.stuck_forward``, ``<name>.stuck_backward``, ``<name>.start_forward``,
    ``<name>.start_backward`` (module docstring).

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
        Mode at the start of a simulation (``0``: stuck; match the initial ``v_rel``).
    can_start : tuple of casadi.SX, optional
        ``(forward, backward)`` expressions that must be positive for the stuck element to
        start sliding that way (used by hard stops); default always.

    Returns
    -------
    FrictionSymbols
        The mode and the force.

    Raises
    ------
    InputError
        If ``friction`` is not a :class:`Stribeck`, ``mode_start`` not -1, 0 or 1, or
        ``v_rel``/``a_rel`` are not scalar expressions.
    ModelError
        If ``f`` is not an algebraic variable of the model, or ``a_rel`` is omitted and
        ``v_rel`` is not a state.
    """
    if not isinstance(friction, Stribeck):
        raise InputError(f"friction must be a Stribeck, got {type(friction).__name__}")
    if mode_start not in (-1, 0, 1) or isinstance(mode_start, bool):
        raise InputError(f"{name}: mode_start must be -1, 0 or 1, got {mode_start!r}")
    kind, fname, _ = model.locate(f)
    if kind != "algebraic" or ca.SX(f).numel() != 1:
        raise ModelError(f"{name}: the friction force must be a scalar algebraic variable, got {kind} {fname!r}")
    v = ca.SX(v_rel) if isinstance(v_rel, (ca.SX, int, float)) else None
    if v is None or v.numel() != 1:
        raise InputError(f"{name}: v_rel must be a scalar SX expression, got {v_rel!r}")
    acc = model.der(v) if a_rel is None else ca.SX(a_rel)
    if acc.numel() != 1:
        raise InputError(f"{name}: a_rel must be a scalar SX expression")
    fwd, bwd = (1.0, 1.0) if can_start is None else can_start
    mode = model.mode(f"{name}_mode", float(mode_start))
    model.equation(
        ca.if_else(mode == 0, acc, f - friction.sliding(v, mode)), name=f"{name}.law", substitute_der=True
    )
    f0 = friction.f0_max
    model.when(ca.if_else(mode == 1, -v, -1.0), assign={mode: 0.0}, name=f"{name}.stuck_forward")
    model.when(ca.if_else(mode == -1, v, -1.0), assign={mode: 0.0}, name=f"{name}.stuck_backward")
    model.when(ca.if_else(ca.logic_and(mode == 0, fwd > 0), f - f0, -1.0), assign={mode: 1.0}, name=f"{name}.start_forward", initial=True)
    model.when(ca.if_else(ca.logic_and(mode == 0, bwd > 0), -f - f0, -1.0), assign={mode: -1.0}, name=f"{name}.start_backward", initial=True)
    return FrictionSymbols(mode=mode, f=ca.SX(f))


def mass_with_stop_and_friction(
    model: Model,
    name: str,
    force: Any,
    friction: Stribeck,
    m: float = 1.0,
    L: float = 0.0,
    smin: float = -25.0,
    smax: float = 25.0,
    e: float = 0.0,
    s_start: float = 0.0,
    v_start: float = 0.0,
) -> FrictionSymbols:
    """MSL ``MassWithStopAndFriction``: a sliding mass with Stribeck friction to the ground and hard stops.

    ``der(s) = v``, ``m der(v) = force - f`` with the friction force ``f`` of
    :func:`add_friction` (relative velocity ``v``); stops at ``smin + L/2 <= s <= smax - L/2``
    with Newton's impact law ``v+ = -e v-`` (clauses ``<name>.stop_min``, ``<name>.stop_max``).
    With ``e = 0`` (the MSL) the mass stays at the stop, stuck, until the force pulls it
    away with more than the static friction.

    Parameters
    ----------
    model : Model
        The model to declare on.
    name : str
        Prefix of the declared names: states ``<name>_s`` [m], ``<name>_v`` [m/s],
        algebraic ``<name>_f`` [N], mode ``<name>_friction_mode``.
    force : casadi.SX or float
        Sum of the external forces on the mass (MSL ``flange_a.f + flange_b.f``), N, an
        expression of the model's variables (e.g. an input or a spring force).
    friction : Stribeck
        Friction characteristic.
    m : float, optional
        Mass, kg, > 0; default 1.
    L : float, optional
        Length of the mass, m, ``>= 0``; default 0.
    smin, smax : float, optional
        Left and right stop, m; default -25 and 25 (MSL start values).
    e : float, optional
        Coefficient of restitution, ``0 <= e <= 1``; default 0 (MSL: the mass stops).
    s_start, v_start : float, optional
        Initial position [m] (within the stops) and velocity [m/s]; the friction starts
        stuck for ``v_start = 0``, else sliding in the direction of ``v_start``.

    Returns
    -------
    FrictionSymbols
        The mode, friction force, position and velocity.

    Raises
    ------
    InputError
        If ``m <= 0``, ``L < 0``, ``smin + L/2 > smax - L/2``, ``e`` is outside ``[0, 1]``,
        or ``s_start`` is outside the stops.
    ModelError
        If a declared name is taken.
    """
    vals = {"m": m, "L": L, "smin": smin, "smax": smax, "e": e, "s_start": s_start, "v_start": v_start}
    for key, val in vals.items():
        if isinstance(val, bool) or not isinstance(val, (int, float, np.number)) or not np.isfinite(val):
            raise InputError(f"{name}: {key} must be a finite number, got {val!r}")
    if m <= 0 or L < 0:
        raise InputError(f"{name}: need m > 0 and L >= 0, got m = {m!r}, L = {L!r}")
    lo, hi = smin + L / 2.0, smax - L / 2.0
    if lo > hi:
        raise InputError(f"{name}: the stops leave no room: smin + L/2 = {lo} > smax - L/2 = {hi}")
    if not 0.0 <= e <= 1.0:
        raise InputError(f"{name}: the coefficient of restitution e must be in [0, 1], got {e!r}")
    if not lo <= s_start <= hi:
        raise InputError(f"{name}: s_start = {s_start} is outside the stops [{lo}, {hi}]")
    s = model.state(f"{name}_s", start=float(s_start))
    v = model.state(f"{name}_v", start=float(v_start))
    f = model.algebraic(f"{name}_f")
    model.equation(model.der(s), v, name=f"{name}.v")
    model.equation(m * model.der(v), force - f, name=f"{name}.newton")
    sym = add_friction(
        model, v, f, friction, name=f"{name}_friction", mode_start=float(np.sign(v_start)), can_start=(hi - s, s - lo)
    )
    after = 0.0 if e == 0.0 else -sym.mode  # bounce: sliding the other way; e = 0: stuck at the stop
    model.when(s - hi, reinit={s: hi, v: -e * v}, assign={sym.mode: after}, name=f"{name}.stop_max")
    model.when(lo - s, reinit={s: lo, v: -e * v}, assign={sym.mode: after}, name=f"{name}.stop_min")
    return FrictionSymbols(mode=sym.mode, f=sym.f, s=s, v=v)
