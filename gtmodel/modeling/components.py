"""Acausal components, Modelica style: parameters, variables, connectors, sub-components, connect().

A component is a Python class (Modelica ``model``, ModelingToolkit.jl ``@mtkmodel``)
whose class attributes declare

* parameters with defaults, units and descriptions: ``c = Parameter(1e5, unit="N/m")``;
* variables: ``s = State(unit="m")`` (differentiated, ``der(s)`` allowed),
  ``f = Variable(unit="N")`` (algebraic), ``u = Input(unit="N")`` (input of the model);
* connectors: ``flange_a = Flange_a()`` (:mod:`gtmodel.modeling.connectors`);
* sub-components: ``belt = SpringDamper(c=2e5)``, named hierarchically (``"axis1.belt.c"``),

and whose :meth:`Component.equations` method writes the equations with the component's
own symbols (``self.c``, ``self.flange_a.s``, ``self.der(self.v)``) and the connections
(:func:`connect`)::

    class Spring(PartialCompliant):
        c = Parameter(1e5, unit="N/m", description="spring constant", lb=0.0)

        def equations(self):
            super().equations()                     # the base class's equations (extends)
            self.equation(self.f, self.c * self.s_rel)

Instantiation with keyword arguments is a modifier (``Spring(c=2e5)``; a state's start
value ``Mass(s=0.1)`` or ``Mass(s={"start": 0.1, "lb": 0})``; a sub-component's
modifiers ``Axis(belt={"c": 2e5})`` or a replacement ``Axis(belt=SpringDamper(...))``).
Subclassing is ``extends``: declarations are inherited and can be redeclared; a
subclass keeps the base's equations by calling ``super().equations()``.

Flattening (:meth:`Component.to_model`) gives today's :class:`~gtmodel.modeling.Model`,
so simulation, :class:`~gtmodel.modeling.Optimization`, collocation and code generation
work unchanged. Per connection set (the connectors joined by ``connect`` at one level of
the hierarchy) it writes the Modelica connection equations: equal potentials, and
``sum(inside flows) - sum(outside flows) = 0``; the flow of a connector connected to
nothing at its parent's level is zero (and so is the flow of the flattened component's
own connectors: free ends). A potential variable that no component equation or output
uses in its whole (cross-level) connection class is dropped with its equalities: so the
velocity of a massless node between two springs does not make the model
under-determined. Every connector variable that is kept is an algebraic variable of the
model; the connection equalities are alias equations that the structural passes may
eliminate.
"""

from __future__ import annotations

import inspect
import logging
import re
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import GtModelError, InputError, ModelError
from gtmodel.modeling.connectors import Connector
from gtmodel.modeling.dae import _as_sx, _shape_to_size, _vector_value
from gtmodel.modeling.model import Model

__all__ = ["Parameter", "Variable", "State", "Input", "Component", "connect"]

