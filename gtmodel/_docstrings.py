"""Docstring sections written once and shared by several functions (internal helper).

Where several public functions take the same arguments with the same meaning (the pose
arguments of :class:`~gtmodel.robots.stiffness.GantryTau3Stiffness`, the ``load``/
``solve``/``write`` functions of the problem kinds), their numpydoc entries are written once
as a section and inserted into each docstring by :func:`fill_doc`. A line holding only
``{name}`` is replaced by the section ``name``, indented like the placeholder; the result is
a complete numpydoc docstring at run time (``help()``, numpydoc's validator, Sphinx).
"""

from __future__ import annotations

import re
import textwrap
from typing import Callable, TypeVar

_F = TypeVar("_F", bound=Callable)


def fill_doc(**sections: str) -> Callable[[_F], _F]:
    """Decorator: replace each placeholder line ``{name}`` of the docstring by ``sections[name]``.

    Parameters
    ----------
    **sections : str
        Section texts (dedented; several lines), by placeholder name.

    Returns
    -------
    callable
        The decorator; it returns the function itself with the filled ``__doc__``.

    Raises
    ------
    KeyError
        A placeholder line names no section (a mistake in the docstring, found on import).
    """

    def fill(func: _F) -> _F:
        def replace(m: re.Match) -> str:
            return textwrap.indent(textwrap.dedent(sections[m.group(2)]).strip("\n"), m.group(1))

        if func.__doc__ is not None:  # None under python -OO
            func.__doc__ = re.sub(r"^([ \t]*)\{(\w+)\}[ \t]*$", replace, func.__doc__, flags=re.MULTILINE)
        return func

    return fill


#: Sections shared by every subpackage (insert with ``fill_doc(**SHARED_DOCS)``):
#: ``solve_args``, the keyword arguments of every declaration's ``solve`` (the problem kinds
#: call it with them, see :meth:`gtmodel.problems.base.ProblemKind.solve`).
SHARED_DOCS = {
    "solve_args": """
        verbose : bool, optional
            Log the solver's progress.
        previous : Any, optional
            The previous solution of a sweep, reused where the declaration can (the
            motion problems reuse its NLP); ignored otherwise.
        warm_start : bool, optional
            Start from ``previous`` where the declaration can; ignored otherwise.
    """,
}
