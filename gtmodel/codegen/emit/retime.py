"""Emitting the online re-timing function ``<prefix>_retime`` (3-link sets, double precision).

The limits struct and the stack sizes are written here from the model; the two passes are
hand-written C, the template files ``harness/template_retime.h`` and
``harness/template_retime.c`` (the algorithm of
:mod:`gtmodel.trajectory.path_constrained.reachability`, statement by statement and in the
same floating-point operations); the coefficients of the rows come from the
CasADi-generated ``<prefix>_cg_retime_rows`` (:func:`retime_rows_function`). The API and
the Python caller: :mod:`gtmodel.codegen.retime`.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.codegen.emit import Fragment, c_float, fill
from gtmodel.codegen.robot import RobotModel
from gtmodel.errors import InputError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.path_projection import PATH_LIMIT_KINDS, PATH_ROW_COUNTS, PATH_SQUARED_KINDS, path_rows_function

__all__ = [
    "RETIME_FIELDS",
    "RETIME_MAX_N_MAX",
    "ROWS",
    "SIDES",
    "check_retime_n_max",
    "retime_fragment",
    "retime_header_lines",
    "retime_rows_function",
    "retime_source_lines",
]

#: Fields of ``<prefix>_retime_limits`` per limit kind (the kind without ``_limit``), in row order.
RETIME_FIELDS = {kind: kind.removesuffix("_limit") for kind in PATH_LIMIT_KINDS}
#: Largest accepted ``N_MAX`` (a work struct of about 90 MB).
RETIME_MAX_N_MAX = 100_000
#: Number of rows and of one-sided rows (every upper bound, the lower bounds of the two-sided kinds).
ROWS = sum(PATH_ROW_COUNTS.values())
SIDES = ROWS + sum(PATH_ROW_COUNTS[k] for k in PATH_LIMIT_KINDS if k not in PATH_SQUARED_KINDS)
#: Outputs of the generated rows function, in the order the C code feeds them.
ROW_OUTPUTS = ("m", "c", "d", "g", "q", "disc", "cos")
_UNITS = {"force_limit": "N", "cart_velocity_limit": "m/s", "cart_acceleration_limit": "m/s^2",
          "tcp_velocity_limit": "m/s", "tcp_speed_limit": "m/s", "tcp_acceleration_limit": "m/s^2"}
_MEANING = {"force_limit": "|tau_i|, actuator (cart) forces (eqs. 6.7, 6.8)", "cart_velocity_limit": "|q_dot_i|",
            "cart_acceleration_limit": "|q_ddot_i|", "tcp_velocity_limit": "|T_dot_j| per axis",
            "tcp_speed_limit": "||T_dot||", "tcp_acceleration_limit": "|T_ddot_j| per axis"}



def check_retime_n_max(n_max: Any, model: RobotModel, real: str) -> int:
    """Validate the ``N_MAX`` of the re-timing function for a model.

    Parameters
    ----------
    n_max : int
        Largest number of grid points, 2 .. :data:`RETIME_MAX_N_MAX`.
    model : RobotModel
        The model (a 3-link parameter set).
    real : str
        Floating-point type of the library (``"double"`` only).

    Returns
    -------
    int
        ``n_max``.

    Raises
    ------
    InputError
        Not an integer in range, a robot that is not a 3-link set, or single precision.
    """
    if isinstance(n_max, bool) or not isinstance(n_max, (int, np.integer)) or not 2 <= n_max <= RETIME_MAX_N_MAX:
        raise InputError(f"retime_n_max: expected an integer from 2 to {RETIME_MAX_N_MAX} (grid points), got {n_max!r}")
    if model.kind != "three_link":
        raise InputError(f"retime_n_max: the re-timing function needs a 3-link parameter set (inverse dynamics), not a {model.kind} model")
    if real != "double":
        raise InputError("retime_n_max: the re-timing function is generated in double precision only (real='double')")
    return int(n_max)


def retime_rows_function(model: RobotModel, name: str) -> ca.Function:
    """The CasADi Function of the row coefficients the C re-timing evaluates, named ``name``.

    :func:`~gtmodel.robots.path_projection.path_rows_function` of the model with the exact
    Coulomb sign, every limit kind and viscous friction (the C zeroes ``d`` when
    ``viscous_friction`` is 0, as the Python solver's Function without it), restricted to
    the outputs :data:`ROW_OUTPUTS`, common subexpressions merged (same operations, the
    same values).

    Parameters
    ----------
    model : RobotModel
        A 3-link model.
    name : str
        Function (C symbol) name.

    Returns
    -------
    casadi.Function
        ``name(T, dT, ddT, sg) -> (m, c, d, g, q, disc, cos)``.
    """
    dyn = GantryTau3Dynamics(model.parameters, friction="exact")
    f = path_rows_function(dyn, PATH_LIMIT_KINDS, viscous=True)
    ins = f.sx_in()
    outs = dict(zip(f.name_out(), f.call(ins)))
    return ca.Function(name, ins, ca.cse([ca.densify(outs[k]) for k in ROW_OUTPUTS]), f.name_in(), list(ROW_OUTPUTS))


def _fields() -> list[tuple[str, str, int]]:
    """``(kind, C field, size)`` in row order."""
    return [(k, RETIME_FIELDS[k], PATH_ROW_COUNTS[k]) for k in PATH_LIMIT_KINDS]


def retime_header_lines(prefix: str, n_max: int, sizes: tuple[int, int, int, int]) -> list[str]:
    """Header declarations of the re-timing function: sizes, limits, work and info structs, prototypes.

    Parameters
    ----------
    prefix : str
        C prefix (``gt_L1``).
    n_max : int
        ``<PREFIX>_RETIME_N_MAX``.
    sizes : tuple of int
        ``(sz_arg, sz_res, sz_iw, sz_w)`` of the generated rows function (for the stack use).

    Returns
    -------
    list of str
        Lines placed after the function prototypes of the header.
    """
    P, U = prefix, prefix.upper()
    out = [
        "/* ---- Online re-timing along a path (Dressler (2012), ch. 3.5; Verscheure et al. (2009); TOPP-RA) ---- */",
        "/* Largest number of grid points (generation option --retime-n-max), rows, one-sided rows. */",
        f"#define {U}_RETIME_N_MAX {n_max}",
        f"#define {U}_RETIME_ROWS {ROWS}",
        f"#define {U}_RETIME_SIDES {SIDES}",
        "",
        "/* Limits of the re-timing: a bound on a magnitude per row, INFINITY for none (at least one finite).",
        f" * Initialise with {P}_retime_limits_init. */",
        f"typedef struct {P}_retime_limits {{",
    ]
    for kind, name, size in _fields():
        decl = f"double {name}[{size}];" if size > 1 else f"double {name};"
        out.append(f"    {decl:<28}/* {_MEANING[kind]} [{_UNITS[kind]}] */")
    out += [
        "    int viscous_friction;       /* 1: the model's viscous friction in the force rows (default), 0: without */",
        "    int constrain_end;          /* 1: rows with s_ddot also at the last point (default), 0: TOPP-RA's scheme */",
        f"}} {P}_retime_limits;",
    ]
    stack = 8 * (sum(sizes) + 7 * ROWS + SIDES * SIDES + 3 * SIDES + 64)  # work arrays, coefficients, pair sets
    out += fill("template_retime.h", P=P, U=U, STACK=stack).splitlines()
    return out + [""]


def retime_source_lines(prefix: str, model: RobotModel, sizes: tuple[int, int, int, int]) -> list[str]:
    """Source of the re-timing function: the model's limits as constants and the two passes.

    Parameters
    ----------
    prefix : str
        C prefix.
    model : RobotModel
        The 3-link model (cart travel and joint-angle limits of the workspace checks).
    sizes : tuple of int
        ``(sz_arg, sz_res, sz_iw, sz_w)`` of the generated rows function.

    Returns
    -------
    list of str
        C lines appended to the wrapper source.
    """
    P, U = prefix, prefix.upper()
    lim = model.parameters.limits
    travel = np.asarray(lim.cart_travel, dtype=float)
    squared = []
    init, rows = [], []
    j = 0
    for kind, name, size in _fields():
        for i in range(size):
            ref = f"limits->{name}[{i}]" if size > 1 else f"limits->{name}"
            init.append(f"    {ref} = INFINITY;")
            rows.append(f"    lim[{j}] = {ref};")
            squared.append("1" if kind in PATH_SQUARED_KINDS else "0")
            j += 1
    head = [
        "",
        f"/* Stack work-array sizes of {P}_cg_retime_rows (at least 1). */",
        f"#define {U}_RETIME_SZ_ARG {max(sizes[0], 1)}",
        f"#define {U}_RETIME_SZ_RES {max(sizes[1], 1)}",
        f"#define {U}_RETIME_SZ_IW {max(sizes[2], 1)}",
        f"#define {U}_RETIME_SZ_W {max(sizes[3], 1)}",
        "/* Workspace of the model (RobotParameters.limits): cart travel [m], cos of the largest joint angle. */",
        f"static const double {P}_retime_travel[3][2] = {{"
        + ", ".join(f"{{{c_float(a)}, {c_float(b)}}}" for a, b in travel) + "};",
        f"#define {U}_RETIME_COS_JOINT_MAX {c_float(float(np.cos(lim.joint_angle_max)))}",
        "/* Rows bounded by the squared limit on one side (velocities), the others on both sides. */",
        f"static const unsigned char {P}_retime_squared[{ROWS}] = {{{', '.join(squared)}}};",
    ]
    return head + fill("template_retime.c", INIT_LIMITS="\n".join(init), ROW_LIMITS="\n".join(rows), P=P, U=U, R=ROWS).splitlines()


def retime_fragment(prefix: str, model: RobotModel, n_max: int, sizes: tuple[int, int, int, int]) -> Fragment:
    """The re-timing function as a fragment of the library (no CasADi Function of its own to declare).

    Parameters
    ----------
    prefix : str
        C prefix (``gt_L1``).
    model : RobotModel
        The 3-link model.
    n_max : int
        ``<PREFIX>_RETIME_N_MAX``.
    sizes : tuple of int
        ``(sz_arg, sz_res, sz_iw, sz_w)`` of the generated rows function.

    Returns
    -------
    Fragment
        :func:`retime_header_lines` and :func:`retime_source_lines`.
    """
    return Fragment(tuple(retime_header_lines(prefix, n_max, sizes)), tuple(retime_source_lines(prefix, model, sizes)))
