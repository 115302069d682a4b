"""Declaration of the lead-through controller step as generated C (Dressler (2012), ch. 8).

The step is the CasADi Function of :meth:`gtmodel.estimation.lead_through.LeadThroughLaw.step_function`
(the ONE graph of the Python controller, nothing is rebuilt here)::

    "lead_through_step"(x[8], F_h[6], F_t[6], n_n[3]) -> (x_next[8], V_tool[6], n[3], valid)

The generated library has (``<P>`` the upper-case prefix)

``int <prefix>_lead_through_step(const double x[8], const double F_h[6], const double F_t[6], const double n_n[3], double x_next[8], double V_tool[6], double n[3])``
    One 4 ms step of the law (eqs. 8.3-8.11): from the state ``x = [V_h (6); contact;
    release]`` and the handle and tool wrenches ``[N; N m]`` (base frame, the tool wrench
    being what the tool exerts on the workpiece) and the nominal normal ``n_n`` (unit,
    into the workpiece) to the next state, the tool velocity reference ``V_tool`` ``[m/s;
    rad/s]`` to apply and the normal ``n`` used. ``x_next`` may alias ``x``. Returns
    ``GT_OK``; ``GT_BAD_ARGUMENT`` for a NULL pointer, a NaN/Inf wrench or state, or an
    ``n_n`` whose norm differs from 1 by more than ``NORMAL_TOLERANCE`` (1e-6); the
    outputs are then not written.
``typedef struct <prefix>_lead_through_state { double x[8]; } <prefix>_lead_through_state;``
    The controller state, owned by the caller (no heap), with
    ``<prefix>_lead_through_init(&state)`` (at rest, no contact) and
    ``<prefix>_lead_through_update(&state, F_h, F_t, n_n, V_tool, n)`` (the state is
    replaced only on ``GT_OK``), emitted by :mod:`gtmodel.codegen.emit.lead_through`.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from gtmodel.codegen.declarations import ArgSpec, FunctionSpec, OutputSpec, StatusCheck
from gtmodel.errors import InputError

__all__ = ["LEAD_THROUGH_INPUTS", "LEAD_THROUGH_OUTPUTS", "LEAD_THROUGH_SIZES", "LEAD_THROUGH_TOLERANCE",
           "check_lead_through_function", "lead_through_spec"]

#: Inputs and outputs of the step Function, in order.
LEAD_THROUGH_INPUTS, LEAD_THROUGH_OUTPUTS = ("x", "F_h", "F_t", "n_n"), ("x_next", "V_tool", "n", "valid")
#: Their sizes.
LEAD_THROUGH_SIZES = {"x": 8, "F_h": 6, "F_t": 6, "n_n": 3, "x_next": 8, "V_tool": 6, "n": 3, "valid": 1}
#: Largest accepted ``|C - Python|`` of a state or output element.
LEAD_THROUGH_TOLERANCE = 1e-12


def check_lead_through_function(f: Any, where: str = "lead_through_step") -> None:
    """Validate a lead-through step Function (names and sizes of :data:`LEAD_THROUGH_SIZES`).

    Parameters
    ----------
    f : casadi.Function
        The step.
    where : str, optional
        Argument name for the messages.

    Raises
    ------
    InputError
        Not a ``casadi.Function``, other names, or an input or output that is not a dense
        column of its size.
    """
    if not isinstance(f, ca.Function):
        raise InputError(f"{where}: expected a casadi.Function, got {type(f).__name__}")
    if tuple(f.name_in()) != LEAD_THROUGH_INPUTS or tuple(f.name_out()) != LEAD_THROUGH_OUTPUTS:
        raise InputError(f"{where}: expected a casadi.Function ({', '.join(LEAD_THROUGH_INPUTS)}) -> "
                         f"({', '.join(LEAD_THROUGH_OUTPUTS)}), got ({', '.join(f.name_in())}) -> ({', '.join(f.name_out())})")
    for name, size in LEAD_THROUGH_SIZES.items():
        sp = f.sparsity_in(name) if name in LEAD_THROUGH_INPUTS else f.sparsity_out(name)
        if (sp.size1(), sp.size2()) != (size, 1) or not sp.is_dense():
            raise InputError(f"{where}: {name!r} must be a dense {size}x1 column, is {sp.size1()}x{sp.size2()}")


def lead_through_spec(f: ca.Function, kind: str) -> FunctionSpec:
    """Declaration of the generated ``<prefix>_lead_through_step``.

    Parameters
    ----------
    f : casadi.Function
        The step (:func:`check_lead_through_function`).
    kind : str
        ``FunctionSpec.kind`` (the controller kind).

    Returns
    -------
    FunctionSpec
        Arguments ``x``, ``F_h``, ``F_t``, ``n_n``; outputs ``x_next``, ``V_tool``, ``n``;
        ``GT_BAD_ARGUMENT`` unless ``valid >= 0`` (a unit ``n_n``).
    """
    return FunctionSpec(
        name="lead_through_step",
        build=lambda model, f=f: f,
        args=(
            ArgSpec("x", "vector", "x", "controller state [V_h (6) m/s, rad/s; contact 0/1; release 0/1]"),
            ArgSpec("F_h", "vector", "F_h", "handle wrench [N; N m], base frame"),
            ArgSpec("F_t", "vector", "F_t", "tool wrench on the workpiece [N; N m], base frame"),
            ArgSpec("n_n", "vector", "n_n", "nominal normal into the workpiece (unit)"),
        ),
        outputs=(
            OutputSpec("x_next", "x_next", "next controller state (may be x: in-place)"),
            OutputSpec("V_tool", "V_tool", "tool velocity reference to apply [m/s; rad/s], eq. 8.3"),
            OutputSpec("n", "n", "contact normal used, eq. 8.10 (unit)"),
        ),
        checks=(StatusCheck("valid", ">=", "0", "GT_BAD_ARGUMENT"),),
        doc=("One step of the two-sensor lead-through controller, Dressler (2012), eqs. 8.3-8.11: handle impedance "
             "without position term (8.5-8.7), tool force P control (8.4), contact-state projections, normal estimate "
             "within the correction range (8.10), safety saturation. GT_BAD_ARGUMENT for a NaN/Inf wrench or state or "
             "an n_n not of unit norm (1e-6). Or keep the state in a <prefix>_lead_through_state with "
             "<prefix>_lead_through_update."),
        tolerance=LEAD_THROUGH_TOLERANCE,
        unit="m/s, rad/s",
        kind=kind,
    )
