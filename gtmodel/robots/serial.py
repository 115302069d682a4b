"""Serial 6R manipulator from a Denavit-Hartenberg table, with the joint-spring compliance model.

Kinematics (standard, i.e. distal, Denavit-Hartenberg convention)::

    A_i(theta_i) = Rz(theta_i + theta_offset_i) Tz(d_i) Tx(a_i) Rx(alpha_i)
    T_TCP(theta) = base A_1 ... A_6 tool

is written once as a CasADi SX graph. The geometric Jacobian ``J = [J_v; J_w]`` (6 x 6,
linear velocity of the TCP over angular velocity) takes its position rows from
``ca.jacobian`` of the TCP position of that graph and its rotation rows from the joint axes
``z_{i-1}`` of the same graph.

Joint-spring compliance (Cvitanic (2021), section 1): every joint is a linear torsional
spring of stiffness ``k_i`` [N m/rad]; under a wrench ``F = [f; m]`` at the TCP (force [N],
moment [N m], base frame) the small deflection screw ``dX = [dp; dphi]`` (translation [m],
rotation vector [rad]) is::

    dX = J K_theta^-1 J^T F                      Cvitanic (2021), eq. (3)
    K_x = J^-T K_theta J^-1                      Cvitanic (2021), eq. (7)

(the complementary stiffness of eq. (2) is neglected). With the compliances ``c_i = 1/k_i``
eq. (3) is linear: ``dX = sum_i c_i J_i (J_i^T F)`` (:meth:`SerialArm.compliance_regressor`).

The only shipped geometry, ``serial_6r_illustrative``, is an ILLUSTRATIVE KR 500-like arm:
the thesis gives no DH table for its KUKA KR 500-3, so its values are assumptions; so are
its joint limits (``[joint_limits]``, :meth:`SerialArm.check_joint_limits`).
"""

from __future__ import annotations

import logging
import math
from functools import cached_property
from pathlib import Path
from typing import Any, Mapping

import casadi as ca
import numpy as np

from gtmodel._arrays import as_array, as_rows
from gtmodel._docstrings import fill_doc
from gtmodel._geometry import rot_x, rot_y, rot_z
from gtmodel.errors import ConvergenceError, InputError, ParameterError, SingularConfigurationError
from gtmodel.robots.parameters import _read_data_file

__all__ = [
    "SerialArm",
    "load_serial_arm",
    "rotation_rpy",
    "SINGULAR_CONDITION",
]

_log = logging.getLogger("gtmodel")

#: Condition number of ``J`` above which a pose is treated as singular.
SINGULAR_CONDITION = 1e8


# numpydoc entries shared by the methods that take the same arguments (gtmodel._docstrings)
_THETA = """
Parameters
----------
theta : array_like, shape (6,)
    Joint angles [rad].
"""
_THETA_ROWS = """
Parameters
----------
theta : array_like, shape (6,) or (N, 6)
    Joint angles [rad].
"""
_WRENCH = """
F : array_like, shape (6,)
    Wrench at the TCP in the base frame: force [N], moment [N m].
"""
_K_THETA = """
k_theta : array_like, shape (6,)
    Joint stiffnesses [N m/rad], all positive.
"""
_ANGLE_RAISES = """
Raises
------
InputError
    Wrong shape or non-finite angles.
"""
_WRENCH_RAISES = """
Raises
------
InputError
    Wrong shapes or non-finite values.
"""
_STIFFNESS_RAISES = """
Raises
------
InputError
    Wrong shapes, non-finite values or a non-positive stiffness.
"""
_doc = fill_doc(
    theta=_THETA,
    theta_rows=_THETA_ROWS,
    wrench=_WRENCH,
    k_theta=_K_THETA,
    angle_raises=_ANGLE_RAISES,
    wrench_raises=_WRENCH_RAISES,
    stiffness_raises=_STIFFNESS_RAISES,
)


def _vector(value: Any, n: int, name: str, positive: bool = False) -> np.ndarray:
    arr = as_array(value, (n,), name)
    if positive and np.any(arr <= 0):
        bad = int(np.flatnonzero(arr <= 0)[0])
        raise InputError(f"{name}: expected positive values, entry {bad} is {float(arr[bad])!r}")
    return arr


