"""Kinematics of the 3-link Gantry-Tau model (nominal and modified), in CasADi.

The closure equation of arm ``i`` (Dressler (2012), eq. 4.9)::

    L_i^2 = || As_i + q_i v_i - T ||^2

is written once, symbolically, in :mod:`gtmodel.robots.kinematic_expressions` (re-exported
here). Inverse kinematics (a quadratic per arm), forward kinematics (trilateration of three
spheres), the inverse Jacobian (eq. 6.5) and the acceleration relation (eq. 6.6) are CasADi
expressions of it; :class:`GantryTau3Kinematics`
wraps them in :class:`casadi.Function` objects (the same graph serves NumPy evaluation,
derivatives for the solvers and generated C) and in NumPy-friendly methods that accept one
pose ``(3,)`` or ``N`` poses ``(N, 3)`` (evaluated with ``Function.map``, not Python loops).

Configurations
--------------
IK: each arm has two solutions, ``q_i = (d.v_i + s_i sqrt(disc_i)) / |v_i|^2`` with
``d = T - As_i``. Configuration ``c`` (an integer 0-7) selects the signs: bit ``i`` clear
gives ``s_i = -1``, for which ``(T - A_i) . v_i > 0`` (the TCP lies ahead of cart ``i``
along its guideway: the nominal assembly), bit ``i`` set gives ``s_i = +1``.

FK: the three spheres (centres ``A_i``, radii ``L_i``) meet in two points mirrored in
the plane of the centres. ``solution=+1`` (default) picks the one on the side the mean
guideway direction points to, ``solution=-1`` the other.
"""

from __future__ import annotations

from functools import cached_property
from typing import Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rows
from gtmodel.errors import InputError, SingularConfigurationError, UnreachablePoseError
from gtmodel.robots.kinematic_expressions import (
    acceleration_expression,
    cart_acceleration_expression,
    closure_residual,
    configuration_signs,
    fk_expression,
    ik_expression,
    jacobian_inverse_expression,
    link_cosines_expression,
)
from gtmodel.robots.mapped import MappedFunction
from gtmodel.robots.parameters import KinematicParameters, RobotParameters, load_parameters
from gtmodel.robots.workspace import within_limits

__all__ = [
    "closure_residual",
    "ik_expression",
    "fk_expression",
    "jacobian_inverse_expression",
    "link_cosines_expression",
    "acceleration_expression",
    "cart_acceleration_expression",
    "configuration_signs",
    "GantryTau3Kinematics",
    "SINGULARITY_TOLERANCE",
    "DEGENERACY_TOLERANCE",
]

#: Smallest accepted |cos| of the angle between a link and its guideway; below it the
#: Jacobian (eq. 6.5) is treated as singular.
SINGULARITY_TOLERANCE = 1e-6
#: Smallest accepted distance [m] of the third sphere centre from the line through the
#: first two in FK (collinear centres give no unique pose).
DEGENERACY_TOLERANCE = 1e-9


# ----------------------------------------------------------------------------- numpy glue
def _solution_sign(solution: int) -> float:
    if solution not in (1, -1) or isinstance(solution, bool):
        raise InputError(f"solution: expected +1 or -1, got {solution!r}")
    return float(solution)


