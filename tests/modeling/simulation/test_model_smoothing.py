"""Smoothing widths declared on a Model (``Model.parameter(..., smoothing=True)``, ``Model.smoothing``).

Independent check: the expected dictionaries are written out by hand from the declarations;
the structural passes are checked on models they really rebuild (a new object, not the input).
"""

from __future__ import annotations

import casadi as ca
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling import Model
from gtmodel.modeling.structure.discontinuities import sign_modes
from gtmodel.modeling.structure.index_reduction import structural_simplify


def _mass_with_alias() -> Model:
    """A mass with a position alias (``s2 = s``): structural_simplify rebuilds it."""
    m = Model("alias")
    m.parameter("k", 2.0)
    m.parameter("v_eps", 0.05, smoothing=True)
    m.parameter("b_eps", 1e-4, smoothing=True)
    s, v = m.state("s", start=1.0), m.state("v")
    s2 = m.algebraic("s2")
    m.equation(m.der(s), v)
    m.equation(m.der(v), -m.variables("parameter")["k"] * s2)
    m.equation(s2, s)
    return m


def test_smoothing_lists_the_widths_in_declaration_order():
    # by hand: two widths, declared in this order, the other parameter left out
    assert _mass_with_alias().smoothing == {"v_eps": 0.05, "b_eps": 1e-4}


def test_a_model_without_widths_has_an_empty_smoothing():
    m = Model("plain")
    m.parameter("k", 1.0)
    assert m.smoothing == {}


def test_smoothing_survives_structural_simplify():
    # the alias equation makes structural_simplify build a new model (checked: not the same object)
    m = _mass_with_alias()
    reduced = structural_simplify(m)
    assert reduced is not m
    assert reduced.smoothing == {"v_eps": 0.05, "b_eps": 1e-4}


def test_smoothing_survives_the_sign_rewrite():
    # sign_modes copies the model and adds a mode parameter (not a width)
    m = _mass_with_alias()
    v = m.variables("state")["v"]
    m.output("coulomb", m.variables("parameter")["v_eps"] * ca.sign(v))
    copy = sign_modes(m)
    assert copy is not None and copy is not m
    assert copy.smoothing == {"v_eps": 0.05, "b_eps": 1e-4}


@pytest.mark.parametrize(
    ("value", "kwargs", "match"),
    [
        (0.0, {}, "smoothing width must be > 0"),
        (-1e-3, {}, "smoothing width must be > 0"),
        ([0.1, 0.2], {}, "smoothing width one number"),
        (0.1, {"shape": 2}, "smoothing width one number"),
        ("a", {}, "numeric"),
    ],
)
def test_bad_widths_are_refused(value, kwargs, match):
    with pytest.raises(InputError, match=match):
        Model("m").parameter("eps", value, smoothing=True, **kwargs)


def test_smoothing_flag_must_be_a_bool():
    with pytest.raises(InputError, match="smoothing must be True or False"):
        Model("m").parameter("eps", 0.1, smoothing="yes")


def test_check_parameter_refuses_a_width_that_is_not_positive():
    # an override of a width (a solver's continuation, a problem file) goes through check_parameter
    m = Model("m")
    m.parameter("eps", 0.1, smoothing=True)
    m.check_parameter("eps", 1e-9)  # any positive value passes
    with pytest.raises(InputError, match="'eps': a smoothing width must be > 0, got 0"):
        m.check_parameter("eps", 0.0)