_log = logging.getLogger("gtmodel")


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

    Raises
    ------
    InputError
        If the default is not finite numbers of the declared size or violates the bounds.
    """

    def __init__(
        self,
        default: Any,
        unit: str = "",
        description: str = "",
        shape: Any = None,
        lb: float | None = None,
        ub: float | None = None,
    ) -> None:
        self.name = ""
        self.unit = unit
        self.description = description
        self.lb = lb
        self.ub = ub
        self.size = None if shape is None else _shape_to_size(shape, "Parameter shape")
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
            another size, or is outside ``[lb, ub]``.
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
        Start value (initial condition of a state, guess otherwise); default 0.
    lb, ub : float or array_like, optional
        Bounds used by optimisation; default unbounded.

    Raises
    ------
    InputError
        If the shape or the values are malformed.
    """

    kind = "algebraic"

    def __init__(
        self, unit: str = "", description: str = "", shape: Any = 1, start: Any = None, lb: Any = None, ub: Any = None
    ) -> None:
        self.name = ""
        self.unit = unit
        self.description = description
        self.size = _shape_to_size(shape, f"{type(self).__name__} shape")
        self.attributes = self.modify({"start": start, "lb": lb, "ub": ub}, f"{type(self).__name__}")

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, instance: Any, owner: type) -> Any:
        if instance is None:
            return self
        return instance._symbol(self.name)

    def modify(self, modifier: Any, where: str, base: dict | None = None) -> dict[str, Any]:
        """Apply a modifier: a start value, or a mapping with ``start``, ``lb``, ``ub``.

        Parameters
        ----------
        modifier : float, array_like or mapping
            ``Mass(s=0.1)`` gives a start value; ``Mass(s={"start": 0.1, "lb": 0.0})``
            any of the attributes.
        where : str
            Name used in messages.
        base : dict, optional
            Attributes to start from (default the declaration's).

        Returns
        -------
        dict
            ``{"start": ndarray or None, "lb": ..., "ub": ...}``.

        Raises
        ------
        ModelError
            If a mapping has keys other than start, lb, ub.
        InputError
            If a value is not numbers of the variable's size.
        """
        out = dict(base if base is not None else getattr(self, "attributes", {"start": None, "lb": None, "ub": None}))
        mod = modifier if isinstance(modifier, dict) else {"start": modifier}
        bad = sorted(set(mod) - {"start", "lb", "ub"})
        if bad:
            raise ModelError(f"{where}: unknown attribute(s) {bad} of variable {self.name!r}; allowed: start, lb, ub")
        for key, value in mod.items():
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

    Today's :meth:`~gtmodel.modeling.Model.flatten` needs index 1: declare as states the
    variables whose derivatives the component writes (a mass's ``s`` and ``v``).

    Parameters
    ----------
    unit : str, optional
        SI unit (documentation).
    description : str, optional
        One-line description.
    shape : int or tuple, optional
        Size; default 1.
    start : float or array_like, optional
        Initial value for simulation; default 0.
    lb, ub : float or array_like, optional
        Bounds used by optimisation.
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
    """

    kind = "input"


_DECLARATIONS = (Parameter, Variable, Connector)
#: The component whose equations() runs, with its flattening (for module-level connect()).
_ACTIVE: list[tuple["_Flattening", "Component"]] = []


def _declarations(cls: type) -> dict[str, Any]:
    """Declarations of a component class (base classes first; a redeclaration replaces)."""
    found: dict[str, Any] = {}
    for klass in reversed(cls.__mro__):
        for name, value in vars(klass).items():
            if isinstance(value, _DECLARATIONS) or isinstance(value, Component):
                found[name] = value
            elif name in found and not name.startswith("__"):
                found.pop(name)  # redefined as something else by a subclass
    return found


class Component:
    """Base class of acausal components; keyword arguments are modifiers.

    Parameters
    ----------
    **modifiers
        ``name=value`` per declared parameter (value), variable (start value or mapping
        with ``start``, ``lb``, ``ub``) or sub-component (mapping of its modifiers, or a
        component instance replacing it, which must have the same connectors).

    Raises
    ------
    ModelError
        Naming the component class, if a modifier names nothing declared (the message
        lists the allowed names) or a replacement lacks a connector.
    InputError
        If a value has the wrong type, size or is out of bounds (naming the parameter).

    Examples
    --------
    >>> from gtmodel.modeling.library.translational import Fixed, Mass, Spring
    >>> class Oscillator(Component):
    ...     fixed = Fixed()
    ...     spring = Spring(c=4.0)
    ...     mass = Mass(m=1.0, s=0.1)
    ...     def equations(self):
    ...         connect(self.fixed.flange, self.spring.flange_a)
    ...         connect(self.spring.flange_b, self.mass.flange_a)
    >>> model = Oscillator(spring={"c": 9.0}).to_model()
    >>> model.variables("parameter")["spring.c"].shape
    (1, 1)
    """

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Give each component class a signature: its parameters (with defaults), then ``**modifiers``."""
        super().__init_subclass__(**kwargs)
        params = [
            inspect.Parameter(
                name, inspect.Parameter.KEYWORD_ONLY, default=float(d.default[0]) if d.size == 1 else d.default.tolist()
            )
            for name, d in _declarations(cls).items()
            if isinstance(d, Parameter)
        ]
        params.append(inspect.Parameter("modifiers", inspect.Parameter.VAR_KEYWORD))
        cls.__signature__ = inspect.Signature(params)

    def __init__(self, **modifiers: Any) -> None:
        cls = type(self)
        decls = _declarations(cls)
        self.name = ""
        self.parent: Component | None = None
        self._path: str | None = None
        self._modifiers = dict(modifiers)
        self._values: dict[str, np.ndarray] = {}
        self._attributes: dict[str, dict[str, Any]] = {}
        self._symbols: dict[str, ca.SX] = {}
        self._ctx: _Flattening | None = None
        unknown = sorted(k for k in modifiers if k not in decls or isinstance(decls[k], Connector))
        if unknown:
            allowed = sorted(k for k, d in decls.items() if not isinstance(d, Connector))
            raise ModelError(f"{cls.__name__}: unknown modifier(s) {unknown}; allowed: {allowed}")
        for name, decl in decls.items():
            where = f"{cls.__name__}.{name}"
            if isinstance(decl, Parameter):
                self._values[name] = decl.validate(modifiers.get(name, decl.default), where)
            elif isinstance(decl, Variable):
                self._attributes[name] = decl.modify(modifiers[name], where) if name in modifiers else dict(decl.attributes)
            elif isinstance(decl, Connector):
                conn = decl._copy()
                conn.name, conn.owner = name, self
                self.__dict__[name] = conn
            else:
                sub = _instantiate(decl, modifiers.get(name), where)
                sub.name, sub.parent = name, self
                self.__dict__[name] = sub

    # ------------------------------------------------------------------ introspection
    @classmethod
    def declarations(cls) -> dict[str, Any]:
        """Declared parameters, variables, connectors and sub-components of the class.

        Returns
        -------
        dict
            Name -> declaration (:class:`Parameter`, :class:`Variable`, a connector or a
            component template), base classes first.
        """
        return _declarations(cls)

    def parameter_values(self) -> dict[str, np.ndarray]:
        """The (modified) parameter values of this component and its sub-components.

        Returns
        -------
        dict of str to numpy.ndarray
            Hierarchical name relative to this component (``"belt.c"``) -> value.
        """
        out = {k: v.copy() for k, v in self._values.items()}
        for name, sub in self.components().items():
            out.update({f"{name}.{k}": v for k, v in sub.parameter_values().items()})
        return out

    def components(self) -> dict[str, "Component"]:
        """Direct sub-components of this instance.

        Returns
        -------
        dict of str to Component
            Attribute name -> instance.
        """
        return {k: v for k, v in self.__dict__.items() if isinstance(v, Component) and k != "parent"}

    def connectors(self) -> dict[str, Connector]:
        """Connectors of this instance.

        Returns
        -------
        dict of str to Connector
            Attribute name -> instance.
        """
        return {k: v for k, v in self.__dict__.items() if isinstance(v, Connector)}

    @property
    def path(self) -> str:
        """Hierarchical name relative to the flattened root (``""`` for the root itself)."""
        if self._path is not None:
            return self._path
        if self.parent is None:
            return ""
        return f"{self.parent.path}.{self.name}" if self.parent.path else self.name

    def _label(self) -> str:
        return f"{self.path or '<root>'} ({type(self).__name__})"

    # ------------------------------------------------------------------ used in equations()
    def equations(self) -> None:
        """Write the component's equations and connections (override; no-op here).

        Use :meth:`equation`, :meth:`der`, :meth:`output` and :func:`connect` with the
        component's symbols. A subclass keeps its base's equations with
        ``super().equations()`` (Modelica ``extends``).
        """

    def _symbol(self, name: str) -> ca.SX:
        try:
            return self._symbols[name]
        except KeyError:
            raise ModelError(
                f"component {self._label()}: {name!r} has a symbol only while the component is flattened "
                "(inside equations()); its value is in parameter_values()"
            ) from None

    def _context(self) -> "_Flattening":
        if self._ctx is None:
            raise ModelError(f"component {self._label()}: equation(), der(), output() and connect() work only inside equations()")
        return self._ctx

    @property
    def time(self) -> ca.SX:
        """The time symbol of the model being flattened (SX scalar), s."""
        return self._context().scratch.time

    def der(self, x: Any) -> ca.SX:
        """``der(x)`` of a state (or elements of one) of the model being flattened.

        Parameters
        ----------
        x : casadi.SX
            A state symbol (``self.v``) or elements of one.

        Returns
        -------
        casadi.SX
            The derivative symbol(s), same size.

        Raises
        ------
        ModelError
            If an element is not a declared state (naming the component).
        """
        try:
            return self._context().scratch.der(x)
        except GtModelError as exc:
            raise ModelError(f"component {self._label()}: {exc}") from None

    def equation(self, lhs: Any, rhs: Any = 0.0, name: str | None = None) -> None:
        """Add the equation ``lhs == rhs`` of this component.

        Parameters
        ----------
        lhs, rhs : casadi.SX or float or array_like
            Expressions of the symbols of this component, its connectors and its
            sub-components; same size (or one of them scalar).
        name : str, optional
            Label for messages (default ``"eq<k>"``), prefixed by the component path.

        Raises
        ------
        ModelError
            If the equation uses symbols of no component of the flattened model.
        InputError
            If the sizes do not match.
        """
        self._context().equation(self, lhs, rhs, name)

    def output(self, name: str, expr: Any) -> None:
        """Declare an output (derived variable) of this component, named ``path.name``.

        Parameters
        ----------
        name : str
            Identifier.
        expr : casadi.SX or float
            Expression of the component's symbols (``der()`` allowed).

        Raises
        ------
        ModelError
            If ``expr`` uses unknown symbols or the name is taken.
        """
        self._context().output(self, name, expr)

    def connect(self, a: Connector, b: Connector) -> None:
        """Connect two connectors of this component or of its direct sub-components.

        Same as the module-level :func:`connect` called inside :meth:`equations`.

        Parameters
        ----------
        a, b : Connector
            Compatible connectors (same variables, units and sizes).

        Raises
        ------
        ModelError
            Naming both connectors: incompatible, identical, or not owned by this
            component or a direct sub-component.
        """
        self._context().connect(self, a, b)

    # ------------------------------------------------------------------ flattening
    def to_model(self, name: str | None = None) -> Model:
        """Flatten this component (and its sub-components) into a :class:`Model`.

        Parameters
        ----------
        name : str, optional
            Model name; default the class name.

        Returns
        -------
        Model
            Parameters ``"sub.param"``, states, algebraic variables (every kept connector
            variable), inputs, equations (components' and connections') and outputs.

        Raises
        ------
        ModelError
            Naming the component: an error in its equations or connections.
        InputError
            Malformed equations (size mismatch).
        """
        return _Flattening(self, name or type(self).__name__).run()

    def __repr__(self) -> str:
        mods = ", ".join(f"{k}={v!r}" for k, v in self._modifiers.items())
        return f"{type(self).__name__}({mods})"


def _instantiate(template: Component, modifier: Any, where: str) -> Component:
    """A fresh instance of a sub-component template, with a modifier applied."""
    if modifier is None:
        return type(template)(**template._modifiers)
    if isinstance(modifier, dict):
        return type(template)(**{**template._modifiers, **modifier})
    if isinstance(modifier, Component):
        need = {k: c.signature() for k, c in template.connectors().items()}
        have = {k: c.signature() for k, c in modifier.connectors().items()}
        missing = sorted(k for k in need if have.get(k) != need[k])
        if missing:
            raise ModelError(
                f"{where}: replacement {type(modifier).__name__} lacks connector(s) {missing} of "
                f"{type(template).__name__}"
            )
        return type(modifier)(**modifier._modifiers)
    raise InputError(f"{where}: a sub-component modifier must be a dict of modifiers or a Component, got {modifier!r}")


def connect(a: Connector, b: Connector) -> None:
    """Connect two connectors (Modelica ``connect(a, b)``), inside a component's ``equations()``.

    Connection semantics (Modelica Language Specification, section 9.2): per connection
    set, potentials are equal and ``sum(inside flows) - sum(outside flows) = 0``.

    Parameters
    ----------
    a, b : Connector
        Connectors of the component whose ``equations()`` runs or of its direct
        sub-components; they must declare the same variables (names, units, sizes).

    Raises
    ------
    ModelError
        Naming both connectors: called outside ``equations()``, a connector connected to
        itself, incompatible connectors, or a connector of another component.
    """
    if not _ACTIVE:
        raise ModelError(
            f"connect({getattr(a, 'path', a)!r}, {getattr(b, 'path', b)!r}) must be called inside a component's equations()"
        )
    ctx, comp = _ACTIVE[-1]
    ctx.connect(comp, a, b)


@dataclass
class _Declared:
    """A variable declared in the scratch model (internal record)."""

    name: str
    kind: str
    sym: ca.SX
    size: int
    start: Any = None
    lb: Any = None
    ub: Any = None
    value: Any = None


@dataclass
class _Flattening:
    """One flattening of a component tree into a Model (internal)."""

    root: Component
    name: str
    scratch: Model = field(init=False)
    declared: list[_Declared] = field(default_factory=list)
    equations: list[tuple[Component, str, ca.SX]] = field(default_factory=list)
    outputs: list[tuple[str, ca.SX]] = field(default_factory=list)
    pairs: dict[int, list[tuple[Connector, Connector]]] = field(default_factory=dict)
    nodes: list[Component] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.scratch = Model(self.name)

    # -------------------------------------------------------------- declarations
    def _declare(self, full: str, kind: str, size: int, **attrs: Any) -> ca.SX:
        m = self.scratch
        if kind == "parameter":
            sym = m.parameter(full, attrs["value"])
        else:
            sym = getattr(m, kind)(full, shape=size, start=attrs.get("start"), lb=attrs.get("lb"), ub=attrs.get("ub"))
        self.declared.append(_Declared(full, kind, sym, size, **attrs))
        return sym

    def _walk(self, comp: Component, path: str) -> None:
        comp._path, comp._ctx, comp._symbols = path, self, {}
        self.nodes.append(comp)
        pre = f"{path}." if path else ""
        try:
            for name, decl in _declarations(type(comp)).items():
                if isinstance(decl, Parameter):
                    comp._symbols[name] = self._declare(pre + name, "parameter", decl.size, value=comp._values[name])
                elif isinstance(decl, Variable):
                    comp._symbols[name] = self._declare(pre + name, decl.kind, decl.size, **comp._attributes[name])
            for cname, conn in comp.connectors().items():
                conn._symbols = {v.name: self._declare(f"{pre}{cname}.{v.name}", "algebraic", v.size) for v in conn.variables()}
        except GtModelError as exc:
            raise ModelError(f"component {comp._label()}: {exc}") from None
        for sname, sub in comp.components().items():
            self._walk(sub, pre + sname)

    # -------------------------------------------------------------- used by components
    def equation(self, comp: Component, lhs: Any, rhs: Any, name: str | None) -> None:
        k = sum(1 for c, _, _ in self.equations if c is comp)
        label = f"{comp.path}.{name or f'eq{k}'}" if comp.path else (name or f"eq{k}")
        a = _as_sx(lhs, f"equation {label!r} lhs")
        b = _as_sx(rhs, f"equation {label!r} rhs")
        if a.numel() != b.numel() and a.numel() != 1 and b.numel() != 1:
            raise InputError(f"component {comp._label()}: equation {label!r}: lhs has {a.numel()} elements but rhs has {b.numel()}")
        res = a - b
        self.scratch.check_symbols(res, f"component {comp._label()}: equation {label!r}")
        self.equations.append((comp, label, res))

    def output(self, comp: Component, name: str, expr: Any) -> None:
        full = f"{comp.path}.{name}" if comp.path else name
        e = _as_sx(expr, f"output {full!r}")
        self.scratch.check_symbols(e, f"component {comp._label()}: output {full!r}")
        if any(n == full for n, _ in self.outputs):
            raise ModelError(f"component {comp._label()}: output {full!r} is declared twice")
        self.outputs.append((full, e))

    def connect(self, comp: Component, a: Any, b: Any) -> None:
        where = f"component {comp._label()}: connect({getattr(a, 'path', a)}, {getattr(b, 'path', b)})"
        for c in (a, b):
            if not isinstance(c, Connector):
                raise ModelError(f"{where}: {c!r} is not a connector (got {type(c).__name__})")
        if a is b:
            raise ModelError(f"{where}: a connector cannot be connected to itself")
        for c in (a, b):
            if c.owner is not comp and c.owner.parent is not comp:
                raise ModelError(
                    f"{where}: connector {c.path} belongs neither to {comp.path or '<root>'} nor to one of its direct "
                    "sub-components"
                )
        if a.signature() != b.signature():
            raise ModelError(
                f"{where}: incompatible connectors {a.path} ({type(a).__name__}: "
                f"{', '.join(v.name for v in a.variables())}) and {b.path} ({type(b).__name__}: "
                f"{', '.join(v.name for v in b.variables())})"
            )
        self.pairs.setdefault(id(comp), []).append((a, b))

    # -------------------------------------------------------------- the flattening
    def run(self) -> Model:
        root = self.root
        try:
            self._walk(root, "")
            for comp in self.nodes:
                _ACTIVE.append((self, comp))
                try:
                    comp.equations()
                except GtModelError as exc:
                    raise type(exc)(str(exc) if comp._label() in str(exc) else f"component {comp._label()}: {exc}") from None
                except (RuntimeError, TypeError, ValueError, NotImplementedError, AttributeError) as exc:
                    raise ModelError(f"component {comp._label()}: error in equations(): {_short(exc)}") from None
                finally:
                    _ACTIVE.pop()
            return self._build()
        finally:
            for comp in self.nodes:
                comp._ctx = None
                comp._path = None

    def _build(self) -> Model:
        sets, inside_connected = self._connection_sets()
        used = self._used_names()
        # potentials dropped when unused in their whole cross-level class (union of sets)
        parent: dict[int, int] = {}

        def find(i: int) -> int:
            while parent.setdefault(i, i) != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for members in sets:
            for conn, _ in members[1:]:
                parent[find(id(conn))] = find(id(members[0][0]))
        classes: dict[int, list[Connector]] = {}
        all_conns = [c for comp in self.nodes for c in comp.connectors().values()]
        for conn in all_conns:
            classes.setdefault(find(id(conn)), []).append(conn)
        dropped: set[str] = set()
        for members in classes.values():
            for var in members[0].variables():
                if var.is_flow:
                    continue
                names = [_element_names(c._symbols[var.name]) for c in members]
                if not any(n in used for ns in names for n in ns):
                    dropped.update(f"{c.path}.{var.name}" for c in members)
        eqs: list[tuple[str, ca.SX]] = [(label, res) for _, label, res in self.equations]
        for members in sets:
            label = "connect(" + ", ".join(c.path for c, _ in members) + ")"
            for var in members[0][0].variables():
                syms = [c._symbols[var.name] for c, _ in members]
                if var.is_flow:
                    eqs.append((f"{label}.{var.name}", sum((sign * s for (c, sign), s in zip(members, syms)), ca.SX.zeros(var.size))))
                elif f"{members[0][0].path}.{var.name}" not in dropped:
                    eqs.extend((f"{label}.{var.name}[{k}]", syms[0] - s) for k, s in enumerate(syms[1:], 1))
        # flows of unconnected connectors are zero; so are those of the root's own connectors
        for conn in all_conns:
            if conn.owner is self.root or id(conn) not in inside_connected:
                for var in conn.variables():
                    if var.is_flow:
                        eqs.append((f"{conn.path}.{var.name} (unconnected)", conn._symbols[var.name]))
        return self._final_model(eqs, dropped)

    def _connection_sets(self) -> tuple[list[list[tuple[Connector, int]]], set[int]]:
        sets: list[list[tuple[Connector, int]]] = []
        inside_connected: set[int] = set()
        for comp in self.nodes:
            pairs = self.pairs.get(id(comp), [])
            groups: list[list[Connector]] = []
            for a, b in pairs:
                ga = next((g for g in groups if any(c is a for c in g)), None)
                gb = next((g for g in groups if any(c is b for c in g)), None)
                if ga is None and gb is None:
                    groups.append([a, b])
                elif ga is not None and gb is None:
                    ga.append(b)
                elif ga is None and gb is not None:
                    gb.append(a)
                elif ga is not gb:
                    ga.extend(gb)
                    groups.remove(gb)
            for g in groups:
                sets.append([(c, -1 if c.owner is comp else 1) for c in g])
                inside_connected.update(id(c) for c in g if c.owner is not comp)
            self._check_outside(comp, groups)
        return sets, inside_connected

    def _check_outside(self, comp: Component, groups: list[list[Connector]]) -> None:
        """A composite's own connector must be connected inside it (or used by its equations)."""
        if not comp.components():
            return
        used = self._used_names(comp)
        for conn in comp.connectors().values():
            if any(c is conn for g in groups for c in g):
                continue
            if not any(n in used for v in conn.variables() for n in _element_names(conn._symbols[v.name])):
                raise ModelError(
                    f"component {comp._label()}: its connector {conn.path} is connected to nothing inside it"
                )

    def _used_names(self, only: Component | None = None) -> set[str]:
        exprs = [res for comp, _, res in self.equations if only is None or comp is only]
        if only is None:
            exprs += [e for _, e in self.outputs]
        if not exprs:
            return set()
        return {s.name() for s in ca.symvar(ca.vertcat(*exprs))}

    def _final_model(self, eqs: list[tuple[str, ca.SX]], dropped: set[str]) -> Model:
        model = Model(self.name)
        old, new = [], []
        for d in self.declared:
            if d.name in dropped:
                continue
            if d.kind == "parameter":
                sym = model.parameter(d.name, d.value)
            else:
                sym = getattr(model, d.kind)(d.name, shape=d.size, start=d.start, lb=d.lb, ub=d.ub)
            old.append(d.sym)
            new.append(sym)
            if d.kind == "state":
                old.append(self.scratch.der(d.sym))
                new.append(model.der(sym))
        o, n = ca.vertcat(*old), ca.vertcat(*new)
        exprs = ca.substitute([r for _, r in eqs] + [e for _, e in self.outputs], [o], [n])
        for (label, _), res in zip(eqs, exprs[: len(eqs)]):
            model.equation(res, 0.0, name=label)
        for (oname, _), e in zip(self.outputs, exprs[len(eqs):]):
            model.output(oname, e)
        _log.debug(
            "flattened component %s: %d variables (%d connector potentials dropped), %d equations",
            self.name, len(self.declared) - len(dropped), len(dropped), len(eqs),
        )
        return model


def _short(exc: Exception) -> str:
    """The informative line of an exception message (CasADi's last line, without its source path)."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    if not lines:
        return type(exc).__name__
    return re.sub(r"^\.\.\./\S+:\d+:\s*", "", lines[-1])


def _element_names(sym: ca.SX) -> list[str]:
    return [sym[i].name() for i in range(int(sym.numel()))]
