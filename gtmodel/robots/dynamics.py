"""Rigid-body dynamics of the 3-link Gantry-Tau with cart friction, in CasADi.

Point masses (Dressler (2012), ch. 6.2): the plate ``m_p`` at the TCP, cart ``i`` ``m_c,i``
at ``A_i = As_i + q_i v_i``, link cluster ``i`` ``m_a,i`` at the link midpoint
``(A_i + T)/2``. Lagrange's equations in minimal coordinates (the TCP position ``T``, or
the cart positions ``q``), the closure equations (eq. 4.9) eliminating the other set::

    M(x) x_ddot + h(x, x_dot) + G(x) = B(x)^T f,      f = tau - f_fric(q_dot)

where ``B = dq/dx`` maps the cart forces ``f`` to generalised forces (``B = J^-1`` of
eq. 6.5 for TCP coordinates, ``I`` for cart coordinates).

- TCP coordinates (:meth:`GantryTau3Dynamics.tcp_terms`, used by inverse/forward dynamics,
  the optimal-control model and the generated C): for point masses ``p_b(T)`` Lagrange's
  equations are ``sum_b m_b J_b^T p_ddot_b + dV/dT = J^-T f`` with ``J_b = dp_b/dT``; the
  cart accelerations come in closed form from eq. 6.6, ``q_ddot_i = (dP_i . T_ddot +
  s_i) / (dP_i . v_i)``. With ``v_i = e_x`` this is the thesis' form
  ``M1 T_ddot + M2 q_ddot + G = J^-T f`` (eq. 6.7).
- Cart coordinates (:meth:`GantryTau3Dynamics.cart_terms`): the kinetic and potential
  energy are differentiated by CasADi's automatic differentiation
  (:func:`lagrange_terms`), the TCP following from the FK.

Tests check both against the thesis' eq. 6.7, a redundant-coordinate formulation with
Lagrange multipliers, and :func:`lagrange_terms` applied in TCP coordinates.
Friction: eq. 6.8 in one of the forms of :mod:`gtmodel.robots.friction`.
"""

from __future__ import annotations

from functools import cached_property
from typing import Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rows
from gtmodel.errors import InputError, SingularConfigurationError
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH, check_friction_form, friction_force
from gtmodel.robots.mapped import MappedFunction as _Mapped
from gtmodel.robots.kinematic_expressions import (
    configuration_signs,
    fk_expression,
    ik_expression,
    jacobian_inverse_expression,
    link_cosines_expression,
)
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE, GantryTau3Kinematics
from gtmodel.robots.parameters import DynamicParameters, RobotParameters, load_parameters

__all__ = ["lagrange_terms", "GantryTau3Dynamics"]


def lagrange_terms(x: ca.SX, x_dot: ca.SX, positions: Sequence[tuple[float, ca.SX]], gravity: float) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX, ca.SX]:
    """Mass matrix, velocity terms and gravity of point masses by Lagrange's equations.

    With ``KE = 1/2 sum m_k |d p_k/dt|^2`` and ``V = g sum m_k p_k,z``, Lagrange's equations
    ``d/dt dKE/dx_dot - dKE/dx + dV/dx = Q`` are written ``M x_ddot + h + G = Q``.

    Parameters
    ----------
    x, x_dot : casadi.SX, shape (n, 1)
        Generalised coordinates and velocities.
    positions : sequence of (float, casadi.SX)
        Pairs ``(m_k, p_k(x))``: mass [kg] and position (3, 1) [m] of each point mass.
    gravity : float
        Gravitational acceleration [m/s^2] along -z.

    Returns
    -------
    M : casadi.SX, shape (n, n)
        Mass matrix ``d^2 KE / dx_dot^2``.
    h : casadi.SX, shape (n, 1)
        Velocity terms ``d(dKE/dx_dot)/dx x_dot - dKE/dx``.
    G : casadi.SX, shape (n, 1)
        Gravity ``dV/dx``.
    KE : casadi.SX, scalar
        Kinetic energy [J].
    V : casadi.SX, scalar
        Potential energy [J] (zero at z = 0).
    """
    KE = 0
    V = 0
    for m, p in positions:
        if m == 0:
            continue
        p_dot = ca.jtimes(p, x, x_dot)
        KE += 0.5 * m * ca.dot(p_dot, p_dot)
        V += m * gravity * p[2]
    KE = ca.SX(KE)
    V = ca.SX(V)
    dKE_dxd = ca.gradient(KE, x_dot)
    M = ca.jacobian(dKE_dxd, x_dot)
    h = ca.jacobian(dKE_dxd, x) @ x_dot - ca.gradient(KE, x)
    G = ca.gradient(V, x)
    return M, h, G, KE, V


