"""ElastoBacklash and Friction (rotational and translational) against their exact non-smooth laws.

The law is read from the flattened element (its ``backlash``/``friction`` equation, the
force set to 0) and evaluated with CasADi. Independent checks: the exact laws written with
NumPy (``np.clip`` dead zone and contact indicator; ``np.sign`` Coulomb with Stribeck) and
the error bounds documented in the classes; derivatives against the analytic slopes
(``c/2`` of the dead zone at a corner, ``(Fc + Fs)/eps + dv`` of the friction at rest).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr

LN2 = np.log(2.0)
#: The two domains: module, relative position, relative speed, force, Stribeck speed names.
DOMAINS = {
    "rotational": (rot, "phi_rel", "w_rel", "tau", "ws"),
    "translational": (tr, "s_rel", "v_rel", "f", "vs"),
}


def _law(element, eq: str) -> ca.Function:
    """``(x, v) -> (force, d force/dx, d force/dv, d2 force/dx2)`` of one flattened element."""
    model = element.to_model()
    _, rel, speed, force, _ = next(d for d in DOMAINS.values() if isinstance(element, (d[0].ElastoBacklash, d[0].Friction)))
    res = dict(model._equations)[eq]  # the element's law as flattened: force - law(x, v)
    alg, states, pars = model.variables("algebraic"), model.variables("state"), model.variables("parameter")
    law = -ca.substitute(res, alg[force], ca.SX(0.0))
    values = [model._vars[n].start for n in pars]
    law = ca.substitute(law, ca.vertcat(*pars.values()), ca.DM(np.concatenate(values)))
    x, v = states[rel], alg[speed]
    return ca.Function("law", [x, v], [law, ca.jacobian(law, x), ca.jacobian(law, v), ca.hessian(law, x)[0]])


def _eval(fn: ca.Function, x, v) -> list[np.ndarray]:
    x, v = np.broadcast_arrays(np.asarray(x, float), np.asarray(v, float))
    out = fn.map(x.size)(x.reshape(1, -1), v.reshape(1, -1))
    return [np.asarray(o).ravel() for o in out]


def _exact_backlash(x, v, c, d, b):
    """The exact law, NumPy: c * dead zone + d * v in contact."""
    return c * (x - np.clip(x, -b / 2, b / 2)) + d * v * (np.abs(x) > b / 2)


def _exact_friction(v, fc, fs, vs, dv):
    """The exact law for v != 0, NumPy: Coulomb + Stribeck times sign(v), plus viscous."""
    return (fc + fs * np.exp(-((v / vs) ** 2))) * np.sign(v) + dv * v


C, D, B = 1e4, 50.0, 0.02


def _backlash(domain: str, eps: float, b: float = B):
    return DOMAINS[domain][0].ElastoBacklash(c=C, d=D, b=b, smoothing=eps)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
@pytest.mark.parametrize("delta_over_eps", [3.0, 10.0, 30.0])
def test_backlash_away_from_the_corners_is_within_the_bound(domain, delta_over_eps):
    # documented: c eps exp(-delta/eps) (spring) + 2 d |v| exp(-delta/eps) (damping in contact)
    eps = 1e-4
    x = np.linspace(-0.05, 0.05, 5001)
    x = x[np.min(np.abs(x[:, None] - np.array([-B / 2, B / 2])), axis=1) >= delta_over_eps * eps]
    v = np.where(np.arange(x.size) % 2, 0.7, -0.3)
    value = _eval(_law(_backlash(domain, eps), "backlash"), x, v)[0]
    err = np.abs(value - _exact_backlash(x, v, C, D, B))
    bound = (C * eps + 2 * D * np.abs(v)) * np.exp(-delta_over_eps) + 1e-12
    assert np.all(err <= bound), float(np.max(err / bound))


@pytest.mark.parametrize("domain", sorted(DOMAINS))
@pytest.mark.parametrize("eps", [1e-3, 1e-5, 1e-8])
def test_backlash_worst_error_is_c_eps_ln2_at_a_corner_and_vanishes_with_eps(domain, eps):
    # documented worst case of the spring torque: c eps ln 2 at x = +-b/2 (here b >> eps)
    x = np.concatenate([np.linspace(-0.05, 0.05, 2001), [-B / 2, B / 2]])
    value = _eval(_law(_backlash(domain, eps), "backlash"), x, 0.0)[0]
    err = np.abs(value - _exact_backlash(x, 0.0, C, D, B))
    assert err.max() <= C * eps * LN2 * (1 + 1e-9) + 1e-9
    np.testing.assert_allclose(err[-2:], C * eps * LN2, rtol=1e-6)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
def test_backlash_without_gap_is_the_linear_spring_damper(domain):
    # documented: softplus(x) - softplus(-x) = x and s(x) + s(-x) = 1, so b = 0 smooths nothing
    x = np.linspace(-1e-3, 1e-3, 101)
    v = np.linspace(-1, 1, 101)
    value = _eval(_law(_backlash(domain, 1e-4, b=0.0), "backlash"), x, v)[0]
    np.testing.assert_allclose(value, C * x + D * v, rtol=0, atol=1e-12)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
def test_backlash_derivatives_are_finite_and_continuous_at_the_corners(domain):
    # analytic at a corner: d force/dx = c/2 (the logistic at 0), d force/dv = d/2 (half in contact),
    # curvature +-c/(4 eps); the same just left and right of it
    eps = 1e-4
    corners = np.array([-B / 2, B / 2])
    x = np.concatenate([corners, corners - 1e-9 * eps, corners + 1e-9 * eps])
    value, dx, dv, dxx = _eval(_law(_backlash(domain, eps), "backlash"), x, 0.0)
    assert np.all(np.isfinite(np.concatenate([value, dx, dv, dxx])))
    np.testing.assert_allclose(dx, C / 2, rtol=1e-6)
    np.testing.assert_allclose(dv, D / 2, rtol=1e-6)
    np.testing.assert_allclose(np.abs(dxx), C / (4 * eps), rtol=1e-6)
    np.testing.assert_allclose(value[2:], np.tile(value[:2], 2), atol=1e-9 * C * eps)


FC, FS, VS, DV = 20.0, 10.0, 0.05, 200.0


def _friction(domain: str, eps: float, fs: float = FS, vs: float = VS):
    mod, _, _, _, stribeck = DOMAINS[domain]
    return mod.Friction(Fc=FC, Fs=fs, dv=DV, smoothing=eps, **{stribeck: vs})


@pytest.mark.parametrize("domain", sorted(DOMAINS))
@pytest.mark.parametrize("fs", [0.0, FS])
@pytest.mark.parametrize("delta_over_eps", [2.0, 5.0, 15.0])
def test_friction_away_from_rest_is_within_the_bound(domain, fs, delta_over_eps):
    # documented: below 2 (Fc + Fs) exp(-2 |v| / eps) at speed |v| (the Stribeck factor is <= 1)
    eps = 1e-3
    v = np.linspace(-0.3, 0.3, 6001)
    v = v[np.abs(v) >= delta_over_eps * eps]
    value = _eval(_law(_friction(domain, eps, fs), "friction"), 0.0, v)[0]
    err = np.abs(value - _exact_friction(v, FC, fs, VS, DV))
    assert np.all(err <= 2 * (FC + fs) * np.exp(-2 * np.abs(v) / eps) + 1e-12)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
@pytest.mark.parametrize("eps", [1e-2, 1e-3, 1e-4])
def test_friction_tends_to_the_exact_law_as_eps_goes_to_zero(domain, eps):
    # at fixed speeds 0.01 and -0.02 m/s (rad/s) the error is below 2 (Fc + Fs) exp(-2 |v| / eps) -> 0
    v = np.array([0.01, -0.02])
    value = _eval(_law(_friction(domain, eps), "friction"), 0.0, v)[0]
    err = np.abs(value - _exact_friction(v, FC, FS, VS, DV))
    assert np.all(err <= 2 * (FC + FS) * np.exp(-2 * np.abs(v) / eps) + 1e-12)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
def test_friction_at_rest_is_zero_with_a_finite_slope(domain):
    # at v = 0: 0, inside the exact law's set [-(Fc + Fs), Fc + Fs]; slope (Fc + Fs)/eps + dv
    # (d tanh = 1 at 0); just off rest the jump of the exact law is the documented worst error
    eps = 1e-3
    value, _, dv, _ = _eval(_law(_friction(domain, eps), "friction"), 0.0, np.array([0.0, 1e-9 * eps]))
    assert value[0] == 0.0
    np.testing.assert_allclose(dv, (FC + FS) / eps + DV, rtol=1e-9)
    np.testing.assert_allclose(_exact_friction(1e-9 * eps, FC, FS, VS, DV) - value[1], FC + FS, rtol=1e-6)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
def test_friction_without_stribeck_does_not_depend_on_the_stribeck_speed(domain):
    # Fs = 0: Coulomb + viscous only; the Stribeck speed then changes nothing
    v = np.linspace(-0.2, 0.2, 41)
    a = _eval(_law(_friction(domain, 1e-3, fs=0.0, vs=0.01), "friction"), 0.0, v)[0]
    b = _eval(_law(_friction(domain, 1e-3, fs=0.0, vs=10.0), "friction"), 0.0, v)[0]
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(a, FC * np.tanh(v / 1e-3) + DV * v, rtol=1e-14, atol=1e-12)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
@pytest.mark.parametrize(
    ("element", "kwargs", "match"),
    [
        ("ElastoBacklash", {"smoothing": 0.0}, "smoothing width must be one number > 0"),
        ("ElastoBacklash", {"smoothing": -1e-5}, "smoothing width must be one number > 0"),
        ("ElastoBacklash", {"b": -1e-3}, "b: must be >= 0"),
        ("ElastoBacklash", {"c": -1.0}, "c: must be >= 0"),
        ("ElastoBacklash", {"d": -1.0}, "d: must be >= 0"),
        ("ElastoBacklash", {"smoothing": float("inf")}, "finite"),
        ("Friction", {"smoothing": 0.0}, "smoothing width must be one number > 0"),
        ("Friction", {"Fc": -1.0}, "Fc: must be >= 0"),
        ("Friction", {"Fs": -1.0}, "Fs: must be >= 0"),
        ("Friction", {"dv": -1.0}, "dv: must be >= 0"),
        ("Friction", {"stribeck": 0.0}, "must be > 0"),
        ("Friction", {"smoothing": True}, "expected a real number"),
    ],
)
def test_bad_element_parameters_are_refused(domain, element, kwargs, match):
    mod, _, _, _, stribeck = DOMAINS[domain]
    kwargs = {stribeck if k == "stribeck" else k: v for k, v in kwargs.items()}
    with pytest.raises(InputError, match=match):
        getattr(mod, element)(**kwargs)


@pytest.mark.parametrize("domain", sorted(DOMAINS))
def test_the_widths_are_listed_with_their_units(domain):
    # by hand: one width per element, in the element's unit (rad or m; rad/s or m/s)
    mod = DOMAINS[domain][0]
    units = {"rotational": ("rad", "rad/s"), "translational": ("m", "m/s")}[domain]
    assert (mod.ElastoBacklash.smoothing.unit, mod.Friction.smoothing.unit) == units
    assert _backlash(domain, 3e-4).to_model().smoothing == {"smoothing": 3e-4}
