"""A compliant, position-controlled linear drive axis composed from the library.

One Gantry-Tau actuator: a servo on the motor angle, the motor inertia, a gear, a belt
pulley, a compliant belt and the cart::

    servo (PositionServo) -- motor (Inertia) -- gear (IdealGear) -- pulley (IdealRollingWheel)
        -- belt (translational SpringDamper) -- cart (Mass) -- flange (for a load or friction)

The servo is the mechanical form of a cascaded P position / P speed controller on the
motor angle, ``tau = kp (phi_f - phi) - kv w``, behind a first-order reference filter
``T der(phi_f) = phi_ref - phi_f`` (the low-bandwidth reference path of the L1's
external control interface, Dressler (2012), eq. (6.11)).

Undamped, the axis is a two-mass oscillator (motor, reflected to the cart coordinate:
``m1 = J (ratio/radius)^2``, position-loop stiffness ``k1 = kp (ratio/radius)^2``; belt
stiffness ``k2``; cart mass ``m2``) with the two modes of
``det(K - M w^2) = 0``, ``M = diag(m1, m2)``, ``K = [[k1 + k2, -k2], [-k2, k2]]``.
:func:`two_mass_parameters` inverts this: given the two modes (for the L1 the 13.83 and
103.34 Hz of Dressler (2012), eq. (6.15)) and the masses, it returns the two stiffnesses
(characteristic polynomial: ``w1^2 + w2^2 = (k1 + k2)/m1 + k2/m2`` and
``w1^2 w2^2 = k1 k2 / (m1 m2)``), and the two damping constants that give the modal
damping ratios (modal approximation ``2 zeta_i w_i phi_i^T M phi_i = phi_i^T C phi_i``).
The identified 2x2 matrices of (6.14) are not symmetric, so no physical chain has them;
what a chain can have is their modes. For the L1 defaults the undamped modes are those
of (6.15) exactly and the damping ratios 0.1669 / 0.00678 (thesis 0.1668 / 0.00679); the
damped natural frequencies are 13.83 / 103.32 Hz, whereas the thesis' non-symmetric
``D`` moves its damped poles to 14.21 / 100.56 Hz (not reproducible by a chain).

The frequency response from the cart-position reference to the cart position has the
shape of (6.11) for axis 3 below the structural modes (within 0.31 dB from 0.05 to
3 Hz, -3 dB at 1.108 Hz against 1.095 Hz; the composed model has no transport delay,
the 5-sample delay of (6.11) is not modelled), and above them the resonance of the
lightly damped second mode.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.modeling.components.component import Component, Input, Parameter, State, Variable, connect
from gtmodel.modeling.library import rotational, translational

__all__ = ["PositionServo", "CompliantDriveAxis", "TwoMassParameters", "two_mass_parameters", "drive_axis_from_modes"]


@dataclass(frozen=True)
class TwoMassParameters:
    """Parameters of a two-mass drive axis, in the cart coordinate [m] unless stated.

    Parameters
    ----------
    m1 : float
        Motor inertia reflected to the cart coordinate [kg].
    m2 : float
        Cart mass [kg].
    k1 : float
        Position-loop stiffness, reflected [N/m].
    k2 : float
        Belt stiffness [N/m].
    c1 : float
        Speed-loop damping, reflected [N s/m].
    c2 : float
        Belt damping [N s/m].
    """

    m1: float
    m2: float
    k1: float
    k2: float
    c1: float
    c2: float


def _positive(value: float, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value) or value <= 0:
        raise InputError(f"{name}: expected a positive finite number, got {value!r}")
    return float(value)


def two_mass_parameters(
    frequencies_hz: tuple[float, float],
    m1: float,
    m2: float,
    damping_ratios: tuple[float, float] = (0.0, 0.0),
    stiff_belt: bool = True,
) -> TwoMassParameters:
    """Stiffnesses and dampings of a grounded two-mass chain with given modes.

    Chain ``ground -k1,c1- m1 -k2,c2- m2``. Stiffnesses from the characteristic
    polynomial of ``det(K - M w^2) = 0`` (exact); dampings from the modal approximation
    ``2 zeta_i w_i phi_i^T M phi_i = phi_i^T C phi_i`` (a 2x2 linear system). The modes
    are those of Dressler (2012), eq. (6.15) for the L1.

    Parameters
    ----------
    frequencies_hz : tuple of float
        The two undamped modes ``f1 < f2`` [Hz].
    m1, m2 : float
        Masses [kg] (motor reflected, cart).
    damping_ratios : tuple of float, optional
        Modal damping ratios ``(zeta1, zeta2)`` (default undamped).
    stiff_belt : bool, optional
        Of the two stiffness solutions, take the one with the stiffer belt ``k2``
        (default) or the softer one.

    Returns
    -------
    TwoMassParameters
        Masses, stiffnesses and dampings.

    Raises
    ------
    InputError
        If the frequencies are not two increasing positive numbers, a mass is not
        positive, no real stiffnesses exist for these masses (``m1`` too small:
        ``(w1^2 + w2^2)^2 < 4 w1^2 w2^2 (1 + m2/m1)``), or the damping ratios need a
        negative damping constant.
    """
    try:
        f1, f2 = (float(f) for f in frequencies_hz)
        z1, z2 = (float(z) for z in damping_ratios)
    except (TypeError, ValueError):
        raise InputError(f"frequencies_hz and damping_ratios: expected two numbers each, got {frequencies_hz!r}, {damping_ratios!r}") from None
    if not (0 < f1 < f2 < math.inf):
        raise InputError(f"frequencies_hz: expected 0 < f1 < f2, got {frequencies_hz!r}")
    if not (z1 >= 0 and z2 >= 0 and math.isfinite(z1 + z2)):
        raise InputError(f"damping_ratios: expected two non-negative numbers, got {damping_ratios!r}")
    m1, m2 = _positive(m1, "m1"), _positive(m2, "m2")
    w1, w2 = 2 * math.pi * f1, 2 * math.pi * f2
    trace, det = w1**2 + w2**2, w1**2 * w2**2
    s = 1 / m1 + 1 / m2
    disc = trace**2 - 4 * det * m2 * s
    if disc < 0:
        raise InputError(
            f"m1 = {m1:g} kg: no real stiffnesses give the modes {f1:g}, {f2:g} Hz with m2 = {m2:g} kg; "
            f"m1 must be >= {m2 / (trace**2 / (4 * det) - 1):g} kg"
        )
    k2 = (trace + (1 if stiff_belt else -1) * math.sqrt(disc)) / (2 * s)
    k1 = det * m1 * m2 / k2
    M = np.diag([m1, m2])
    K = np.array([[k1 + k2, -k2], [-k2, k2]])
    lam, vecs = np.linalg.eig(np.linalg.solve(M, K))
    order = np.argsort(lam.real)
    rows = []
    for i, w in zip(order, (w1, w2)):
        phi = vecs[:, i].real
        rows.append(([phi[0] ** 2, (phi[0] - phi[1]) ** 2], 2 * w * float(phi @ M @ phi)))
    G = np.array([r[0] for r in rows])
    rhs = np.array([r[1] for r in rows]) * np.array([z1, z2])
    c1, c2 = np.linalg.solve(G, rhs)
    if c1 < 0 or c2 < 0:
        raise InputError(
            f"damping_ratios {damping_ratios!r}: need a negative damping constant (c1 = {c1:g}, c2 = {c2:g} N s/m)"
        )
    return TwoMassParameters(m1=m1, m2=m2, k1=k1, k2=k2, c1=float(c1), c2=float(c2))


class PositionServo(Component):
    """Cascaded P position / P speed servo on a motor angle, with a first-order reference filter.

    ``T der(phi_f) = phi_ref - phi_f``, the measured angle ``phi = flange.phi`` and speed
    ``w = der(phi)``, and the torque on the motor ``kp (phi_f - phi) - kv w``
    (``flange.tau`` is its negative): the
    mechanical form of ``tau = Kv (Kp (phi_f - phi) - w)`` with ``kp = Kv Kp``,
    ``kv = Kv``. Input ``phi_ref`` [rad], motor-angle reference.

    Parameters
    ----------
    kp : float, optional
        Position-loop stiffness [N m/rad], >= 0.
    kv : float, optional
        Speed-loop gain [N m s/rad], >= 0.
    T : float, optional
        Reference filter time constant [s], > 0.
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    kp = Parameter(10.0, unit="N.m/rad", description="position-loop stiffness Kv*Kp", lb=0.0)
    kv = Parameter(0.1, unit="N.m.s/rad", description="speed-loop gain Kv", lb=0.0)
    T = Parameter(0.145, unit="s", description="time constant of the reference filter", lb=1e-9)
    phi_ref = Input(unit="rad", description="motor-angle reference")
    phi_f = State(unit="rad", description="filtered motor-angle reference")
    phi = State(unit="rad", description="measured motor angle")
    w = Variable(unit="rad/s", description="measured motor speed, der(phi)")
    flange = rotational.Flange_b("flange on the motor shaft")

    def equations(self) -> None:
        """Reference filter, the measured angle and speed, and the control torque."""
        self.equation(self.T * self.der(self.phi_f), self.phi_ref - self.phi_f, name="filter")
        self.equation(self.phi, self.flange.phi, name="angle")
        self.equation(self.w, self.der(self.phi), name="speed")
        self.equation(-self.flange.tau, self.kp * (self.phi_f - self.phi) - self.kv * self.w, name="control")


