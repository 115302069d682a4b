"""The robot arm of COPS 3.0 (Dolan, More, Munson 2004, problem 9; Monterey Phoenix arm).

A rigid arm of length ``L`` rotating about a vertical axis (``theta``) and tilting
(``phi``), with a gripper at ``rho`` along it; the moments of inertia
``I_theta = ((L - rho)^3 + rho^3) sin(phi)^2 / 3`` and ``I_phi = ((L - rho)^3 + rho^3) / 3``.
COPS states the problem without units (``L = 5``, ``|u| <= 1``): the length ``rho``, its
rate and the inputs are scaled (unit ``"1"``, as for the Goddard rocket), the angles are in
``rad`` (``|theta| <= pi``) and their rates in ``rad/s``.
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class RobotArm(Model):
    """States rho, theta, phi and their rates; inputs u_rho, u_theta, u_phi."""

    def __init__(self) -> None:
        super().__init__("robot_arm")
        L = self.parameter("L", 5.0)
        rho = self.state("rho", unit="1", start=4.5)
        theta = self.state("theta", unit="rad")
        phi = self.state("phi", unit="rad", start=0.785398163397448)
        rho_d = self.state("rho_d", unit="1")
        theta_d = self.state("theta_d", unit="rad/s")
        phi_d = self.state("phi_d", unit="rad/s")
        u_rho = self.input("u_rho", unit="1")
        u_theta = self.input("u_theta", unit="1")
        u_phi = self.input("u_phi", unit="1")
        inertia = ((L - rho) ** 3 + rho**3) / 3
        self.equation(self.der(rho), rho_d, name="rho")
        self.equation(self.der(theta), theta_d, name="theta")
        self.equation(self.der(phi), phi_d, name="phi")
        self.equation(L * self.der(rho_d), u_rho, name="rho_dd")
        self.equation(inertia * ca.sin(phi) ** 2 * self.der(theta_d), u_theta, name="theta_dd")
        self.equation(inertia * self.der(phi_d), u_phi, name="phi_dd")
