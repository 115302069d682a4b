"""Equation-based models in the spirit of Modelica, on CasADi SX symbols.

A :class:`Model` collects declared variables (parameters, states, algebraic variables,
inputs), equations that may contain ``der()`` symbols, and named outputs. ``flatten()``
turns it into a semi-explicit DAE (:class:`FlatDAE`)::

    xdot = f(t, x, z, u, p)
       0 = g(t, x, z, u, p)

and ``simulate()`` integrates it with CasADi's IDAS or CVODES.

Design note: ``casadi.DaeBuilder`` is not used because its 3.8 API is FMI/MX-oriented
(variables addressed by name strings with causality/variability attributes, no
symbolic elimination of equations that are implicit but linear in ``der()``), whereas a
thin layer over SX symbols keeps every expression SX for AD and C generation.

Naming of scalar elements: a scalar variable ``m`` is called ``"m"``; element ``i`` of a
vector variable ``T`` of size 3 is called ``"T[i]"``. These expanded names are used for
``FlatDAE.x_names`` (etc.) and for the columns of data frames and CSV files.
"""

from __future__ import annotations

import keyword
import logging
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import ConvergenceError, InputError, ModelError

__all__ = ["Model", "FlatDAE", "SimulationResult", "expand_names"]

_log = logging.getLogger("gtmodel")

_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_KINDS = ("parameter", "state", "algebraic", "input")


def expand_names(name: str, size: int) -> list[str]:
    """Expand a declared variable name into scalar element names.

    Parameters
    ----------
    name : str
        Declared variable name.
    size : int
        Number of scalar elements of the variable.

    Returns
    -------
    list of str
        ``[name]`` if ``size == 1``, else ``["name[0]", ..., "name[size-1]"]``.
    """
    if size == 1:
        return [name]
    return [f"{name}[{i}]" for i in range(size)]


@dataclass
class _Var:
    """One declared variable (internal record)."""

    name: str
    kind: str
    sym: ca.SX
    start: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    der: ca.SX | None = None

    @property
    def size(self) -> int:
        return int(self.sym.numel())


def _as_sx(expr: Any, what: str) -> ca.SX:
    """Convert numbers, numpy arrays, DM and SX to a column SX; reject MX."""
    if isinstance(expr, ca.MX):
        raise InputError(f"{what}: MX expressions are not supported, use the SX symbols of the model")
    try:
        sx = ca.SX(expr)
    except Exception as exc:  # noqa: BLE001 - casadi raises NotImplementedError/TypeError
        raise InputError(f"{what}: cannot convert {type(expr).__name__} to a CasADi SX expression") from exc
    if not sx.is_column():
        sx = ca.vec(sx)
    return sx


def _shape_to_size(shape: Any, what: str) -> int:
    """Accept 1, n, (n,), (n, 1) and return n."""
    if isinstance(shape, (int, np.integer)) and not isinstance(shape, bool):
        n = int(shape)
    elif isinstance(shape, (tuple, list)) and len(shape) in (1, 2) and all(
        isinstance(s, (int, np.integer)) and not isinstance(s, bool) for s in shape
    ):
        if len(shape) == 2 and int(shape[1]) != 1:
            raise InputError(f"{what}: only column vectors are supported, got shape {tuple(shape)}")
        n = int(shape[0])
    else:
        raise InputError(f"{what}: shape must be a positive int or (n,) / (n, 1), got {shape!r}")
    if n < 1:
        raise InputError(f"{what}: shape must be positive, got {shape!r}")
    return n


def _vector_value(value: Any, size: int, what: str, default: float = 0.0) -> np.ndarray:
    """Broadcast a scalar or array to a float vector of ``size`` elements."""
    if value is None:
        return np.full(size, float(default))
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what}: expected a number or array of {size} numbers, got {value!r}") from exc
    if arr.size == 1:
        arr = np.full(size, float(arr[0]))
    if arr.size != size:
        raise InputError(f"{what}: expected {size} values, got {arr.size}")
    return arr


def _symbol_names(syms: Sequence[ca.SX]) -> list[str]:
    return [str(s) for s in syms]


