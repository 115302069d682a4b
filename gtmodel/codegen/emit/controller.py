"""Emitting the controller of the 4 ms loop: sample time, Kalman state functions, ILC sizes, filters.

The controller's functions (``kalman_step``, ``ilc_correction``, ``kf_step``,
``ekf_step``) are wrappers of their CasADi Functions like the robot's (declared by
:meth:`gtmodel.codegen.controller.Controller.specs`); this fragment adds the sizes, the
sample time and the caller-owned state structs with their ``_init``/``_update`` functions,
from the template files ``harness/template_controller.h``, ``template_kalman_state.h``/``.c``,
``template_ilc.h`` and those of :mod:`gtmodel.codegen.emit.filter`.
"""

from __future__ import annotations

from gtmodel.codegen.controller import Controller
from gtmodel.codegen.emit import Fragment, c_float, fill
from gtmodel.codegen.emit.filter import filter_fragment
from gtmodel.codegen.emit.lead_through import lead_through_fragment

__all__ = ["controller_fragment"]


def _kalman_values(prefix: str, controller: Controller, real: str) -> dict[str, object]:
    nx, ny, nz = controller.kalman_sizes
    return {"PREFIX": prefix, "M": prefix.upper(), "REAL": real, "NX": nx, "NY": ny, "NZ": nz}


def _filters(prefix: str, controller: Controller, real: str) -> Fragment:
    """The filters' and the lead-through step's state functions."""
    parts = [filter_fragment(prefix, name, getattr(controller, name), real) for name in controller.filter_sizes]
    if controller.lead_through_step is not None:
        parts.append(lead_through_fragment(prefix, real))
    return Fragment.join(parts)


def _header_lines(prefix: str, controller: Controller, real: str) -> list[str]:
    """Sizes, sample time, the Kalman and filter state structs (after the prototypes)."""
    M = prefix.upper()
    out = fill("template_controller.h", M=M, DT=c_float(controller.dt)).splitlines()
    if controller.kalman_step is not None:
        out += fill("template_kalman_state.h", **_kalman_values(prefix, controller, real)).splitlines()
    if controller.ilc_correction is not None:
        out += fill("template_ilc.h", M=M, LENGTH=controller.ilc_length, D=controller.ilc_d).splitlines()
    return out + list(_filters(prefix, controller, real).header)


def _source_lines(prefix: str, controller: Controller, real: str) -> list[str]:
    """``<prefix>_kalman_init``/``_update`` and the filters' ``_init``/``_update`` (may be empty)."""
    out = [] if controller.kalman_step is None else fill("template_kalman_state.c", **_kalman_values(prefix, controller, real)).splitlines()
    return out + list(_filters(prefix, controller, real).source)


def controller_fragment(prefix: str, controller: Controller, real: str) -> Fragment:
    """The controller as a fragment of the library: its header and source lines and its specs.

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
    Fragment
        Header: sizes, the sample time ``<PREFIX>_CONTROLLER_DT``, the Kalman, ILC and filter
        state structs; source: ``<prefix>_kalman_init``/``_update`` and the filters'
        ``_init``/``_update`` (``<prefix>_kf_*``, ``<prefix>_ekf_*``); specs:
        :meth:`Controller.specs <gtmodel.codegen.controller.Controller.specs>`.
    """
    return Fragment(tuple(_header_lines(prefix, controller, real)), tuple(_source_lines(prefix, controller, real)), controller.specs())