def rotation_rpy(rpy: Any) -> np.ndarray:
    """Rotation matrix ``Rz(yaw) Ry(pitch) Rx(roll)`` from roll, pitch, yaw.

    Parameters
    ----------
    rpy : array_like, shape (3,)
        Roll, pitch, yaw [rad].

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        The rotation matrix.

    Raises
    ------
    InputError
        Wrong shape or non-finite values.
    """
    r, p, y = _vector(rpy, 3, "rpy")
    return np.array(rot_z(y)) @ np.array(rot_y(p)) @ np.array(rot_x(r))


def _dh_sx(theta: ca.SX, a: float, alpha: float, d: float) -> ca.SX:
    """Standard DH transform Rz(theta) Tz(d) Tx(a) Rx(alpha) as a 4x4 SX."""
    ct, st = ca.cos(theta), ca.sin(theta)
    ca_, sa = math.cos(alpha), math.sin(alpha)
    return ca.vertcat(
        ca.horzcat(ct, -st * ca_, st * sa, a * ct),
        ca.horzcat(st, ct * ca_, -ct * sa, a * st),
        ca.horzcat(0, sa, ca_, d),
        ca.horzcat(0, 0, 0, 1),
    )


class SerialArm:
    """A 6R serial manipulator from a standard DH table, CasADi graph and joint-spring model.

    Parameters
    ----------
    a : array_like, shape (6,)
        DH link lengths ``a_i`` [m].
    alpha : array_like, shape (6,)
        DH link twists ``alpha_i`` [rad].
    d : array_like, shape (6,)
        DH link offsets ``d_i`` [m].
    theta_offset : array_like, shape (6,), optional
        Added to the joint angles [rad] (default zeros).
    tool : array_like, shape (4, 4), optional
        Flange -> TCP homogeneous transform [m] (default identity).
    base : array_like, shape (4, 4), optional
        World -> joint-1 frame homogeneous transform [m] (default identity).
    name : str, optional
        Name of the arm.
    description : str, optional
        What the geometry is (and whether it is illustrative).
    joint_limits : array_like, shape (6, 2), optional
        Lower and upper limit per joint [rad] (default None: no limits); checked by
        :meth:`check_joint_limits`.

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, a ``tool``/``base`` that is not a rigid transform,
        or joint limits with a lower limit not below the upper one.

    Notes
    -----
    The wrist centre is the origin of DH frame 5 (after joints 1-5); for the spherical
    wrist of the illustrative arm it depends on joints 1-3 only. Cvitanic (2021), eqs.
    (3), (4), (7).
    """

    n_joints = 6

    def __init__(
        self,
        a: Any,
        alpha: Any,
        d: Any,
        theta_offset: Any = None,
        tool: Any = None,
        base: Any = None,
        name: str = "serial_arm",
        description: str = "",
        joint_limits: Any = None,
    ) -> None:
        self.a = _vector(a, 6, "a")
        self.alpha = _vector(alpha, 6, "alpha")
        self.d = _vector(d, 6, "d")
        self.theta_offset = np.zeros(6) if theta_offset is None else _vector(theta_offset, 6, "theta_offset")
        self.tool = self._transform(tool, "tool")
        self.base = self._transform(base, "base")
        self.name = str(name)
        self.description = str(description)
        self.joint_limits = None if joint_limits is None else self._limits(joint_limits)

    @staticmethod
    def _limits(value: Any) -> np.ndarray:
        arr = as_array(value, (6, 2), "joint_limits")  # [rad], rows (lower, upper)
        bad = np.flatnonzero(arr[:, 0] >= arr[:, 1])
        if bad.size:
            i = int(bad[0])
            raise InputError(f"joint_limits: expected lower < upper limit, joint {i + 1} has {arr[i].tolist()} rad")
        return arr

    def check_joint_limits(self, theta: Any, name: str = "theta") -> np.ndarray:
        """Refuse joint angles outside the arm's joint limits (none if ``joint_limits`` is None).

        Parameters
        ----------
        theta : array_like, shape (6,) or (N, 6)
            Joint angles [rad].
        name : str, optional
            Argument name used in the message.

        Returns
        -------
        numpy.ndarray, shape (N, 6)
            The angles as rows.

        Raises
        ------
        InputError
            Wrong shape, a non-finite angle, or an angle outside its limits: the message
            names the row, the joint and its limits in degrees.
        """
        th, _ = as_rows(theta, name, 6)
        if self.joint_limits is None:
            return th
        lo, hi = self.joint_limits[:, 0], self.joint_limits[:, 1]
        out = (th < lo) | (th > hi)
        if np.any(out):
            r, j = (int(v[0]) for v in np.nonzero(out))
            raise InputError(
                f"{name}: row {r}: joint {j + 1} = {math.degrees(th[r, j]):.6g} deg is outside the joint limits "
                f"{math.degrees(lo[j]):.6g}..{math.degrees(hi[j]):.6g} deg of {self.name}"
            )
        return th

    @staticmethod
    def _transform(value: Any, name: str) -> np.ndarray:
        if value is None:
            return np.eye(4)
        arr = np.asarray(value, dtype=float)
        if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
            raise InputError(f"{name}: expected a finite 4x4 homogeneous transform, got shape {arr.shape}")
        rot = arr[:3, :3]
        if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-9) or not np.allclose(arr[3], [0, 0, 0, 1]):
            raise InputError(f"{name}: the 4x4 transform is not rigid (rotation not orthonormal or last row not [0 0 0 1])")
        return arr

    # ------------------------------------------------------------------ symbolic graph
    @cached_property
    def _graph(self) -> dict[str, ca.SX]:
        theta = ca.SX.sym("theta", 6)
        T = ca.SX(self.base)
        z_axes, origins = [T[:3, 2]], [T[:3, 3]]
        frames = []
        for i in range(6):
            T = ca.mtimes(T, _dh_sx(theta[i] + float(self.theta_offset[i]), float(self.a[i]), float(self.alpha[i]), float(self.d[i])))
            frames.append(T)
            z_axes.append(T[:3, 2])
            origins.append(T[:3, 3])
        T_tcp = ca.mtimes(T, ca.SX(self.tool))
        p = T_tcp[:3, 3]
        J_v = ca.jacobian(p, theta)
        J_w = ca.horzcat(*z_axes[:6])
        J = ca.vertcat(J_v, J_w)
        p_wc = frames[4][:3, 3]
        return {"theta": theta, "T": T_tcp, "p": p, "J": J, "p_wc": p_wc, "J_wc": ca.jacobian(p_wc, theta)}

    @cached_property
    def fk_function(self) -> ca.Function:
        """CasADi function ``theta (6) -> T (4x4)``, base -> TCP homogeneous transform [m]."""
        g = self._graph
        return ca.Function("fk", [g["theta"]], [g["T"]], ["theta"], ["T"])

    @cached_property
    def jacobian_function(self) -> ca.Function:
        """CasADi function ``theta (6) -> J (6x6)``, geometric Jacobian ``[J_v; J_w]`` of the TCP."""
        g = self._graph
        return ca.Function("jacobian", [g["theta"]], [g["J"]], ["theta"], ["J"])

    @cached_property
    def wrist_function(self) -> ca.Function:
        """CasADi function ``theta (6) -> (p_wc (3), J_wc (3x6))``, wrist centre and its Jacobian."""
        g = self._graph
        return ca.Function("wrist", [g["theta"]], [g["p_wc"], g["J_wc"]], ["theta"], ["p_wc", "J_wc"])

    @cached_property
    def deflection_function(self) -> ca.Function:
        """CasADi function ``(theta (6), F (6), k_theta (6)) -> dX (6)``, Cvitanic (2021), eq. (3)."""
        g = self._graph
        F = ca.SX.sym("F", 6)
        k = ca.SX.sym("k_theta", 6)
        J = g["J"]
        dX = ca.mtimes(J, ca.mtimes(ca.diag(1 / k), ca.mtimes(J.T, F)))
        return ca.Function("deflection", [g["theta"], F, k], [dX], ["theta", "F", "k_theta"], ["dX"])

    @cached_property
    def complementary_stiffness_function(self) -> ca.Function:
        """CasADi function ``(theta (6), F (6)) -> K_c (6x6)``, ``K_c = d(J^T F)/d theta``, Cvitanic (2021), eq. (2).

        ``ca.jacobian`` of the joint torques ``J(theta)^T F`` of the same graph, for a wrench
        ``F`` fixed in the base frame [N m/rad].
        """
        g = self._graph
        F = ca.SX.sym("F", 6)
        K_c = ca.jacobian(ca.mtimes(g["J"].T, F), g["theta"])
        return ca.Function("complementary_stiffness", [g["theta"], F], [K_c], ["theta", "F"], ["K_c"])

    @cached_property
    def loaded_deflection_function(self) -> ca.Function:
        """CasADi function ``(theta, F, k_theta) -> dX = J (K_theta - K_c)^-1 J^T F``, Cvitanic (2021), eq. (2).

        The deflection with the complementary stiffness ``K_c`` kept (first order in the
        deflection about the loaded equilibrium ``K_theta dtheta = J(theta + dtheta)^T F``).
        """
        g = self._graph
        F = ca.SX.sym("F", 6)
        k = ca.SX.sym("k_theta", 6)
        J = g["J"]
        K_c = ca.jacobian(ca.mtimes(J.T, F), g["theta"])
        dtheta = ca.solve(ca.diag(k) - K_c, ca.mtimes(J.T, F))
        return ca.Function("loaded_deflection", [g["theta"], F, k], [ca.mtimes(J, dtheta)], ["theta", "F", "k_theta"], ["dX"])

    @cached_property
    def regressor_function(self) -> ca.Function:
        """CasADi function ``(theta, F) -> A (6x6)`` with ``dX = A c``, ``c_i = 1/k_i``, eq. (3)."""
        g = self._graph
        F = ca.SX.sym("F", 6)
        J = g["J"]
        A = ca.mtimes(J, ca.diag(ca.mtimes(J.T, F)))
        return ca.Function("compliance_regressor", [g["theta"], F], [A], ["theta", "F"], ["A"])

    # ------------------------------------------------------------------ numeric API
    def _eval(self, fn: ca.Function, theta: Any, F: Any = None, k_theta: Any = None) -> list[np.ndarray]:
        """Validate ``theta`` (and ``F``, ``k_theta`` when given) and evaluate a function of the graph."""
        args = [_vector(theta, 6, "theta")]
        if F is not None:
            args.append(_vector(F, 6, "F"))
        if k_theta is not None:
            args.append(_vector(k_theta, 6, "k_theta", positive=True))
        out = fn(*args)
        return [np.array(o) for o in (out if isinstance(out, (list, tuple)) else [out])]

    @_doc
    def fk(self, theta: Any) -> np.ndarray:
        """Forward kinematics: base -> TCP homogeneous transform.

        {theta_rows}

        Returns
        -------
        numpy.ndarray, shape (4, 4) or (N, 4, 4)
            ``T_TCP(theta)`` [m]; rotation in ``[:3, :3]``, position in ``[:3, 3]``.

        {angle_raises}
        """
        th, single = as_rows(theta, "theta", 6)
        out = np.stack([np.array(self.fk_function(row)) for row in th])
        return out[0] if single else out

    @_doc
    def position(self, theta: Any) -> np.ndarray:
        """TCP position.

        {theta_rows}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            TCP position in the base frame [m].

        {angle_raises}
        """
        T = self.fk(theta)
        return T[..., :3, 3]

    @_doc
    def jacobian(self, theta: Any) -> np.ndarray:
        """Geometric Jacobian ``[J_v; J_w]`` of the TCP (rows: linear then angular velocity).

        {theta}

        Returns
        -------
        numpy.ndarray, shape (6, 6)
            ``J`` with ``[v; omega] = J theta_dot`` [m/rad; 1].

        {angle_raises}
        """
        return self._eval(self.jacobian_function, theta)[0]

    @_doc
    def wrist_centre(self, theta: Any) -> np.ndarray:
        """Wrist-centre position (origin of DH frame 5).

        {theta}

        Returns
        -------
        numpy.ndarray, shape (3,)
            Wrist centre in the base frame [m].

        {angle_raises}
        """
        return self._eval(self.wrist_function, theta)[0].reshape(3)

    @_doc
    def wrist_jacobian(self, theta: Any) -> np.ndarray:
        """Jacobian of the wrist-centre position (zero columns 4-6 for a spherical wrist).

        {theta}

        Returns
        -------
        numpy.ndarray, shape (3, 6)
            ``d p_wc / d theta`` [m/rad]; used by DPP, Cvitanic (2021), eq. (4).

        {angle_raises}
        """
        return self._eval(self.wrist_function, theta)[1]

    def _checked_jacobian(self, theta: np.ndarray) -> np.ndarray:
        J = self.jacobian(theta)
        cond = np.linalg.cond(J)
        if not np.isfinite(cond) or cond > SINGULAR_CONDITION:
            raise SingularConfigurationError(
                f"{self.name}: Jacobian is singular at theta = {np.round(theta, 6).tolist()} rad (condition number {cond:.3g})"
            )
        return J

    @_doc
    def deflection(self, theta: Any, F: Any, k_theta: Any, complementary: bool = False) -> np.ndarray:
        """Static TCP deflection of the joint-spring model, Cvitanic (2021), eq. (3) (or (2)).

        {theta}
        {wrench}
        {k_theta}
        complementary : bool, optional
            Keep the complementary stiffness ``K_c = d(J^T F)/d theta`` of eq. (2):
            ``dX = J (K_theta - K_c)^-1 J^T F`` (default False: eq. (3), ``K_c`` neglected).

        Returns
        -------
        numpy.ndarray, shape (6,)
            ``dX``: translation [m], rotation vector [rad].

        {stiffness_raises}
        """
        fn = self.loaded_deflection_function if complementary else self.deflection_function
        return self._eval(fn, theta, F, k_theta)[0].reshape(6)

    @_doc
    def complementary_stiffness(self, theta: Any, F: Any) -> np.ndarray:
        """Complementary stiffness ``K_c = d(J(theta)^T F)/d theta``, Cvitanic (2021), eq. (2).

        The load-dependent term of ``K = J^-T (K_theta - K_c) J^-1`` that eq. (3) neglects;
        computed by ``ca.jacobian`` of the joint torques of the CasADi graph, for a wrench
        held constant in the base frame.

        {theta}
        {wrench}

        Returns
        -------
        numpy.ndarray, shape (6, 6)
            ``K_c`` [N m/rad].

        {wrench_raises}
        """
        return self._eval(self.complementary_stiffness_function, theta, F)[0]

    @_doc
    def compliance_regressor(self, theta: Any, F: Any) -> np.ndarray:
        """Regressor ``A`` of eq. (3) in the compliances: ``dX = A c`` with ``c_i = 1/k_i``.

        {theta}
        {wrench}

        Returns
        -------
        numpy.ndarray, shape (6, 6)
            Column ``i`` is ``J_i (J_i^T F)`` [m N m, N m]; Cvitanic (2021), eq. (3).

        {wrench_raises}
        """
        return self._eval(self.regressor_function, theta, F)[0]

    @_doc
    def cartesian_stiffness(self, theta: Any, k_theta: Any) -> np.ndarray:
        """Cartesian stiffness ``K_x = J^-T K_theta J^-1``, Cvitanic (2021), eq. (7).

        {theta}
        {k_theta}

        Returns
        -------
        numpy.ndarray, shape (6, 6)
            ``K_x`` mapping ``[dp; dphi]`` to ``[f; m]`` [N/m, N, N m/rad].

        {stiffness_raises}
        SingularConfigurationError
            ``J`` is singular (condition number above :data:`SINGULAR_CONDITION`).
        """
        th = _vector(theta, 6, "theta")
        k = _vector(k_theta, 6, "k_theta", positive=True)
        J = self._checked_jacobian(th)
        Jinv = np.linalg.inv(J)
        return Jinv.T @ np.diag(k) @ Jinv

    def ik(self, T_target: Any, theta0: Any, tol: float = 1e-10, max_iter: int = 50) -> np.ndarray:
        """Inverse kinematics by Newton's method on the CasADi FK and Jacobian.

        Iterates ``theta <- theta + J^-1 [p_t - p; e_R]`` with the orientation error
        ``e_R = 1/2 sum_i r_i x r_t,i`` (columns of ``R`` and ``R_target``).

        Parameters
        ----------
        T_target : array_like, shape (4, 4)
            Target TCP pose (homogeneous transform) [m].
        theta0 : array_like, shape (6,)
            Start angles [rad]; selects the configuration (branch) of the solution.
        tol : float, optional
            Convergence tolerance on the 6-D error norm [m, rad].
        max_iter : int, optional
            Maximum number of Newton steps.

        Returns
        -------
        numpy.ndarray, shape (6,)
            Joint angles [rad] reaching ``T_target``.

        Raises
        ------
        InputError
            Wrong shapes or a non-rigid target.
        SingularConfigurationError
            A Newton step met a singular Jacobian.
        ConvergenceError
            No convergence within ``max_iter`` steps (target out of reach?).
        """
        Tt = self._transform(T_target, "T_target")
        th = _vector(theta0, 6, "theta0").copy()
        err = np.inf
        for _ in range(int(max_iter)):
            T = np.array(self.fk_function(th))
            e_p = Tt[:3, 3] - T[:3, 3]
            e_r = 0.5 * sum(np.cross(T[:3, i], Tt[:3, i]) for i in range(3))
            e = np.concatenate([e_p, e_r])
            err = float(np.linalg.norm(e))
            if err < tol:
                return th
            J = self._checked_jacobian(th)
            th = th + np.linalg.solve(J, e)
        raise ConvergenceError(f"{self.name}: inverse kinematics did not converge in {max_iter} steps (error {err:.3g})")