# Defaults: the L1 (Dressler (2012)): modes 13.826 / 103.337 Hz and damping ratios
# 0.1668 / 0.00679 of (6.14)-(6.15) (gtmodel.robots.structural), cart 3 mass 38.23 kg
# (Table 6.3), reference filter from (6.11) for axis 3 (a = 0.9728, T_s = 4 ms); motor
# 1.2e-3 kg m^2, gear 10, pulley radius 0.025 m (assumed: not in the thesis; the reflected
# motor inertia, 192 kg, must exceed about 140 kg for non-negative dampers to give both
# damping ratios).
_J, _RATIO, _RADIUS, _M_CART = 1.2e-3, 10.0, 0.025, 38.23
_REFLECT = (_RATIO / _RADIUS) ** 2
_L1 = two_mass_parameters((13.8258, 103.3373), _J * _REFLECT, _M_CART, (0.16683, 0.0067885))
_T_REF = LOOP_PERIOD_S / -math.log(0.9728)


class CompliantDriveAxis(Component):
    """Position-controlled belt-driven axis: servo, motor, gear, pulley, belt, cart.

    Defaults model one L1 actuator (see the module docstring and
    :func:`drive_axis_from_modes`). Input ``servo.phi_ref`` [rad] (motor angle; the cart
    position reference is ``phi_ref radius / ratio``); connector ``flange`` is the cart's
    free side (for a load or friction), a free end when the axis is flattened alone.

    Parameters
    ----------
    **modifiers
        Sub-component modifiers, e.g. ``CompliantDriveAxis(belt={"c": 2e6})``.
    """

    servo = PositionServo(kp=_L1.k1 / _REFLECT, kv=_L1.c1 / _REFLECT, T=_T_REF)
    motor = rotational.Inertia(J=_J)
    gear = rotational.IdealGear(ratio=_RATIO)
    pulley = rotational.IdealRollingWheel(radius=_RADIUS)
    belt = translational.SpringDamper(c=_L1.k2, d=_L1.c2)
    cart = translational.Mass(m=_M_CART)
    flange = translational.Flange_b("free side of the cart")

    def equations(self) -> None:
        """The connections of the chain."""
        connect(self.servo.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.pulley.flangeR)
        connect(self.pulley.flangeT, self.belt.flange_a)
        connect(self.belt.flange_b, self.cart.flange_a)
        connect(self.cart.flange_b, self.flange)


