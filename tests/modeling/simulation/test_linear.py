"""Tests of the linearisation of models (gtmodel.modeling.simulation.linear).

References: hand-derived Jacobians of small linear and nonlinear models (stated per test).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Model
from gtmodel.modeling.simulation.linear import linearize


def msd(k=4.0, c=0.4, mass=2.0):
    m = Model("msd")
    kk, cc, mm = m.parameter("k", k), m.parameter("c", c), m.parameter("mass", mass)
    x, v = m.state("x"), m.state("v")
    u = m.input("u")
    m.equation(m.der(x), v)
    m.equation(mm * m.der(v), -kk * x - cc * v + u)
    m.output("force", kk * x)
    return m


def test_mass_spring_damper_matrices():
    # closed form: A = [[0, 1], [-k/m, -c/m]], B = [0, 1/m]; output k x: C = [k, 0]
    lin = linearize(msd(), outputs=["force", "v"])
    np.testing.assert_allclose(lin.A, [[0.0, 1.0], [-2.0, -0.2]], atol=1e-14)
    np.testing.assert_allclose(lin.B, [[0.0], [0.5]], atol=1e-14)
    np.testing.assert_allclose(lin.C, [[4.0, 0.0], [0.0, 1.0]], atol=1e-14)
    np.testing.assert_allclose(lin.D, [[0.0], [0.0]], atol=1e-14)
    assert lin.y_names == ["force", "v"]
    # closed form poles: -zeta w0 +- j w0 sqrt(1 - zeta^2) with w0^2 = 2, 2 zeta w0 = 0.2
    np.testing.assert_allclose(np.sort_complex(lin.poles()), np.sort_complex(np.roots([1.0, 0.2, 2.0])), atol=1e-12)


def test_algebraic_variables_are_eliminated():
    # closed form: x' = -z + u, 0 = z - a x  =>  A = -a, B = 1; z as output: C = a
    m = Model("dae")
    a = m.parameter("a", 2.0)
    x, z, u = m.state("x", start=1.0), m.algebraic("z"), m.input("u")
    m.equation(m.der(x), -z + u)
    m.equation(z, a * x)
    lin = linearize(m, outputs=["z"], p={"a": 3.0})
    np.testing.assert_allclose([lin.A[0, 0], lin.B[0, 0], lin.C[0, 0]], [-3.0, 1.0, 3.0], atol=1e-14)
    assert lin.z[0] == pytest.approx(3.0)  # consistent z at x = 1


def test_nonlinear_model_at_an_operating_point():
    # closed form: pendulum x'' = -sin(x) at x = 0.3: A = [[0, 1], [-cos(0.3), 0]]
    m = Model("pendulum")
    x, v = m.state("x"), m.state("v")
    m.equation(m.der(x), v)
    m.equation(m.der(v), -ca.sin(x))
    lin = linearize(m, x={"x": 0.3})
    np.testing.assert_allclose(lin.A, [[0.0, 1.0], [-np.cos(0.3), 0.0]], atol=1e-14)
    sys = lin.to_state_space()
    assert sys.nstates == 2 and sys.ninputs == 0


BAD = [
    ("not a model", lambda: linearize("msd"), InputError, r"model must be a gtmodel\.modeling\.Model, got str"),
    ("output", lambda: linearize(msd(), outputs=["nope"]), InputError, r"outputs: \['nope'\] are no states"),
    ("state name", lambda: linearize(msd(), x={"y": 1.0}), InputError, r"x: 'y' is not a state of model 'msd'"),
    ("state size", lambda: linearize(msd(), x=[1.0, 2.0, 3.0]), InputError, r"x: expected 2 values, got 3"),
    ("parameter", lambda: linearize(msd(), p={"kk": 1.0}), InputError, r"model 'msd' has no parameter 'kk'"),
]


@pytest.mark.parametrize("make, error, match", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input(make, error, match):
    with pytest.raises(error, match=match):
        make()


def test_singular_algebraic_equations_are_named():
    # 0 = z^2 - x^2 has a singular Jacobian in z at z = x = 0
    m = Model("singular")
    x, z = m.state("x"), m.algebraic("z")
    m.equation(m.der(x), z)
    m.equation(z**2, x**2)
    with pytest.raises(ModelError, match=r"algebraic equations of model 'singular' are singular in z"):
        linearize(m)
