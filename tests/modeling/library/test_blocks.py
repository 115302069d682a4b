"""Smooth laws and the Limiter/DeadZone blocks against their exact non-smooth laws.

Independent checks: the exact laws written with NumPy (``np.maximum``, ``np.clip``); the
smooth values against NumPy's own stable softplus (``eps * np.logaddexp(0, x / eps)``);
the documented error bounds (``eps ln 2`` at a corner, ``eps exp(-delta/eps)`` at a distance
``delta``); derivatives against the analytic ones of the logistic.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Component
from gtmodel.modeling.components.component import State
from gtmodel.modeling.library import blocks

LN2 = np.log(2.0)
X = ca.SX.sym("x")
EPS = ca.SX.sym("eps")


def _fn(law) -> ca.Function:
    """value, first and second derivative of ``law(x, eps)`` in x, as a CasADi Function of (x, eps)."""
    e = law(X, EPS)
    return ca.Function("law", [X, EPS], [e, ca.jacobian(e, X), ca.hessian(e, X)[0]])


def _eval(law, x: np.ndarray, eps: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    f = _fn(law).map(x.size)
    out = f(x.reshape(1, -1), eps)
    return tuple(np.asarray(o).ravel() for o in out)


LIMITS = (-1.0, 2.0)
LAWS = {
    "softplus": (lambda x, e: blocks.softplus(x, e), lambda x: np.maximum(x, 0.0), (0.0,)),
    "limit": (lambda x, e: blocks.smooth_limit(x, LIMITS[0], LIMITS[1], e), lambda x: np.clip(x, *LIMITS), LIMITS),
    "dead_zone": (
        lambda x, e: blocks.smooth_dead_zone(x, LIMITS[0], LIMITS[1], e),
        lambda x: x - np.clip(x, *LIMITS),
        LIMITS,
    ),
}


def test_softplus_is_numpys_stable_softplus():
    # independent: NumPy's logaddexp(0, x/eps) = ln(1 + exp(x/eps)), stable for large |x|
    x = np.concatenate([np.linspace(-3, 3, 601), [-1e6, -50.0, 50.0, 1e6]])
    value, _, _ = _eval(blocks.softplus, x, 0.1)
    np.testing.assert_allclose(value, 0.1 * np.logaddexp(0.0, x / 0.1), rtol=1e-13, atol=1e-300)


@pytest.mark.parametrize("law", sorted(LAWS))
@pytest.mark.parametrize("delta_over_eps", [2.0, 5.0, 20.0])
def test_error_away_from_the_corners_is_below_the_bound(law, delta_over_eps):
    # documented: the error at a distance delta from every corner is below eps exp(-delta/eps)
    # per corner (two corners for limit and dead zone)
    smooth, exact, corners = LAWS[law]
    eps = 0.01
    x = np.linspace(-4, 4, 8001)
    dist = np.min(np.abs(x[:, None] - np.array(corners)[None, :]), axis=1)
    x = x[dist >= delta_over_eps * eps]
    value, _, _ = _eval(smooth, x, eps)
    err = np.abs(value - exact(x))
    bound = len(corners) * eps * np.exp(-delta_over_eps) + 1e-15  # + rounding of values up to 4
    assert err.max() <= bound, (err.max(), bound)


@pytest.mark.parametrize("law", sorted(LAWS))
@pytest.mark.parametrize("eps", [0.1, 1e-3, 1e-6])
def test_worst_error_is_eps_ln2_at_a_corner_and_vanishes_with_eps(law, eps):
    # documented worst case: eps ln 2, attained at the corner (the band is >> eps wide);
    # so the smooth law tends to the exact one as eps -> 0
    smooth, exact, corners = LAWS[law]
    x = np.concatenate([np.linspace(-4, 4, 4001), corners])
    value, _, _ = _eval(smooth, x, eps)
    err = np.abs(value - exact(x))
    assert err.max() <= eps * LN2 + 1e-14
    assert err[-len(corners):] == pytest.approx(eps * LN2, rel=1e-6)


@pytest.mark.parametrize("law", sorted(LAWS))
def test_derivatives_are_finite_and_continuous_at_the_corners(law):
    # independent: at a corner the smooth law's slope is 1/2 (d softplus = logistic = 1/2 at 0)
    # and its curvature +-1/(4 eps); left and right of it (+-1e-9 eps) the same values
    smooth, _, corners = LAWS[law]
    eps = 1e-3
    c = np.array(corners)
    x = np.concatenate([c, c - 1e-9 * eps, c + 1e-9 * eps])
    value, slope, curv = _eval(smooth, x, eps)
    assert np.all(np.isfinite(np.concatenate([value, slope, curv])))
    k = len(corners)
    np.testing.assert_allclose(slope[:k], 0.5, atol=1e-9)
    np.testing.assert_allclose(np.abs(curv[:k]), 1 / (4 * eps), rtol=1e-9)
    np.testing.assert_allclose(slope[k:], np.tile(slope[:k], 2), atol=1e-9)
    np.testing.assert_allclose(curv[k:], np.tile(curv[:k], 2), rtol=1e-6)


@pytest.mark.parametrize("law", sorted(LAWS))
def test_no_overflow_and_exact_slopes_far_from_the_corners(law):
    # independent: far from the corners the exact law's slope (0 or 1), no inf/nan in the
    # value or the reverse-mode gradient (the unselected branch is clamped)
    smooth, exact, _ = LAWS[law]
    x = np.array([-1e8, -1e4, 1e4, 1e8])
    value, slope, curv = _eval(smooth, x, 1e-6)
    grad = ca.Function("g", [X, EPS], [ca.gradient(smooth(X, EPS), X)]).map(x.size)(x.reshape(1, -1), 1e-6)
    np.testing.assert_allclose(value, exact(x), rtol=1e-12)
    expected_slope = (exact(x + 1.0) - exact(x)).round()
    np.testing.assert_array_equal(slope, expected_slope)
    np.testing.assert_array_equal(np.asarray(grad).ravel(), expected_slope)
    np.testing.assert_array_equal(curv, 0.0)


def test_limiter_output_stays_within_its_limits():
    # documented: softplus is increasing and 1-Lipschitz, so uMin <= y <= uMax for every width
    x = np.linspace(-10, 10, 2001)
    value, _, _ = _eval(lambda u, e: blocks.smooth_limit(u, -1.0, 2.0, e), x, 0.5)
    assert value.min() >= -1.0 and value.max() <= 2.0


def test_smooth_sign_and_step():
    # independent: np.tanh and the logistic 1/(1 + exp(-x/eps)); bounds 2 exp(-2|x|/eps) and exp(-|x|/eps)
    x = np.linspace(-1, 1, 201)
    eps = 0.05
    sgn, _, _ = _eval(blocks.smooth_sign, x, eps)
    step, _, _ = _eval(blocks.smooth_step, x, eps)
    np.testing.assert_allclose(sgn, np.tanh(x / eps), atol=1e-15)
    np.testing.assert_allclose(step, 1 / (1 + np.exp(-x / eps)), atol=1e-15)
    off = np.abs(x) > 0
    ulp = np.finfo(float).eps  # rounding of values near 1
    assert np.all(np.abs(sgn - np.sign(x))[off] <= 2 * np.exp(-2 * np.abs(x[off]) / eps) + ulp)
    assert np.all(np.abs(step - np.heaviside(x, 0.5))[off] <= np.exp(-np.abs(x[off]) / eps) + ulp)


# ---------------------------------------------------------------- the blocks in a model
class Ramp(Component):
    """A ramp ``r = t`` (a state with der(r) = 1) through a Limiter and a DeadZone."""

    r = State(description="the ramp", start=-3.0, fixed=True)
    lim = blocks.Limiter(uMax=1.0, uMin=-0.5, smoothing=1e-3)
    dz = blocks.DeadZone(uMax=1.0, uMin=-0.5, smoothing=1e-3)

    def equations(self):
        self.equation(self.der(self.r), 1.0)
        self.equation(self.lim.u, self.r)
        self.equation(self.dz.u, self.r)


def test_blocks_wired_in_a_component_follow_the_exact_law():
    # independent: np.clip of the ramp's value, at grid points 0.1 or more from the corners
    t = np.linspace(0.0, 6.0, 61)
    model = Ramp().to_model()
    assert model.smoothing == {"lim.smoothing": 1e-3, "dz.smoothing": 1e-3}
    res = model.simulate(t)
    r = t - 3.0
    away = np.min(np.abs(r[:, None] - np.array([-0.5, 1.0])), axis=1) >= 0.1
    np.testing.assert_allclose(res.x["r"], r, atol=1e-9)
    exact = np.clip(r, -0.5, 1.0)
    np.testing.assert_allclose(res.z["lim.y"][away], exact[away], atol=1e-9)
    np.testing.assert_allclose(res.z["dz.y"][away], (r - exact)[away], atol=1e-9)


def test_an_unwired_block_input_leaves_the_model_short():
    class Unwired(Component):
        lim = blocks.Limiter()

    with pytest.raises(ModelError):
        Unwired().to_model().simulate(np.linspace(0, 1, 3))


@pytest.mark.parametrize("cls", [blocks.Limiter, blocks.DeadZone])
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"smoothing": 0.0}, "smoothing width must be one number > 0"),
        ({"smoothing": -1e-3}, "smoothing width must be one number > 0"),
        ({"uMin": 2.0, "uMax": 1.0}, "uMin must be <= uMax"),
        ({"uMax": float("nan")}, "finite"),
        ({"smoothing": [1e-3, 2e-3]}, "expected 1 value"),
    ],
)
def test_bad_block_parameters_are_refused(cls, kwargs, match):
    with pytest.raises(InputError, match=match):
        cls(**kwargs)