def drive_axis_from_modes(
    frequencies_hz: tuple[float, float],
    damping_ratios: tuple[float, float] = (0.0, 0.0),
    J: float = _J,
    ratio: float = _RATIO,
    radius: float = _RADIUS,
    m_cart: float = _M_CART,
    bandwidth_hz: float = 1.0 / (2 * math.pi * _T_REF),
) -> CompliantDriveAxis:
    """A :class:`CompliantDriveAxis` whose two undamped modes are ``frequencies_hz``.

    Stiffnesses and dampings by :func:`two_mass_parameters` (Dressler (2012), eq. (6.15)
    modes) in the cart coordinate, converted to the motor side with ``(radius/ratio)^2``;
    reference filter ``T = 1 / (2 pi bandwidth_hz)`` (the pole of (6.11)).

    Parameters
    ----------
    frequencies_hz : tuple of float
        Undamped modes ``f1 < f2`` [Hz].
    damping_ratios : tuple of float, optional
        Modal damping ratios (default undamped).
    J : float, optional
        Motor inertia [kg m^2].
    ratio : float, optional
        Gear ratio (motor angle / pulley angle).
    radius : float, optional
        Pulley radius [m].
    m_cart : float, optional
        Cart mass [kg].
    bandwidth_hz : float, optional
        Reference filter bandwidth [Hz].

    Returns
    -------
    CompliantDriveAxis
        The axis with these parameters as modifiers.

    Raises
    ------
    InputError
        Non-positive values, or modes no chain with these masses has
        (see :func:`two_mass_parameters`).
    """
    J, ratio, radius = _positive(J, "J"), _positive(ratio, "ratio"), _positive(radius, "radius")
    bw = _positive(bandwidth_hz, "bandwidth_hz")
    reflect = (ratio / radius) ** 2
    tm = two_mass_parameters(frequencies_hz, J * reflect, m_cart, damping_ratios)
    return CompliantDriveAxis(
        servo={"kp": tm.k1 / reflect, "kv": tm.c1 / reflect, "T": 1.0 / (2 * math.pi * bw)},
        motor={"J": J},
        gear={"ratio": ratio},
        pulley={"radius": radius},
        belt={"c": tm.k2, "d": tm.c2},
        cart={"m": tm.m2},
    )