@dataclass
class FlatDAE:
    """A flattened semi-explicit DAE ``xdot = f(t, x, z, u, p)``, ``0 = g(t, x, z, u, p)``.

    Parameters
    ----------
    name : str
        Model name.
    t : casadi.SX
        Time symbol (1x1), s.
    x, z, u, p : casadi.SX
        Column vectors of state, algebraic, input and parameter symbols; they are the
        vertical concatenation of the declared symbols in declaration order.
    xdot : casadi.SX
        Column vector of ``der()`` symbols, same layout as ``x``.
    ode_expr, alg_expr : casadi.SX
        ``f`` (nx x 1) and ``g`` (nz x 1) as expressions of ``t, x, z, u, p``.
    output_exprs : dict of str to casadi.SX
        Declared outputs, ``der()`` replaced by ``f``.
    ode, alg, outputs : casadi.Function
        ``ode(t, x, z, u, p) -> xdot``, ``alg(t, x, z, u, p) -> g`` and
        ``outputs(t, x, z, u, p) -> (one output per declared output name)``.
    x_vars, z_vars, u_vars, p_vars : dict of str to slice
        Declared names mapped to their slice in ``x``, ``z``, ``u``, ``p``.
    x_names, z_names, u_names, p_names, output_names : list of str
        Expanded scalar names (``"T[0]"`` style, see the module docstring).
    output_sizes : dict of str to int
        Number of elements per output.
    x_start, z_start, p_value : numpy.ndarray
        Start values of states and algebraics, parameter values.
    x_lb, x_ub, z_lb, z_ub, u_lb, u_ub : numpy.ndarray
        Bounds declared on the model (``-inf``/``inf`` when not given).
    """

    name: str
    t: ca.SX
    x: ca.SX
    z: ca.SX
    u: ca.SX
    p: ca.SX
    xdot: ca.SX
    ode_expr: ca.SX
    alg_expr: ca.SX
    output_exprs: dict[str, ca.SX]
    ode: ca.Function
    alg: ca.Function
    outputs: ca.Function
    x_vars: dict[str, slice]
    z_vars: dict[str, slice]
    u_vars: dict[str, slice]
    p_vars: dict[str, slice]
    x_names: list[str]
    z_names: list[str]
    u_names: list[str]
    p_names: list[str]
    output_names: list[str]
    output_sizes: dict[str, int]
    x_start: np.ndarray
    z_start: np.ndarray
    p_value: np.ndarray
    x_lb: np.ndarray
    x_ub: np.ndarray
    z_lb: np.ndarray
    z_ub: np.ndarray
    u_lb: np.ndarray
    u_ub: np.ndarray

    @property
    def nx(self) -> int:
        """Number of scalar states."""
        return int(self.x.numel())

    @property
    def nz(self) -> int:
        """Number of scalar algebraic variables."""
        return int(self.z.numel())

    @property
    def nu(self) -> int:
        """Number of scalar inputs."""
        return int(self.u.numel())

    @property
    def npar(self) -> int:
        """Number of scalar parameters."""
        return int(self.p.numel())

    def parameter_vector(self, p: Mapping[str, Any] | None = None) -> np.ndarray:
        """Parameter vector with defaults overridden by ``p``.

        Parameters
        ----------
        p : mapping of str to float or array_like, optional
            Parameter values by declared name; missing names keep their default.

        Returns
        -------
        numpy.ndarray
            Shape ``(npar,)``.

        Raises
        ------
        InputError
            If a name is not a parameter of the model or a value has the wrong size.
        """
        vec = self.p_value.copy()
        for name, value in (p or {}).items():
            if name not in self.p_vars:
                raise InputError(
                    f"model {self.name!r} has no parameter {name!r}; parameters: {sorted(self.p_vars)}"
                )
            sl = self.p_vars[name]
            vec[sl] = _vector_value(value, sl.stop - sl.start, f"parameter {name!r}")
        return vec


def _unpack(vars_: Mapping[str, slice], data: np.ndarray) -> dict[str, np.ndarray]:
    """Split an ``(N, n)`` array into declared variables: ``(N,)`` scalars, ``(N, k)`` vectors."""
    out: dict[str, np.ndarray] = {}
    for name, sl in vars_.items():
        block = data[:, sl]
        out[name] = block[:, 0].copy() if block.shape[1] == 1 else block.copy()
    return out


