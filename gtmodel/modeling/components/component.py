"""Acausal components, Modelica style: parameters, variables, connectors, sub-components, connect().

A component is a Python class (Modelica ``model``, ModelingToolkit.jl ``@mtkmodel``)
whose class attributes declare

* parameters with defaults, units and descriptions: ``c = Parameter(1e5, unit="N/m")``;
* variables: ``s = State(unit="m")`` (differentiated, ``der(s)`` allowed),
  ``f = Variable(unit="N")`` (algebraic), ``u = Input(unit="N")`` (input of the model);
* structural parameters (plain Python values that choose equations):
  ``exact = Structural(True, description="...")``;
* connectors: ``flange_a = Flange_a()`` (:mod:`gtmodel.modeling.components.connectors`);
* sub-components: ``belt = SpringDamper(c=2e5)``, named hierarchically (``"axis1.belt.c"``),

and whose :meth:`Component.equations` method writes the equations with the component's
own symbols (``self.c``, ``self.flange_a.s``, ``self.der(self.v)``) and the connections
(:func:`connect`)::

    class Spring(PartialCompliant):
        c = Parameter(1e5, unit="N/m", description="spring constant", lb=0.0)

        def equations(self):
            super().equations()                     # the base class's equations (extends)
            self.equation(self.f, self.c * self.s_rel)

A sub-component's parameter can be bound to a parameter of the enclosing class
(Modelica ``IdealGear gear(ratio=n)``)::

    class Axis(Component):
        n = Parameter(10.0, unit="1", description="gear ratio")
        gear = IdealGear(ratio=n)          # one model parameter "n", no "gear.ratio"

Instantiation with keyword arguments is a modifier (``Spring(c=2e5)``; a state's start
value ``Mass(s=0.1)`` or ``Mass(s={"start": 0.1, "lb": 0})``, an initial condition
(Modelica's ``fixed = true``) unless ``{"start": 0.1, "fixed": False}`` makes it a guess;
a sub-component's
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
potential of a connector that nothing uses does not make the model under-determined.
Every connector variable that is kept is an algebraic variable of the model; the
connection equalities are alias equations that the structural passes
(:mod:`gtmodel.modeling.structure.index_reduction`) eliminate. Declared states need not be
independent: a damper's relative position (a state, as in the MSL) or two rigidly
joined masses make a higher-index model, which ``Model.simulate`` reduces. Components reach the rest of the
:class:`Model` API (initial equations, events) through :meth:`Component.model_call`.
"""

from __future__ import annotations

import inspect
import logging
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel.errors import GtModelError, InputError, ModelError
from gtmodel.modeling.components.connectors import Connector
from gtmodel.modeling.components.declarations import Input, Parameter, State, Structural, Variable, _ComponentBase, _declarations
from gtmodel.modeling.components.flattening import _ACTIVE, _Flattening
from gtmodel.modeling.simulation.model import Model

#: pandas, imported on first use (~0.5 s of CPU, only for DataFrames).
pd = lazy_module("pandas")

__all__ = ["Parameter", "Variable", "State", "Input", "Structural", "Component", "connect"]

_log = logging.getLogger("gtmodel")


class Component(_ComponentBase):
    """Base class of acausal components; keyword arguments are modifiers.

    Parameters
    ----------
    **modifiers
        ``name=value`` per declared parameter (value, or a :class:`Parameter` declared by
        the enclosing class: a binding), variable (start value or mapping with ``start``,
        ``lb``, ``ub``) or sub-component (mapping of its modifiers, or a component
        instance replacing it, which must have the same connectors).

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
        params += [
            inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=d.default)
            for name, d in _declarations(cls).items()
            if isinstance(d, Structural)
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
                value = modifiers.get(name, decl.default)
                if isinstance(value, Parameter):  # binding to a parameter of the enclosing class
                    if value.size != decl.size:
                        raise InputError(f"{where}: bound to a parameter of {value.size} value(s), expected {decl.size}")
                    self._values[name] = value
                else:
                    self._values[name] = decl.validate(value, where)
            elif isinstance(decl, Structural):
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
        decls = _declarations(type(self))
        out = {k: self._value(k) for k in self._values if isinstance(decls.get(k), Parameter)}
        for name, sub in self.components().items():
            out.update({f"{name}.{k}": v for k, v in sub.parameter_values().items()})
        return out

    def describe(self) -> pd.DataFrame:
        """A table of the declarations of this component and its sub-components.

        Returns
        -------
        pandas.DataFrame
            One row per parameter, structural parameter, variable and connector variable,
            columns ``name`` (hierarchical, relative to this component), ``kind``
            (``parameter``, ``structural``, ``state``, ``algebraic``, ``input``,
            ``potential``, ``flow``), ``value`` (parameter value or variable start,
            ``None`` for connector variables), ``fixed`` (whether a variable's start is an
            initial condition, Modelica's ``fixed``; ``None`` where no start applies),
            ``unit`` and ``description``.
        """
        return pd.DataFrame(self._declaration_rows(), columns=["name", "kind", "value", "fixed", "unit", "description"])

    def _declaration_rows(self) -> list[dict[str, Any]]:
        """The rows of :meth:`describe` as dicts (without pandas: its import is a gtmodel solve process's ~0.6 CPU-s)."""
        rows: list[dict[str, Any]] = []

        def walk(comp: Component, pre: str) -> None:
            for name, decl in _declarations(type(comp)).items():
                if isinstance(decl, Parameter):
                    value = comp._value(name)
                    rows.append(dict(name=pre + name, kind="parameter", value=value[0] if value.size == 1 else value,
                                     unit=decl.unit, description=decl.description))
                elif isinstance(decl, Structural):
                    rows.append(dict(name=pre + name, kind="structural", value=comp._values[name], unit="",
                                     description=decl.description))
                elif isinstance(decl, Variable):
                    start = comp._attributes[name]["start"]
                    value = None if start is None else (start[0] if start.size == 1 else start)
                    flags = comp._attributes[name].get("fixed")
                    fixed = None if flags is None else (bool(flags[0]) if flags.size == 1 else flags.tolist())
                    rows.append(dict(name=pre + name, kind=decl.kind, value=value, fixed=fixed, unit=decl.unit,
                                     description=decl.description))
            for cname, conn in comp.connectors().items():
                for var in conn.variables():
                    rows.append(dict(name=f"{pre}{cname}.{var.name}", kind="flow" if var.is_flow else "potential",
                                     value=None, unit=var.unit, description=var.description))
            for sname, sub in comp.components().items():
                walk(sub, f"{pre}{sname}.")

        walk(self, "")
        return rows

    def _value(self, name: str) -> np.ndarray:
        value = self._values[name]
        if isinstance(value, Parameter):
            parent = self.parent
            if parent is None or value.name not in parent._values:
                return value.default.copy()
            return parent._value(value.name)
        return value.copy()

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

    def output(self, name: str, expr: Any, unit: str = "") -> None:
        """Declare an output (derived variable) of this component, named ``path.name``.

        Parameters
        ----------
        name : str
            Identifier.
        expr : casadi.SX or float
            Expression of the component's symbols (``der()`` allowed).
        unit : str, optional
            SI unit (e.g. ``"N"``), carried to the flat model's :attr:`~gtmodel.modeling.Model.units`.

        Raises
        ------
        ModelError
            If ``expr`` uses unknown symbols or the name is taken.
        """
        self._context().output(self, name, expr, unit)

    def model_call(self, method: str, *args: Any, **kwargs: Any) -> Any:
        """Call a method of the flattened :class:`~gtmodel.modeling.Model` from a component.

        The extension hook for what :class:`Model` offers beyond variables and equations
        (e.g. an ``initial_equation`` or an event declaration added by another pass): the
        call runs at once on the model being built (its return value, e.g. a new symbol,
        is returned) and is replayed on the flattened model, after the variables are
        declared and before the equations are added, with every CasADi SX argument
        (also inside lists, tuples and dicts) rewritten to the flattened model's symbols.
        Symbols returned by the call are mapped too. Names given to the model should be
        prefixed with :attr:`path`.

        Parameters
        ----------
        method : str
            Name of a public :class:`Model` method.
        *args, **kwargs
            Its arguments.

        Returns
        -------
        object
            What the method returns on the model being built.

        Raises
        ------
        ModelError
            If ``method`` is not a public method of the model, or the method raises.
        """
        return self._context().model_call(self, method, args, kwargs)

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
            variable), inputs, equations (components' and connections') and outputs; the
            declared units and descriptions by flat name in ``model.exchange_metadata``
            (``{name: (unit, description)}``, what an exported FMU states, as for the
            component itself).

        Raises
        ------
        ModelError
            Naming the component: an error in its equations or connections.
        InputError
            Malformed equations (size mismatch).
        """
        model = _Flattening(self, name or type(self).__name__).run()
        model.exchange_metadata = {str(row["name"]): (str(row.get("unit") or ""), str(row.get("description") or ""))
                                   for row in self._declaration_rows() if row.get("unit") or row.get("description")}
        return model

    def __repr__(self) -> str:
        mods = ", ".join(f"{k}={v!r}" for k, v in self._modifiers.items())
        return f"{type(self).__name__}({mods})"


def _instantiate(template: Component, modifier: Any, where: str) -> Component:
    """A fresh instance of a sub-component template, with a modifier applied."""
    if modifier is None:
        return type(template)(**template._modifiers)
    if isinstance(modifier, dict):
        return type(template)(**_merge(template._modifiers, modifier))
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


def _merge(inner: dict, outer: dict) -> dict:
    """Nested modifiers: the outer ones win per name, dicts of sub-components merge (Modelica)."""
    out = dict(inner)
    for key, value in outer.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict) and key in out:
            out[key] = _merge(out[key], value)
        elif isinstance(value, dict) and key in out and not isinstance(out[key], (dict, Component)):
            out[key] = {"start": out[key], **value}  # a variable's start, modified: Mass(s=0.1) + {"fixed": False}
        else:
            out[key] = value
    return out


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
