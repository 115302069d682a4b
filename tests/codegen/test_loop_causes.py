"""Why a loop controller failed, with numbers (gtmodel.codegen.check.loop_causes.noise_gain).

References: the one-sigma response of a linear map to independent errors, ``sqrt(sum_j (K_ij s_j)^2)``,
computed by hand for a gain table; and the Riccati gain's limit ``(B^T P B)^-1 B^T P A``: a mass held
at rest by a regularised Coulomb friction (slope ``Fc / eps`` at rest) barely moves under its force,
and the TV-LQR's gain there hardly changes with the input weight, where a mass with a mild viscous
friction's gain falls as the weight grows.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from gtmodel.codegen.check.loop_causes import NOISE_GAIN_NOTE, noise_gain, noise_gain_text
from gtmodel.control.tracking import tracking_controller
from gtmodel.modeling import Model, explicit_ode

DT = 0.004


def table(K_hold=None) -> SimpleNamespace:
    K = np.array([[[1.0, 2.0]], [[3.0, 4.0]]])  # (n = 2, nu = 1, nx = 2)
    return SimpleNamespace(K=K, K_hold=None if K_hold is None else np.array([K_hold]), t0=-DT, dt=DT, u_lb=np.array([-2.0]),
                           u_ub=np.array([2.0]))


@pytest.mark.parametrize("K_hold, value, time, state, share", [
    (None, 5.0, 0.0, "s", 0.8),                   # period 1: sqrt(3^2 + 4^2) = 5, 4 of it from the second state's
    ([[6.0, 0.0]], 6.0, math.inf, "p", 1.0),      # the held end's 6, all from the first state
])
def test_the_inputs_one_sigma_response_is_the_gains_norm_weighted_by_the_noise(K_hold, value, time, state, share):
    g = noise_gain(table(K_hold), [1.0, 1.0], ["p", "s"], ["f"])
    assert g["value"] == pytest.approx(value) and g["relative"] == pytest.approx(value / 2.0)
    assert g["time"] == pytest.approx(time) and g["state"] == state and g["share"] == pytest.approx(share)


@pytest.mark.parametrize("controller, sigma", [
    (SimpleNamespace(), [1.0, 1.0]),  # no gain table (an MPC)
    (table(), [0.0, 0.0]),           # no noise
])
def test_no_figure_without_a_gain_table_or_noise(controller, sigma):
    assert noise_gain(controller, sigma, ["p", "s"], ["f"]) is None


def test_the_clause_names_the_figures_only_above_its_note():
    g = noise_gain(table(), [1.0, 1.0], ["p", "s"], ["f"])
    assert g["relative"] > NOISE_GAIN_NOTE
    assert "turns a one-sigma error" in noise_gain_text(g) and "5 of f (2.5 times its half range; 80 % of it from s" in noise_gain_text(g)
    assert noise_gain_text(noise_gain(table(), [0.01, 0.01], ["p", "s"], ["f"])) == ""


def _friction_mass(Fc: float, eps: float, d: float):
    m = Model("friction_mass")
    s, v, f = m.state("s"), m.state("v"), m.input("f")
    m.equation(m.der(s), v)
    m.equation(m.der(v), (f - Fc * ca.tanh(v / eps) - d * v) / 2.0)
    return explicit_ode(m)


def _gain(ode, R: float) -> float:
    t = np.linspace(0.0, 0.4, 101)  # the mass at rest at s = 0 the whole time
    c = tracking_controller(ode, t, np.zeros((101, 2)), np.zeros((101, 1)), Q=[1e6, 1.0], R=[R], u_lb=[-20.0], u_ub=[20.0])
    return noise_gain(c, [1e-3, 1e-2], ["s", "v"], ["f"])["value"]


def test_at_rest_in_a_regularised_friction_the_gain_ignores_the_input_weight():
    stuck, viscous = _friction_mass(10.0, 1e-4, 0.0), _friction_mass(0.0, 1.0, 1.0)
    assert _gain(stuck, 1e-2) > 20.0  # the noise alone spans the input's range
    assert _gain(stuck, 1e2) == pytest.approx(_gain(stuck, 1e-2), rel=0.1)  # 10^4 times the weight: the same gain
    assert _gain(viscous, 1e2) < 0.1 * _gain(viscous, 1e-2)
