"""Equation-based models in the spirit of Modelica, on CasADi SX symbols.

A :class:`Model` collects declared variables (parameters, states, algebraic variables,
inputs), equations that may contain ``der()`` symbols, and named outputs. ``flatten()``
turns it into a semi-explicit DAE (:class:`FlatDAE`)::

    xdot = f(t, x, z, u, p)
       0 = g(t, x, z, u, p)

and ``simulate()`` integrates it with CasADi's IDAS or CVODES.

Design note: ``casadi.DaeBuilder`` is not used because its 3.8 API is FMI/MX-oriented (variables addressed by
name strings with causality/variability attributes, no symbolic elimination of equations that are implicit but
linear in ``der()``), whereas a thin layer over SX symbols keeps every expression SX for AD and C generation.

Naming of scalar elements: a scalar variable ``m`` is called ``"m"``; element ``i`` of a vector variable ``T``
of size 3 is called ``"T[i]"``. These expanded names are used for ``FlatDAE.x_names`` (etc.) and for the columns
of data frames and CSV files.
"""

from __future__ import annotations

import keyword
import logging
import re
from collections.abc import Mapping, Sequence
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import (
    FlatDAE,
    SimulationResult,
    _as_sx,
    _shape_to_size,
    _symbol_names,
    _vector_value,
    casadi_name,
    fixed_flags,
)
from gtmodel.modeling.structure.discontinuities import sign_modes
from gtmodel.modeling.simulation.flatten import _KINDS, _Var, flatten_model
from gtmodel.modeling.simulation.event_simulation import simulate_events, simulate_events_reduced
from gtmodel.modeling.structure.events import EventsMixin, EventSpec
from gtmodel.modeling.simulation.integration import SIMULATE_DOCS, integrator_options, simulate_model
from gtmodel.modeling.simulation.structured_simulation import consistent_start, simulate_structured

__all__ = ["Model"]

_log = logging.getLogger("gtmodel")

#: Identifiers, or dotted paths of identifiers for the hierarchical names of composed
#: models (``"axis1.belt.c"``, :mod:`gtmodel.modeling.components.component`).
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$")


#: Docstring entries shared by :meth:`Model.state`, :meth:`Model.algebraic` and :meth:`Model.input`.
_DECLARE_DOCS = {
    "name_shape": """
        name : str
            Identifier, unique in the model.
        shape : int or tuple, optional
            Size ``n`` or ``(n,)``/``(n, 1)``; default 1.
        """,
    "unit": """
        unit : str, optional
            SI unit (e.g. ``"m"``, ``"N"``), shown on plots (:attr:`units`); default none.
        """,
    "fixed": """
        fixed : bool or array_like of bool, optional
            Whether ``start`` is an initial condition that :meth:`Model.simulate` must meet (Modelica's ``fixed
            = true``: kept through alias elimination and index reduction, an error if it contradicts the model
            or the other initial conditions); default False: ``start`` is a guess, used as the initial value
            only where the initialisation has degrees of freedom left (see
            :mod:`gtmodel.modeling.structure.initialization`).
        """,
    "raises": """
        Raises
        ------
        InputError
            If the name, shape, start or bounds are malformed.
        ModelError
            If the name is already declared or ``lb > ub``.
        """,
}


