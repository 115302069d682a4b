"""Connectors of composed models: potential and flow variables, Modelica style.

A connector class declares its variables with :class:`Potential` (across variables:
position, angle, voltage; equal at a connection) and :class:`Flow` (through variables:
force, torque, current; summing to zero at a connection), as Modelica's ``connector``
with and without the ``flow`` prefix and ModelingToolkit.jl's ``@connector`` with
``connect = Flow`` metadata::

    class Pin(Connector):
        v = Potential(unit="V", description="potential at the pin")
        i = Flow(unit="A", description="current flowing into the pin")

Two connectors can be connected when they declare the same variables (names, kinds,
sizes and units), whatever their class names: ``Flange_a`` and ``Flange_b`` are
compatible, as in the Modelica Standard Library where they differ only in the icon.

The library's mechanical connectors are those of the MSL (position and cut force; angle
and cut torque): velocities are component-internal, ``v = der(s)``.

Connector instances are declared as class attributes of components
(``flange_a = Flange_a()``); each component instance gets its own copies, whose
variables are CasADi symbols named by the hierarchical path (``"axis.belt.flange_a.s"``)
while the component is flattened.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import _shape_to_size

__all__ = ["Potential", "Flow", "Connector", "Frame", "Frame_a", "Frame_b"]


class _ConnectorVariable:
    """A variable declared in a connector class (internal base of Potential and Flow)."""

    is_flow = False

    def __init__(self, unit: str = "", description: str = "", shape: Any = 1) -> None:
        if not isinstance(unit, str) or not isinstance(description, str):
            raise InputError(f"{type(self).__name__}: unit and description must be strings")
        self.unit = unit
        self.description = description
        self.size = _shape_to_size(shape, f"{type(self).__name__} shape")
        self.name = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, instance: Any, owner: type) -> Any:
        if instance is None:
            return self
        return instance._symbol(self.name)

    def signature(self) -> tuple[str, bool, int, str]:
        """``(name, is_flow, size, unit)``: what must agree for two connectors to connect."""
        return (self.name, self.is_flow, self.size, self.unit)


class Potential(_ConnectorVariable):
    """A potential (across) variable of a connector: equal at a connection.

    Modelica: a connector variable without the ``flow`` prefix.

    Parameters
    ----------
    unit : str, optional
        SI unit (documentation only, e.g. ``"m"``).
    description : str, optional
        One-line description.
    shape : int or tuple, optional
        Size ``n`` or ``(n,)``; default 1.

    Raises
    ------
    InputError
        If the unit/description are not strings or the shape is malformed.
    """


class Flow(_ConnectorVariable):
    """A flow (through) variable of a connector: sums to zero at a connection.

    Modelica: a connector variable with the ``flow`` prefix; positive when flowing into
    the component. The flow of an unconnected connector is zero.

    Parameters
    ----------
    unit : str, optional
        SI unit (documentation only, e.g. ``"N"``).
    description : str, optional
        One-line description.
    shape : int or tuple, optional
        Size ``n`` or ``(n,)``; default 1.

    Raises
    ------
    InputError
        If the unit/description are not strings or the shape is malformed.
    """

    is_flow = True


class Connector:
    """Base class of connectors: subclass it and declare :class:`Potential`/:class:`Flow` variables.

    Parameters
    ----------
    description : str, optional
        Description of this connector instance (e.g. ``"left flange"``).

    Raises
    ------
    InputError
        If ``description`` is not a string.
    ModelError
        If the connector class declares no variables.

    Examples
    --------
    >>> class Pin(Connector):
    ...     v = Potential(unit="V")
    ...     i = Flow(unit="A")
    >>> [v.name for v in Pin.variables()]
    ['v', 'i']
    """

    def __init__(self, description: str = "") -> None:
        if not isinstance(description, str):
            raise InputError(f"{type(self).__name__}: description must be a string, got {description!r}")
        if not self.variables():
            raise ModelError(f"connector class {type(self).__name__} declares no Potential or Flow variables")
        self.description = description
        self.name = ""
        self.owner: Any = None
        self._symbols: dict[str, ca.SX] = {}

    @classmethod
    def variables(cls) -> list[_ConnectorVariable]:
        """The declared variables, base classes first, in declaration order.

        Returns
        -------
        list of Potential or Flow
            Declarations (a subclass redefining a name replaces it in place).
        """
        found: dict[str, _ConnectorVariable] = {}
        for klass in reversed(cls.__mro__):
            for name, value in vars(klass).items():
                if isinstance(value, _ConnectorVariable):
                    found[name] = value
        return list(found.values())

    @classmethod
    def signature(cls) -> tuple[tuple[str, bool, int, str], ...]:
        """What two connectors must share to be connected: names, kinds, sizes, units.

        Returns
        -------
        tuple
            One ``(name, is_flow, size, unit)`` per variable, sorted by name.
        """
        return tuple(sorted(v.signature() for v in cls.variables()))

    @property
    def path(self) -> str:
        """Hierarchical name, e.g. ``"axis.belt.flange_a"`` (known once placed in a component)."""
        owner_path = self.owner.path if self.owner is not None else ""
        return f"{owner_path}.{self.name}" if owner_path else self.name

    def _symbol(self, name: str) -> ca.SX:
        try:
            return self._symbols[name]
        except KeyError:
            raise ModelError(
                f"connector {self.path or type(self).__name__}: variable {name!r} has a symbol only while its "
                "component is flattened (inside equations())"
            ) from None

    def _copy(self) -> "Connector":
        return type(self)(self.description)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.path or '<unplaced>'})"


class Frame(Connector):
    """3-D mechanical frame (translation only): position and cut force, world coordinates.

    A minimal form of ``Modelica.Mechanics.MultiBody.Interfaces.Frame`` without the
    orientation and torque (the Gantry-Tau links and carts exchange forces at spherical
    joints). Variables: ``r`` (3) [m] position of the frame origin; ``f`` (3) [N] cut
    force acting on the component at the frame.

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """

    r = Potential(unit="m", description="position of the frame origin, world coordinates", shape=3)
    f = Flow(unit="N", description="cut force acting on the component, world coordinates", shape=3)


class Frame_a(Frame):  # noqa: N801 - Modelica Standard Library name
    """3-D frame, "a" side (identical to :class:`Frame`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """


class Frame_b(Frame):  # noqa: N801 - Modelica Standard Library name
    """3-D frame, "b" side (identical to :class:`Frame`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """
