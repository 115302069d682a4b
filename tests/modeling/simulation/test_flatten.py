"""Tests of the messages of gtmodel.modeling.simulation.flatten: structural errors name equations and variables.

``flatten()`` and ``Optimization`` (which flattens) give the one message of the structural
check (:func:`gtmodel.modeling.structure.analysis.check_structure`, as ``simulate()`` and
``structural_simplify`` do) for a model that is over- or under-determined or structurally
singular, and blame the index only on a structurally regular model (Pantelides' test on
the model, independent of the flattening's own checks).
"""

from __future__ import annotations

import pytest

from gtmodel.errors import ModelError
from gtmodel.modeling import Model, Optimization, check_structure

from ..structure._dae_builders import cartesian_pendulum


def _under():
    m = Model("under")
    x = m.state("x")
    y = m.algebraic("y")
    m.algebraic("z")  # in no equation
    m.equation(m.der(x), -x, name="decay")
    m.equation(y, x, name="copy")
    return m


def _over():
    m = Model("over")
    x = m.state("x")
    m.equation(m.der(x), -x, name="decay")
    m.equation(x, 1.0, name="pinned")
    return m


def _singular():
    """As many equations as unknowns, but a is fixed twice and b by none: no index reduction helps."""
    m = Model("singular")
    x = m.state("x")
    a = m.algebraic("a")
    b = m.algebraic("b")
    m.equation(m.der(x), -x + b, name="decay")
    m.equation(a, 1.0, name="a_one")
    m.equation(a**2, 1.0, name="a_squared")
    return m


def _singular_states():
    """Two states, x fixed twice (by its ODE and a constraint), y by nothing: structurally singular."""
    m = Model("dependent")
    x = m.state("x")
    m.state("y")
    m.equation(m.der(x), -x, name="decay")
    m.equation(x, 1.0, name="pinned")
    return m


FLATTENS = {"flatten": lambda m: m.flatten(), "Optimization": lambda m: Optimization(m).flat()}


@pytest.mark.parametrize("how", sorted(FLATTENS))
@pytest.mark.parametrize(
    "build, match",
    [
        # flatten() words the count; Optimization (which reduces a model as simulate() does) gives the structural check's words
        (_under, r"model 'under' (has 2 scalar equations but 1 states \+ 2 algebraic variables = 3 unknowns "
                 r"\(under-determined\)|is under-determined \(2 scalar equations, 3 unknowns\)); variables \['z'\] are under-determined"),
        (_over, r"model 'over' (has 2 scalar equations .* \(over-determined\)|is over-determined \(2 scalar equations, 1 unknowns\)); "
                r"equations \['decay', 'pinned'\] over-determine variables \['x'\]"),
        (_singular, r"model 'singular' is structurally singular .* equations \['a_one', 'a_squared'\] over-determine "
                    r"variables \['a'\].*\['x', 'b'\] are under-determined"),
        (_singular_states, r"model 'dependent' is structurally singular .* equations \['decay', 'pinned'\] over-determine "
                           r"variables \['x'\].*\['y'\] are under-determined"),
    ],
    ids=["under", "over", "singular", "singular_states"],
)
def test_structural_errors_name_equations_and_variables(build, match, how):
    with pytest.raises(ModelError, match=match) as err:
        FLATTENS[how](build())
    assert "index" not in str(err.value) and "structural_simplify" not in str(err.value)  # never blamed on the index
    with pytest.raises(ModelError) as same:  # the same diagnosis as the structural check's (simulate())
        check_structure(build())
    assert str(same.value).split("; ", 1)[-1] in str(err.value)


def test_a_high_index_model_is_blamed_on_its_index_naming_the_equations():
    # the pendulum passes the structural check (Pantelides' test): its index is the trouble
    check_structure(cartesian_pendulum())
    with pytest.raises(ModelError, match=r"the algebraic equations \['length'\] are not solvable for the algebraic "
                                         r"variables \['lam'\] \(not index 1\).*structural_simplify"):
        cartesian_pendulum().flatten()


def test_optimization_reduces_a_high_index_model_as_simulate_does():
    # Optimization takes the model as written: the index-3 pendulum flattens after reduction
    opt = Optimization(cartesian_pendulum())
    assert opt.flat().x_names == ["y", "v"] and opt.user_model is not opt.model  # two states left of four (dummy derivatives)