def _arm_from_mapping(data: Mapping[str, Any], origin: str) -> SerialArm:
    dh = data.get("dh")
    if not isinstance(dh, Mapping):
        raise ParameterError(f"{origin}: missing table [dh]")
    convention = dh.get("convention", "standard")
    if convention != "standard":
        raise ParameterError(f"{origin}: dh.convention: only 'standard' DH is supported, got {convention!r}")
    values = {}
    for key in ("a", "alpha_deg", "d", "theta_offset_deg"):
        if key not in dh:
            raise ParameterError(f"{origin}: dh.{key}: missing (expected 6 numbers)")
        try:
            values[key] = _vector(dh[key], 6, f"dh.{key}")
        except InputError as exc:
            raise ParameterError(f"{origin}: {exc}") from None
    tool_tab = data.get("tool", {})
    try:
        t = _vector(tool_tab.get("translation", [0, 0, 0]), 3, "tool.translation")
        rpy = _vector(tool_tab.get("rpy_deg", [0, 0, 0]), 3, "tool.rpy_deg")
    except InputError as exc:
        raise ParameterError(f"{origin}: {exc}") from None
    tool = np.eye(4)
    tool[:3, :3] = rotation_rpy(np.radians(rpy))
    tool[:3, 3] = t
    limits = None
    lim_tab = data.get("joint_limits")
    if lim_tab is not None:
        if not isinstance(lim_tab, Mapping):
            raise ParameterError(f"{origin}: joint_limits: expected a table with lower_deg and upper_deg")
        try:
            lo = _vector(lim_tab.get("lower_deg"), 6, "joint_limits.lower_deg")
            hi = _vector(lim_tab.get("upper_deg"), 6, "joint_limits.upper_deg")
            limits = SerialArm._limits(np.radians(np.column_stack([lo, hi])))
        except InputError as exc:
            raise ParameterError(f"{origin}: {exc}") from None
    return SerialArm(
        values["a"],
        np.radians(values["alpha_deg"]),
        values["d"],
        np.radians(values["theta_offset_deg"]),
        tool=tool,
        name=str(data.get("name", origin)),
        description=str(data.get("description", "")),
        joint_limits=limits,
    )


