"""The unit of a time derivative (gtmodel.modeling.units.derivative_unit).

Reference: each row is derived by hand, unit / s^order with the exponents of equal symbols
added, written as the Modelica Standard Library writes its units (``rad/s2``, ``N.m``,
``N/(m.s)``; SIunits of MSL 4: AngularAcceleration "rad/s2", Jerk "m/s3").
"""

from __future__ import annotations

import pytest

from gtmodel.errors import GtModelError, InputError
from gtmodel.modeling.units import derivative_unit

#: (unit, order, the derivative's unit by hand)
DERIVATIVES = [
    ("A", 1, "A/s"),  # di/dt of an inductor's current
    ("rad", 1, "rad/s"),  # angle -> angular velocity
    ("rad", 2, "rad/s2"),  # angle -> angular acceleration
    ("rad/s", 1, "rad/s2"),  # angular velocity -> angular acceleration
    ("m", 1, "m/s"),
    ("m/s", 1, "m/s2"),
    ("m/s2", 1, "m/s3"),  # acceleration -> jerk
    ("m/s^2", 1, "m/s3"),  # the caret exponent read, written back in Modelica's form
    ("1", 1, "1/s"),  # a dimensionless quantity's rate
    ("1", 2, "1/s2"),
    ("s", 1, "1"),  # a time's rate is dimensionless
    ("s", 2, "1/s"),
    ("N.m", 1, "N.m/s"),
    ("N/m", 1, "N/(m.s)"),  # several factors below the line: in parentheses
    ("N.s/m", 1, "N/m"),  # s cancels
    ("N.s/m", 2, "N/(m.s)"),
    ("N.m.s/rad", 1, "N.m/rad"),
    ("N m/rad", 1, "N.m/(rad.s)"),  # a space-joined product read too
    ("kg.m2", 1, "kg.m2/s"),
    ("1/s", 1, "1/s2"),
    ("Hz", 1, "Hz/s"),  # symbols are not converted into each other
    ("mg/(kg.d)", 1, "mg/(kg.d.s)"),
    ("V", 0, "V"),  # order 0: the unit itself
]


@pytest.mark.parametrize("unit, order, expected", DERIVATIVES, ids=[f"{u}-{o}" for u, o, _ in DERIVATIVES])
def test_the_derivative_unit_is_the_unit_per_second_to_the_order(unit, order, expected):
    assert derivative_unit(unit, order) == expected


#: Not a product of powers of unit symbols (or no unit at all): no unit is made up.
NOT_UNITS = ["", "m, rad", "m (max over the links)", "/s", "m//s", "m/", "2 m"]


@pytest.mark.parametrize("unit", NOT_UNITS)
def test_a_unit_that_is_not_a_product_of_symbols_gives_no_derivative_unit(unit):
    assert derivative_unit(unit) == ""


@pytest.mark.parametrize("order", [-1, 1.5, True, "1"])
def test_a_bad_order_is_an_input_error(order):
    with pytest.raises(InputError, match="order must be an integer >= 0") as info:
        derivative_unit("m", order)
    assert isinstance(info.value, GtModelError)