def _mass(m, i: int):
    """Entry i of a mass vector: a float, or a CasADi symbol kept symbolic."""
    if isinstance(m, (ca.SX, ca.MX)):
        return m[i]
    return float(m[i])


class GantryTau3Dynamics:
    """Rigid-body dynamics with cart friction of a 3-link Gantry-Tau (eqs. 6.7, 6.8).

    Parameters
    ----------
    parameters : RobotParameters or str or pathlib.Path
        A parameter set or the name/path of one.
    friction : {"exact", "tanh", "piecewise"}, optional
        Form of the sign in the friction model (default ``"exact"``); see
        :mod:`gtmodel.robots.friction`.
    friction_width : float, optional
        Velocity width [m/s] of the smooth forms (default 0.01 m/s).
    asymmetric : bool, optional
        Use the asymmetric friction of Table 6.1 (default False: symmetric Table 6.3).
    gravity : bool, optional
        Include gravity (default True).
    compiled : bool, optional
        Evaluate the numpy API (and the kinematics') through the Functions' generated C,
        compiled once to cached shared libraries (default False; see
        :class:`gtmodel.robots.mapped.MappedFunction`). Same results to 1e-12.

    Raises
    ------
    InputError
        Invalid friction form/width, or asymmetric friction without its parameters.
    """

    def __init__(
        self,
        parameters: RobotParameters | str,
        friction: str = "exact",
        friction_width: float = DEFAULT_FRICTION_WIDTH,
        asymmetric: bool = False,
        gravity: bool = True,
        compiled: bool = False,
    ) -> None:
        self.parameters = load_parameters(parameters)
        check_friction_form(friction, friction_width)
        if asymmetric and self.parameters.dynamics.asymmetric is None:
            raise InputError(f"asymmetric friction requested but parameter set {self.parameters.name!r} has none")
        self.friction = friction
        self.friction_width = float(friction_width)
        self.asymmetric = bool(asymmetric)
        self.gravity = bool(gravity)
        self.compiled = bool(compiled)
        self.kinematics = GantryTau3Kinematics(self.parameters, self.compiled)
        kp = self.parameters.kinematics
        self.L, self.As, self.v = np.asarray(kp.L), np.asarray(kp.As), np.asarray(kp.v)

    # ----------------------------------------------------------------- symbolic core
    def friction_force(self, q_dot: ca.SX | ca.MX, dynamics: DynamicParameters | None = None) -> ca.SX | ca.MX:
        """Friction force of this model, eq. 6.8 (see :func:`gtmodel.robots.friction.friction_force`).

        Parameters
        ----------
        q_dot : casadi.SX or casadi.MX, shape (3, 1)
            Cart velocities [m/s].
        dynamics : DynamicParameters, optional
            Parameters to use instead of the parameter set's (default None); their
            friction coefficients may be CasADi symbols (identification regressor).

        Returns
        -------
        casadi.SX or casadi.MX, shape (3, 1)
            Friction force [N].
        """
        d = self.parameters.dynamics if dynamics is None else dynamics
        return friction_force(q_dot, d, self.friction, self.friction_width, self.asymmetric)

    def _bodies(self, T, q):
        d = self.parameters.dynamics
        bodies = [(float(d.m_p), T)]
        for i in range(3):
            A = self.As[i] + q[i] * self.v[i]
            bodies.append((float(d.m_c[i]), A))
            bodies.append((float(d.m_a[i]), (A + T) / 2))
        return bodies

    def tcp_terms(self, T: ca.SX, T_dot: ca.SX, s: ca.SX | Sequence[float], dynamics: DynamicParameters | None = None) -> dict[str, ca.SX]:
        """Lagrange terms in TCP coordinates: eq. 6.7 generalised to any ``v_i``.

        ``M T_ddot + h + G = J^-T f`` with ``M = m_p I + sum_i (m_c,i |v_i|^2 g_i g_i^T +
        m_a,i J_i^T J_i)``, ``g_i = dq_i/dT`` (row i of eq. 6.5), ``J_i = (I + v_i g_i^T)/2``
        (link midpoint), and ``h`` from the velocity part ``s_i / (dP_i . v_i)`` of the cart
        accelerations (eq. 6.6).

        Parameters
        ----------
        T, T_dot : casadi.SX, shape (3, 1)
            TCP position [m] and velocity [m/s].
        s : casadi.SX or array_like, shape (3,)
            IK root signs (see :func:`gtmodel.robots.kinematic_expressions.configuration_signs`).
        dynamics : DynamicParameters, optional
            Parameters to use instead of the parameter set's (default None). ``m_p``,
            ``m_c`` and ``m_a`` may be CasADi symbols: the terms are linear in them, which
            the identification regressor uses (``tau = Y theta``, Dressler (2012), ch. 6.2).

        Returns
        -------
        dict
            ``M`` (3, 3) [kg], ``h`` (3,) [N], ``G`` (3,) [N], ``Jinv`` (3, 3), ``q`` (3,) [m],
            ``q_dot`` (3,) [m/s], ``disc`` (3,) [m^2], ``KE``, ``V`` [J].
        """
        p = self.parameters.dynamics if dynamics is None else dynamics
        g_acc = p.g if self.gravity else 0.0
        q, disc = ik_expression(T, s, self.L, self.As, self.v)
        Jinv = jacobian_inverse_expression(T, q, self.As, self.v)
        q_dot = Jinv @ T_dot
        ez = ca.DM([0.0, 0.0, 1.0])
        eye = ca.DM.eye(3)
        # Lagrange's equations of point masses p_b(T): sum_b m_b J_b^T p_ddot_b + dV/dT = Q,
        # with J_b = dp_b/dT and p_ddot_b = J_b T_ddot + (velocity terms); the cart
        # accelerations q_ddot_i = g_i . T_ddot + sigma_i come from eq. 6.6.
        M = p.m_p * eye
        h = ca.SX.zeros(3)
        G = g_acc * p.m_p * ez
        KE = 0.5 * p.m_p * ca.sumsqr(T_dot)
        V = g_acc * p.m_p * T[2]
        for i in range(3):
            v = ca.DM(self.v[i])
            A = ca.DM(self.As[i]) + q[i] * v
            g = Jinv[i, :].T  # dq_i/dT, eq. 6.5
            sigma = ca.sumsqr(T_dot - q_dot[i] * v) / ca.dot(T - A, v)  # velocity part of q_ddot_i, eq. 6.6
            m_c, m_a = _mass(p.m_c, i), _mass(p.m_a, i)
            J_mid = (eye + v @ g.T) / 2  # d/dT of the link midpoint (T + A_i)/2
            M += m_c * float(self.v[i] @ self.v[i]) * (g @ g.T) + m_a * (J_mid.T @ J_mid)
            h += m_c * float(self.v[i] @ self.v[i]) * sigma * g + m_a * (J_mid.T @ (v * sigma / 2))
            G += g_acc * (m_c * float(self.v[i][2]) * g + m_a * (J_mid.T @ ez))
            mid_dot = (T_dot + q_dot[i] * v) / 2
            KE += 0.5 * m_c * float(self.v[i] @ self.v[i]) * q_dot[i] ** 2 + 0.5 * m_a * ca.sumsqr(mid_dot)
            V += g_acc * (m_c * A[2] + m_a * (T[2] + A[2]) / 2)
        return dict(M=M, h=h, G=G, Jinv=Jinv, q=q, q_dot=q_dot, disc=disc, KE=KE, V=V)

    def cart_terms(self, q: ca.SX, q_dot: ca.SX, solution: float | ca.SX = 1.0) -> dict[str, ca.SX]:
        """Lagrange terms in cart coordinates (``T`` from forward kinematics, eq. 4.9).

        Parameters
        ----------
        q, q_dot : casadi.SX, shape (3, 1)
            Cart positions [m] and velocities [m/s].
        solution : float or casadi.SX, optional
            FK assembly (+1 or -1).

        Returns
        -------
        dict
            ``M`` (3, 3) [kg], ``h`` (3,) [N], ``G`` (3,) [N], ``T`` (3,) [m], ``T_dot`` (3,)
            [m/s], ``h2`` (FK discriminant) [m^2], ``KE``, ``V`` [J].
        """
        T, h2, _ = fk_expression(q, solution, self.L, self.As, self.v)
        M, h, G, KE, V = lagrange_terms(q, q_dot, self._bodies(T, q), self.parameters.dynamics.g if self.gravity else 0.0)
        return dict(M=M, h=h, G=G, T=T, T_dot=ca.jtimes(T, q, q_dot), h2=h2, KE=KE, V=V)

    def _cos_min(self, T, q):
        return ca.mmin(ca.fabs(link_cosines_expression(T, q, self.As, self.v)))

    def inverse_dynamics_expression(self, T: ca.SX, T_dot: ca.SX, T_ddot: ca.SX, s: ca.SX | Sequence[float], dynamics: DynamicParameters | None = None) -> tuple[ca.SX, dict[str, ca.SX]]:
        """Actuator forces as a CasADi expression, Dressler (2012), eqs. 6.7 and 6.8.

        ``tau = J^T (M T_ddot + h + G) + f_fric(q_dot)``. With symbolic ``dynamics`` the
        result is linear in the masses and friction coefficients, ``tau = Y theta``
        (the identification regressor, ch. 6.2).

        Parameters
        ----------
        T, T_dot, T_ddot : casadi.SX, shape (3, 1)
            TCP position [m], velocity [m/s] and acceleration [m/s^2].
        s : casadi.SX or array_like, shape (3,)
            IK root signs (see :func:`gtmodel.robots.kinematic_expressions.configuration_signs`).
        dynamics : DynamicParameters, optional
            Parameters to use instead of the parameter set's (default None); may hold
            CasADi symbols (see :meth:`tcp_terms`).

        Returns
        -------
        tau : casadi.SX, shape (3, 1)
            Actuator forces [N].
        terms : dict
            The :meth:`tcp_terms` used.
        """
        t = self.tcp_terms(T, T_dot, s, dynamics)
        f = ca.solve(t["Jinv"].T, t["M"] @ T_ddot + t["h"] + t["G"])
        return f + self.friction_force(t["q_dot"], dynamics), t

    # ----------------------------------------------------------------- CasADi Functions
    @cached_property
    def inverse_dynamics_function(self) -> ca.Function:
        """CasADi Function ``inverse_dynamics(T, T_dot, T_ddot, s) -> (tau, disc, cos_min)``.

        ``tau = J^T (M T_ddot + h + G) + f_fric(q_dot)`` [N] (eqs. 6.7, 6.8); ``disc`` (3)
        and ``cos_min`` as in :attr:`GantryTau3Kinematics.jacobian_function` for status checks.
        """
        T, T_dot, T_ddot, s = (ca.SX.sym(n, 3) for n in ("T", "T_dot", "T_ddot", "s"))
        tau, t = self.inverse_dynamics_expression(T, T_dot, T_ddot, s)
        return ca.Function(
            "inverse_dynamics",
            [T, T_dot, T_ddot, s],
            [tau, t["disc"], self._cos_min(T, t["q"])],
            ["T", "T_dot", "T_ddot", "s"],
            ["tau", "disc", "cos_min"],
        )

    @cached_property
    def forward_dynamics_function(self) -> ca.Function:
        """CasADi Function ``forward_dynamics(T, T_dot, tau, s) -> (T_ddot, disc, cos_min)`` (eqs. 6.7, 6.8)."""
        T, T_dot, tau, s = (ca.SX.sym(n, 3) for n in ("T", "T_dot", "tau", "s"))
        t = self.tcp_terms(T, T_dot, s)
        f = tau - self.friction_force(t["q_dot"])
        T_ddot = ca.solve(t["M"], t["Jinv"].T @ f - t["h"] - t["G"])
        return ca.Function(
            "forward_dynamics",
            [T, T_dot, tau, s],
            [T_ddot, t["disc"], self._cos_min(T, t["q"])],
            ["T", "T_dot", "tau", "s"],
            ["T_ddot", "disc", "cos_min"],
        )

    @cached_property
    def energy_function(self) -> ca.Function:
        """CasADi Function ``energy(T, T_dot, s) -> (KE, V)``: kinetic and potential energy [J]."""
        T, T_dot, s = (ca.SX.sym(n, 3) for n in ("T", "T_dot", "s"))
        t = self.tcp_terms(T, T_dot, s)
        return ca.Function("energy", [T, T_dot, s], [t["KE"], t["V"]], ["T", "T_dot", "s"], ["KE", "V"])

    @cached_property
    def _inv(self) -> _Mapped:
        return _Mapped(self.inverse_dynamics_function, self.compiled)

    @cached_property
    def _fwd(self) -> _Mapped:
        return _Mapped(self.forward_dynamics_function, self.compiled)

    def _checked(self, mapped: _Mapped, T, a, b, configuration, names):
        Tn, single = as_rows(T, names[0], 3)
        An, _ = as_rows(a, names[1], 3)
        Bn, _ = as_rows(b, names[2], 3)
        if not (Tn.shape == An.shape == Bn.shape):
            raise InputError(f"{', '.join(names)}: expected equal shapes, got {Tn.shape}, {An.shape}, {Bn.shape}")
        s = configuration_signs(configuration)
        out, disc, cos_min = mapped(Tn.T, An.T, Bn.T, s[:, None])
        self.kinematics._check_reach(disc, Tn)
        cos_min = cos_min.ravel()
        if (cos_min < SINGULARITY_TOLERANCE).any():
            k = int(np.argmin(cos_min))
            raise SingularConfigurationError(f"pose T={Tn[k].tolist()} is singular: a link is perpendicular to its guideway")
        out = out.T
        return out[0] if single else out

    # ----------------------------------------------------------------- numpy API
    def inverse_dynamics(self, T: np.typing.ArrayLike, T_dot: np.typing.ArrayLike, T_ddot: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """Actuator forces for a TCP motion, Dressler (2012), eqs. 6.7 and 6.8.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position [m].
        T_dot : array_like, shape (3,) or (N, 3)
            TCP velocity [m/s].
        T_ddot : array_like, shape (3,) or (N, 3)
            TCP acceleration [m/s^2].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`GantryTau3Kinematics.ik`).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Actuator (cart) forces ``tau`` [N].

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        SingularConfigurationError
            A link is perpendicular to its guideway.
        InputError
            Wrong or mismatched shapes, non-finite values.
        """
        return self._checked(self._inv, T, T_dot, T_ddot, configuration, ("T", "T_dot", "T_ddot"))

    def forward_dynamics(self, T: np.typing.ArrayLike, T_dot: np.typing.ArrayLike, tau: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """TCP acceleration for actuator forces, Dressler (2012), eqs. 6.7 and 6.8.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position [m].
        T_dot : array_like, shape (3,) or (N, 3)
            TCP velocity [m/s].
        tau : array_like, shape (3,) or (N, 3)
            Actuator forces [N].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`GantryTau3Kinematics.ik`).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            TCP acceleration [m/s^2].

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        SingularConfigurationError
            A link is perpendicular to its guideway.
        InputError
            Wrong or mismatched shapes, non-finite values.
        """
        return self._checked(self._fwd, T, T_dot, tau, configuration, ("T", "T_dot", "tau"))

    def gravity_forces(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """Actuator forces that hold the robot at rest: ``J^T G`` (Dressler (2012), Table 6.2).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position [m].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`GantryTau3Kinematics.ik`).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Static actuator forces [N] (friction is zero at rest in every form).

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        InputError
            Wrong shape or non-finite values.
        """
        Tn, single = as_rows(T, "T", 3)
        zero = np.zeros_like(Tn)
        out = self.inverse_dynamics(Tn, zero, zero, configuration)
        return out[0] if single else out
