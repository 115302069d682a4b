"""The KF and EKF steps of the laser tracker + IMU fusion as generated C (Cvitanic (2021), ch. 4).

Each filter step is a CasADi Function of :mod:`gtmodel.estimation.filters`
(``KalmanFilter(...).step_function()``, ``ExtendedKalmanFilter(...).step_function()``; the
ONE graph of the Python filters, nothing is rebuilt here)::

    "kf_step" / "ekf_step"(x[nx], P[nx,nx], z[nz]) -> (x_next[nx], P_next[nx,nx], pivots[nz+nx])

predict-then-update from the posterior ``(x_{k-1|k-1}, P_{k-1|k-1})`` and the measurement
``z_k`` to ``(x_{k|k}, P_{k|k})`` (eqs. (21)-(29); Joseph form, ``P`` symmetrised, the
quaternion renormalised in the graph); ``pivots`` are the Cholesky diagonals of the
innovation covariance ``S`` and of ``P_next``: all finite and positive exactly when both
are positive definite.

For ``name`` in ``kf``, ``ekf`` the generated library has (``<P>`` the upper-case prefix)

``int <prefix>_<name>_step(const double x[NX], const double P[NX*NX], const double z[NZ], double x_next[NX], double P_next[NX*NX])``
    One filter step. ``P`` and ``P_next`` are ROW-MAJOR ``NX x NX`` (element ``(r, c)`` at
    ``NX*r + c``; the filter's covariances are symmetric, so the order matters only for a
    non-symmetric input). ``x_next``/``P_next`` may alias ``x``/``P`` (in-place update).
    Returns ``GT_OK``; ``GT_BAD_ARGUMENT`` (a NULL pointer, a non-finite ``x``, ``P`` or
    ``z``); ``GT_NUMERIC_ERROR`` (a pivot ``<= 0`` or NaN: ``S`` or ``P_next`` not
    positive definite, e.g. after a covariance that is not; or a non-finite result).
    On any status other than ``GT_OK`` the outputs are not written.
``typedef struct <prefix>_<name>_state { double x[NX]; double P[NX*NX]; } <prefix>_<name>_state;``
    The filter state, owned by the caller (stack, static, or part of a bigger struct; no heap).
``int <prefix>_<name>_init(<prefix>_<name>_state *state, const double x0[NX], const double P0[NX*NX])``
    Set the prior. ``GT_BAD_ARGUMENT`` for a NULL pointer or a non-finite value (state
    untouched). A covariance that is not positive definite is reported by the first update.
``int <prefix>_<name>_update(<prefix>_<name>_state *state, const double z[NZ])``
    ``<prefix>_<name>_step`` on the state; the state is replaced only when ``GT_OK`` is returned.

and the sizes ``<P>_<NAME>_NX``, ``<P>_<NAME>_NZ`` (``<P>_KF_NX 9``, ``<P>_EKF_NX 19`` ...).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from gtmodel.codegen.declarations import ArgSpec, FunctionSpec, OutputSpec, StatusCheck
from gtmodel.errors import InputError

__all__ = [
    "FILTER_FUNCTIONS",
    "FILTER_INPUTS",
    "FILTER_OUTPUTS",
    "FILTER_TOLERANCE",
    "check_filter_function",
    "filter_sizes",
    "filter_spec",
    "filter_header_lines",
    "filter_source_lines",
]

#: Names of the filter step functions (the C symbols are ``<prefix>_<name>``).
FILTER_FUNCTIONS = ("kf_step", "ekf_step")
#: Inputs and outputs of a filter step Function, in order.
FILTER_INPUTS, FILTER_OUTPUTS = ("x", "P", "z"), ("x_next", "P_next", "pivots")
#: Largest accepted ``|C - Python|`` of a filter state or covariance element.
FILTER_TOLERANCE = 1e-12

_DESCRIPTION = {
    "kf_step": "Kalman filter of the translation-only (3-axis) end-effector model, Cvitanic (2021), eqs. (21)-(26), (29)",
    "ekf_step": "extended Kalman filter of the 19-D end-effector model (position, velocity, acceleration, "
                "unit quaternion, angular velocity and acceleration), Cvitanic (2021), eqs. (21)-(29)",
}


def _shape(f: ca.Function, name: str, io: str) -> tuple[int, int, bool]:
    sp = f.sparsity_in(name) if io == "input" else f.sparsity_out(name)
    return sp.size1(), sp.size2(), sp.is_dense()


def check_filter_function(f: Any, where: str) -> tuple[int, int]:
    """Validate a filter step Function and return its sizes.

    Parameters
    ----------
    f : casadi.Function
        ``(x[nx], P[nx,nx], z[nz]) -> (x_next[nx], P_next[nx,nx], pivots[nz+nx])``, inputs
        and outputs named exactly so, dense.
    where : str
        Argument name for the messages (``"kf_step"``).

    Returns
    -------
    tuple of int
        ``(nx, nz)``.

    Raises
    ------
    InputError
        Not a ``casadi.Function``, other names, a sparse or misshaped input or output.
    """
    if not isinstance(f, ca.Function):
        raise InputError(f"{where}: expected a casadi.Function, got {type(f).__name__}")
    if tuple(f.name_in()) != FILTER_INPUTS or tuple(f.name_out()) != FILTER_OUTPUTS:
        raise InputError(
            f"{where}: expected a casadi.Function ({', '.join(FILTER_INPUTS)}) -> ({', '.join(FILTER_OUTPUTS)}), "
            f"got ({', '.join(f.name_in())}) -> ({', '.join(f.name_out())})"
        )
    nx, nz = f.size1_in("x"), f.size1_in("z")
    expected = {("input", "x"): (nx, 1), ("input", "P"): (nx, nx), ("input", "z"): (nz, 1),
                ("output", "x_next"): (nx, 1), ("output", "P_next"): (nx, nx), ("output", "pivots"): (nz + nx, 1)}
    for (io, name), shape in expected.items():
        r, c, dense = _shape(f, name, io)
        if (r, c) != shape or not dense or min(shape) == 0:
            raise InputError(f"{where}: {io} {name!r} must be a dense {shape[0]}x{shape[1]} matrix "
                             f"(nx = {nx}, nz = {nz}), is {r}x{c}{'' if dense else ' (sparse)'}")
    return nx, nz


def filter_sizes(f: ca.Function | None) -> tuple[int, int]:
    """``(nx, nz)`` of a filter step Function (zeros for None).

    Parameters
    ----------
    f : casadi.Function or None
        A validated filter step Function.

    Returns
    -------
    tuple of int
        ``(nx, nz)``.
    """
    return (0, 0) if f is None else (f.size1_in("x"), f.size1_in("z"))


def _row_major(f: ca.Function, name: str) -> ca.Function:
    """``f`` with ``P`` given as the ``nx*nx`` row-major column the C API passes (a permutation: same values)."""
    nx, nz = filter_sizes(f)
    x, p, z = ca.MX.sym("x", nx), ca.MX.sym("P", nx * nx), ca.MX.sym("z", nz)
    out = f(x, ca.reshape(p, nx, nx).T, z)
    return ca.Function(name, [x, p, z], list(out), list(FILTER_INPUTS), list(FILTER_OUTPUTS))


def filter_spec(name: str, f: ca.Function, kind: str) -> FunctionSpec:
    """Declaration of the generated ``<prefix>_<name>`` (``kf_step`` or ``ekf_step``).

    Parameters
    ----------
    name : {"kf_step", "ekf_step"}
        Function name.
    f : casadi.Function
        The filter step Function (:func:`check_filter_function`).
    kind : str
        ``FunctionSpec.kind`` (the controller kind).

    Returns
    -------
    FunctionSpec
        Arguments ``x``, ``P`` (row-major), ``z``; outputs ``x_next``, ``P_next``;
        ``GT_NUMERIC_ERROR`` unless every pivot is ``> 0``.
    """
    nx, nz = filter_sizes(f)
    return FunctionSpec(
        name=name,
        build=lambda model, f=f: _row_major(f, name),
        args=(
            ArgSpec("x", "vector", "x", "posterior state x_{k-1|k-1}"),
            ArgSpec("P", "vector", "P", f"posterior covariance P_{{k-1|k-1}}, {nx}x{nx} row-major"),
            ArgSpec("z", "vector", "z", "measurement z_k (the model's measurement layout)"),
        ),
        outputs=(
            OutputSpec("x_next", "x_next", "posterior state x_{k|k} (may be x: in-place)"),
            OutputSpec("P_next", "P_next", f"posterior covariance P_{{k|k}}, {nx}x{nx} row-major, symmetric (may be P)"),
        ),
        checks=(StatusCheck("pivots", ">", "0", "GT_NUMERIC_ERROR"),),
        doc=(f"One predict-then-update step of the {_DESCRIPTION[name]}; Joseph form, P symmetrised"
             + (", the quaternion renormalised" if name == "ekf_step" else "")
             + f". GT_NUMERIC_ERROR when a Cholesky pivot of the innovation covariance ({nz}x{nz}) or of "
             f"P_next is not positive (not positive definite) or a result is not finite. Or keep the "
             f"state in a <prefix>_{name[:-5]}_state with <prefix>_{name[:-5]}_update."),
        tolerance=FILTER_TOLERANCE,
        unit="state and covariance units",
        kind=kind,
    )


def filter_header_lines(prefix: str, name: str, f: ca.Function, real: str) -> list[str]:
    """Header lines of one filter: sizes, the state struct, ``_init`` and ``_update``.

    Parameters
    ----------
    prefix : str
        C prefix (``gt_L1``).
    name : {"kf_step", "ekf_step"}
        The step function.
    f : casadi.Function
        Its Function (sizes).
    real : {"double", "float"}
        Floating-point type.

    Returns
    -------
    list of str
        Lines placed after the function prototypes of the header.
    """
    nx, nz = filter_sizes(f)
    stem = name[:-5]
    P = f"{prefix.upper()}_{stem.upper()}"
    st = f"{prefix}_{stem}_state"
    return [
        f"/* Sizes of the {stem.upper()} (Cvitanic (2021), ch. 4): state, measurement, pivots (S then P_next). */",
        f"#define {P}_NX {nx}",
        f"#define {P}_NZ {nz}",
        f"#define {P}_NPIVOTS {nz + nx}",
        f"/* State of the {stem.upper()}, owned by the caller (stack, static or in a bigger struct; no heap). */",
        f"typedef struct {st} {{",
        f"    {real} x[{nx}];  /* posterior mean x_{{k|k}} */",
        f"    {real} P[{nx * nx}]; /* posterior covariance P_{{k|k}}, row-major {nx}x{nx} */",
        f"}} {st};",
        "",
        "/*",
        " * Set the prior (x0, P0 row-major). Returns GT_OK, or GT_BAD_ARGUMENT (a NULL pointer,",
        " * a non-finite value; state untouched). A P0 that is not positive definite is reported",
        " * by the first update (GT_NUMERIC_ERROR).",
        " */",
        f"int {prefix}_{stem}_init({st} *state, const {real} x0[{nx}], const {real} P0[{nx * nx}]);",
        "",
        "/*",
        f" * One filter step on the state: {prefix}_{name}(state->x, state->P, z, ...). The state is",
        " * replaced only when GT_OK is returned. Returns GT_OK, GT_BAD_ARGUMENT (NULL pointer,",
        " * non-finite z or state), GT_NUMERIC_ERROR (covariance not positive definite or a",
        " * non-finite result).",
        " */",
        f"int {prefix}_{stem}_update({st} *state, const {real} z[{nz}]);",
        "",
    ]


def filter_source_lines(prefix: str, name: str, f: ca.Function, real: str) -> list[str]:
    """Wrapper source of one filter's ``_init`` and ``_update``.

    Parameters
    ----------
    prefix : str
        C prefix (``gt_L1``).
    name : {"kf_step", "ekf_step"}
        The step function.
    f : casadi.Function
        Its Function (sizes).
    real : {"double", "float"}
        Floating-point type.

    Returns
    -------
    list of str
        C lines appended to the wrapper source.
    """
    nx, nz = filter_sizes(f)
    stem = name[:-5]
    st = f"{prefix}_{stem}_state"
    return [
        f"int {prefix}_{stem}_init({st} *state, const {real} x0[{nx}], const {real} P0[{nx * nx}])",
        "{",
        "    int i;",
        "    if (state == NULL || x0 == NULL || P0 == NULL) return GT_BAD_ARGUMENT;",
        f"    for (i = 0; i < {nx}; ++i) {{",
        "        if (!isfinite(x0[i])) return GT_BAD_ARGUMENT;",
        "    }",
        f"    for (i = 0; i < {nx * nx}; ++i) {{",
        "        if (!isfinite(P0[i])) return GT_BAD_ARGUMENT;",
        "    }",
        f"    for (i = 0; i < {nx}; ++i) state->x[i] = x0[i];",
        f"    for (i = 0; i < {nx * nx}; ++i) state->P[i] = P0[i];",
        "    return GT_OK;",
        "}",
        "",
        f"int {prefix}_{stem}_update({st} *state, const {real} z[{nz}])",
        "{",
        "    if (state == NULL) return GT_BAD_ARGUMENT;",
        "    /* the step writes its outputs only on GT_OK (computed in its own work arrays first) */",
        f"    return {prefix}_{name}(state->x, state->P, z, state->x, state->P);",
        "}",
        "",
    ]
