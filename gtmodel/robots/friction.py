"""Cart friction models: Coulomb + viscous, Dressler (2012), eq. 6.8 and Table 6.1.

``f_i = tau_i - f_fric,i(q_dot_i)`` with ``f_fric = f_c sign(q_dot) + f_v q_dot``.
``sign`` is discontinuous, which breaks gradient-based optimisation, so three forms of
the sign are offered:

``"exact"``
    ``sign(q_dot)`` (0 at rest). For simulation and identification.
``"tanh"``
    ``tanh(q_dot / width)``: smooth; within 0.4 % of the exact force once
    ``|q_dot| > 3 width``. Used by the optimal-control problems.
``"piecewise"``
    The piecewise-linear form of Dressler (2012), Fig. 3.6: linear through zero on
    ``|q_dot| < width``, ``+-1`` outside.

The asymmetric variant (Table 6.1) uses ``(f_c+, f_v+)`` for positive and
``(f_c-, f_v-)`` for negative velocity; with a smooth sign ``sigma`` it is written as
``f = sigma (f_c+ + f_c-)/2 + sigma^2 (f_c+ - f_c-)/2 + q_dot ((f_v+ + f_v-)/2 + sigma (f_v+ - f_v-)/2)``,
which equals the two branches wherever ``|sigma| = 1`` and is zero at rest.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gtmodel.defaults import DEFAULT_FRICTION_WIDTH, FRICTION_FORMS
from gtmodel.errors import InputError
from gtmodel.robots.parameters import DynamicParameters

__all__ = ["FRICTION_FORMS", "DEFAULT_FRICTION_WIDTH", "sign_approximation", "friction_force", "check_friction_form"]

# FRICTION_FORMS (the selectable forms of the sign function) and DEFAULT_FRICTION_WIDTH (the
# velocity width [m/s] of the smooth and piecewise-linear forms) are written once, in
# gtmodel.defaults, where the problem files' light schemas read them too.


def check_friction_form(form: str, width: float) -> None:
    """Validate a friction form and its width.

    Parameters
    ----------
    form : str
        One of :data:`FRICTION_FORMS`.
    width : float
        Velocity width [m/s] of the smooth forms; must be positive.

    Raises
    ------
    InputError
        Unknown form or non-positive width.
    """
    if form not in FRICTION_FORMS:
        raise InputError(f"friction: expected one of {', '.join(FRICTION_FORMS)}, got {form!r}")
    if not (isinstance(width, (int, float)) and np.isfinite(width) and width > 0):
        raise InputError(f"friction_width: expected a positive velocity in m/s, got {width!r}")


def sign_approximation(q_dot: ca.SX | ca.MX, form: str = "exact", width: float = DEFAULT_FRICTION_WIDTH) -> ca.SX | ca.MX:
    """The sign function of the friction model in the chosen form.

    Parameters
    ----------
    q_dot : casadi.SX or casadi.MX, shape (3, 1)
        Cart velocities [m/s].
    form : {"exact", "tanh", "piecewise"}, optional
        See the module docstring.
    width : float, optional
        Velocity width [m/s] of the smooth forms.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        Values in [-1, 1].

    Raises
    ------
    InputError
        Unknown form or non-positive width.
    """
    check_friction_form(form, width)
    if form == "exact":
        return ca.sign(q_dot)
    if form == "tanh":
        return ca.tanh(q_dot / width)
    return ca.fmin(ca.fmax(q_dot / width, -1), 1)


def friction_force(q_dot: ca.SX | ca.MX, dynamics: DynamicParameters, form: str = "exact", width: float = DEFAULT_FRICTION_WIDTH, asymmetric: bool = False) -> ca.SX | ca.MX:
    """Friction force on the carts, Dressler (2012), eq. 6.8 (Table 6.1 if asymmetric).

    Parameters
    ----------
    q_dot : casadi.SX or casadi.MX, shape (3, 1)
        Cart velocities [m/s].
    dynamics : DynamicParameters
        Provides ``f_c``, ``f_v`` (and ``asymmetric`` for the asymmetric variant). The
        coefficients may be numbers or CasADi symbols (``SX``/``MX`` columns of 3), e.g.
        to build the identification regressor ``d tau / d theta``.
    form : {"exact", "tanh", "piecewise"}, optional
        Form of the sign function.
    width : float, optional
        Velocity width [m/s] of the smooth forms.
    asymmetric : bool, optional
        Use the asymmetric parameters of Table 6.1.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        Friction force opposing the motion [N]; the actuator force is
        ``tau = f + friction_force``.

    Raises
    ------
    InputError
        Unknown form, non-positive width, or ``asymmetric`` without asymmetric parameters.
    """
    sigma = sign_approximation(q_dot, form, width)
    if not asymmetric:
        return _coefficients(dynamics.f_c) * sigma + _coefficients(dynamics.f_v) * q_dot
    a = dynamics.asymmetric
    if a is None:
        raise InputError("asymmetric friction requested but the parameter set has no [dynamics.asymmetric_friction] table")
    fc_plus, fc_minus = _coefficients(a.f_c_plus), _coefficients(a.f_c_minus)
    fv_plus, fv_minus = _coefficients(a.f_v_plus), _coefficients(a.f_v_minus)
    fc_mean = (fc_plus + fc_minus) / 2
    fc_diff = (fc_plus - fc_minus) / 2
    fv_mean = (fv_plus + fv_minus) / 2
    fv_diff = (fv_plus - fv_minus) / 2
    return fc_mean * sigma + fc_diff * sigma**2 + q_dot * (fv_mean + fv_diff * sigma)


def _coefficients(x):
    """Friction coefficients as a CasADi column: numbers become ``DM``; symbols (``SX``/``MX``,
    e.g. the parameters of a regressor, :mod:`gtmodel.calibration.identification`)
    pass through unchanged."""
    if isinstance(x, (ca.SX, ca.MX)):
        return x
    return ca.DM(np.asarray(x, dtype=float))
