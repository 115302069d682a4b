"""Controller functions of the 4 ms loop as generated C: the Kalman step and the ILC correction.

The controller side of the loop (Dressler (2012), ch. 7) adds two functions to a
generated library, each wrapping a CasADi Function the caller gives (the ONE graph of the
Python implementation, e.g. ``gtmodel.estimation.StationaryKalman.step_function()`` and
``gtmodel.estimation.ilc_correction_function(table)``; nothing is rebuilt here):

``<prefix>_kalman_step(x[nx], y[ny], x_next[nx], z_hat[nz])``
    One step of the stationary Kalman filter (eqs. 7.19-7.22): from the state ``x_k`` and
    the measurements ``y_k`` (``[z_kin; a_m]``: kinematic tool position [m] and tool
    accelerometer [m/s^2]) to ``x_{k+1}`` and the tool position estimate ``z_hat``.
    The state lives in the caller's memory; two convenience functions keep it in a
    caller-owned struct ``<prefix>_kalman_state`` (stack, static or part of a bigger
    struct: no heap): ``<prefix>_kalman_init(&state, x0)`` (``x0`` NULL: zeros) and
    ``<prefix>_kalman_update(&state, y, z_hat)`` (the state is replaced by ``x_{k+1}``
    only when ``GT_OK`` is returned).
``<prefix>_ilc_correction(k, u[d])``
    The learned ILC correction ``u_k`` (eq. 7.2, the converged ``u`` of the last
    iteration, with the lead-in/out time window already applied by ``Q``) at cycle ``k``
    of the trial, a lookup of the learned table by the cycle count. **Outside the table**
    (``k < 0`` or ``k >= <PREFIX>_ILC_LENGTH``: before the trial starts, after it ends)
    the correction is zero and the status ``GT_OK``: the time window takes the table to
    zero at both ends, so zero outside continues it; the C function returns exactly what
    the Python Function returns there (checked by the self-check at ``k = -10 .. N + 9``).

Both return the shared status codes (:data:`~gtmodel.codegen.declarations.STATUS_CODES`):
``GT_BAD_ARGUMENT`` for a NULL pointer or a non-finite input (outputs untouched),
``GT_NUMERIC_ERROR`` for a non-finite result. The header also defines the sizes
(``<PREFIX>_KALMAN_NX``, ``_NY``, ``_NZ``, ``<PREFIX>_ILC_LENGTH``, ``<PREFIX>_ILC_D``) and
the sample time ``<PREFIX>_CONTROLLER_DT``.

A :class:`Controller` holds the Functions (and the learned table); it is passed to
:func:`gtmodel.codegen.generate` (``controller=``) or saved to / loaded from a controller
file (:mod:`gtmodel.codegen.controller_file`) for ``gtmodel codegen --controller FILE``.
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from gtmodel.codegen.c_text import _c_float
from gtmodel.codegen.declarations import CONTROLLER_KIND, ArgSpec, FunctionSpec, OutputSpec
from gtmodel.codegen.filter_step import (
    FILTER_FUNCTIONS, check_filter_function, filter_header_lines, filter_sizes, filter_source_lines, filter_spec,
)
from gtmodel.errors import InputError

if TYPE_CHECKING:  # annotations only
    from gtmodel.codegen.generate import GeneratedCode

__all__ = [
    "CONTROLLER_KIND",
    "CONTROLLER_FUNCTIONS",
    "DEFAULT_DT",
    "ILC_TABLE_TOLERANCE",
    "Controller",
    "controller_part",
    "robot_part",
    "controller_header_lines",
    "controller_source_lines",
]

#: Names of the controller functions (the C symbols are ``<prefix>_<name>``).
CONTROLLER_FUNCTIONS = ("kalman_step", "ilc_correction", *FILTER_FUNCTIONS)
#: Sample time of the loop [s] (Dressler (2012), ch. 3.2).
DEFAULT_DT = 0.004
#: Largest accepted ``|ilc_correction(k) - table[k]| / (1 + |table[k]|)`` when a Controller is built.
ILC_TABLE_TOLERANCE = 1e-12


def _dense_column(f: ca.Function, name: str, where: str, io: str) -> int:
    sp = f.sparsity_in(name) if io == "input" else f.sparsity_out(name)
    if sp.size2() != 1 or not sp.is_dense():
        raise InputError(f"{where}: {io} {name!r} must be a dense column vector, is {sp.size1()}x{sp.size2()}"
                         + ("" if sp.is_dense() else " (sparse)"))
    return sp.size1()


def _check_function(f: Any, where: str, inputs: tuple[str, ...], outputs: tuple[str, ...]) -> dict[str, int]:
    if not isinstance(f, ca.Function):
        raise InputError(f"{where}: expected a casadi.Function, got {type(f).__name__}")
    if tuple(f.name_in()) != inputs or tuple(f.name_out()) != outputs:
        raise InputError(
            f"{where}: expected a casadi.Function ({', '.join(inputs)}) -> ({', '.join(outputs)}), "
            f"got ({', '.join(f.name_in())}) -> ({', '.join(f.name_out())})"
        )
    sizes = {n: _dense_column(f, n, where, "input") for n in inputs}
    sizes.update({n: _dense_column(f, n, where, "output") for n in outputs})
    if any(v == 0 for v in sizes.values()):
        raise InputError(f"{where}: empty input or output in {sizes}")
    return sizes


@dataclass(frozen=True)
class Controller:
    """The controller functions of the 4 ms loop to generate as C (Dressler (2012), ch. 7).

    Parameters
    ----------
    kalman_step : casadi.Function or None, optional
        ``"kalman_step"(x[nx], y[ny]) -> (x_next[nx], z_hat[nz])``: one step of the
        stationary Kalman filter (eqs. 7.19-7.22), inputs and outputs named exactly so,
        dense column vectors; e.g. ``StationaryKalman(...).step_function()``.
    ilc_correction : casadi.Function or None, optional
        ``"ilc_correction"(k) -> u[d]``: the learned correction at cycle ``k`` (a scalar
        input holding an integer), 0 outside ``[0, N)``; e.g.
        ``ilc_correction_function(ilc_table)``.
    ilc_table : array_like or None, optional
        The learned table ``(N, d)`` the Function looks up (unit of the corrected
        reference, m); required with ``ilc_correction``. It fixes
        ``<PREFIX>_ILC_LENGTH = N`` and is checked against the Function: ``u(k)`` equals
        ``ilc_table[k]`` for every ``k`` in ``[0, N)`` (to ``ILC_TABLE_TOLERANCE``
        relative) and ``u(-1) = u(N) = 0``.
    dt : float, optional
        Sample time of the loop [s] (default 0.004); the header's
        ``<PREFIX>_CONTROLLER_DT``. For the filters of the tracker + IMU fusion the
        sensors' sample time (0.001 at 1 kHz): the self-check's measurement record uses it.
    kf_step : casadi.Function or None, optional
        ``"kf_step"(x[nx], P[nx,nx], z[nz]) -> (x_next[nx], P_next[nx,nx], pivots[nz+nx])``:
        one step of the Kalman filter of the 3-axis (translation-only) end-effector model,
        Cvitanic (2021), eqs. (21)-(26); e.g. ``KalmanFilter(...).step_function()`` of
        :mod:`gtmodel.estimation.filters` (nx 9, nz 6). Generated as ``<prefix>_kf_step``
        with the state struct ``<prefix>_kf_state`` (:mod:`gtmodel.codegen.filter_step`).
    ekf_step : casadi.Function or None, optional
        The same signature for the extended Kalman filter of the 19-D model, eqs. (21)-(29)
        (nx 19, nz 13; ``ExtendedKalmanFilter(...).step_function()``); ``<prefix>_ekf_step``.

    Raises
    ------
    InputError
        No function given; a Function is not a ``casadi.Function`` or has another
        signature (names, dense column vectors, ``nx`` of ``x`` and ``x_next`` equal,
        ``k`` scalar; the filter steps: ``P`` and ``P_next`` ``nx x nx``, ``pivots`` of
        ``nz + nx``); ``ilc_correction`` without ``ilc_table`` or the reverse; a table
        that is not ``(N, d)`` finite with ``d`` the size of ``u``, or does not match the
        Function; ``dt`` not positive and finite.
    """

    kalman_step: ca.Function | None = field(default=None, repr=False)
    ilc_correction: ca.Function | None = field(default=None, repr=False)
    ilc_table: np.ndarray | None = field(default=None, repr=False, compare=False)
    dt: float = DEFAULT_DT
    kf_step: ca.Function | None = field(default=None, repr=False)
    ekf_step: ca.Function | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if all(getattr(self, n) is None for n in CONTROLLER_FUNCTIONS):
            raise InputError(f"controller: expected at least one of {', '.join(CONTROLLER_FUNCTIONS)}")
        for name in FILTER_FUNCTIONS:
            if getattr(self, name) is not None:
                check_filter_function(getattr(self, name), name)
        if isinstance(self.dt, bool) or not isinstance(self.dt, (int, float, np.floating)) or not (np.isfinite(self.dt) and self.dt > 0):
            raise InputError(f"dt: expected a positive sample time [s], got {self.dt!r}")
        object.__setattr__(self, "dt", float(self.dt))
        if self.kalman_step is not None:
            s = _check_function(self.kalman_step, "kalman_step", ("x", "y"), ("x_next", "z_hat"))
            if s["x"] != s["x_next"]:
                raise InputError(f"kalman_step: x has {s['x']} elements but x_next has {s['x_next']}")
        if (self.ilc_correction is None) != (self.ilc_table is None):
            raise InputError("ilc_table: expected together with ilc_correction (the table the Function looks up), "
                             f"got {'a table without a Function' if self.ilc_correction is None else 'a Function without its table'}")
        if self.ilc_correction is not None:
            s = _check_function(self.ilc_correction, "ilc_correction", ("k",), ("u",))
            if s["k"] != 1:
                raise InputError(f"ilc_correction: input 'k' must be scalar, has {s['k']} elements")
            table = np.asarray(self.ilc_table, dtype=float) if np.asarray(self.ilc_table).dtype.kind in "fiu" else None
            if table is None or table.ndim != 2 or table.shape[0] < 1 or not np.all(np.isfinite(table)):
                raise InputError(f"ilc_table: expected an (N, d) array of finite values, got {np.shape(self.ilc_table)}"
                                 + ("" if table is None or np.all(np.isfinite(table)) else " with non-finite values"))
            if table.shape[1] != s["u"]:
                raise InputError(f"ilc_table: has {table.shape[1]} columns but ilc_correction's u has {s['u']} elements")
            table = table.copy()
            table.setflags(write=False)
            object.__setattr__(self, "ilc_table", table)
            self._check_table()

    def _check_table(self) -> None:
        n = len(self.ilc_table)
        k = np.arange(-1, n + 1, dtype=float)
        u = np.asarray(ca.DM(self.ilc_correction.map(k.size)(k[None, :]))).T
        ref = np.vstack([np.zeros((1, self.ilc_d)), self.ilc_table, np.zeros((1, self.ilc_d))])
        err = np.abs(u - ref) / (1.0 + np.abs(ref))
        if not np.all(err <= ILC_TABLE_TOLERANCE):
            i = int(np.argmax(np.where(np.isfinite(err), err, np.inf).max(axis=1)))
            raise InputError(
                f"ilc_correction: u(k={int(k[i])}) = {u[i].tolist()} differs from "
                + (f"ilc_table[{int(k[i])}] = {ref[i].tolist()}" if 0 <= k[i] < n else "0 (outside the table)")
            )

    def content_hash(self) -> str:
        """SHA-256 of what the generated C computes: the Functions (CasADi serialisation), the table and ``dt``.

        The hash a controller-only library carries instead of a robot's parameter hash.

        Returns
        -------
        str
            64 hexadecimal digits.
        """
        h = hashlib.sha256(repr(self.dt).encode())
        for name in self.functions:
            h.update(name.encode() + b"\0" + getattr(self, name).serialize().encode())
        if self.ilc_table is not None:
            h.update(np.ascontiguousarray(self.ilc_table).tobytes())
        return h.hexdigest()

    @property
    def functions(self) -> tuple[str, ...]:
        """Names of the given functions, from :data:`CONTROLLER_FUNCTIONS`."""
        return tuple(n for n in CONTROLLER_FUNCTIONS if getattr(self, n) is not None)

    @property
    def kalman_sizes(self) -> tuple[int, int, int]:
        """``(nx, ny, nz)`` of ``kalman_step`` (zeros without it)."""
        f = self.kalman_step
        return (f.numel_in("x"), f.numel_in("y"), f.numel_out("z_hat")) if f is not None else (0, 0, 0)

    @property
    def filter_sizes(self) -> dict[str, tuple[int, int]]:
        """``{"kf_step": (nx, nz), "ekf_step": (nx, nz)}`` of the given filter steps."""
        return {n: filter_sizes(getattr(self, n)) for n in FILTER_FUNCTIONS if getattr(self, n) is not None}

    @property
    def ilc_length(self) -> int:
        """Number of cycles ``N`` of the learned table (0 without it)."""
        return 0 if self.ilc_table is None else int(len(self.ilc_table))

    @property
    def ilc_d(self) -> int:
        """Size ``d`` of the correction ``u`` (0 without it)."""
        return 0 if self.ilc_correction is None else int(self.ilc_correction.numel_out("u"))

    def specs(self) -> tuple[FunctionSpec, ...]:
        """Declarations of the generated controller functions (``kind`` = :data:`CONTROLLER_KIND`).

        Returns
        -------
        tuple of FunctionSpec
            ``kalman_step``, ``ilc_correction``, ``kf_step``, ``ekf_step`` (those given), each wrapping the given Function
            (the self-check compares with that Function evaluated from Python).
        """
        out = []
        if self.kalman_step is not None:
            f = self.kalman_step
            out.append(FunctionSpec(
                name="kalman_step",
                build=lambda model, f=f: f,
                args=(
                    ArgSpec("x", "vector", "x", "filter state x_k (per direction position [m], velocity [m/s], acceleration [m/s^2])"),
                    ArgSpec("y", "vector", "y", "measurements y_k: kinematic tool position z_kin [m], then tool accelerometer a_m [m/s^2]"),
                ),
                outputs=(
                    OutputSpec("x_next", "x_next", "next filter state x_{k+1} (same layout as x)"),
                    OutputSpec("z_hat", "z_hat", "tool position estimate [m]"),
                ),
                doc=("One step of the stationary Kalman filter of the tool position, Dressler (2012), "
                     "eqs. 7.19-7.22 (the model extended with velocity and acceleration states; constant gain). "
                     "x_next may be x (in-place update); or keep the state in a <prefix>_kalman_state with "
                     "<prefix>_kalman_update."),
                tolerance=1e-12,
                unit="m, m/s, m/s^2",
                kind=CONTROLLER_KIND,
            ))
        if self.ilc_correction is not None:
            f = self.ilc_correction
            out.append(FunctionSpec(
                name="ilc_correction",
                build=lambda model, f=f: f,
                args=(ArgSpec("k", "index", "k", "cycle count of the trial (0 = first sample of the table; any int)"),),
                outputs=(OutputSpec("u", "u", "learned ILC correction u_k added to the reference [m]; 0 outside the table"),),
                doc=(f"The learned ILC correction u_k, Dressler (2012), eq. 7.2 (table of {self.ilc_length} cycles of "
                     "4 ms, the lead-in/out time window included): a lookup by the cycle count k. Outside "
                     "the table (k < 0 or k >= ILC_LENGTH) the correction is 0 and the status GT_OK."),
                tolerance=1e-12,
                unit="m",
                kind=CONTROLLER_KIND,
            ))
        out += [filter_spec(n, getattr(self, n), CONTROLLER_KIND) for n in self.filter_sizes]
        return tuple(out)


def controller_part(generated: "GeneratedCode") -> "GeneratedCode":
    """The generated code restricted to its controller functions.

    Parameters
    ----------
    generated : GeneratedCode
        A library generated with ``controller=``.

    Returns
    -------
    GeneratedCode
        The same files, ``specs`` and ``functions`` only those of kind
        :data:`CONTROLLER_KIND`.
    """
    specs = tuple(s for s in generated.specs if s.kind == CONTROLLER_KIND)
    return dataclasses.replace(generated, specs=specs, functions=tuple(s.name for s in specs))


def robot_part(generated: "GeneratedCode") -> "GeneratedCode":
    """The generated code restricted to its robot-model functions (what :func:`~gtmodel.codegen.check.check` checks).

    Parameters
    ----------
    generated : GeneratedCode
        Any generated library.

    Returns
    -------
    GeneratedCode
        The same files, ``specs`` and ``functions`` without the controller functions.
    """
    specs = tuple(s for s in generated.specs if s.kind != CONTROLLER_KIND)
    if len(specs) == len(generated.specs):
        return generated
    return dataclasses.replace(generated, specs=specs, functions=tuple(s.name for s in specs))


def controller_header_lines(prefix: str, controller: Controller, real: str) -> list[str]:
    """Header declarations of the controller: sizes, sample time, the Kalman state struct.

    Parameters
    ----------
    prefix : str
        C prefix (``gt_L1``).
    controller : Controller
        The controller generated.
    real : {"double", "float"}
        Floating-point type.

    Returns
    -------
    list of str
        Lines placed after the function prototypes of the header.
    """
    P = prefix.upper()
    out = [
        "/* ---- Controller of the 4 ms loop (Dressler (2012), ch. 7) ---- */",
        "/* Sample time of the loop [s]. */",
        f"#define {P}_CONTROLLER_DT {_c_float(controller.dt)}",
    ]
    if controller.kalman_step is not None:
        nx, ny, nz = controller.kalman_sizes
        out += [
            "/* Sizes of the Kalman filter: state, measurements [z_kin; a_m], tool position estimate. */",
            f"#define {P}_KALMAN_NX {nx}",
            f"#define {P}_KALMAN_NY {ny}",
            f"#define {P}_KALMAN_NZ {nz}",
            "/* State of the Kalman filter, owned by the caller (stack, static or in a bigger struct; no heap). */",
            f"typedef struct {prefix}_kalman_state {{",
            f"    {real} x[{nx}]; /* x_k, the layout of {prefix}_kalman_step's x */",
            f"}} {prefix}_kalman_state;",
            "",
            "/*",
            " * Set the filter state to x0 (NULL: zeros).",
            " * Returns GT_OK, or GT_BAD_ARGUMENT (state NULL or x0 non-finite; state untouched).",
            " */",
            f"int {prefix}_kalman_init({prefix}_kalman_state *state, const {real} x0[{nx}]);",
            "",
            "/*",
            f" * One cycle of the Kalman filter: {prefix}_kalman_step(state->x, y, x_next, z_hat), then",
            " * state->x = x_next. On any status other than GT_OK neither the state nor z_hat is",
            " * written. Returns GT_OK, GT_BAD_ARGUMENT (a NULL pointer, non-finite y or state),",
            " * GT_NUMERIC_ERROR.",
            " */",
            f"int {prefix}_kalman_update({prefix}_kalman_state *state, const {real} y[{ny}], {real} z_hat[{nz}]);",
            "",
        ]
    if controller.ilc_correction is not None:
        out += [
            "/* Cycles of the learned ILC table (k = 0 .. ILC_LENGTH - 1) and size of the correction. */",
            f"#define {P}_ILC_LENGTH {controller.ilc_length}",
            f"#define {P}_ILC_D {controller.ilc_d}",
            "",
        ]
    for name in controller.filter_sizes:
        out += filter_header_lines(prefix, name, getattr(controller, name), real)
    return out


def controller_source_lines(prefix: str, controller: Controller, real: str) -> list[str]:
    """Wrapper source of the Kalman state functions (``<prefix>_kalman_init``, ``_update``).

    Parameters
    ----------
    prefix : str
        C prefix (``gt_L1``).
    controller : Controller
        The controller generated.
    real : {"double", "float"}
        Floating-point type.

    Returns
    -------
    list of str
        C lines appended to the wrapper source (empty without ``kalman_step`` and filters):
        also ``<prefix>_kf_init``/``_update`` and ``<prefix>_ekf_init``/``_update``.
    """
    filters = [line for name in controller.filter_sizes
               for line in filter_source_lines(prefix, name, getattr(controller, name), real)]
    if controller.kalman_step is None:
        return filters
    nx = controller.kalman_sizes[0]
    st = f"{prefix}_kalman_state"
    return [
        f"int {prefix}_kalman_init({st} *state, const {real} x0[{nx}])",
        "{",
        "    int i;",
        "    if (state == NULL) return GT_BAD_ARGUMENT;",
        "    if (x0 != NULL) {",
        f"        for (i = 0; i < {nx}; ++i) {{",
        "            if (!isfinite(x0[i])) return GT_BAD_ARGUMENT;",
        "        }",
        "    }",
        f"    for (i = 0; i < {nx}; ++i) state->x[i] = x0 != NULL ? x0[i] : ({real})0;",
        "    return GT_OK;",
        "}",
        "",
        f"int {prefix}_kalman_update({st} *state, const {real} y[{controller.kalman_sizes[1]}], {real} z_hat[{controller.kalman_sizes[2]}])",
        "{",
        f"    {real} x_next[{nx}];",
        "    int i, status;",
        "    if (state == NULL) return GT_BAD_ARGUMENT;",
        f"    status = {prefix}_kalman_step(state->x, y, x_next, z_hat);",
        "    if (status != GT_OK) return status;",
        f"    for (i = 0; i < {nx}; ++i) state->x[i] = x_next[i];",
        "    return GT_OK;",
        "}",
        "",
        *filters,
    ]
