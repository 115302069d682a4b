"""Tests of Pantelides' algorithm, dummy derivatives and structural_simplify.

References: energy conservation and the position constraint (exact invariants), the same
mechanisms in minimal coordinates (a second formulation, an ODE), closed forms.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import ModelError
from gtmodel.modeling import Model, structural_simplify
from gtmodel.modeling.index_reduction import pantelides, reduced_system, select_dummies
from gtmodel.modeling.structure import eliminate_aliases, scalarize

from ._dae_builders import angle_pendulum, cartesian_pendulum, slider_crank, slider_crank_minimal

RTOL, ATOL = 1e-10, 1e-12  # IDAS tolerances for the invariants below


@pytest.fixture(scope="module")
def pendulum_run():
    t = np.linspace(0.0, 10.0, 501)
    return t, cartesian_pendulum(theta0=2.0).simulate(t, rtol=RTOL, atol=ATOL)


def test_pantelides_differentiates_the_length_constraint_twice():
    # reference: the index-3 pendulum (Hairer & Wanner): the constraint twice, the velocity
    # definitions once; 2 degrees of freedom remain (11 variables, 9 equations)
    aug = pantelides(scalarize(cartesian_pendulum()))
    assert aug.eq_names[5:] == ["der(length)", "der(vel_x)", "der(vel_y)", "der(der(length))"]
    assert len(aug.syms) - len(aug.res) == 2


@pytest.mark.parametrize(
    "theta0, states",
    [(2.0, ["y", "v"]), (0.1, ["x", "u"])],  # reference: the larger of |x|, |y| is the dummy
    ids=["x_large", "y_large"],
)
def test_dummy_selection_keeps_the_well_conditioned_states(theta0, states):
    m = cartesian_pendulum(theta0)
    s = scalarize(m)
    aug = pantelides(s)
    v = np.concatenate([s.start, np.zeros(len(aug.syms) - s.n_vars)])
    sel = select_dummies(aug, (0.0, v, np.zeros(0), s.p_value))
    assert [aug.names[k] for k in reduced_system(aug, sel)[0]] == states


def test_pendulum_keeps_length_and_energy_over_10_s(pendulum_run):
    # reference: the length constraint x^2 + y^2 = L^2 and energy conservation (exact invariants)
    t, res = pendulum_run
    radius = np.hypot(res.x["x"], res.x["y"])
    assert np.max(np.abs(radius - 1.0)) < 1e-8
    e = res.outputs["energy"]
    assert np.max(np.abs(e - e[0])) / abs(e[0]) < 1e-6
    assert np.any(res.x["x"] > 0.5) and np.any(res.x["x"] < -0.5)  # it swings over x = 0 (dummy switches)


def test_pendulum_matches_minimal_coordinates(pendulum_run):
    # reference: theta'' = -(g/L) sin(theta) integrated as an ODE (a second formulation)
    t, res = pendulum_run
    ref = angle_pendulum(theta0=2.0).simulate(t, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(res.x["x"], ref.outputs["pos_x"], atol=1e-6)
    np.testing.assert_allclose(res.x["y"], ref.outputs["pos_y"], atol=1e-6)


def test_slider_crank_matches_minimal_coordinates_and_conserves_energy():
    # reference: Lagrange's equation in the crank angle (slider_crank_minimal) and energy conservation
    t = np.linspace(0.0, 2.0, 201)
    res = slider_crank().simulate(t, rtol=RTOL, atol=ATOL)
    ref = slider_crank_minimal().simulate(t, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(res.x["theta"], ref.x["theta"], atol=1e-7)
    np.testing.assert_allclose(res.x["s"], ref.outputs["s"], atol=1e-7)
    e = res.outputs["energy"]
    assert np.max(np.abs(e - e[0])) / e[0] < 1e-6


def test_structural_simplify_gives_an_index1_model():
    # reference: the pendulum's own invariants over 0.5 s (no dummy switch needed from theta0 = 2)
    red = structural_simplify(cartesian_pendulum(theta0=2.0))
    flat = red.flatten()
    assert flat.x_names == ["y", "v"]
    assert {"x", "u", "lam", "der_x", "der2_x"} <= set(flat.z_names)
    res = red.simulate(np.linspace(0.0, 0.3, 31), rtol=RTOL, atol=ATOL)
    assert np.max(np.abs(res.z["x"] ** 2 + res.x["y"] ** 2 - 1.0)) < 1e-9


def test_index1_model_is_returned_unchanged():
    m = angle_pendulum()
    assert structural_simplify(m) is m


def test_constraint_on_a_state_is_differentiated():
    # reference: x' = z, x = 1 + t^2 / 2  =>  z = t (closed form)
    m = Model("prescribed")
    x = m.state("x", start=1.0)
    z = m.algebraic("z")
    m.equation(m.der(x), z)
    m.equation(x, 1.0 + 0.5 * m.time**2)
    t = np.linspace(0.0, 1.0, 11)
    res = m.simulate(t)
    np.testing.assert_allclose(res.z["z"], t, atol=1e-8)
    np.testing.assert_allclose(res.x["x"], 1.0 + 0.5 * t**2, atol=1e-8)


def _input_in_constraint():
    m = Model("m")
    x = m.state("x")
    z = m.algebraic("z")
    f = m.input("f")
    m.equation(m.der(x), z)
    m.equation(x, f, name="follow")
    m.simulate([0.0, 1.0])


def _singular():
    m = Model("m")
    x = m.state("x")
    y = m.algebraic("y")
    z = m.algebraic("z")
    m.equation(m.der(x), y)
    m.equation(y, ca.sin(x), name="e1")
    m.equation(2 * y, x, name="e2")
    z  # noqa: B018 - z appears in no equation
    structural_simplify(m)


@pytest.mark.parametrize(
    "build, match",
    [
        (_input_in_constraint, r"equation 'follow' must be differentiated .* input\(s\) \['f'\]"),
        (_singular, r"structurally singular .* over-determine variables \['x', 'y'\].*\['z'\] are under-determined"),
    ],
    ids=["input_in_constraint", "singular"],
)
def test_reduction_errors(build, match):
    with pytest.raises(ModelError, match=match):
        build()