class Model(EventsMixin):
    """An equation-based model (Modelica-inspired) built from CasADi SX symbols.

    Parameters
    ----------
    name : str
        Model name, used in messages and CasADi function names.

    Raises
    ------
    InputError
        If ``name`` is not a non-empty string.

    Examples
    --------
    >>> m = Model("oscillator")
    >>> k = m.parameter("k", 4.0)
    >>> x = m.state("x", start=1.0)
    >>> v = m.state("v")
    >>> m.equation(m.der(x), v)
    >>> m.equation(m.der(v), -k * x)
    """

    def __init__(self, name: str) -> None:
        if not isinstance(name, str) or not name:
            raise InputError(f"model name must be a non-empty string, got {name!r}")
        casadi_name(name)  # a name with no C/CasADi form is refused here (InputError), not by CasADi later
        self.name = name
        self._vars: dict[str, _Var] = {}
        self._time = ca.SX.sym("time")
        self._equations: list[tuple[str, ca.SX]] = []
        self._outputs: dict[str, ca.SX] = {}
        self._output_units: dict[str, str] = {}  # the outputs declared with a unit
        self._events: EventSpec | None = None  # modes and when-clauses (gtmodel.modeling.structure.events)
        self._der_substituted: set[int] = set()  # equations whose der() stands for the ODE rhs
        self._initial_equations: list[tuple[str, ca.SX]] = []
        self._hashes: set[int] = {self._time.element_hash()}  # of every declared symbol element
        #: What flattening found doubtful (connectors left open), kept through reduction and
        #: repeated in the summary of a problem solved on the model.
        self.warnings: list[str] = []

    # ------------------------------------------------------------------ declarations
    @property
    def units(self) -> dict[str, str]:
        """SI unit of every state, algebraic variable, input and output declared with one, by name."""
        out = {name: var.unit for name, var in self._vars.items() if var.unit}
        out.update({name: u for name, u in getattr(self, "_output_units", {}).items() if u and name in self._outputs})
        return out

    @property
    def time(self) -> ca.SX:
        """The time symbol (SX scalar), s."""
        return self._time

    def _declare(
        self,
        name: str,
        kind: str,
        size: int,
        start: Any = None,
        lb: Any = None,
        ub: Any = None,
        unit: str = "",
        fixed: Any = False,
    ) -> ca.SX:
        if not isinstance(name, str) or not _NAME_RE.fullmatch(name) or any(keyword.iskeyword(n) for n in name.split(".")):
            raise InputError(f"{kind} name must be an identifier, got {name!r}")
        if name in self._vars or name in self._outputs or name in ("time", "t", "final_time"):
            raise ModelError(f"model {self.name!r}: name {name!r} is already declared or reserved")
        what = f"{kind} {name!r}"
        sym = ca.SX.sym(name, size)
        lbv = _vector_value(lb, size, f"{what} lb", -np.inf)
        ubv = _vector_value(ub, size, f"{what} ub", np.inf)
        bad = np.nonzero(lbv > ubv)[0]
        if bad.size:
            raise ModelError(f"{what}: lower bound exceeds upper bound at elements {bad.tolist()}")
        if not isinstance(unit, str):
            raise InputError(f"{what} unit: expected a string such as 'm', got {unit!r}")
        flags = fixed_flags(fixed, size, f"{what} fixed")
        if kind in ("parameter", "input") and flags.any():
            raise ModelError(f"{what}: only states and algebraic variables have initial conditions (fixed)")
        var = _Var(name, kind, sym, _vector_value(start, size, f"{what} start"), lbv, ubv, unit=unit, fixed=flags,
                   given=start is not None)
        if kind == "state":
            var.der = ca.SX.sym(f"der({name})", size)
        self._vars[name] = var
        for s in (sym, var.der) if var.der is not None else (sym,):
            self._hashes.update(s[i].element_hash() for i in range(size))
        return sym

    def parameter(self, name: str, value: Any, shape: Any = None, min: Any = None, max: Any = None,  # noqa: A002
                  smoothing: bool = False) -> ca.SX:
        """Declare a parameter with a numeric default value.

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        value : float or array_like
            Default value (SI units); overridable at simulation/optimisation time.
        shape : int or tuple, optional
            Size ``n`` or ``(n,)``/``(n, 1)``; inferred from ``value`` when omitted.
        min, max : float or array_like, optional
            The physically meaningful range (Modelica's ``min``/``max`` attributes), e.g.
            ``min=1e-6`` for a mass: a value outside it, the default or an override (a
            problem file's ``[model.parameters]``, :meth:`Optimization.set_parameter`), is
            refused naming the parameter. Default: unbounded.
        smoothing : bool, optional
            True: the parameter is a smoothing width, one number > 0 (every value checked),
            whose limit 0 is the exact non-smooth law (listed in :attr:`smoothing`, kept by
            the structural passes). Default False.

        Returns
        -------
        casadi.SX
            Parameter symbol, ``(n, 1)``.

        Raises
        ------
        InputError
            If the name is not an identifier, the value/shape are inconsistent, the
            value lies outside ``[min, max]``, or a smoothing width is not one number > 0.
        ModelError
            If the name is already declared, or ``min`` exceeds ``max``.
        """
        try:
            arr = np.asarray(value, dtype=float).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise InputError(f"parameter {name!r}: value must be numeric, got {value!r}") from exc
        if arr.size == 0 or not np.all(np.isfinite(arr)):
            raise InputError(f"parameter {name!r}: value must be finite and non-empty, got {value!r}")
        size = arr.size if shape is None else _shape_to_size(shape, f"parameter {name!r}")
        if not isinstance(smoothing, (bool, np.bool_)) or (smoothing and size != 1):
            raise InputError(f"parameter {name!r}: smoothing must be True or False, and a smoothing width one number")
        sym = self._declare(name, "parameter", size, start=arr, lb=min, ub=max)
        self._vars[name].smoothing = bool(smoothing)
        self.check_parameter(name, arr)
        return sym

    @property
    def smoothing(self) -> dict[str, float]:
        """The smoothing-width parameters (``parameter(..., smoothing=True)``): name -> default, in declaration order."""
        return {v.name: float(v.start[0]) for v in self._vars.values() if v.kind == "parameter" and v.smoothing}

    def check_parameter(self, name: str, value: Any) -> None:
        """Check a value of a parameter against its ``min``/``max`` range (:meth:`parameter`).

        Parameters
        ----------
        name : str
            A declared parameter.
        value : float or array_like
            The value, of the parameter's size.

        Raises
        ------
        InputError
            A value outside the range (or a smoothing width not > 0), naming the parameter and the value.
        ModelError
            ``name`` is not a parameter of the model.
        """
        var = self._vars.get(name)
        if var is None or var.kind != "parameter":
            raise ModelError(f"model {self.name!r} has no parameter {name!r}")
        v = np.asarray(value, dtype=float).reshape(-1)
        if var.smoothing and not np.all(v > 0):
            raise InputError(f"parameter {name!r}: a smoothing width must be > 0, got {', '.join(f'{x:g}' for x in v)}")
        bad = np.nonzero((v < var.lb) | (v > var.ub))[0] if v.size == var.lb.size else np.zeros(0, int)
        if bad.size:
            i = int(bad[0])
            raise InputError(f"parameter {name!r}: {v[i]:g} is outside its range [{var.lb[i]:g}, {var.ub[i]:g}]"
                             + (f" (element {i})" if v.size > 1 else ""))

    @fill_doc(**_DECLARE_DOCS)
    def state(
        self, name: str, shape: Any = 1, start: Any = None, lb: Any = None, ub: Any = None, unit: str = "",
        fixed: Any = False,
    ) -> ca.SX:
        """Declare a differential state.

        Parameters
        ----------
        {name_shape}
        start : float or array_like, optional
            Start value (the initial value where the initialisation leaves it free, and
            the guess of the initialisation and of optimisation); default 0.
        lb, ub : float or array_like, optional
            Bounds (Modelica ``min``/``max``) used by optimisation; default unbounded.
        {unit}
        {fixed}

        Returns
        -------
        casadi.SX
            State symbol, ``(n, 1)``.

        {raises}
        """
        return self._declare(name, "state", _shape_to_size(shape, f"state {name!r}"), start, lb, ub, unit, fixed)

    @fill_doc(**_DECLARE_DOCS)
    def algebraic(
        self, name: str, shape: Any = 1, start: Any = None, lb: Any = None, ub: Any = None, unit: str = "",
        fixed: Any = False,
    ) -> ca.SX:
        """Declare an algebraic variable.

        Parameters
        ----------
        {name_shape}
        start : float or array_like, optional
            Start value (guess for the consistent initialisation); default 0.
        lb, ub : float or array_like, optional
            Bounds used by optimisation; default unbounded.
        {unit}
        {fixed}

        Returns
        -------
        casadi.SX
            Algebraic symbol, ``(n, 1)``.

        {raises}
        """
        return self._declare(
            name, "algebraic", _shape_to_size(shape, f"algebraic {name!r}"), start, lb, ub, unit, fixed
        )

    @fill_doc(**_DECLARE_DOCS)
    def input(
        self, name: str, shape: Any = 1, lb: Any = None, ub: Any = None, start: Any = None, unit: str = ""
    ) -> ca.SX:
        """Declare an input (control) variable.

        Parameters
        ----------
        {name_shape}
        lb, ub : float or array_like, optional
            Bounds used by optimisation; default unbounded.
        start : float or array_like, optional
            Nominal value, used as initial guess by optimisation; default 0.
        {unit}

        Returns
        -------
        casadi.SX
            Input symbol, ``(n, 1)``.

        {raises}
        """
        return self._declare(name, "input", _shape_to_size(shape, f"input {name!r}"), start, lb, ub, unit)

    def der(self, x: ca.SX) -> ca.SX:
        """Symbol of the time derivative of a declared state (or of elements of one).

        Parameters
        ----------
        x : casadi.SX
            A state symbol returned by :meth:`state`, or a selection of its scalar
            elements (e.g. ``T[0]``, ``T[1:]``).

        Returns
        -------
        casadi.SX
            ``der(x)``, same size as ``x``.

        Raises
        ------
        ModelError
            If an element of ``x`` is not a state element.
        """
        xs = _as_sx(x, "der()")
        out = []
        for i in range(xs.numel()):
            el = xs[i]
            found = None
            if el.is_symbolic():
                for var in self._vars.values():
                    if var.kind != "state":
                        continue
                    for j in range(var.size):
                        if ca.is_equal(el, var.sym[j]):
                            found = var.der[j]
                            break
                    if found is not None:
                        break
            if found is None:
                raise ModelError(
                    f"model {self.name!r}: der() needs a declared state, got {el} "
                    f"(states: {[v.name for v in self._vars.values() if v.kind == 'state']})"
                )
            out.append(found)
        return ca.vertcat(*out)

    def _known_symbols(self) -> list[ca.SX]:
        syms = [self._time]
        for var in self._vars.values():
            syms.append(var.sym)
            if var.der is not None:
                syms.append(var.der)
        return syms

    def check_symbols(self, expr: ca.SX, what: str, extra: Sequence[ca.SX] = ()) -> None:
        """Raise if ``expr`` contains symbols not declared by this model.

        Parameters
        ----------
        expr : casadi.SX
            Expression to check.
        what : str
            Description used in the error message.
        extra : sequence of casadi.SX, optional
            Additional allowed symbols (e.g. ``final_time`` of an optimisation).

        Raises
        ------
        ModelError
            Naming the unknown symbols.
        """
        # element hashes identify SX symbols (O(1) per symbol; many-component models check
        # thousands of equations)
        known = self._hashes | {s[i].element_hash() for s in extra for i in range(s.numel())}
        unknown = [s for s in ca.symvar(expr) if s.element_hash() not in known]
        if unknown:
            raise ModelError(f"{what}: unknown symbol(s) {_symbol_names(unknown)} not declared by model {self.name!r}")

    def _der_vector(self) -> ca.SX:
        ders = [v.der for v in self._vars.values() if v.kind == "state"]
        return ca.vertcat(*ders) if ders else ca.SX(0, 1)

    def equation(self, lhs: Any, rhs: Any = 0.0, name: str | None = None, substitute_der: bool = False) -> None:
        """Add the equation ``lhs == rhs`` (residual ``lhs - rhs``).

        Parameters
        ----------
        lhs, rhs : casadi.SX or float or array_like
            Expressions of declared symbols and ``der()`` symbols; same size (or one
            of them scalar). The residual must be linear in the ``der()`` symbols.
        name : str, optional
            Label used in error messages; default ``"eq<k>"``.
        substitute_der : bool, optional
            If true, ``der()`` in this equation stands for the ODE right-hand side ``f(t, x, z, u, p)`` obtained
            from the other equations (substituted on flattening), so the equation is algebraic: e.g. the locked
            mode of a friction element, relative acceleration zero, which determines the friction force (Otter,
            Elmqvist and Mattsson (1999)). Default false.

        Raises
        ------
        InputError
            If sizes do not match or MX expressions are passed.
        ModelError
            If the equation contains unknown symbols or is nonlinear in ``der()``.
        """
        label = name or f"eq{len(self._equations)}"
        a = _as_sx(lhs, f"equation {label!r} lhs")
        b = _as_sx(rhs, f"equation {label!r} rhs")
        if a.numel() != b.numel() and a.numel() != 1 and b.numel() != 1:
            raise InputError(f"equation {label!r}: lhs has {a.numel()} elements but rhs has {b.numel()}")
        res = a - b
        if res.numel() == 0:
            raise InputError(f"equation {label!r} is empty")
        self.check_symbols(res, f"equation {label!r}")
        xdot = self._der_vector()
        if xdot.numel() and ca.depends_on(res, xdot) and not ca.is_linear(res, xdot):
            raise ModelError(f"model {self.name!r}: equation {label!r} is nonlinear in der() symbols; "
                             "only equations linear in der() are supported")
        if substitute_der:
            self._der_substituted.add(len(self._equations))
        self._equations.append((label, res))

    def initial_equation(self, lhs: Any, rhs: Any = 0.0, name: str | None = None) -> None:
        """Add the initial equation ``lhs == rhs`` (Modelica's ``initial equation``).

        Holds at the start time only; :meth:`simulate` then solves the consistent initialisation
        (:mod:`gtmodel.modeling.structure.initialization`) instead of fixing every state at its start value: the
        initial equations and the states named in an ``x0`` mapping must together fix the model's degrees of
        freedom. :meth:`flatten` (and so ``Optimization``, which states its own point constraints) ignores them.

        Parameters
        ----------
        lhs, rhs : casadi.SX or float or array_like
            Expressions of declared symbols, ``der()`` symbols and time; same size (or one
            of them scalar).
        name : str, optional
            Label used in error messages; default ``"init<k>"``.

        Raises
        ------
        InputError
            If sizes do not match or MX expressions are passed.
        ModelError
            If the equation contains unknown symbols.
        """
        label = name or f"init{len(self._initial_equations)}"
        a = _as_sx(lhs, f"initial equation {label!r} lhs")
        b = _as_sx(rhs, f"initial equation {label!r} rhs")
        if a.numel() != b.numel() and a.numel() != 1 and b.numel() != 1:
            raise InputError(f"initial equation {label!r}: lhs has {a.numel()} elements but rhs has {b.numel()}")
        res = a - b
        if res.numel() == 0:
            raise InputError(f"initial equation {label!r} is empty")
        self.check_symbols(res, f"initial equation {label!r}")
        self._initial_equations.append((label, res))

    def output(self, name: str, expr: Any, unit: str = "") -> ca.SX:
        """Declare a named derived variable (energy, force, ...).

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        expr : casadi.SX or float
            Expression of declared symbols (``der()`` allowed; replaced by the ODE
            right-hand side on flattening).
        unit : str, optional
            SI unit (e.g. ``"J"``), shown with the output (:attr:`units`); default none.

        Returns
        -------
        casadi.SX
            ``expr`` as a column SX, for use in further expressions.

        Raises
        ------
        InputError
            If the name is not an identifier.
        ModelError
            If the name is taken or ``expr`` contains unknown symbols.
        """
        if not isinstance(name, str) or not _NAME_RE.fullmatch(name):
            raise InputError(f"output name must be an identifier, got {name!r}")
        if not isinstance(unit, str):
            raise InputError(f"output {name!r} unit: expected a string such as 'J', got {unit!r}")
        if name in self._vars or name in self._outputs:
            raise ModelError(f"model {self.name!r}: name {name!r} is already declared")
        e = _as_sx(expr, f"output {name!r}")
        self.check_symbols(e, f"output {name!r}")
        self._outputs[name] = e
        if unit:
            self._output_units[name] = unit
        return e

    # ------------------------------------------------------------------ queries
    def variables(self, kind: str) -> dict[str, ca.SX]:
        """Declared symbols of one kind.

        Parameters
        ----------
        kind : {"parameter", "state", "algebraic", "input"}
            Variable category.

        Returns
        -------
        dict of str to casadi.SX
            Name -> symbol, in declaration order.

        Raises
        ------
        InputError
            If ``kind`` is unknown.
        """
        if kind not in _KINDS:
            raise InputError(f"kind must be one of {_KINDS}, got {kind!r}")
        return {v.name: v.sym for v in self._vars.values() if v.kind == kind}

    @property
    def outputs(self) -> dict[str, ca.SX]:
        """Declared outputs: name -> expression, in declaration order."""
        return dict(self._outputs)

    def locate(self, sym: Any) -> tuple[str, str, list[int]]:
        """Find which declared variable the scalar elements of ``sym`` belong to.

        Parameters
        ----------
        sym : casadi.SX
            A declared symbol or a selection of elements of one.

        Returns
        -------
        tuple
            ``(kind, name, indices)`` with the element indices within the variable.

        Raises
        ------
        ModelError
            If ``sym`` is not (part of) a single declared variable.
        """
        xs = _as_sx(sym, "variable")
        if xs.numel() == 0:
            raise ModelError("empty variable selection")
        for var in self._vars.values():
            idx = []
            for i in range(xs.numel()):
                el = xs[i]
                hit = [j for j in range(var.size) if el.is_symbolic() and ca.is_equal(el, var.sym[j])]
                if not hit:
                    break
                idx.append(hit[0])
            if len(idx) == xs.numel():
                return var.kind, var.name, idx
        raise ModelError(f"{xs} is not a declared variable of model {self.name!r}")

    # ------------------------------------------------------------------ flattening
    def flatten(self) -> FlatDAE:
        """Flatten the model into a semi-explicit DAE.

        Equations containing ``der()`` are solved for ``der()`` symbolically
        (``M(.) xdot = -b(.)`` with ``M = d res / d xdot``, ``casadi.solve``).

        Returns
        -------
        FlatDAE
            The semi-explicit DAE and its CasADi Functions.

        Raises
        ------
        ModelError
            If the number of scalar equations differs from states + algebraics, the
            equations are not solvable for ``der()`` (naming the states), or the
            algebraic equations are not index-1 in the algebraic variables.
        """
        return flatten_model(self)

    # ------------------------------------------------------------------ simulation
    @fill_doc(**SIMULATE_DOCS)
    def simulate(
        self,
        t_grid: Any,
        x0: Any = None,
        u: Any = None,
        p: Mapping[str, Any] | None = None,
        integrator: str = "idas",
        rtol: float = 1e-8,
        atol: float = 1e-10,
        z0: Any = None,
        options: Mapping[str, Any] | None = None,
    ) -> SimulationResult:
        """Integrate the model on a time grid.

        A model with when-clauses (:meth:`when`) or ``sign()`` in its equations is integrated with events
        (:func:`gtmodel.modeling.simulation.event_simulation.simulate_events`,
        :func:`gtmodel.modeling.structure.discontinuities.sign_modes`), its events reported in
        :attr:`SimulationResult.events`; if it does not flatten (aliases, high index), it is reduced once first,
        keeping the reinit targets as states
        (:func:`~gtmodel.modeling.simulation.event_simulation.simulate_events_reduced`: ``x0`` a mapping, no
        ``z0``); with initial equations, fixed starts or ``x0`` entries that the reduction could drop, the
        consistent start is solved first
        (:func:`~gtmodel.modeling.simulation.structured_simulation.consistent_start`, the modes at their start
        values; clauses declared ``initial=True`` fire after it). Otherwise, a model that :meth:`flatten`
        accepts and that has no initial equations (nor fixed starts of algebraic variables) is simulated as it
        is. Otherwise the structural passes run first
        (:func:`~gtmodel.modeling.simulation.structured_simulation.simulate_structured`): the structural check
        (one error naming the equations and variables), alias elimination, index reduction by Pantelides'
        algorithm with dummy derivatives (re-selected where the selection turns singular), and the consistent
        initialisation with the :meth:`initial_equation` s. Start values follow Modelica
        (:mod:`gtmodel.modeling.structure.initialization`): every ``x0`` entry and every start declared
        ``fixed=True`` (a component modifier's start value is) is an initial condition, kept whichever states
        the index reduction selects; contradictory ones are one error naming them; the remaining freedom (a
        model without initial equations) is taken from the start values, given ones first.

        Parameters
        ----------
        {simulate_args}

        {simulate_returns}
        """
        integrator_options(options, rtol, atol, integrator)  # bad options refused by name before any work
        model = sign_modes(self, sliding=integrator != "cvodes") or self  # sign() switched by events
        if model._events is not None and model._events.whens:
            flat = model._flattens()
            if model._needs_initialisation(flat, x0):  # consistent start (structured_simulation), then events
                start = consistent_start(model, t_grid, x0, u, p, z0)
                x0 = {k: v for k, v in start.items() if model._vars[k].kind == "state"}
                z0 = np.concatenate([v for k, v in start.items() if model._vars[k].kind == "algebraic"] or [np.zeros(0)])
                if not flat:
                    return simulate_events_reduced(model, t_grid, x0, u, p, integrator, rtol, atol, consistent=True,
                                                   options=options)
            if not flat:  # aliases or high index: reduced once (event_simulation)
                if z0 is not None:
                    raise InputError(f"model {self.name!r} is index-reduced for the event simulation: z0 is not supported")
                return simulate_events_reduced(model, t_grid, x0, u, p, integrator, rtol, atol, options=options)
            return simulate_events(model, t_grid, x0, u, p, integrator, rtol, atol, z0, options=options)
        if self._needs_initialisation(True, x0) or not self._flattens():
            return simulate_structured(self, t_grid, x0, u, p, integrator, rtol, atol, z0, options)
        return simulate_model(self, t_grid, x0, u, p, integrator, rtol, atol, z0, options)

    def _needs_initialisation(self, flat: bool, x0: Any) -> bool:
        """Whether the start must be solved (initial equations, fixed starts the flat DAE cannot keep).

        A flat (index-1, alias-free) model keeps its states' starts and ``x0`` as they are;
        initial equations, a fixed start of an algebraic variable, and on a model that is
        reduced first also fixed starts and ``x0`` entries of states, need the initialisation
        of :mod:`gtmodel.modeling.structure.initialization`.
        """
        if self._initial_equations:
            return True
        for v in self._vars.values():
            if v.fixed is not None and v.fixed.any() and (v.kind == "algebraic" or (v.kind == "state" and not flat)):
                return True
        return not flat and isinstance(x0, Mapping)

    def _flattens(self) -> bool:
        """Whether :meth:`flatten` accepts the model as it is (else simulate reduces it)."""
        try:
            self.flatten()
        except ModelError:
            return False
        return True
