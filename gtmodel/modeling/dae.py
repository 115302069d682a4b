"""The flat semi-explicit DAE of a model (:class:`FlatDAE`), simulation results, and value checks.

``xdot = f(t, x, z, u, p)``, ``0 = g(t, x, z, u, p)`` as produced by
:meth:`gtmodel.modeling.Model.flatten`; shared helpers of the modelling layer (scalar
element names, symbol and value checks, unpacking of sampled trajectories).
"""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel._escape import casadi_name
from gtmodel._tables import with_unit
from gtmodel.errors import InputError

#: pandas, imported on first use (~0.5 s of CPU, only for DataFrames).
pd = lazy_module("pandas")

__all__ = ["FlatDAE", "SimulationResult", "expand_names", "fixed_flags", "casadi_name"]


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


def fixed_flags(value: Any, size: int, what: str) -> np.ndarray:
    """A ``fixed`` attribute as a boolean vector of ``size`` elements.

    Parameters
    ----------
    value : bool or array_like of bool
        One flag for all elements, or one per element.
    size : int
        Number of scalar elements of the variable.
    what : str
        Name used in the message.

    Returns
    -------
    numpy.ndarray
        ``(size,)`` of bool.

    Raises
    ------
    InputError
        If ``value`` is not booleans (numbers and strings are refused) or has another size.
    """
    arr = np.asarray(value, dtype=object).reshape(-1)
    if arr.size == 0 or not all(isinstance(v, (bool, np.bool_)) for v in arr):
        raise InputError(f"{what}: expected True or False (or one per element), got {value!r}")
    if arr.size == 1:
        arr = np.repeat(arr, size)
    if arr.size != size:
        raise InputError(f"{what}: expected 1 or {size} flags, got {arr.size}")
    return arr.astype(bool)


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


def _columns(t: np.ndarray, *groups: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A ``t`` column and one column per scalar element, by name (the columns of :func:`_frame`)."""
    cols: dict[str, np.ndarray] = {"t": np.asarray(t, dtype=float)}
    for group in groups:
        for name, arr in group.items():
            arr = np.asarray(arr, dtype=float)
            if arr.ndim == 1:
                cols[name] = arr
            else:
                for nm, col in zip(expand_names(name, arr.shape[1]), arr.T):
                    cols[nm] = col
    return cols


def _frame(t: np.ndarray, *groups: Mapping[str, np.ndarray]) -> Any:
    """Build a pandas DataFrame with a ``t`` column and one column per scalar element."""
    return pd.DataFrame(_columns(t, *groups))


def _write_columns(path: Path, cols: Mapping[str, np.ndarray], units: Mapping[str, str] | None = None) -> None:
    """Write named float (or string) columns as CSV, byte for byte as ``pandas.DataFrame(cols).to_csv(path, index=False)``.

    Without importing pandas (~1 s at a ``gtmodel solve`` process's start): the header row,
    then each value as pandas writes it (``numpy`` ``astype(str)``, the shortest repr; NaN
    as an empty field), ``csv`` minimal quoting, ``\n`` line ends. With ``units`` (name ->
    unit) a column's header is ``name [unit]`` (:func:`gtmodel._tables.with_unit`, read back
    by :func:`gtmodel._tables.read_table`).
    """
    def as_text(v: Any) -> np.ndarray:
        a = np.asarray(v)
        if a.dtype.kind in "US":
            return a.astype(str)
        c = a.astype(float)
        return np.where(np.isnan(c), "", c.astype(str))

    text = [as_text(v) for v in cols.values()]
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow([with_unit(c, (units or {}).get(c)) for c in cols])
        writer.writerows(zip(*text))


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
        Parameter values used (for a mode of :meth:`Model.mode`: its start value).
    events : list of EventRecord
        State events in time order (:mod:`gtmodel.modeling.structure.events`): time, when-clause
        name and mode values after it; empty for a model without when-clauses.
    """

    t: np.ndarray
    x: dict[str, np.ndarray]
    z: dict[str, np.ndarray]
    u: dict[str, np.ndarray]
    outputs: dict[str, np.ndarray]
    p: dict[str, np.ndarray] = field(default_factory=dict)
    events: list[Any] = field(default_factory=list)

    def to_dataframe(self) -> Any:
        """Return all trajectories as a pandas DataFrame.

        Returns
        -------
        pandas.DataFrame
            Column ``"t"`` then one column per scalar element (``"T[0]"`` style names)
            of states, algebraics, inputs and outputs, one row per time sample.
        """
        return _frame(self.t, self.x, self.z, self.u, self.outputs)


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
    ps = np.tile(pv.reshape(-1, 1), (1, n)) if pv.ndim == 1 else pv.T  # (npar,) or (N, npar)
    vals = fmap(t.reshape(1, -1), xs.T, zs.T, us.T, ps)
    if not isinstance(vals, (list, tuple)):
        vals = [vals]
    out = {}
    for name, v in zip(dae.output_sizes, vals):
        a = np.array(v).reshape(dae.output_sizes[name], n).T
        out[name] = a[:, 0].copy() if a.shape[1] == 1 else a
    return out
