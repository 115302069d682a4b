"""Smoothing widths declared on components (``Parameter(..., smoothing=True)``) reach ``Model.smoothing``.

Independent check: the expected names are the hierarchical names written out by hand
from the class declarations below.
"""

from __future__ import annotations

import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Component, connect
from gtmodel.modeling.components.declarations import Parameter
from gtmodel.modeling.library import translational as tr


class SoftSpring(tr.PartialCompliant):
    """A linear spring that declares a width (its law does not use it: the test needs only the flag)."""

    c = Parameter(10.0, unit="N/m", description="spring constant")
    eps = Parameter(1e-3, unit="m", description="declared width", smoothing=True)

    def equations(self):
        super().equations()
        self.equation(self.f, self.c * self.s_rel + 0.0 * self.eps, name="law")


class Chain(Component):
    """fixed -- soft spring -- mass -- soft spring (its width bound to the chain's) -- mass."""

    gains = Parameter([1.0, 2.0], description="a vector parameter declared before the width (not a width)")
    width = Parameter(2e-3, unit="m", description="one width for the second spring")
    fixed = tr.Fixed()
    s1 = SoftSpring()
    m1 = tr.Mass(m=1.0, s=0.1)
    s2 = SoftSpring(eps=width)
    m2 = tr.Mass(m=1.0)

    def equations(self):
        connect(self.fixed.flange, self.s1.flange_a)
        connect(self.s1.flange_b, self.m1.flange_a)
        connect(self.m1.flange_b, self.s2.flange_a)
        connect(self.s2.flange_b, self.m2.flange_a)


def test_declared_widths_are_listed_by_hierarchical_name():
    # by hand: s1.eps is declared; s2.eps is bound to the chain's ``width``, which becomes a width
    assert Chain().to_model().smoothing == {"width": 2e-3, "s1.eps": 1e-3}


def test_a_modifier_sets_the_listed_value():
    assert Chain(s1={"eps": 5e-4}).to_model().smoothing["s1.eps"] == 5e-4


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"s1": {"eps": 0.0}}, "smoothing width must be one number > 0"),
        ({"s1": {"eps": -1e-3}}, "smoothing width must be one number > 0"),
        ({"width": -1.0}, "smoothing width must be one number > 0"),
    ],
)
def test_a_width_that_is_not_positive_is_refused(kwargs, match):
    # s1.eps is checked when the component is built; ``width`` only becomes a width by the
    # binding, so it is checked when the tree is flattened
    with pytest.raises((InputError, ModelError), match=match):
        Chain(**kwargs).to_model()


@pytest.mark.parametrize(
    ("default", "kwargs", "match"),
    [
        (0.0, {}, "smoothing width must be one number > 0"),
        (1e-3, {"shape": 2}, "a smoothing width is one number"),
        (1e-3, {"smoothing": 1}, "expected True or False"),
    ],
)
def test_bad_declarations_are_refused(default, kwargs, match):
    with pytest.raises(InputError, match=match):
        Parameter(default, **({"smoothing": True} | kwargs))
