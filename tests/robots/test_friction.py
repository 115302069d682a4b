"""Cart friction forms (Dressler (2012), eq. 6.8, Table 6.1, Fig. 3.6), against closed forms."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.robots.friction import friction_force, sign_approximation
from gtmodel.robots.parameters import load_parameters

EXACT_TOL = 1e-12
WIDTH = 0.01
#: tanh(3) = 0.99505: beyond 3 widths the smooth Coulomb force is within 0.5 % of sign().
TANH_3W_RTOL = 5e-3

P = load_parameters("L1").dynamics
VELOCITIES = np.array([-1.0, -0.2, -0.004, 0.0, 0.004, 0.2, 1.0])


def _evaluate(form, asymmetric=False, width=WIDTH):
    qd = ca.SX.sym("qd", 3)
    f = ca.Function("f", [qd], [friction_force(qd, P, form, width, asymmetric)])
    return np.array([np.asarray(f(np.full(3, v))).ravel() for v in VELOCITIES])


def test_exact_is_coulomb_plus_viscous():
    expected = np.outer(np.sign(VELOCITIES), P.f_c) + np.outer(VELOCITIES, P.f_v)
    np.testing.assert_allclose(_evaluate("exact"), expected, atol=EXACT_TOL)


def test_tanh_closed_form_and_close_to_exact_beyond_three_widths():
    expected = np.outer(np.tanh(VELOCITIES / WIDTH), P.f_c) + np.outer(VELOCITIES, P.f_v)
    got = _evaluate("tanh")
    np.testing.assert_allclose(got, expected, atol=EXACT_TOL)
    far = np.abs(VELOCITIES) > 3 * WIDTH
    coulomb = got[far] - np.outer(VELOCITIES[far], P.f_v)
    np.testing.assert_allclose(coulomb, np.outer(np.sign(VELOCITIES[far]), P.f_c), rtol=TANH_3W_RTOL)


def test_piecewise_linear_of_fig_3_6():
    sat = np.clip(VELOCITIES / WIDTH, -1, 1)
    expected = np.outer(sat, P.f_c) + np.outer(VELOCITIES, P.f_v)
    np.testing.assert_allclose(_evaluate("piecewise"), expected, atol=EXACT_TOL)


@pytest.mark.parametrize("form", ["exact", "tanh", "piecewise"])
def test_zero_at_rest(form):
    assert np.all(_evaluate(form)[VELOCITIES == 0] == 0)


def test_asymmetric_branches_table_6_1():
    a = P.asymmetric
    got = _evaluate("exact", asymmetric=True)
    for k, v in enumerate(VELOCITIES):
        if v > 0:
            expected = a.f_c_plus + a.f_v_plus * v
        elif v < 0:
            expected = -a.f_c_minus + a.f_v_minus * v
        else:
            expected = np.zeros(3)
        np.testing.assert_allclose(got[k], expected, atol=EXACT_TOL)


def test_asymmetric_smooth_is_differentiable_at_zero():
    qd = ca.SX.sym("qd", 3)
    f = friction_force(qd, P, "tanh", WIDTH, asymmetric=True)
    J = ca.Function("J", [qd], [ca.jacobian(f, qd)])
    left, right = (np.asarray(J(np.full(3, s * 1e-9))) for s in (-1, 1))
    np.testing.assert_allclose(left, right, rtol=1e-6)


BAD = [
    ("form", dict(form="stribeck", width=WIDTH), "friction: expected one of"),
    ("width_zero", dict(form="tanh", width=0.0), "friction_width: expected a positive"),
    ("width_nan", dict(form="tanh", width=float("nan")), "friction_width: expected a positive"),
]


@pytest.mark.parametrize("case, kwargs, match", BAD, ids=[b[0] for b in BAD])
def test_bad_forms(case, kwargs, match):
    with pytest.raises(InputError, match=match):
        sign_approximation(ca.SX.sym("v"), **kwargs)