def load_serial_arm(name_or_path: str | Path = "serial_6r_illustrative") -> SerialArm:
    """Load a serial arm from a DH file by name (shipped) or path.

    The format (TOML): ``name``, ``description``, table ``[dh]`` with ``convention =
    "standard"``, ``a`` [m], ``alpha_deg``, ``d`` [m], ``theta_offset_deg`` (6 numbers
    each) and optional ``[tool]`` with ``translation`` [m] and ``rpy_deg``. The only
    shipped file, ``serial_6r_illustrative``, is an ILLUSTRATIVE KR 500-like geometry
    (assumed values: Cvitanic (2021) gives no DH table).

    Parameters
    ----------
    name_or_path : str or pathlib.Path, optional
        A shipped file's name or a path.

    Returns
    -------
    SerialArm
        The arm.

    Raises
    ------
    ParameterError
        Unknown name, unreadable file, TOML syntax error or an invalid field (the message
        names the file and the field).
    """
    data, origin, _ = _read_data_file(name_or_path, "serial arm file", "not a shipped arm and no such file", any_suffix_must_exist=True)
    if data.get("model", "serial_dh") != "serial_dh":
        raise ParameterError(f"{origin}: model: expected 'serial_dh', got {data.get('model')!r}")
    return _arm_from_mapping(data, origin)
