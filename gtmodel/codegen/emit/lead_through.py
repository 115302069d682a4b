"""Emitting the lead-through controller step's state struct, ``_init`` and ``_update``.

The step itself is a wrapper of its CasADi Function like every other (declared by
:func:`gtmodel.codegen.specs.lead_through.lead_through_spec`); this fragment adds the
caller-owned state struct ``<prefix>_lead_through_state`` and the two functions that keep
the state in it, from the templates ``harness/template_lead_through_state.h``/``.c``.
"""

from __future__ import annotations

from gtmodel.codegen.emit import Fragment, fill

__all__ = ["lead_through_fragment"]


def lead_through_fragment(prefix: str, real: str) -> Fragment:
    """The lead-through step's state functions as a fragment (its spec is the controller's).

    Parameters
    ----------
    prefix : str
        C prefix (``gt``).
    real : {"double", "float"}
        Floating-point type.

    Returns
    -------
    Fragment
        Header: sizes, the state struct, the ``_init`` and ``_update`` prototypes; source:
        their definitions.
    """
    values = {"PREFIX": prefix, "M": prefix.upper(), "REAL": real}
    return Fragment(tuple(fill("template_lead_through_state.h", **values).splitlines()),
                    tuple(fill("template_lead_through_state.c", **values).splitlines()))