class GantryTau3Kinematics:
    """Kinematics of a 3-link Gantry-Tau (nominal "ideal" or "modified" model).

    Parameters
    ----------
    parameters : RobotParameters or KinematicParameters or str or pathlib.Path
        A parameter set, or the name/path of one (see
        :func:`gtmodel.robots.parameters.load_parameters`).
    compiled : bool, optional
        Evaluate the numpy API through the Functions' generated C, compiled once to cached
        shared libraries (default False; see :class:`gtmodel.robots.mapped.MappedFunction`).

    Notes
    -----
    The CasADi Functions (attributes ``*_function``) have the parameters embedded as
    constants, so they can be code-generated as they are. Their inputs are column
    vectors; ``s`` (3) holds IK root signs and ``solution`` (1) the FK branch.
    """

    def __init__(self, parameters: RobotParameters | KinematicParameters | str, compiled: bool = False) -> None:
        self.compiled = bool(compiled)
        if isinstance(parameters, KinematicParameters):
            self.parameters: RobotParameters | None = None
            self.kinematic_parameters = parameters
        else:
            self.parameters = load_parameters(parameters)
            self.kinematic_parameters = self.parameters.kinematics
        kp = self.kinematic_parameters
        self.L = np.asarray(kp.L, dtype=float)
        self.As = np.asarray(kp.As, dtype=float)
        self.v = np.asarray(kp.v, dtype=float)

    # --------------------------------------------------------------- CasADi Functions
    @cached_property
    def ik_function(self) -> ca.Function:
        """CasADi Function ``ik(T[3], s[3]) -> (q[3], disc[3])``, see :func:`ik_expression`."""
        T = ca.SX.sym("T", 3)
        s = ca.SX.sym("s", 3)
        q, disc = ik_expression(T, s, self.L, self.As, self.v)
        return ca.Function("ik", [T, s], [q, disc], ["T", "s"], ["q", "disc"])

    @cached_property
    def fk_function(self) -> ca.Function:
        """CasADi Function ``fk(q[3], solution) -> (T[3], h2, j)``, see :func:`fk_expression`."""
        q = ca.SX.sym("q", 3)
        sol = ca.SX.sym("solution")
        T, h2, j = fk_expression(q, sol, self.L, self.As, self.v)
        return ca.Function("fk", [q, sol], [T, h2, j], ["q", "solution"], ["T", "h2", "j"])

    @cached_property
    def jacobian_function(self) -> ca.Function:
        """CasADi Function ``jacobian(T[3], s[3]) -> (J[3x3], Jinv[3x3], q[3], disc[3], cos_min)``.

        ``cos_min`` is the smallest ``|dP_i . v_i| / (|dP_i| |v_i|)``: near zero the
        configuration is singular (eq. 6.5).
        """
        T = ca.SX.sym("T", 3)
        s = ca.SX.sym("s", 3)
        q, disc = ik_expression(T, s, self.L, self.As, self.v)
        Jinv = jacobian_inverse_expression(T, q, self.As, self.v)
        J = ca.inv(Jinv)
        cos_min = ca.mmin(ca.fabs(link_cosines_expression(T, q, self.As, self.v)))
        return ca.Function(
            "jacobian", [T, s], [J, Jinv, q, disc, cos_min], ["T", "s"], ["J", "Jinv", "q", "disc", "cos_min"]
        )

    @cached_property
    def link_cosines_function(self) -> ca.Function:
        """CasADi Function ``link_cosines(T[3], s[3]) -> (cos[3], q[3], disc[3])``, see :func:`link_cosines_expression`."""
        T = ca.SX.sym("T", 3)
        s = ca.SX.sym("s", 3)
        q, disc = ik_expression(T, s, self.L, self.As, self.v)
        c = link_cosines_expression(T, q, self.As, self.v)
        return ca.Function("link_cosines", [T, s], [c, q, disc], ["T", "s"], ["cos", "q", "disc"])

    @cached_property
    def _cos(self) -> MappedFunction:
        return MappedFunction(self.link_cosines_function, self.compiled)

    @cached_property
    def acceleration_function(self) -> ca.Function:
        """CasADi Function ``acceleration(T, T_dot, q_ddot, s) -> T_ddot`` (eq. 6.6), all (3,)."""
        T, T_dot, q_ddot, s = (ca.SX.sym(n, 3) for n in ("T", "T_dot", "q_ddot", "s"))
        q, _ = ik_expression(T, s, self.L, self.As, self.v)
        q_dot = jacobian_inverse_expression(T, q, self.As, self.v) @ T_dot
        T_ddot = acceleration_expression(T, T_dot, q, q_dot, q_ddot, self.As, self.v)
        return ca.Function("acceleration", [T, T_dot, q_ddot, s], [T_ddot], ["T", "T_dot", "q_ddot", "s"], ["T_ddot"])

    @cached_property
    def cart_acceleration_function(self) -> ca.Function:
        """CasADi Function ``cart_acceleration(T, T_dot, T_ddot, s) -> (q_dot, q_ddot)`` (eq. 6.6), all (3,)."""
        T, T_dot, T_ddot, s = (ca.SX.sym(n, 3) for n in ("T", "T_dot", "T_ddot", "s"))
        q, _ = ik_expression(T, s, self.L, self.As, self.v)
        q_dot = jacobian_inverse_expression(T, q, self.As, self.v) @ T_dot
        q_ddot = cart_acceleration_expression(T, T_dot, T_ddot, q, q_dot, self.As, self.v)
        return ca.Function(
            "cart_acceleration", [T, T_dot, T_ddot, s], [q_dot, q_ddot], ["T", "T_dot", "T_ddot", "s"], ["q_dot", "q_ddot"]
        )

    @cached_property
    def _ik(self) -> MappedFunction:
        return MappedFunction(self.ik_function, self.compiled)

    @cached_property
    def _fk(self) -> MappedFunction:
        return MappedFunction(self.fk_function, self.compiled)

    @cached_property
    def _jac(self) -> MappedFunction:
        return MappedFunction(self.jacobian_function, self.compiled)

    @cached_property
    def _acc(self) -> MappedFunction:
        return MappedFunction(self.acceleration_function, self.compiled)

    @cached_property
    def _cacc(self) -> MappedFunction:
        return MappedFunction(self.cart_acceleration_function, self.compiled)

    # --------------------------------------------------------------- checks
    def _check_reach(self, disc: np.ndarray, T: np.ndarray) -> None:
        bad = disc < 0  # (3, N)
        if bad.any():
            k = int(np.argwhere(bad)[0][1])
            arms = [int(a) for a in np.flatnonzero(bad[:, k])]
            where = "" if T.shape[0] == 1 else f" (row {k})"
            details = []
            for i in arms:
                d = T[k] - self.As[i]
                vh = self.v[i] / np.linalg.norm(self.v[i])
                dist = float(np.sqrt(max(d @ d - (d @ vh) ** 2, 0.0)))
                details.append(f"arm {i + 1} (distance to guideway {dist:.4f} m > link length {self.L[i]:.4f} m)")
            raise UnreachablePoseError(f"pose T={T[k].tolist()}{where} is unreachable: " + ", ".join(details))

    # --------------------------------------------------------------- public numpy API
    def ik(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """Cart positions for TCP positions (inverse kinematics, eq. 4.9).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position(s) [m].
        configuration : int or sequence of int, optional
            IK configuration 0-7 or three root signs (default 0: the nominal assembly, the
            TCP ahead of every cart along its guideway). See :func:`configuration_signs`.

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Cart positions q [m].

        Raises
        ------
        UnreachablePoseError
            Some arm cannot reach some pose; the message names the arm and the row.
        InputError
            Wrong shape, non-finite values or an invalid configuration.
        """
        Tn, single = as_rows(T, "T", 3)
        s = configuration_signs(configuration)
        q, disc = self._ik(Tn.T, s[:, None])
        self._check_reach(disc, Tn)
        q = q.T
        return q[0] if single else q

    def fk(self, q: np.typing.ArrayLike, solution: int = 1) -> np.ndarray:
        """TCP positions for cart positions (forward kinematics by trilateration, eq. 4.9).

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m].
        solution : {1, -1}, optional
            FK assembly: +1 (default) the TCP on the side of the sphere-centre plane the
            mean guideway direction points to, -1 its mirror image.

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            TCP position(s) T [m].

        Raises
        ------
        UnreachablePoseError
            The three spheres do not intersect (no pose for these joint values) or their
            centres are collinear; the message names the row.
        InputError
            Wrong shape, non-finite values or an invalid ``solution``.
        """
        qn, single = as_rows(q, "q", 3)
        sol = _solution_sign(solution)
        T, h2, j = self._fk(qn.T, np.array([[sol]]))
        h2 = h2.ravel()
        j = j.ravel()
        bad = (h2 < 0) | ~(j > DEGENERACY_TOLERANCE)
        if np.any(bad):
            k = int(np.argmax(bad))
            where = "" if single else f" (row {k})"
            why = "the centres of the three link spheres are collinear" if not j[k] > DEGENERACY_TOLERANCE else (
                "the three link spheres do not intersect"
            )
            raise UnreachablePoseError(f"joint values q={qn[k].tolist()}{where} admit no pose: {why}")
        T = T.T
        return T[0] if single else T

    def _jacobians(self, T, configuration) -> tuple[np.ndarray, np.ndarray, bool]:
        Tn, single = as_rows(T, "T", 3)
        s = configuration_signs(configuration)
        J, Jinv, _, disc, cos_min = self._jac(Tn.T, s[:, None])
        self._check_reach(disc, Tn)
        cos_min = cos_min.ravel()
        if np.any(cos_min < SINGULARITY_TOLERANCE):
            k = int(np.argmin(cos_min))
            raise SingularConfigurationError(
                f"pose T={Tn[k].tolist()} is singular: a link is perpendicular to its guideway "
                f"(|cos| = {cos_min[k]:.3g} < {SINGULARITY_TOLERANCE})"
            )
        n = Tn.shape[0]
        # mapped outputs are horizontally stacked 3x3 blocks
        J = J.reshape(3, n, 3).transpose(1, 0, 2) if n > 1 else J[None]
        Jinv = Jinv.reshape(3, n, 3).transpose(1, 0, 2) if n > 1 else Jinv[None]
        return J, Jinv, single

    def jacobian(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """Jacobian ``J`` with ``T_dot = J q_dot`` (inverse of eq. 6.5).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position(s) [m].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).

        Returns
        -------
        numpy.ndarray, shape (3, 3) or (N, 3, 3)
            ``J`` (dimensionless).

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        SingularConfigurationError
            A link is perpendicular to its guideway (``|cos| < SINGULARITY_TOLERANCE``).
        InputError
            Wrong shape or non-finite values.
        """
        J, _, single = self._jacobians(T, configuration)
        return J[0] if single else J

    def jacobian_inverse(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """Inverse Jacobian ``J^-1`` with ``q_dot = J^-1 T_dot``, Dressler (2012), eq. 6.5.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position(s) [m].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).

        Returns
        -------
        numpy.ndarray, shape (3, 3) or (N, 3, 3)
            ``J^-1`` (dimensionless); row i is ``dP_i^T / (dP_i . v_i)``.

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        SingularConfigurationError
            A link is perpendicular to its guideway.
        InputError
            Wrong shape or non-finite values.
        """
        _, Jinv, single = self._jacobians(T, configuration)
        return Jinv[0] if single else Jinv

    def acceleration(self, T: np.typing.ArrayLike, T_dot: np.typing.ArrayLike, q_ddot: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """TCP acceleration from cart accelerations, Dressler (2012), eq. 6.6.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position(s) [m].
        T_dot : array_like, shape (3,) or (N, 3)
            TCP velocity [m/s].
        q_ddot : array_like, shape (3,) or (N, 3)
            Cart accelerations [m/s^2].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            TCP acceleration [m/s^2].

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        InputError
            Wrong or mismatched shapes, non-finite values.
        """
        Tn, single = as_rows(T, "T", 3)
        Td, _ = as_rows(T_dot, "T_dot", 3)
        qdd, _ = as_rows(q_ddot, "q_ddot", 3)
        if not (Tn.shape == Td.shape == qdd.shape):
            raise InputError(f"T, T_dot, q_ddot: expected equal shapes, got {Tn.shape}, {Td.shape}, {qdd.shape}")
        s = configuration_signs(configuration)
        _, disc = self._ik(Tn.T, s[:, None])
        self._check_reach(disc, Tn)
        (out,) = self._acc(Tn.T, Td.T, qdd.T, s[:, None])
        out = out.T
        return out[0] if single else out

    def cart_motion(self, T: np.typing.ArrayLike, T_dot: np.typing.ArrayLike, T_ddot: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cart positions, velocities and accelerations for a TCP motion (eqs. 4.9, 6.5, 6.6).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position(s) [m].
        T_dot : array_like, shape (3,) or (N, 3)
            TCP velocity [m/s].
        T_ddot : array_like, shape (3,) or (N, 3)
            TCP acceleration [m/s^2].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).

        Returns
        -------
        q, q_dot, q_ddot : numpy.ndarray, each shape (3,) or (N, 3)
            Cart positions [m], velocities [m/s] and accelerations [m/s^2].

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        InputError
            Wrong or mismatched shapes, non-finite values.
        """
        Tn, single = as_rows(T, "T", 3)
        Td, _ = as_rows(T_dot, "T_dot", 3)
        Tdd, _ = as_rows(T_ddot, "T_ddot", 3)
        if not (Tn.shape == Td.shape == Tdd.shape):
            raise InputError(f"T, T_dot, T_ddot: expected equal shapes, got {Tn.shape}, {Td.shape}, {Tdd.shape}")
        s = configuration_signs(configuration)
        q, disc = self._ik(Tn.T, s[:, None])
        self._check_reach(disc, Tn)
        qd, qdd = self._cacc(Tn.T, Td.T, Tdd.T, s[:, None])
        out = (q.T, qd.T, qdd.T)
        return tuple(o[0] for o in out) if single else out

    # --------------------------------------------------------------- workspace
    def link_angles(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """Angle between each link and its guideway direction [rad].

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position(s) [m].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Angle of link i to ``v_i`` (0 = link along the guideway) [rad].

        Raises
        ------
        UnreachablePoseError
            The pose is unreachable (names the arm).
        InputError
            Wrong shape or non-finite values.
        """
        Tn, single = as_rows(T, "T", 3)
        s = configuration_signs(configuration)
        c, _, disc = self._cos(Tn.T, s[:, None])
        self._check_reach(disc, Tn)
        ang = np.arccos(np.clip(np.abs(c.T), 0.0, 1.0))
        return ang[0] if single else ang

    def in_workspace(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """Whether poses are reachable within cart travel and spherical-joint limits.

        A pose is in the workspace if every arm reaches it (eq. 4.9), every cart position
        lies in ``limits.cart_travel`` and every link makes at most
        ``limits.joint_angle_max`` with its guideway.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP position(s) [m].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).
        limits : bool, optional
            If False, only reachability is checked (no travel or joint-angle limits).

        Returns
        -------
        bool or numpy.ndarray of bool, shape (N,)
            True where the pose is in the workspace.

        Raises
        ------
        InputError
            Wrong shape, non-finite values, or no limits known (kinematic parameters only).
        """
        if limits and self.parameters is None:
            raise InputError("in_workspace: needs a full RobotParameters set with limits")
        Tn, single = as_rows(T, "T", 3)
        s = configuration_signs(configuration)
        c, q, disc = self._cos(Tn.T, s[:, None])
        if limits:
            lim = self.parameters.limits
            ok = within_limits(q.T, disc.T, c.T, lim.cart_travel, lim.joint_angle_max)
        else:
            ok = within_limits(q.T, disc.T)
        return bool(ok[0]) if single else ok

    def require_in_workspace(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """Cart positions of a pose, which must lie in the workspace (see :meth:`in_workspace`).

        Parameters
        ----------
        T : array_like, shape (3,)
            TCP position [m].
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).

        Returns
        -------
        numpy.ndarray, shape (3,)
            Cart positions q [m].

        Raises
        ------
        UnreachablePoseError
            Some arm cannot reach ``T`` (names the arm), or a cart position or link angle
            is outside the limits (the message gives both with their limits).
        InputError
            Wrong shape, non-finite values, or no limits known.
        """
        q = self.ik(T, configuration)
        if not self.in_workspace(T, configuration):
            lim = self.parameters.limits
            ang = np.degrees(self.link_angles(T, configuration))
            raise UnreachablePoseError(
                f"pose {np.asarray(T, dtype=float).tolist()} is outside the workspace of {self.parameters.name}: "
                f"cart positions {np.round(q, 4).tolist()} m (travel {lim.cart_travel.tolist()} m), "
                f"link angles {np.round(ang, 1).tolist()} deg (limit {np.degrees(lim.joint_angle_max):.1f} deg)"
            )
        return q

    def workspace_bounds(self) -> np.ndarray:
        """Axis-aligned box that contains the whole workspace.

        Returns
        -------
        numpy.ndarray, shape (3, 2)
            Row k: ``(min, max)`` of TCP coordinate k [m]: the intersection over the arms
            of the guideway segment's bounding box grown by the link length.

        Raises
        ------
        InputError
            No limits known (kinematic parameters only).
        """
        if self.parameters is None:
            raise InputError("workspace_bounds: needs a full RobotParameters set with limits")
        lim = self.parameters.limits.cart_travel
        # T lies within L_i of guideway segment i for every arm: intersect the boxes
        lo = np.full(3, -np.inf)
        hi = np.full(3, np.inf)
        for i in range(3):
            ends = np.array([self.As[i] + lim[i, k] * self.v[i] for k in range(2)])
            lo = np.maximum(lo, ends.min(axis=0) - self.L[i])
            hi = np.minimum(hi, ends.max(axis=0) + self.L[i])
        return np.column_stack([lo, hi])

    def workspace_grid(self, step: float = 0.05, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """Regular grid of TCP positions filling the workspace.

        Parameters
        ----------
        step : float, optional
            Grid spacing [m] (default 0.05).
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik`).
        limits : bool, optional
            If False, keep every reachable grid point (see :meth:`in_workspace`).

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            Grid points inside the workspace (see :meth:`in_workspace`) [m].

        Raises
        ------
        InputError
            Non-positive step or no limits known.
        """
        if not step > 0:
            raise InputError(f"step: expected a positive spacing in m, got {step!r}")
        box = self.workspace_bounds()
        axes = [np.arange(lo, hi + step / 2, step) for lo, hi in box]
        X = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        return X[self.in_workspace(X, configuration, limits=limits)]
