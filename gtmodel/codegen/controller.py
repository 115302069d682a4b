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

An :class:`EstimatorILCBundle` (formerly ``Controller``, still an alias) holds the Functions
(and the learned table); it is passed to
:func:`gtmodel.codegen.generate` (``controller=``) or saved to / loaded from a controller
file (:mod:`gtmodel.codegen.controller_file`) for ``gtmodel codegen --controller FILE``.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.codegen.declarations import CONTROLLER_KIND, ArgSpec, FunctionSpec, OutputSpec
from gtmodel.codegen.specs.filter import FILTER_FUNCTIONS, check_filter_function, filter_sizes, filter_spec
from gtmodel.codegen.specs.lead_through import check_lead_through_function, lead_through_spec
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError

__all__ = [
    "CONTROLLER_KIND",
    "CONTROLLER_FUNCTIONS",
    "DEFAULT_DT",
    "ILC_TABLE_TOLERANCE",
    "EstimatorILCBundle",
    "Controller",
]

#: Names of the controller functions (the C symbols are ``<prefix>_<name>``).
CONTROLLER_FUNCTIONS = ("kalman_step", "ilc_correction", *FILTER_FUNCTIONS, "lead_through_step")
#: Sample time of the loop [s] (Dressler (2012), ch. 3.2): the one loop period of gtmodel.defaults.
DEFAULT_DT = LOOP_PERIOD_S
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
class EstimatorILCBundle:
    """The estimator and ILC functions of the 4 ms loop to generate as C (Dressler (2012), ch. 7): one bundle.

    The Kalman step and the learned ILC correction, the fusion's KF/EKF steps and the
    lead-through step, any of them, with their sample time (the ``estimator_ilc`` file kind
    of :data:`gtmodel.problems.registry.LOOP_KINDS`). Named ``Controller`` before (that name
    is kept as an alias); the loop's tracking and MPC controllers are
    :mod:`gtmodel.control`'s.

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
        Sample time of the loop [s] (default: the loop period,
        ``gtmodel.defaults.LOOP_PERIOD_S``); the header's
        ``<PREFIX>_CONTROLLER_DT``. For the filters of the tracker + IMU fusion the
        sensors' sample time (0.001 at 1 kHz): the self-check's measurement record uses it.
    kf_step : casadi.Function or None, optional
        ``"kf_step"(x[nx], P[nx,nx], z[nz]) -> (x_next[nx], P_next[nx,nx], pivots[nz+nx])``:
        one step of the Kalman filter of the 3-axis (translation-only) end-effector model,
        Cvitanic (2021), eqs. (21)-(26); e.g. ``KalmanFilter(...).step_function()`` of
        :mod:`gtmodel.estimation.filters` (nx 9, nz 6). Generated as ``<prefix>_kf_step``
        with the state struct ``<prefix>_kf_state`` (:mod:`gtmodel.codegen.specs.filter`).
    ekf_step : casadi.Function or None, optional
        The same signature for the extended Kalman filter of the 19-D model, eqs. (21)-(29)
        (nx 19, nz 13; ``ExtendedKalmanFilter(...).step_function()``); ``<prefix>_ekf_step``.
    lead_through_step : casadi.Function or None, optional
        ``"lead_through_step"(x[8], F_h[6], F_t[6], n_n[3]) -> (x_next[8], V_tool[6], n[3], valid)``:
        one step of the two-sensor lead-through controller, Dressler (2012), eqs. 8.3-8.11
        (``LeadThroughLaw(...).step_function()`` of :mod:`gtmodel.estimation.lead_through`);
        ``<prefix>_lead_through_step`` with the state struct ``<prefix>_lead_through_state``
        (:mod:`gtmodel.codegen.specs.lead_through`).

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
    lead_through_step: ca.Function | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if all(getattr(self, n) is None for n in CONTROLLER_FUNCTIONS):
            raise InputError(f"controller: expected at least one of {', '.join(CONTROLLER_FUNCTIONS)}")
        for name in FILTER_FUNCTIONS:
            if getattr(self, name) is not None:
                check_filter_function(getattr(self, name), name)
        if self.lead_through_step is not None:
            check_lead_through_function(self.lead_through_step)
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
            ``kalman_step``, ``ilc_correction``, ``kf_step``, ``ekf_step``, ``lead_through_step`` (those given), each wrapping the given Function
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
        if self.lead_through_step is not None:
            out.append(lead_through_spec(self.lead_through_step, CONTROLLER_KIND))
        return tuple(out)


#: The former name of :class:`EstimatorILCBundle` (kept for existing code).
Controller = EstimatorILCBundle
