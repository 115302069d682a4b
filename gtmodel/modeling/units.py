"""Units of a model's variables: the unit of a time derivative, written in Modelica's unit syntax.

A unit is a string in the syntax of the Modelica Language Specification (sec. 19.2), as the
component library writes them: factors joined by ``.``, an integer exponent after a factor
(``m/s2``, ``kg.m2``), one ``/`` and a denominator in parentheses when it has several factors
(``N/(m.s)``), ``"1"`` for a dimensionless quantity. :func:`derivative_unit` gives the unit of
``der(x)`` from the unit of ``x``: the index reduction names the derivatives it keeps as
variables (``der_ind_i``, ``der2_load_phi``) and gives them this unit.
"""

from __future__ import annotations

import re

from gtmodel.errors import InputError

__all__ = ["derivative_unit"]

#: One factor: a unit symbol (``m``, ``rad``, ``Ohm``) and an optional integer exponent,
#: Modelica's ``s2``/``m-1`` or the caret form ``s^2`` (read, written back as ``s2``).
_FACTOR = re.compile(r"([A-Za-z_]+)(?:\^?(-?\d+))?")


def _factors(text: str) -> list[tuple[str, int]] | None:
    """``text`` (factors joined by ``.``, ``*`` or spaces) as ``(symbol, exponent)`` pairs; None if it is not that."""
    text = text.strip()
    if text.startswith("(") and text.endswith(")"):
        text = text[1:-1].strip()
    if text == "1":
        return []
    out = []
    for part in re.split(r"[.*\s]+", text):
        m = _FACTOR.fullmatch(part)
        if not m:
            return None
        out.append((m.group(1), int(m.group(2) or 1)))
    return out


def _exponents(unit: str) -> dict[str, int] | None:
    """The net exponent of each symbol of ``unit`` (in order of appearance); None if ``unit`` is not parsed."""
    net: dict[str, int] = {}
    for k, part in enumerate(unit.split("/")):
        factors = _factors(part)
        if factors is None or (k > 0 and not part.strip()):
            return None
        for sym, e in factors:
            net[sym] = net.get(sym, 0) + (e if k == 0 else -e)
    return net


def _written(net: dict[str, int]) -> str:
    """Net exponents as a Modelica unit string: ``"rad/s2"``, ``"N/(m.s)"``, ``"1/s"``, ``"1"``.

    The factors keep their order of appearance, the second last in a denominator."""

    def factor(sym: str, e: int) -> str:
        return sym if e == 1 else f"{sym}{e}"

    num = ".".join(factor(s, e) for s, e in net.items() if e > 0) or "1"
    den = [factor(s, -e) for s, e in sorted(net.items(), key=lambda item: item[0] == "s") if e < 0]  # the second last
    if not den:
        return num
    return f"{num}/{den[0]}" if len(den) == 1 else f"{num}/({'.'.join(den)})"


def derivative_unit(unit: str, order: int = 1) -> str:
    """The unit of the ``order``-th time derivative of a variable of unit ``unit``: ``unit / s^order``.

    The exponents of equal symbols are added (``N.s/m`` gives ``N/m``, ``s`` gives ``"1"``);
    symbols are not converted into each other (``Hz`` stays ``Hz/s``, not ``1/s2``).

    Parameters
    ----------
    unit : str
        The variable's unit in Modelica's syntax (``"A"``, ``"rad/s"``, ``"N.m"``, ``"1"``);
        the caret exponent ``"m/s^2"`` is read too.
    order : int, optional
        The order of the derivative, >= 0 (default 1; 0 gives ``unit`` back).

    Returns
    -------
    str
        The derivative's unit in Modelica's syntax (``"A/s"``, ``"rad/s2"``, ``"N.m/s"``,
        ``"N/(m.s)"``, ``"1/s"``); ``""`` (no unit) when ``unit`` is empty or not a product
        of powers of unit symbols (e.g. ``"m, rad"``): no unit is made up.

    Raises
    ------
    InputError
        If ``order`` is not an integer >= 0.

    Examples
    --------
    >>> derivative_unit("A")
    'A/s'
    >>> derivative_unit("rad/s")
    'rad/s2'
    >>> derivative_unit("rad", order=2)
    'rad/s2'
    >>> derivative_unit("N.s/m")
    'N/m'
    """
    if isinstance(order, bool) or not isinstance(order, int) or order < 0:
        raise InputError(f"derivative_unit: order must be an integer >= 0, got {order!r}")
    if order == 0 or not unit:
        return unit
    net = _exponents(unit)
    if net is None:
        return ""
    net["s"] = net.get("s", 0) - order
    return _written(net)