def _frame(t: np.ndarray, *groups: Mapping[str, np.ndarray]) -> Any:
    """Build a pandas DataFrame with a ``t`` column and one column per scalar element."""
    import pandas as pd

    cols: dict[str, np.ndarray] = {"t": np.asarray(t, dtype=float)}
    for group in groups:
        for name, arr in group.items():
            arr = np.asarray(arr, dtype=float)
            if arr.ndim == 1:
                cols[name] = arr
            else:
                for nm, col in zip(expand_names(name, arr.shape[1]), arr.T):
                    cols[nm] = col
    return pd.DataFrame(cols)


@dataclass
class SimulationResult:
    """Result of :meth:`Model.simulate`.

    Parameters
    ----------
    t : numpy.ndarray
        Time grid, shape ``(N,)``, s.
    x, z, u, outputs : dict of str to numpy.ndarray
        Declared name -> values on the grid, ``(N,)`` for scalars and ``(N, n)`` for
        vector variables. ``u`` holds the input applied on ``[t[k], t[k+1])`` at row
        ``k`` (the last row repeats the last interval).
    p : dict of str to numpy.ndarray
        Parameter values used.
    """

    t: np.ndarray
    x: dict[str, np.ndarray]
    z: dict[str, np.ndarray]
    u: dict[str, np.ndarray]
    outputs: dict[str, np.ndarray]
    p: dict[str, np.ndarray] = field(default_factory=dict)

    def to_dataframe(self) -> Any:
        """Return all trajectories as a pandas DataFrame.

        Returns
        -------
        pandas.DataFrame
            Column ``"t"`` then one column per scalar element (``"T[0]"`` style names)
            of states, algebraics, inputs and outputs, one row per time sample.
        """
        return _frame(self.t, self.x, self.z, self.u, self.outputs)


