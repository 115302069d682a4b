"""Suggestions for a mistyped name: the model's close names, the Modelica Standard Library's first.

Used where a problem names a variable the model does not have (the problem files' tables,
:mod:`gtmodel.problems.kinds.optimal_control`; the expression language,
:mod:`gtmodel.modeling.ocp.expressions`).
"""

from __future__ import annotations

import difflib
from collections.abc import Collection

__all__ = ["close_names", "MSL_NAMES"]

#: Names a user writes for a variable that the Modelica Standard Library (and so the library's
#: components) calls otherwise: last part of a dotted name -> the MSL's (``link.omega`` is ``link.w``).
MSL_NAMES: dict[str, str] = {
    "omega": "w", "theta": "phi", "angle": "phi", "speed": "w", "angular_velocity": "w", "alpha": "a",
    "acceleration": "a", "torque": "tau", "position": "s", "x": "s", "velocity": "v", "force": "f",
    "current": "i", "voltage": "v", "inertia": "J", "mass": "m",
}


def close_names(name: str, known: Collection[str], n: int = 4) -> list[str]:
    """Known names a mistyped one likely means, best first.

    A name whose last part is another library's word for an MSL variable (``omega``,
    ``theta``, ``torque``, ...: :data:`MSL_NAMES`) first suggests the MSL name on the same path
    (``link.omega`` -> ``link.w``); then the closest by :func:`difflib.get_close_matches`.

    Parameters
    ----------
    name : str
        The unknown name.
    known : collection of str
        The names that exist.
    n : int, optional
        At most this many suggestions (default 4).

    Returns
    -------
    list of str
        Suggestions, possibly empty.
    """
    known = set(known)
    head, _, last = str(name).rpartition(".")
    msl = MSL_NAMES.get(last.lower())
    out = [f"{head}.{msl}" if head else msl] if msl and (f"{head}.{msl}" if head else msl) in known else []
    ranked = sorted(difflib.get_close_matches(str(name), sorted(known), n=n),
                    key=lambda c: (-difflib.SequenceMatcher(None, str(name), c).ratio(), c))
    return (out + [c for c in ranked if c not in out])[:n]
