"""Orbit raising of Bryson and Ho (1975, sec. 2.5): a low-thrust transfer to the largest circular orbit.

A spacecraft of initial mass ``m0`` in a circular orbit of radius ``r0`` thrusts with constant
magnitude ``T`` in a direction given by the unit vector ``(u1, u2)`` (radial, tangential);
its mass falls at the rate ``mdot``. In the normalised units of Bryson and Ho (``mu = r0 =
m0 = 1``): ``T = 0.1405``, ``mdot = 0.0749``, final time 3.32 (about 193 days for the
Earth-Mars transfer of the source). Polar coordinates: radius ``r``, polar angle ``theta``,
radial velocity ``vr`` and tangential velocity ``vt``. Units: the normalised ones of the source
(unit ``"1"``), the polar angle in ``rad``, the thrust direction ``(u1, u2)`` dimensionless.
"""

from __future__ import annotations

from gtmodel.modeling import Model


class OrbitRaising(Model):
    """States r, theta, vr, vt; inputs u1 (radial) and u2 (tangential) thrust direction."""

    def __init__(self) -> None:
        super().__init__("orbit_raising")
        mu = self.parameter("mu", 1.0)
        thrust = self.parameter("thrust", 0.1405)
        mdot = self.parameter("mdot", 0.0749)
        m0 = self.parameter("m0", 1.0)
        r = self.state("r", unit="1", start=1.0)
        theta = self.state("theta", unit="rad", start=0.0)
        vr = self.state("vr", unit="1", start=0.0)
        vt = self.state("vt", unit="1", start=1.0)
        u1 = self.input("u1", unit="1", start=0.0)
        u2 = self.input("u2", unit="1", start=1.0)
        accel = thrust / (m0 - mdot * self.time)
        self.equation(self.der(r), vr, name="radius")
        self.equation(self.der(theta), vt / r, name="angle")
        self.equation(self.der(vr), vt**2 / r - mu / r**2 + accel * u1, name="radial")
        self.equation(self.der(vt), -vr * vt / r + accel * u2, name="tangential")
