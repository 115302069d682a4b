"""Emitting the KF/EKF steps of the tracker + IMU fusion: state struct, ``_init`` and ``_update``.

The step functions themselves are wrappers of their CasADi Functions like every other
(declared by :func:`gtmodel.codegen.specs.filter.filter_spec`); this fragment adds the
caller-owned state struct ``<prefix>_<stem>_state`` and the two functions that keep the
state in it, from the template files ``harness/template_filter_state.h``/``.c``.
"""

from __future__ import annotations

import casadi as ca

from gtmodel.codegen.emit import Fragment, fill
from gtmodel.codegen.specs.filter import filter_sizes

__all__ = ["filter_fragment"]


def _values(prefix: str, name: str, f: ca.Function, real: str) -> dict[str, object]:
    """The markers of the filter templates."""
    nx, nz = filter_sizes(f)
    stem = name[:-5]
    return {"PREFIX": prefix, "NAME": name, "STEM": stem, "STEM_U": stem.upper(), "M": f"{prefix.upper()}_{stem.upper()}",
            "ST": f"{prefix}_{stem}_state", "REAL": real, "NX": nx, "NZ": nz, "NX2": nx * nx, "NPIVOTS": nz + nx}


def filter_fragment(prefix: str, name: str, f: ca.Function, real: str) -> Fragment:
    """One filter step's state functions as a fragment (its spec is the controller's).

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
    Fragment
        Header: sizes, the state struct, the ``_init`` and ``_update`` prototypes
        (``template_filter_state.h``); source: their definitions (``template_filter_state.c``).
    """
    values = _values(prefix, name, f, real)
    return Fragment(tuple(fill("template_filter_state.h", **values).splitlines()),
                    tuple(fill("template_filter_state.c", **values).splitlines()))