class Model:
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
        self.name = name
        self._vars: dict[str, _Var] = {}
        self._time = ca.SX.sym("time")
        self._equations: list[tuple[str, ca.SX]] = []
        self._outputs: dict[str, ca.SX] = {}

    # ------------------------------------------------------------------ declarations
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
    ) -> ca.SX:
        if not isinstance(name, str) or not _NAME_RE.match(name) or keyword.iskeyword(name):
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
        var = _Var(name, kind, sym, _vector_value(start, size, f"{what} start"), lbv, ubv)
        if kind == "state":
            var.der = ca.SX.sym(f"der({name})", size)
        self._vars[name] = var
        return sym

    def parameter(self, name: str, value: Any, shape: Any = None) -> ca.SX:
        """Declare a parameter with a numeric default value.

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        value : float or array_like
            Default value (SI units); overridable at simulation/optimisation time.
        shape : int or tuple, optional
            Size ``n`` or ``(n,)``/``(n, 1)``; inferred from ``value`` when omitted.

        Returns
        -------
        casadi.SX
            Parameter symbol, ``(n, 1)``.

        Raises
        ------
        InputError
            If the name is not an identifier, or the value/shape are inconsistent.
        ModelError
            If the name is already declared.
        """
        try:
            arr = np.asarray(value, dtype=float).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise InputError(f"parameter {name!r}: value must be numeric, got {value!r}") from exc
        if arr.size == 0 or not np.all(np.isfinite(arr)):
            raise InputError(f"parameter {name!r}: value must be finite and non-empty, got {value!r}")
        size = arr.size if shape is None else _shape_to_size(shape, f"parameter {name!r}")
        return self._declare(name, "parameter", size, start=arr)

    def state(
        self, name: str, shape: Any = 1, start: Any = None, lb: Any = None, ub: Any = None
    ) -> ca.SX:
        """Declare a differential state.

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        shape : int or tuple, optional
            Size ``n`` or ``(n,)``/``(n, 1)``; default 1.
        start : float or array_like, optional
            Start value (initial condition for simulation, initial guess); default 0.
        lb, ub : float or array_like, optional
            Bounds (Modelica ``min``/``max``) used by optimisation; default unbounded.

        Returns
        -------
        casadi.SX
            State symbol, ``(n, 1)``.

        Raises
        ------
        InputError
            If the name, shape, start or bounds are malformed.
        ModelError
            If the name is already declared or ``lb > ub``.
        """
        return self._declare(name, "state", _shape_to_size(shape, f"state {name!r}"), start, lb, ub)

    def algebraic(
        self, name: str, shape: Any = 1, start: Any = None, lb: Any = None, ub: Any = None
    ) -> ca.SX:
        """Declare an algebraic variable.

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        shape : int or tuple, optional
            Size ``n`` or ``(n,)``/``(n, 1)``; default 1.
        start : float or array_like, optional
            Start value (guess for the consistent initialisation); default 0.
        lb, ub : float or array_like, optional
            Bounds used by optimisation; default unbounded.

        Returns
        -------
        casadi.SX
            Algebraic symbol, ``(n, 1)``.

        Raises
        ------
        InputError
            If the name, shape, start or bounds are malformed.
        ModelError
            If the name is already declared or ``lb > ub``.
        """
        return self._declare(
            name, "algebraic", _shape_to_size(shape, f"algebraic {name!r}"), start, lb, ub
        )

    def input(
        self, name: str, shape: Any = 1, lb: Any = None, ub: Any = None, start: Any = None
    ) -> ca.SX:
        """Declare an input (control) variable.

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        shape : int or tuple, optional
            Size ``n`` or ``(n,)``/``(n, 1)``; default 1.
        lb, ub : float or array_like, optional
            Bounds used by optimisation; default unbounded.
        start : float or array_like, optional
            Nominal value, used as initial guess by optimisation; default 0.

        Returns
        -------
        casadi.SX
            Input symbol, ``(n, 1)``.

        Raises
        ------
        InputError
            If the name, shape or bounds are malformed.
        ModelError
            If the name is already declared or ``lb > ub``.
        """
        return self._declare(name, "input", _shape_to_size(shape, f"input {name!r}"), start, lb, ub)

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
        known = ca.vertcat(*[ca.vec(s) for s in list(self._known_symbols()) + list(extra)])
        unknown = [s for s in ca.symvar(expr) if not ca.depends_on(s, known)]
        if unknown:
            raise ModelError(
                f"{what}: unknown symbol(s) {_symbol_names(unknown)} not declared by model {self.name!r}"
            )

    def _der_vector(self) -> ca.SX:
        ders = [v.der for v in self._vars.values() if v.kind == "state"]
        return ca.vertcat(*ders) if ders else ca.SX(0, 1)

    def equation(self, lhs: Any, rhs: Any = 0.0, name: str | None = None) -> None:
        """Add the equation ``lhs == rhs`` (residual ``lhs - rhs``).

        Parameters
        ----------
        lhs, rhs : casadi.SX or float or array_like
            Expressions of declared symbols and ``der()`` symbols; same size (or one
            of them scalar). The residual must be linear in the ``der()`` symbols.
        name : str, optional
            Label used in error messages; default ``"eq<k>"``.

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
            raise InputError(
                f"equation {label!r}: lhs has {a.numel()} elements but rhs has {b.numel()}"
            )
        res = a - b
        if res.numel() == 0:
            raise InputError(f"equation {label!r} is empty")
        self.check_symbols(res, f"equation {label!r}")
        xdot = self._der_vector()
        if xdot.numel() and ca.depends_on(res, xdot) and not ca.is_linear(res, xdot):
            raise ModelError(
                f"model {self.name!r}: equation {label!r} is nonlinear in der() symbols; "
                "only equations linear in der() are supported"
            )
        self._equations.append((label, res))

    def output(self, name: str, expr: Any) -> ca.SX:
        """Declare a named derived variable (energy, force, ...).

        Parameters
        ----------
        name : str
            Identifier, unique in the model.
        expr : casadi.SX or float
            Expression of declared symbols (``der()`` allowed; replaced by the ODE
            right-hand side on flattening).

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
        if not isinstance(name, str) or not _NAME_RE.match(name):
            raise InputError(f"output name must be an identifier, got {name!r}")
        if name in self._vars or name in self._outputs:
            raise ModelError(f"model {self.name!r}: name {name!r} is already declared")
        e = _as_sx(expr, f"output {name!r}")
        self.check_symbols(e, f"output {name!r}")
        self._outputs[name] = e
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
        by_kind = {k: [v for v in self._vars.values() if v.kind == k] for k in _KINDS}

        def cat(vs: list[_Var], attr: str = "sym") -> ca.SX:
            return ca.vertcat(*[getattr(v, attr) for v in vs]) if vs else ca.SX(0, 1)

        def slices(vs: list[_Var]) -> dict[str, slice]:
            out, k = {}, 0
            for v in vs:
                out[v.name] = slice(k, k + v.size)
                k += v.size
            return out

        def names(vs: list[_Var]) -> list[str]:
            return [n for v in vs for n in expand_names(v.name, v.size)]

        def arr(vs: list[_Var], attr: str) -> np.ndarray:
            return np.concatenate([getattr(v, attr) for v in vs]) if vs else np.zeros(0)

        states, algs = by_kind["state"], by_kind["algebraic"]
        x, xdot, z = cat(states), cat(states, "der"), cat(algs)
        u, p = cat(by_kind["input"]), cat(by_kind["parameter"])
        nx, nz = int(x.numel()), int(z.numel())
        x_names, z_names = names(states), names(algs)

        res = ca.vertcat(*[r for _, r in self._equations]) if self._equations else ca.SX(0, 1)
        neq = int(res.numel())
        if neq != nx + nz:
            raise ModelError(
                f"model {self.name!r} has {neq} scalar equations but {nx} states + {nz} "
                f"algebraic variables = {nx + nz} unknowns"
            )
        diff_rows = [i for i in range(neq) if nx and ca.depends_on(res[i], xdot)]
        alg_rows = [i for i in range(neq) if i not in set(diff_rows)]
        res_d = res[diff_rows] if diff_rows else ca.SX(0, 1)
        res_a = res[alg_rows] if alg_rows else ca.SX(0, 1)

        # --- differential part: M xdot + b = 0
        if nx:
            M = ca.jacobian(res_d, xdot)
            missing = [x_names[j] for j in range(nx) if M[:, j].nnz() == 0]
            if missing:
                raise ModelError(
                    f"model {self.name!r}: der() of state(s) {missing} appear(s) in no equation"
                )
            if len(diff_rows) != nx or ca.sprank(M) < nx:
                raise ModelError(
                    f"model {self.name!r}: the equations containing der() ({len(diff_rows)} scalar) "
                    f"cannot be solved for der() of the {nx} states {x_names} (structurally singular)"
                )
            b = ca.substitute(res_d, xdot, ca.SX.zeros(nx))
            if not ca.depends_on(M, ca.vertcat(x, z, u, p, self._time)) and M.is_constant():
                Mn = np.array(ca.DM(M))
                if np.linalg.matrix_rank(Mn) < nx:
                    raise ModelError(
                        f"model {self.name!r}: the der() coefficient matrix is singular for states {x_names}"
                    )
                if np.allclose(Mn, np.eye(nx)):
                    f = -b
                else:
                    f = ca.SX(ca.DM(np.linalg.solve(Mn, np.eye(nx)))) @ (-b)
            else:
                f = ca.solve(M, -b)
            f = ca.simplify(f) if f.numel() < 50 else f
        else:
            f = ca.SX(0, 1)

        # --- algebraic part: index-1 check
        if nz:
            Jz = ca.jacobian(res_a, z)
            if int(res_a.numel()) != nz or ca.sprank(Jz) < nz:
                no_z = [z_names[j] for j in range(nz) if Jz[:, j].nnz() == 0]
                raise ModelError(
                    f"model {self.name!r}: the algebraic equations are not solvable for the algebraic "
                    f"variables {no_z or z_names} (not index 1); high-index DAEs are not supported"
                )
        elif res_a.numel():
            # unreachable by the count check, kept for safety
            raise ModelError(f"model {self.name!r}: algebraic equations without algebraic variables")

        g = res_a
        args = [self._time, x, z, u, p]
        argn = ["t", "x", "z", "u", "p"]
        out_exprs = {
            n: (ca.substitute(e, xdot, f) if nx else e) for n, e in self._outputs.items()
        }
        ode = ca.Function(f"{self.name}_ode", args, [f], argn, ["xdot"])
        alg = ca.Function(f"{self.name}_alg", args, [g], argn, ["g"])
        outputs = ca.Function(
            f"{self.name}_outputs", args, list(out_exprs.values()), argn, list(out_exprs.keys())
        )
        return FlatDAE(
            name=self.name,
            t=self._time,
            x=x,
            z=z,
            u=u,
            p=p,
            xdot=xdot,
            ode_expr=f,
            alg_expr=g,
            output_exprs=out_exprs,
            ode=ode,
            alg=alg,
            outputs=outputs,
            x_vars=slices(states),
            z_vars=slices(algs),
            u_vars=slices(by_kind["input"]),
            p_vars=slices(by_kind["parameter"]),
            x_names=x_names,
            z_names=z_names,
            u_names=names(by_kind["input"]),
            p_names=names(by_kind["parameter"]),
            output_names=[n for k, e in out_exprs.items() for n in expand_names(k, int(e.numel()))],
            output_sizes={k: int(e.numel()) for k, e in out_exprs.items()},
            x_start=arr(states, "start"),
            z_start=arr(algs, "start"),
            p_value=arr(by_kind["parameter"], "start"),
            x_lb=arr(states, "lb"),
            x_ub=arr(states, "ub"),
            z_lb=arr(algs, "lb"),
            z_ub=arr(algs, "ub"),
            u_lb=arr(by_kind["input"], "lb"),
            u_ub=arr(by_kind["input"], "ub"),
        )

    # ------------------------------------------------------------------ simulation
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
    ) -> SimulationResult:
        """Integrate the model on a time grid.

        Parameters
        ----------
        t_grid : array_like
            Strictly increasing output times, shape ``(N,)`` with ``N >= 2``, s.
            Integration starts at ``t_grid[0]``.
        x0 : array_like or mapping, optional
            Initial state, shape ``(nx,)``, or a mapping from state names to values;
            default the declared start values.
        u : float, array_like or callable, optional
            Inputs, held piecewise constant on the grid: a constant ``(nu,)``; an array
            ``(N-1, nu)`` or ``(N, nu)`` whose row ``k`` applies on ``[t_k, t_{k+1})``
            (a 1-D array is accepted when ``nu == 1``); or a callable ``u(t) -> (nu,)``
            sampled at the start of each interval (zero-order hold). Default: the
            declared input start values.
        p : mapping of str to float or array_like, optional
            Parameter overrides by name.
        integrator : {"idas", "cvodes"}, optional
            SUNDIALS integrator; CVODES only for models without algebraic variables.
        rtol, atol : float, optional
            Relative and absolute tolerances.
        z0 : array_like, optional
            Guess for the algebraic variables at ``t_grid[0]``, shape ``(nz,)``;
            default the declared start values. IDAS computes consistent values.

        Returns
        -------
        SimulationResult
            Trajectories on ``t_grid``.

        Raises
        ------
        InputError
            On malformed arguments.
        ModelError
            If the model cannot be flattened.
        ConvergenceError
            If the integrator fails or returns non-finite values.
        """
        dae = self.flatten()
        t = np.asarray(t_grid, dtype=float).reshape(-1)
        if t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise InputError("t_grid must be finite, strictly increasing, with at least 2 points")
        if integrator not in ("idas", "cvodes"):
            raise InputError(f"integrator must be 'idas' or 'cvodes', got {integrator!r}")
        if integrator == "cvodes" and dae.nz:
            raise InputError("integrator 'cvodes' cannot handle algebraic variables; use 'idas'")
        n = t.size
        # initial state
        if x0 is None:
            x0v = dae.x_start.copy()
        elif isinstance(x0, Mapping):
            x0v = dae.x_start.copy()
            for name, val in x0.items():
                if name not in dae.x_vars:
                    raise InputError(f"x0: {name!r} is not a state of model {self.name!r}")
                sl = dae.x_vars[name]
                x0v[sl] = _vector_value(val, sl.stop - sl.start, f"x0[{name!r}]")
        else:
            x0v = _vector_value(x0, dae.nx, "x0")
        z0v = dae.z_start.copy() if z0 is None else _vector_value(z0, dae.nz, "z0")
        pv = dae.parameter_vector(p)
        # inputs per interval: (n-1, nu)
        u_default = np.concatenate(
            [v.start for v in self._vars.values() if v.kind == "input"]
        ) if dae.nu else np.zeros(0)
        if u is None:
            u_int = np.tile(u_default, (n - 1, 1))
        elif callable(u):
            u_int = np.array([_vector_value(u(tk), dae.nu, f"u({tk})") for tk in t[:-1]])
        else:
            ua = np.asarray(u, dtype=float)
            if ua.size == dae.nu and not (dae.nu == 1 and ua.ndim == 1 and ua.size in (n - 1, n) and ua.size > 1):
                u_int = np.tile(ua.reshape(-1), (n - 1, 1))
            else:
                if ua.ndim == 1 and dae.nu == 1:
                    ua = ua.reshape(-1, 1)
                if ua.ndim != 2 or ua.shape[1] != dae.nu or ua.shape[0] not in (n - 1, n):
                    raise InputError(
                        f"u: expected a constant of {dae.nu} values or an array of shape "
                        f"({n - 1}, {dae.nu}) or ({n}, {dae.nu}), got shape {np.shape(u)}"
                    )
                u_int = ua[: n - 1]
        u_int = np.asarray(u_int, dtype=float).reshape(n - 1, dae.nu)
        if not np.all(np.isfinite(u_int)):
            raise InputError("u contains non-finite values")
        # CasADi's integrator holds u[:, k] on (tout[k-1], tout[k]]; tout[0] = t0
        u_cas = np.vstack([u_int[:1], u_int]).T if dae.nu else np.zeros((0, n))

        ddict: dict[str, Any] = {"t": dae.t, "x": dae.x, "u": dae.u, "p": dae.p, "ode": dae.ode_expr}
        if dae.nz:
            ddict["z"] = dae.z
            ddict["alg"] = dae.alg_expr
        opts = {
            "reltol": float(rtol),
            "abstol": float(atol),
            "show_eval_warnings": False,
            "disable_internal_warnings": True,
        }
        try:
            F = ca.integrator(f"{self.name}_sim", integrator, ddict, float(t[0]), list(t), opts)
            res = F(x0=x0v, z0=z0v, p=pv, u=u_cas)
        except RuntimeError as exc:
            lines = [ln for ln in str(exc).splitlines() if "returned" in ln] or str(exc).splitlines()
            raise ConvergenceError(
                f"simulation of model {self.name!r} with {integrator} failed: "
                f"{lines[0].strip() if lines else exc}"
            ) from exc
        xs = np.array(res["xf"]).reshape(dae.nx, n).T
        zs = np.array(res["zf"]).reshape(dae.nz, n).T
        if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(zs))):
            raise ConvergenceError(f"simulation of model {self.name!r} produced non-finite values")
        us = np.vstack([u_int, u_int[-1:]])
        outs = _eval_outputs(dae, t, xs, zs, us, pv)
        _log.debug("simulated model %s on %d points with %s", self.name, n, integrator)
        return SimulationResult(
            t=t,
            x=_unpack(dae.x_vars, xs),
            z=_unpack(dae.z_vars, zs),
            u=_unpack(dae.u_vars, us),
            outputs=outs,
            p={k: pv[s].copy() for k, s in dae.p_vars.items()},
        )


def _eval_outputs(
    dae: FlatDAE,
    t: np.ndarray,
    xs: np.ndarray,
    zs: np.ndarray,
    us: np.ndarray,
    pv: np.ndarray,
) -> dict[str, np.ndarray]:
    """Evaluate declared outputs at samples (rows) of ``t, x, z, u``."""
    if not dae.output_sizes:
        return {}
    n = t.size
    fmap = dae.outputs.map(n)
    vals = fmap(t.reshape(1, -1), xs.T, zs.T, us.T, np.tile(pv.reshape(-1, 1), (1, n)))
    if not isinstance(vals, (list, tuple)):
        vals = [vals]
    out = {}
    for name, v in zip(dae.output_sizes, vals):
        a = np.array(v).reshape(dae.output_sizes[name], n).T
        out[name] = a[:, 0].copy() if a.shape[1] == 1 else a
    return out
