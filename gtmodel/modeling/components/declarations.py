"""Declarations of component classes: parameters and variables (Modelica ``parameter`` and variables).

Used as class attributes of :class:`~gtmodel.modeling.components.component.Component` subclasses::

    c = Parameter(1e5, unit="N/m", description="spring constant", lb=0.0)
    eps = Parameter(1e-6, unit="m", description="width of the smoothed gap", smoothing=True)
    s = State(unit="m", description="position")          # der(s) may appear
    f = Variable(unit="N", description="spring force")     # algebraic
    u = Input(unit="N", description="driving force")      # model input

While a component is flattened, reading the attribute on an instance gives the CasADi
symbol of the variable (``self.c``); :meth:`Parameter.validate` and
:meth:`Variable.modify` check modifier values.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.components.connectors import Connector
from gtmodel.modeling.dae import _shape_to_size, _vector_value, fixed_flags

__all__ = ["Parameter", "Variable", "State", "Input", "Structural"]


class Parameter:
    """A parameter declaration of a component: default value, unit, description, bounds.

    Modelica: ``parameter SI.TranslationalSpringConstant c(min=0) = 1e5 "Spring constant"``.

    Parameters
    ----------
    default : float or array_like
        Default value (SI units).
    unit : str, optional
        SI unit (documentation, e.g. ``"N/m"``).
    description : str, optional
        One-line description.
    shape : int or tuple, optional
        Size ``n`` or ``(n,)``; inferred from ``default`` when omitted.
    lb, ub : float, optional
        Inclusive bounds checked on every value (Modelica ``min``/``max``).
    smoothing : bool, optional
        True marks a smoothing width (in the parameter's own unit): the component's
        law is smooth for a width > 0 and its exact non-smooth law is the limit as the
        width goes to 0 (the non-smooth elements of :mod:`gtmodel.modeling.library`).
        Such a parameter is one number and must be > 0 (every value is checked, as a
        strict lower bound 0); flattening passes the flag on to
        ``Model.parameter(..., smoothing=True)``, so a solver finds the widths in
        ``Model.smoothing``. Default False.

    Raises
    ------
    InputError
        If the default is not finite numbers of the declared size or violates the bounds,
        or (``smoothing``) is not one number > 0.
    """

    def __init__(
        self,
        default: Any,
        unit: str = "",
        description: str = "",
        shape: Any = None,
        lb: float | None = None,
        ub: float | None = None,
        smoothing: bool = False,
    ) -> None:
        if not isinstance(smoothing, (bool, np.bool_)):
            raise InputError(f"Parameter smoothing: expected True or False, got {smoothing!r}")
        self.name = ""
        self.unit = unit
        self.description = description
        self.lb = lb
        self.ub = ub
        self.smoothing = bool(smoothing)
        self.size = None if shape is None else _shape_to_size(shape, "Parameter shape")
        if self.smoothing and self.size not in (None, 1):
            raise InputError(f"Parameter shape: a smoothing width is one number, got shape {shape!r}")
        self.default = self.validate(default, "Parameter default")
        self.size = self.default.size

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, instance: Any, owner: type) -> Any:
        if instance is None:
            return self
        return instance._symbol(self.name)

    def validate(self, value: Any, where: str) -> np.ndarray:
        """Check a value of this parameter.

        Parameters
        ----------
        value : float or array_like
            Candidate value.
        where : str
            Name used in the message (e.g. ``"Spring.c"``).

        Returns
        -------
        numpy.ndarray
            The value as a float vector, shape ``(n,)``.

        Raises
        ------
        InputError
            If ``value`` is not real finite numbers (bools and strings are rejected), has
            another size, is outside ``[lb, ub]``, or (a smoothing width) is not one
            number > 0.
        """
        if isinstance(value, (bool, np.bool_, str, bytes)) or isinstance(value, (ca.SX, ca.MX)):
            raise InputError(f"{where}: expected a real number, got {type(value).__name__} {value!r}")
        try:
            arr = np.asarray(value, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(f"{where}: expected a real number, got {type(value).__name__} {value!r}") from None
        if arr.size == 0 or not np.all(np.isfinite(arr)):
            raise InputError(f"{where}: expected finite numbers, got {value!r}")
        if self.size is not None and arr.size != self.size:
            raise InputError(f"{where}: expected {self.size} value(s), got {arr.size}")
        if self.lb is not None and np.any(arr < self.lb):
            raise InputError(f"{where}: must be >= {self.lb}, got {value!r}")
        if self.ub is not None and np.any(arr > self.ub):
            raise InputError(f"{where}: must be <= {self.ub}, got {value!r}")
        if getattr(self, "smoothing", False) and (arr.size != 1 or np.any(arr <= 0)):
            raise InputError(f"{where}: a smoothing width must be one number > 0, got {value!r}")
        return arr


class Variable:
    """An algebraic variable declaration of a component (base of :class:`State`, :class:`Input`).

    Parameters
    ----------
    unit : str, optional
        SI unit (documentation).
    description : str, optional
        One-line description.
    shape : int or tuple, optional
        Size ``n`` or ``(n,)``; default 1.
    start : float or array_like, optional
        Start value; default 0. A guess for the initialisation unless ``fixed``.
    lb, ub : float or array_like, optional
        Bounds used by optimisation; default unbounded.
    fixed : bool or array_like of bool, optional
        Whether the start value is an initial condition (Modelica's ``fixed``); default
        False for a declaration. A modifier that gives a start value makes it True
        (``Mass(s=3)``) unless it says otherwise (``Mass(s={"start": 3, "fixed": False})``).

    Raises
    ------
    InputError
        If the shape or the values are malformed.
    """

    kind = "algebraic"

    def __init__(
        self, unit: str = "", description: str = "", shape: Any = 1, start: Any = None, lb: Any = None, ub: Any = None,
        fixed: Any = False,
    ) -> None:
        self.name = ""
        self.unit = unit
        self.description = description
        self.size = _shape_to_size(shape, f"{type(self).__name__} shape")
        if self.kind == "input" and fixed is not False:
            raise ModelError(f"{type(self).__name__}: an input has no initial condition; fixed must stay False, got {fixed!r}")
        self.attributes = self.modify(
            {"start": start, "lb": lb, "ub": ub, **({} if self.kind == "input" else {"fixed": fixed})},
            f"{type(self).__name__}",
        )

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, instance: Any, owner: type) -> Any:
        if instance is None:
            return self
        return instance._symbol(self.name)

    def modify(self, modifier: Any, where: str, base: dict | None = None) -> dict[str, Any]:
        """Apply a modifier: a start value, or a mapping with ``start``, ``fixed``, ``lb``, ``ub``.

        A start value given by a modifier is an initial condition (``fixed`` True) unless
        the mapping sets ``fixed`` (the user's value is honoured, never replaced: see
        :mod:`gtmodel.modeling.structure.initialization`); an input's start is its nominal
        value and takes no ``fixed``.

        Parameters
        ----------
        modifier : float, array_like or mapping
            ``Mass(s=0.1)`` gives a fixed start value; ``Mass(s={"start": 0.1, "lb": 0.0})``
            any of the attributes (``{"start": 0.1, "fixed": False}``: a guess).
        where : str
            Name used in messages.
        base : dict, optional
            Attributes to start from (default the declaration's).

        Returns
        -------
        dict
            ``{"start": ndarray or None, "lb": ..., "ub": ..., "fixed": bool ndarray}``
            (no ``fixed`` for an input).

        Raises
        ------
        ModelError
            If a mapping has keys other than start, fixed, lb, ub (fixed: not for an input).
        InputError
            If a value is not numbers of the variable's size, or ``fixed`` not booleans.
        """
        defaults = {"start": None, "lb": None, "ub": None}
        if self.kind != "input":
            defaults["fixed"] = np.zeros(self.size, dtype=bool)
        out = dict(base if base is not None else getattr(self, "attributes", defaults))
        mod = dict(modifier) if isinstance(modifier, dict) else {"start": modifier}
        allowed = set(defaults)
        bad = sorted(set(mod) - allowed)
        if bad:
            raise ModelError(
                f"{where}: unknown attribute(s) {bad} of variable {self.name!r}; allowed: {', '.join(sorted(allowed))}"
            )
        if "fixed" in allowed and "fixed" not in mod and mod.get("start") is not None:
            mod["fixed"] = True  # a start value the user gives is an initial condition
        for key, value in mod.items():
            if key == "fixed":
                out[key] = fixed_flags(value, self.size, f"{where}: fixed of variable {self.name!r}")
                continue
            if value is None:
                continue
            if isinstance(value, (bool, np.bool_, str, bytes)):
                raise InputError(f"{where}: {key} of variable {self.name!r} must be numbers, got {value!r}")
            out[key] = _vector_value(value, self.size, f"{where}: {key} of variable {self.name!r}")
            if not np.all(np.isfinite(out[key])) and key == "start":
                raise InputError(f"{where}: start of variable {self.name!r} must be finite, got {value!r}")
        return out


class State(Variable):
    """A differentiated variable: ``der()`` of it may appear in the equations.

    Declare as states the variables whose derivatives the component writes (a mass's
    ``s`` and ``v``, a damper's ``s_rel``). States of different components may be
    dependent (a damper's ``s_rel`` and the positions of the masses it joins); the
    structural passes then choose the states (``Model.simulate`` does). Give such states
    consistent start values, or an initial equation.

    Parameters
    ----------
    unit : str, optional
        SI unit (documentation).
    description : str, optional
        One-line description.
    shape : int or tuple, optional
        Size; default 1.
    start : float or array_like, optional
        Start value; default 0 (a guess unless ``fixed``).
    lb, ub : float or array_like, optional
        Bounds used by optimisation.
    fixed : bool or array_like of bool, optional
        Whether the declared start is an initial condition; default False (a modifier's
        start value is fixed, see :class:`Variable`).
    """

    kind = "state"


class Input(Variable):
    """An input of the model (a force or voltage source's signal, a control).

    Parameters
    ----------
    unit : str, optional
        SI unit (documentation).
    description : str, optional
        One-line description.
    shape : int or tuple, optional
        Size; default 1.
    start : float or array_like, optional
        Nominal value (simulation default, optimisation guess); default 0.
    lb, ub : float or array_like, optional
        Bounds used by optimisation.
    fixed : bool, optional
        Not used (an input has no initial condition); must stay False.
    """

    kind = "input"


class Structural:
    """A structural parameter: a Python value fixed when the model is built (MTK ``@structural_parameters``).

    Unlike a :class:`Parameter` it is no symbol of the model: ``equations()`` reads the
    plain value (e.g. to choose equations, as Modelica's ``parameter Boolean`` in
    ``if`` clauses).

    Parameters
    ----------
    default : object
        Default value.
    choices : sequence, optional
        Allowed values (default: any value of the default's type).
    description : str, optional
        One-line description.

    Raises
    ------
    InputError
        If the default is not among the choices.
    """

    def __init__(self, default: Any, choices: Any = None, description: str = "") -> None:
        self.name = ""
        self.choices = tuple(choices) if choices is not None else None
        self.description = description
        self.default = self.validate(default, "Structural default")

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, instance: Any, owner: type) -> Any:
        if instance is None:
            return self
        return instance._values[self.name]

    def validate(self, value: Any, where: str) -> Any:
        """Check a value of this structural parameter.

        Parameters
        ----------
        value : object
            Candidate value.
        where : str
            Name used in the message.

        Returns
        -------
        object
            ``value``.

        Raises
        ------
        InputError
            If ``value`` is not one of the choices (or not of the default's type).
        """
        if self.choices is not None:
            if value not in self.choices:
                raise InputError(f"{where}: expected one of {list(self.choices)}, got {value!r}")
        elif hasattr(self, "default") and not isinstance(value, type(self.default)):
            raise InputError(f"{where}: expected a {type(self.default).__name__}, got {value!r}")
        return value


class _ComponentBase:
    """Marker base of :class:`~gtmodel.modeling.components.component.Component` (internal)."""


_DECLARATIONS = (Parameter, Variable, Structural, Connector, _ComponentBase)


def _declarations(cls: type) -> dict[str, Any]:
    """Declarations of a component class (base classes first; a redeclaration replaces)."""
    found: dict[str, Any] = {}
    for klass in reversed(cls.__mro__):
        for name, value in vars(klass).items():
            if isinstance(value, _DECLARATIONS):
                found[name] = value
            elif name in found and not name.startswith("__"):
                found.pop(name)  # redefined as something else by a subclass
    return found
