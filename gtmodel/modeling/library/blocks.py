"""Signal blocks with a declared smoothing, named as ``Modelica.Blocks.Nonlinear``, and the smooth laws of the library.

Blocks: :class:`Limiter` (saturation) and :class:`DeadZone`. Each has a real input ``u``
and output ``y`` (algebraic variables of the block, in the unit of the signal) and a
smoothing width ``smoothing`` (same unit, > 0, declared with ``smoothing=True``, so it is
listed in ``Model.smoothing``). The exact non-smooth law is the limit as the width goes to 0.

Wiring: the enclosing component writes one equation that gives ``u`` and uses ``y`` in
its own equations (a block has no connector: a signal is not a physical flange)::

    class SignalTorque(rotational.Torque):   # extends Torque: tau from an equation, not a model input
        tau = Variable(unit="N.m", description="accelerating torque, from a signal")

    class SaturatedServo(Component):
        motor = rotational.Inertia(J=1e-3)
        drive = SignalTorque()
        limit = blocks.Limiter(uMax=2.0, uMin=-2.0, smoothing=1e-3)   # torque limit [N m]
        ...
        def equations(self):
            connect(self.drive.flange, self.motor.flange_a)
            self.equation(self.limit.u, self.kp * (self.phi_ref - self.motor.phi))  # what u is
            self.equation(self.drive.tau, self.limit.y)                              # where y goes

(:class:`~gtmodel.modeling.library.rotational.Torque` declares ``tau`` an input of the
model: an equation for it would over-determine the model, hence the redeclaration.) A
``u`` that no equation gives leaves the model one equation short: the structural check
names it. The worked example is in ``docs/own_model.md``, section 6.

Smooth laws (symbolic; CasADi ``SX``/``MX``, or numbers as ``DM``), each written so that
no ``exp`` overflows and every derivative, at every point, is that of an analytic branch
(no ``fabs``/``fmax``/``sign``, whose derivatives CasADi gives as one-sided or zero at the
corner, and whose ``sign`` would be taken for an event by the simulator):

* :func:`softplus`: ``eps ln(1 + exp(x/eps))``, the smooth ``max(x, 0)``; error in
  ``(0, eps ln 2]``, ``eps ln 2`` at ``x = 0``, ``<= eps exp(-|x|/eps)`` at ``|x|``;
* :func:`smooth_step`: its derivative, the logistic ``1 / (1 + exp(-x/eps))``, the smooth
  unit step (``1/2`` at the corner, ``<= exp(-|x|/eps)`` off it);
* :func:`smooth_sign`: ``tanh(x/eps)``, the smooth ``sign(x)`` of Coulomb friction (0 at
  the corner, ``<= 2 exp(-2|x|/eps)`` off it);
* :func:`smooth_limit`, :func:`smooth_dead_zone`: differences of two softplus (below).

Reference: Modelica Standard Library 4.0, ``Modelica.Blocks.Nonlinear.Limiter`` and
``DeadZone``; the softplus smoothing of a ramp: Chen and Mangasarian (1996), "A class of
smoothing functions for nonlinear and mixed complementarity problems", Comput. Optim.
Appl. 5, 97-138.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import InputError
from gtmodel.modeling.components.component import Component, Parameter, Variable

__all__ = ["softplus", "smooth_step", "smooth_sign", "smooth_limit", "smooth_dead_zone", "Limiter", "DeadZone"]

#: ln 2: the worst-case error of softplus, in units of the smoothing width.
LN2 = float(np.log(2.0))


def _sym(x: Any) -> Any:
    """``x`` as a CasADi expression (SX and MX kept; numbers as DM)."""
    return x if isinstance(x, (ca.SX, ca.MX, ca.DM)) else ca.DM(np.asarray(x, dtype=float))


def softplus(x: Any, smoothing: Any) -> Any:
    """The smooth ramp ``eps ln(1 + exp(x/eps))``, numerically stable: the smooth ``max(x, 0)``.

    Written as ``x + eps ln(1 + exp(-x/eps))`` for ``x > 0`` and ``eps ln(1 + exp(x/eps))``
    otherwise, each branch's argument clamped where it is not selected, so no ``exp``
    overflows and no derivative is ``0 * inf`` (reverse mode included).

    Parameters
    ----------
    x : casadi.SX, casadi.MX, casadi.DM, float or array_like
        Argument, any shape.
    smoothing : casadi.SX, casadi.MX or float
        Width ``eps`` > 0, in the unit of ``x``.

    Returns
    -------
    casadi.SX, casadi.MX or casadi.DM
        Same shape as ``x``. ``softplus(x) - max(x, 0) = eps ln(1 + exp(-|x|/eps))``: in
        ``(0, eps ln 2]``, ``eps ln 2`` at ``x = 0``, below ``eps exp(-|x|/eps)``.
    """
    x, eps = _sym(x), _sym(smoothing)
    pos = x > 0
    xp = ca.if_else(pos, x, 0.0)  # x where the positive branch is used, else 0 (no overflow in exp(-xp/eps))
    xn = ca.if_else(pos, 0.0, x)
    return ca.if_else(pos, xp + eps * ca.log1p(ca.exp(-xp / eps)), eps * ca.log1p(ca.exp(xn / eps)))


def smooth_step(x: Any, smoothing: Any) -> Any:
    """The logistic ``1 / (1 + exp(-x/eps))`` = ``(1 + tanh(x / (2 eps))) / 2``: the smooth unit step, d softplus/dx.

    Parameters
    ----------
    x : casadi.SX, casadi.MX, casadi.DM, float or array_like
        Argument, any shape.
    smoothing : casadi.SX, casadi.MX or float
        Width ``eps`` > 0, in the unit of ``x``.

    Returns
    -------
    casadi.SX, casadi.MX or casadi.DM
        Same shape as ``x``, in ``(0, 1)``: ``1/2`` at ``x = 0``; its distance to the step
        ``H(x)`` is below ``exp(-|x|/eps)``.
    """
    x, eps = _sym(x), _sym(smoothing)
    return 0.5 * (1.0 + ca.tanh(x / (2.0 * eps)))


def smooth_sign(x: Any, smoothing: Any) -> Any:
    """The smooth sign ``tanh(x/eps)`` (Coulomb friction's ``sign(v)``).

    Parameters
    ----------
    x : casadi.SX, casadi.MX, casadi.DM, float or array_like
        Argument, any shape.
    smoothing : casadi.SX, casadi.MX or float
        Width ``eps`` > 0, in the unit of ``x``.

    Returns
    -------
    casadi.SX, casadi.MX or casadi.DM
        Same shape as ``x``, in ``(-1, 1)``: 0 at ``x = 0`` (a value of the set-valued
        ``sign(0) = [-1, 1]``); ``|sign(x) - tanh(x/eps)| = 1 - tanh(|x|/eps) < 2 exp(-2|x|/eps)``.
    """
    x, eps = _sym(x), _sym(smoothing)
    return ca.tanh(x / eps)


def smooth_limit(u: Any, u_min: Any, u_max: Any, smoothing: Any) -> Any:
    """Smooth saturation ``u_min + softplus(u - u_min) - softplus(u - u_max)`` of ``min(max(u, u_min), u_max)``.

    The smooth value stays in ``[u_min, u_max]`` (softplus is increasing and 1-Lipschitz),
    so a bound on the output holds exactly; the error is below ``eps ln 2`` everywhere
    (``eps ln 2`` at a corner when ``u_max - u_min >> eps``) and below
    ``eps (exp(-|u - u_min|/eps) + exp(-|u - u_max|/eps))`` away from the corners.

    Parameters
    ----------
    u : casadi.SX, casadi.MX, casadi.DM, float or array_like
        Input, any shape.
    u_min, u_max : casadi.SX, casadi.MX or float
        Limits, ``u_min <= u_max``.
    smoothing : casadi.SX, casadi.MX or float
        Width ``eps`` > 0, in the unit of ``u``.

    Returns
    -------
    casadi.SX, casadi.MX or casadi.DM
        Same shape as ``u``.
    """
    return u_min + softplus(_sym(u) - u_min, smoothing) - softplus(_sym(u) - u_max, smoothing)


def smooth_dead_zone(u: Any, u_min: Any, u_max: Any, smoothing: Any) -> Any:
    """Smooth dead zone ``softplus(u - u_max) - softplus(u_min - u)`` of ``u - min(max(u, u_min), u_max)``.

    Equal to ``u - smooth_limit(u, ...)``: the same error bound, ``eps ln 2``, reached at a
    corner; below ``eps (exp(-|u - u_min|/eps) + exp(-|u - u_max|/eps))`` away from them.
    With ``u_min = u_max`` it is ``u - u_max`` exactly (no dead zone, nothing smoothed).

    Parameters
    ----------
    u : casadi.SX, casadi.MX, casadi.DM, float or array_like
        Input, any shape.
    u_min, u_max : casadi.SX, casadi.MX or float
        Ends of the dead band, ``u_min <= u_max``.
    smoothing : casadi.SX, casadi.MX or float
        Width ``eps`` > 0, in the unit of ``u``.

    Returns
    -------
    casadi.SX, casadi.MX or casadi.DM
        Same shape as ``u``.
    """
    return softplus(_sym(u) - u_max, smoothing) - softplus(u_min - _sym(u), smoothing)


class _Positive(Parameter):
    """A parameter that must be > 0 (a strict bound; ``lb`` is inclusive)."""

    def validate(self, value: Any, where: str) -> np.ndarray:
        """Check a value: :meth:`Parameter.validate` and every element > 0.

        Parameters
        ----------
        value : float or array_like
            Candidate value.
        where : str
            Name used in the message.

        Returns
        -------
        numpy.ndarray
            The value, shape ``(n,)``.

        Raises
        ------
        InputError
            As :meth:`Parameter.validate`, or if an element is not > 0.
        """
        arr = super().validate(value, where)
        if np.any(arr <= 0):
            raise InputError(f"{where}: must be > 0, got {value!r}")
        return arr


class _Band(Component):
    """Base of the blocks on a band ``[uMin, uMax]``: ``u``, ``y``, the limits and the width (internal)."""

    uMax = Parameter(1.0, description="upper limit of the band (unit of u)")  # noqa: N815 - MSL name
    uMin = Parameter(-1.0, description="lower limit of the band (unit of u)")  # noqa: N815 - MSL name
    smoothing = Parameter(1e-3, description="smoothing width (unit of u), > 0", smoothing=True)
    u = Variable(description="input signal (an equation of the enclosing component gives it)")
    y = Variable(description="output signal")

    def __init__(self, **modifiers: Any) -> None:
        super().__init__(**modifiers)
        lo, hi = self._values["uMin"], self._values["uMax"]
        if isinstance(lo, np.ndarray) and isinstance(hi, np.ndarray) and np.any(lo > hi):
            raise InputError(f"{type(self).__name__}: uMin must be <= uMax, got uMin={lo[0]:g} > uMax={hi[0]:g}")


class Limiter(_Band):
    """Saturation of a signal (MSL ``Blocks.Nonlinear.Limiter``), smoothed.

    Exact law: ``y = min(max(u, uMin), uMax)``. Smooth law (:func:`smooth_limit`):
    ``y = uMin + softplus(u - uMin) - softplus(u - uMax)``, ``softplus(x) = eps ln(1 + exp(x/eps))``;
    ``y`` stays in ``[uMin, uMax]`` for every width. Worst-case error ``eps ln 2`` (at a
    corner ``u = uMin`` or ``uMax``), below ``eps (exp(-|u - uMin|/eps) + exp(-|u - uMax|/eps))``
    elsewhere; the limit as ``eps -> 0`` is the exact law. MSL's ``strict``,
    ``homotopyType`` and ``limitsAtInit`` are not modelled.

    Parameters
    ----------
    uMax : float, optional
        Upper limit (unit of ``u``; default 1).
    uMin : float, optional
        Lower limit, ``<= uMax`` (default -1).
    smoothing : float, optional
        Smoothing width ``eps`` (unit of ``u``), > 0 (default 1e-3); listed in
        ``Model.smoothing``.
    **modifiers
        Further modifiers (start values of ``u``, ``y``), see
        :class:`~gtmodel.modeling.components.component.Component`.

    Raises
    ------
    InputError
        If ``smoothing <= 0`` or ``uMin > uMax``.
    """

    def equations(self) -> None:
        """``y = uMin + softplus(u - uMin) - softplus(u - uMax)``."""
        self.equation(self.y, smooth_limit(self.u, self.uMin, self.uMax, self.smoothing), name="limit")


class DeadZone(_Band):
    """Dead zone of a signal (MSL ``Blocks.Nonlinear.DeadZone``), smoothed.

    Exact law: ``y = u - uMax`` for ``u > uMax``, ``u - uMin`` for ``u < uMin``, else 0
    (``y = u - min(max(u, uMin), uMax)``). Smooth law (:func:`smooth_dead_zone`):
    ``y = softplus(u - uMax) - softplus(uMin - u)``, ``softplus(x) = eps ln(1 + exp(x/eps))``.
    Worst-case error ``eps ln 2`` (at a corner), below
    ``eps (exp(-|u - uMin|/eps) + exp(-|u - uMax|/eps))`` elsewhere; the limit as ``eps -> 0``
    is the exact law. MSL's ``deadZoneAtInit`` is not modelled.

    Parameters
    ----------
    uMax : float, optional
        Upper end of the dead band (unit of ``u``; default 1).
    uMin : float, optional
        Lower end, ``<= uMax`` (default -1).
    smoothing : float, optional
        Smoothing width ``eps`` (unit of ``u``), > 0 (default 1e-3); listed in
        ``Model.smoothing``.
    **modifiers
        Further modifiers (start values of ``u``, ``y``), see
        :class:`~gtmodel.modeling.components.component.Component`.

    Raises
    ------
    InputError
        If ``smoothing <= 0`` or ``uMin > uMax``.
    """

    def equations(self) -> None:
        """``y = softplus(u - uMax) - softplus(uMin - u)``."""
        self.equation(self.y, smooth_dead_zone(self.u, self.uMin, self.uMax, self.smoothing), name="dead_zone")
