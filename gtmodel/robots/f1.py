"""Kinematics of the F1-type 6-DOF Gantry-Tau as a closure model, Dressler (2012), eqs. 4.16-4.33.

The F1 has vertical guideways (``z`` along the actuators). Cart 1 carries link 1, cart 2
a joint plate turning about one axis (``q4``) with links 2a, 2b, cart 3 a two-axis joint
plate (``q5``, then ``q6``) with links 3a, 3b, 3c. Actuator values
``q = (q1, q2, q3, q4, q5, q6)``: cart positions [m] and joint-plate angles [rad]. The
joint points (eqs. 4.19-4.24)::

    A_1  = A0_1 + q1 v1                                            (4.20, Abj_1 absorbed)
    A_2j = R1u2 Ry(q4) Abj_2j + A0_2 + q2 v2                       (4.21, 4.22)
    A_3j = R1u3 Ry(q5) R2u3 Rx(q6) Abj_3j + A0_3 + q3 v3 + R1u3 Ry(q5) r3   (4.23, 4.24)
    B_ij = T + R_T B0_ij                                           (4.19)

``R1u2``, ``R1u3``, ``R2u3`` are given as quaternions ``(w, x, y, z)`` (normalised inside
:func:`~gtmodel.robots.closure.quaternion_to_rotation`). The closure equations
``||A_ij - B_ij||^2 = L_ij^2`` are written once (:meth:`F1Closure.link_points`); inverse
and forward kinematics, Jacobians and the generated-C Functions are built on that graph.

Home pose and assembly modes
    ``q_home`` (from the parameter file; for the shipped F1 ``q4 = -q5 = -90 deg``, the
    5-DOF configuration of eqs. 4.25-4.26 in which arms 2 and 3 are near
    parallelograms) and its FK from the implicit 5-DOF solution (arm 3 a parallelogram,
    position by trilateration, plate below the carts) give the home pose. The IK of arm
    3 has up to 8 real branches and the FK several assembly modes close to each other;
    the *nominal* branch and mode are the ones connected to the home pose. Both default
    starts are therefore continuations from the home pose (:data:`START_SUBSTEPS`
    sub-steps of :data:`START_NEWTON_STEPS` Newton steps). A start from the 5-DOF
    solution of each ``q`` alone is up to 58 deg off in orientation on the F1 grid
    (median 17 deg: the plate twists strongly about the links for a small link
    non-parallelism) and does not converge within :data:`FK_MAX_ITER` for 4 of its 1246
    poses; before poses of other aspects are removed from the grid it lands on another
    mode for about 1 pose in 14.

Inverse kinematics (eqs. 4.27-4.29)
    Arm 1 in closed form (a quadratic in ``q1``; the ``+`` root: cart joint ``A_1`` above
    ``B_1`` along ``v1``, the plate hanging below the carts). Arm 2 (``q2, q4``) and arm 3
    (``q3, q5, q6``) by Newton's method on ``e = L^2 - ||B - A(Q)||^2`` with CasADi AD
    Jacobians, started from a previous solution (real-time use) or from
    :attr:`F1Closure.ik_start_function`. Tolerance :data:`IK_TOLERANCE`, limit
    :data:`IK_MAX_ITER`.

Forward kinematics (eqs. 4.30-4.33)
    Newton's method on the link lengths ``||B_ij - A_ij|| - L_ij`` over the pose, with a
    multiplicative orientation update ``R_T <- Rot(dw) R_T`` (``dw`` a rotation vector; the
    ZYZ angles of eq. 4.15 are in gimbal lock at the nominal orientation). The AD Jacobian
    of the link lengths w.r.t. ``(T, w)`` *is* the Stewart-platform inverse Jacobian of
    eq. 4.31, row ``[AB^T/|AB|, (R_T B0 x AB)^T/|AB|]``: the ZYZ derivatives
    ``AT^T dR/dalpha B0`` are replaced by the rotation-vector ones (``d(R_T B0)/dw_k =
    e_k x R_T B0``). Started from a previous pose or :attr:`F1Closure.fk_start_function`.
    Tolerance :data:`FK_TOLERANCE`, limit :data:`FK_MAX_ITER`.

Parameters are in SI units; the parameter file :file:`data/F1.toml` is printed in mm and
converted at load (:func:`load_f1`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._toml import read_toml
from gtmodel.errors import ConvergenceError, InputError, ParameterError, UnreachablePoseError
from gtmodel.robots.closure import ClosureModel, quaternion_to_rotation, rotation_to_quaternion, rotation_vector_to_rotation
from gtmodel.robots.kinematics import fk_expression, ik_expression

__all__ = [
    "F1Closure",
    "F1Limits",
    "load_f1",
    "F1_LINKS",
    "F1_FIXED_FOR_IDENTIFIABILITY",
    "IK_TOLERANCE",
    "IK_MAX_ITER",
    "FK_TOLERANCE",
    "FK_MAX_ITER",
    "START_SUBSTEPS",
    "FK_CONTINUATION_STEPS",
    "START_NEWTON_STEPS",
    "GRID_FK_TOLERANCE",
    "ROTATION_TOLERANCE",
]

#: Link names per arm.
F1_LINKS: tuple[tuple[str, ...], ...] = (("1",), ("2a", "2b"), ("3a", "3b", "3c"))
#: Parameters fixed for identifiability in Dressler (2012), Table 5.4 (names of
#: :meth:`F1Closure.parameter_names`; the last entry is the equality constraint
#: ``Abj_2b_z = Abj_2a_z``).
F1_FIXED_FOR_IDENTIFIABILITY: tuple[str, ...] = ("Abj_2b_y", "r3_y", "r3_z", "Abj_3c_x", "Abj_3c_z", "Abj_2b_z = Abj_2a_z")
#: Newton tolerance of the IK: max |L^2 - ||B - A||^2| over the links of arms 2, 3 [m^2]
#: (about 3e-14 m in link length).
IK_TOLERANCE = 1e-13
#: Newton iteration limit of the IK (the unrolled Functions run exactly this many).
IK_MAX_ITER = 20
#: Newton tolerance of the FK: max | ||B - A|| - L | over the six links [m].
FK_TOLERANCE = 1e-13
#: Newton iteration limit of the FK (the unrolled Functions run exactly this many).
FK_MAX_ITER = 20
#: Default starts (:attr:`F1Closure.ik_start_function`, :attr:`F1Closure.fk_start_function`):
#: continuation from the home pose in this many equal sub-steps ...
START_SUBSTEPS = 12
#: ... each followed by this many Newton steps.
START_NEWTON_STEPS = 2
#: Steps in ``q`` of the second FK start (:meth:`F1Closure.fk` with the default start): a
#: pose whose continuation from the home pose fails is reached from the nearest converged
#: pose of the same call in this many equal steps.
FK_CONTINUATION_STEPS = 8
#: Newton steps per evaluation in the NumPy methods: :meth:`F1Closure.ik` and
#: :meth:`F1Closure.fk` run chunks of this many unrolled steps on the poses not yet
#: converged (the same iterates as one unrolled run of ``max_iter`` steps).
_CHUNK = 4
#: Largest distance [m] (and rotation-matrix entry difference) between a grid pose and the
#: FK of its IK solution for :meth:`F1Closure.workspace_grid` to keep it.
GRID_FK_TOLERANCE = 1e-9
#: Largest accepted deviation of an input orientation from a rotation, max |R^T R - I|.
ROTATION_TOLERANCE = 1e-8

_DATA_PACKAGE = "gtmodel.robots"

# (name, size) in parameter-vector order: arm 1 (10), arm 2 (24), arm 3 (38); eqs. 5.10-5.12.
_BLOCKS: tuple[tuple[str, int], ...] = (
    ("L_1", 1), ("A0_1", 3), ("v1", 3), ("B0_1", 3),
    ("L_2a", 1), ("L_2b", 1), ("A0_2", 3), ("v2", 3), ("q1u2", 4),
    ("Abj_2a", 3), ("Abj_2b", 3), ("B0_2a", 3), ("B0_2b", 3),
    ("L_3a", 1), ("L_3b", 1), ("L_3c", 1), ("A0_3", 3), ("v3", 3), ("q1u3", 4), ("r3", 3), ("q2u3", 4),
    ("Abj_3a", 3), ("Abj_3b", 3), ("Abj_3c", 3), ("B0_3a", 3), ("B0_3b", 3), ("B0_3c", 3),
)
_SUFFIX = {1: ("",), 3: ("_x", "_y", "_z"), 4: ("_w", "_x", "_y", "_z")}
_OFFSET: dict[str, tuple[int, int]] = {}
_k = 0
for _name, _size in _BLOCKS:
    _OFFSET[_name] = (_k, _size)
    _k += _size
_N_PARAMETERS = _k
_NAMES: tuple[str, ...] = tuple(n + s for n, size in _BLOCKS for s in _SUFFIX[size])
del _k, _name, _size


# ------------------------------------------------------------------ small helpers
def _rot_x(a: Any) -> Any:
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))


def _rot_y(a: Any) -> Any:
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))


def _rot_z(a: Any) -> Any:
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


def _rotation_log(M: Any) -> Any:
    """Rotation vector of a rotation matrix (angle below pi), the inverse of Rodrigues' formula."""
    c = ca.fmin(ca.fmax((M[0, 0] + M[1, 1] + M[2, 2] - 1) / 2, -1), 1)
    th = ca.acos(c)
    vee = ca.vertcat(M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1])
    f = ca.if_else(th < 1e-4, 0.5 + th * th / 12, th / (2 * ca.sin(th) + 1e-300))
    return f * vee


def _get(p: Any, name: str) -> Any:
    i, n = _OFFSET[name]
    return p[i] if n == 1 else p[i:i + n]


def _check_max_iter(max_iter: Any) -> int:
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise InputError(f"max_iter: expected a positive integer, got {max_iter!r}")
    return int(max_iter)


def _as_rows(x: Any, name: str, width: int) -> tuple[np.ndarray, bool]:
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of shape ({width},) or (N, {width}), got {x!r}") from None
    single = arr.ndim == 1
    arr = arr[None, :] if single else arr
    if arr.ndim != 2 or arr.shape[1] != width or arr.shape[0] == 0:
        raise InputError(f"{name}: expected shape ({width},) or (N, {width}), got {np.shape(x)}")
    bad = ~np.all(np.isfinite(arr), axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise InputError(f"{name}: row {k} is not finite: {arr[k].tolist()}")
    return arr, single


def _as_rotations(R: Any, n: int, name: str = "R") -> np.ndarray:
    try:
        arr = np.asarray(R, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected rotation matrices of shape (3, 3) or (N, 3, 3), got {R!r}") from None
    if arr.shape == (3, 3):
        arr = np.broadcast_to(arr, (n, 3, 3))
    if arr.shape != (n, 3, 3):
        raise InputError(f"{name}: expected shape (3, 3) or ({n}, 3, 3) to match the positions, got {np.shape(R)}")
    if not np.all(np.isfinite(arr)):
        k = int(np.argmax(~np.all(np.isfinite(arr.reshape(n, 9)), axis=1)))
        raise InputError(f"{name}: matrix {k} is not finite")
    dev = np.abs(np.einsum("nji,njk->nik", arr, arr) - np.eye(3)).reshape(n, 9).max(axis=1)
    det = np.linalg.det(arr)
    bad = (dev > ROTATION_TOLERANCE) | (det <= 0)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise InputError(f"{name}: matrix {k} is not a rotation (max |R^T R - I| = {dev[k]:.3g}, det = {det[k]:.6g})")
    return arr


class _Mapped:
    """Evaluate a CasADi Function on N samples (columns), caching ``map`` per N."""

    def __init__(self, f: ca.Function) -> None:
        self.f = f
        self._maps: dict[int, ca.Function] = {}

    def __call__(self, n: int, *args: np.ndarray) -> list[np.ndarray]:
        if n == 1:
            out = self.f(*args)
        else:
            if n not in self._maps:
                self._maps[n] = self.f.map(n)
            out = self._maps[n](*args)
        if not isinstance(out, (list, tuple)):
            out = [out]
        return [np.asarray(o) for o in out]


# ------------------------------------------------------------------ limits
@dataclass(frozen=True)
class F1Limits:
    """Motion limits of the F1 and the reorientation range of its workspace grid.

    Parameters
    ----------
    cart_travel : numpy.ndarray, shape (3, 2)
        Row i is ``(q_min, q_max)`` of cart i+1 [m].
    joint_plate_range : numpy.ndarray, shape (3, 2)
        Rows ``(min, max)`` of ``q4, q5, q6`` [rad].
    ball_joint_angle_max : float
        Largest angle of a link to its ball-joint axis [rad] (see
        :meth:`F1Closure.ball_joint_angles`), Dressler (2012), ch. 5.5: 45 deg.
    reorientation_range : numpy.ndarray, shape (3,)
        Largest rotation from the home orientation about the world x, y, z axes used by
        :meth:`F1Closure.workspace_grid` [rad].
    error_amplification_max : numpy.ndarray, shape (2,)
        Largest TCP position error per link-length error [m/m] and orientation error per
        link-length error [rad/m] (:meth:`F1Closure.error_amplification`), the margin to
        the FK (type II) singularities.
    joint_plate_amplification_max : float
        Largest joint-plate rotation per plate rotation [rad/rad]
        (:meth:`F1Closure.joint_plate_amplification`), the margin to the IK (type I)
        singularities.
    source : str
        Where the numbers come from.
    """

    cart_travel: np.ndarray
    joint_plate_range: np.ndarray
    ball_joint_angle_max: float
    reorientation_range: np.ndarray
    error_amplification_max: np.ndarray
    joint_plate_amplification_max: float
    source: str = ""


# ------------------------------------------------------------------ the model
class F1Closure(ClosureModel):
    """The F1-type 6-DOF Gantry-Tau as a closure model, Dressler (2012), eqs. 4.16-4.33.

    72 parameters (arm 1: 10, arm 2: 24, arm 3: 38; eqs. 5.10-5.12), named as in the
    thesis' Table 5.4 (:meth:`parameter_names`, e.g. ``"L_1"``, ``"A0_1_x"``, ``"v1_z"``,
    ``"q1u2_w"``, ``"r3_y"``, ``"Abj_2b_y"``, ``"B0_3c_z"``).

    Parameters
    ----------
    p : array_like, shape (72,)
        Parameter values in the order of :meth:`parameter_names`, SI units. Quaternions
        need not be unit (the rotation formula normalises them).
    q_home : array_like, shape (6,)
        Actuator values of the home pose (centre of the workspace, reference of the
        default IK start and of the ball-joint axes) [m, rad].
    limits : F1Limits or None, optional
        Motion limits; needed by :meth:`workspace_grid` and :meth:`in_workspace`.
    name : str, optional
        Name in messages and reports.
    source : str, optional
        Where the parameters come from.

    Raises
    ------
    InputError
        If ``p`` or ``q_home`` has the wrong size or is not finite.

    Notes
    -----
    The home pose (:attr:`home`) is the FK of ``q_home`` from the implicit 5-DOF
    solution, with the plate below the carts (``(A_ij - B_ij) . v_i > 0``). The nominal
    IK branch and FK assembly mode, which :meth:`ik` and :meth:`fk` return by default,
    are the ones connected to the home pose (continuation starts, see the module notes).
    """

    orientation = True
    n_q = 6
    links = F1_LINKS

    def __init__(
        self,
        p: np.typing.ArrayLike,
        q_home: np.typing.ArrayLike,
        limits: F1Limits | None = None,
        name: str = "F1",
        source: str = "",
    ) -> None:
        pa = np.array(p, dtype=float).ravel()
        if pa.size != _N_PARAMETERS or not np.all(np.isfinite(pa)):
            raise InputError(f"{name}: expected {_N_PARAMETERS} finite parameters, got {pa.size} values")
        qh = np.array(q_home, dtype=float).ravel()
        if qh.size != 6 or not np.all(np.isfinite(qh)):
            raise InputError(f"q_home: expected 6 finite actuator values, got {np.shape(q_home)}")
        pa.setflags(write=False)
        qh.setflags(write=False)
        self._p = pa
        self.q_home = qh
        self.limits = limits
        self.name = name
        self.source = source
        self._fk_cache: dict[int, _Mapped] = {}
        self._ik_cache: dict[int, _Mapped] = {}

    # -------------------------------------------------------------- interface
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the 72 parameters (Dressler (2012), Table 5.4 notation).

        Returns
        -------
        tuple of str
            Arm 1: ``L_1, A0_1_x..z, v1_x..z, B0_1_x..z``; arm 2: ``L_2a, L_2b, A0_2_*,
            v2_*, q1u2_w..z, Abj_2a_*, Abj_2b_*, B0_2a_*, B0_2b_*``; arm 3: ``L_3a..L_3c,
            A0_3_*, v3_*, q1u3_*, r3_*, q2u3_*, Abj_3a..3c_*, B0_3a..3c_*``.
        """
        return _NAMES

    def parameter_vector(self) -> np.ndarray:
        """Current parameter values (SI units).

        Returns
        -------
        numpy.ndarray, shape (72,)
        """
        return self._p.copy()

    def quaternion_indices(self) -> list[tuple[int, int, int, int]]:
        """Indices of the quaternions ``q1u2``, ``q1u3``, ``q2u3`` (each ``w, x, y, z``).

        Returns
        -------
        list of tuple of int
            Three 4-tuples of indices into :meth:`parameter_vector`.
        """
        return [tuple(range(_OFFSET[n][0], _OFFSET[n][0] + 4)) for n in ("q1u2", "q1u3", "q2u3")]  # type: ignore[misc]

    @staticmethod
    def joint_plate_rotations(p: Any, q: Any) -> tuple[Any, Any]:
        """Orientations of the joint plates 2 and 3, Dressler (2012), eqs. 4.21-4.24.

        Parameters
        ----------
        p : casadi.SX or casadi.DM or array_like, shape (72,)
            Parameters.
        q : casadi.SX or casadi.DM or array_like, shape (6,)
            Actuator values [m, rad].

        Returns
        -------
        J2 : casadi.SX or casadi.DM, shape (3, 3)
            ``R1u2 Ry(q4)``.
        J3 : casadi.SX or casadi.DM, shape (3, 3)
            ``R1u3 Ry(q5) R2u3 Rx(q6)``.
        """
        J2 = ca.mtimes(quaternion_to_rotation(_get(p, "q1u2")), _rot_y(q[3]))
        R1u3, R2u3 = quaternion_to_rotation(_get(p, "q1u3")), quaternion_to_rotation(_get(p, "q2u3"))
        J3 = ca.mtimes([R1u3, _rot_y(q[4]), R2u3, _rot_x(q[5])])
        return J2, J3

    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """Joint points and link lengths of one arm, Dressler (2012), eqs. 4.19-4.24.

        Parameters
        ----------
        p : casadi.SX, shape (72,)
            Parameters (numeric ``casadi.DM`` works too).
        q : casadi.SX, shape (6,)
            Actuator values ``q1..q3`` [m], ``q4..q6`` [rad].
        T : casadi.SX, shape (3,)
            TCP position [m].
        R : casadi.SX, shape (3, 3)
            Plate orientation ``R_T``.
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        A : casadi.SX, shape (3, n_links)
            Actuator-side joint points [m] (eqs. 4.20, 4.21, 4.23).
        B : casadi.SX, shape (3, n_links)
            ``T + R_T B0_ij`` [m] (eq. 4.19).
        L : casadi.SX, shape (n_links,)
            Link lengths [m].

        Raises
        ------
        InputError
            If ``arm`` is not 0, 1 or 2.
        """
        if arm not in (0, 1, 2):
            raise InputError(f"arm must be one of 0..2, got {arm!r}")
        names = F1_LINKS[arm]
        if arm == 0:
            A = [_get(p, "A0_1") + q[0] * _get(p, "v1")]
        else:
            J2, J3 = self.joint_plate_rotations(p, q)
            if arm == 1:
                base = _get(p, "A0_2") + q[1] * _get(p, "v2")
                A = [ca.mtimes(J2, _get(p, f"Abj_{n}")) + base for n in names]
            else:
                R1u3_Rq5 = ca.mtimes(quaternion_to_rotation(_get(p, "q1u3")), _rot_y(q[4]))
                base = _get(p, "A0_3") + q[2] * _get(p, "v3") + ca.mtimes(R1u3_Rq5, _get(p, "r3"))
                A = [ca.mtimes(J3, _get(p, f"Abj_{n}")) + base for n in names]
        B = [T + ca.mtimes(R, _get(p, f"B0_{n}")) for n in names]
        L = [_get(p, f"L_{n}") for n in names]
        return ca.horzcat(*A), ca.horzcat(*B), ca.vertcat(*L)

    def with_parameters(self, p: np.typing.ArrayLike) -> "F1Closure":
        """The same model (home, limits) with other parameter values.

        Parameters
        ----------
        p : array_like, shape (72,)
            Values in the order of :meth:`parameter_names`.

        Returns
        -------
        F1Closure

        Raises
        ------
        InputError
            If ``p`` has the wrong size or is not finite.
        """
        return F1Closure(p, self.q_home, self.limits, self.name, "calibrated")

    def transformed(self, R: np.typing.ArrayLike, t: np.typing.ArrayLike) -> "F1Closure":
        """The model in another frame, ``x' = R x + t`` (Dressler (2012), eqs. 5.3-5.4).

        ``A0_i -> R A0_i + t``, ``v_i -> R v_i``, and the joint-plate base frames
        ``R1u2 -> R R1u2``, ``R1u3 -> R R1u3`` (their quaternions are recomputed). ``q2u3``,
        ``r3`` and ``Abj`` are expressed in the joint-plate frames and ``B0`` in the plate
        frame, so they do not change; the pose transforms as ``T' = R T + t``,
        ``R_T' = R R_T`` (eq. 4.19 gives ``B' = T' + R_T' B0``). Actuator values, lengths
        and limits are unchanged.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Rotation of the frame change.
        t : array_like, shape (3,)
            Translation [m].

        Returns
        -------
        F1Closure

        Raises
        ------
        InputError
            If ``R`` is not a rotation or ``t`` not a finite 3-vector.
        """
        Rm = _as_rotations(R, 1)[0]
        tv = np.asarray(t, dtype=float).ravel()
        if tv.shape != (3,) or not np.all(np.isfinite(tv)):
            raise InputError(f"t: expected a finite translation of shape (3,), got {np.shape(t)}")
        p = self._p.copy()

        def put(name: str, value: np.ndarray) -> None:
            i, n = _OFFSET[name]
            p[i:i + n] = value

        for i in (1, 2, 3):
            put(f"A0_{i}", Rm @ _get(self._p, f"A0_{i}") + tv)
            put(f"v{i}", Rm @ _get(self._p, f"v{i}"))
        for name in ("q1u2", "q1u3"):
            qv = _get(self._p, name)
            put(name, np.linalg.norm(qv) * rotation_to_quaternion(Rm @ quaternion_to_rotation(qv)))
        return F1Closure(p, self.q_home, self.limits, self.name, self.source)

    # -------------------------------------------------------------- symbolic building blocks
    @cached_property
    def _p_dm(self) -> ca.DM:
        return ca.DM(self._p)

    def _arm_residual(self, arm: int, q: Any, T: Any, R: Any, squared: bool = True) -> Any:
        """``L^2 - ||B - A||^2`` (IK residual, eq. 4.27) or ``||B - A|| - L`` (FK)."""
        A, B, L = self.link_points(self._p_dm, q, T, R, arm)
        D = B - A
        d2 = ca.sum1(D * D).T
        return L * L - d2 if squared else ca.sqrt(d2) - L

    def _arm1_closed_form(self, T: Any, R: Any) -> tuple[Any, Any]:
        """``q1`` (``+`` root: cart joint above the plate joint along ``v1``) and the discriminant."""
        A, B, L = self.link_points(self._p_dm, ca.DM.zeros(6), T, R, 0)
        v1 = ca.DM(_get(self._p, "v1")).T
        # the 3-link quadratic of eq. 4.9 with As = A0_1 - B_1 and T = 0 (so d = B_1 - A0_1)
        # (ik_expression solves three arms at once: the same arm three times, first row used)
        q, disc = ik_expression(
            ca.DM.zeros(3), [1.0, 1.0, 1.0], ca.repmat(L, 3, 1), ca.repmat((A - B).T, 3, 1), ca.repmat(v1, 3, 1)
        )
        return q[0], disc[0]

    def _five_dof_start(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The implicit 5-DOF solution for ``q`` (used to find the home pose).

        Orientation: arm 3 a parallelogram, ``R0 = R1u3 Ry(q5) R2u3 Rx(q6) C3`` with ``C3``
        the rotation that best maps the centred plate points ``B0_3j`` onto ``Abj_3j``
        (Kabsch); position: trilateration of arm 1 and the mean joint points of arms 2 and
        3 (mean link lengths), plate below the carts.
        """
        Abj = np.array([_get(self._p, f"Abj_{n}") for n in F1_LINKS[2]])
        B0 = np.array([_get(self._p, f"B0_{n}") for n in F1_LINKS[2]])
        U, _, Vt = np.linalg.svd((Abj - Abj.mean(axis=0)).T @ (B0 - B0.mean(axis=0)))
        C3 = U @ np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))]) @ Vt
        qd = ca.DM(q)
        _, J3 = self.joint_plate_rotations(self._p_dm, qd)
        R0 = ca.mtimes(J3, ca.DM(C3))
        centres, radii, v = [], [], []
        for arm in range(3):
            A, B, L = self.link_points(self._p_dm, qd, ca.DM.zeros(3), R0, arm)
            n = len(F1_LINKS[arm])
            centres.append((ca.sum2(A - B) / n).T)
            radii.append(ca.sum1(L) / n)
            v.append(ca.DM(_get(self._p, f"v{arm + 1}")).T)
        T0, _, _ = fk_expression(ca.DM.zeros(3), -1.0, ca.vertcat(*radii), ca.vertcat(*centres), ca.vertcat(*v))
        return np.asarray(T0).ravel(), np.asarray(R0)

    def _ik_start_expr(self, T: Any, R: Any) -> tuple[Any, Any]:
        T_h, R_h = self.home
        w = _rotation_log(ca.mtimes(R, ca.DM(R_h).T))
        step2, step3 = self._ik_steps
        x2 = ca.DM(self.q_home[[1, 3]])
        x3 = ca.DM(self.q_home[[2, 4, 5]])
        for k in range(1, START_SUBSTEPS + 1):
            s = k / START_SUBSTEPS
            T_s = ca.DM(T_h) + s * (T - ca.DM(T_h))
            R_s = ca.mtimes(rotation_vector_to_rotation(s * w), ca.DM(R_h))
            for _ in range(START_NEWTON_STEPS):
                x2 = step2(x2, T_s, R_s)[0]
                x3 = step3(x3, T_s, R_s)[0]
        q1, disc = self._arm1_closed_form(T, R)
        return ca.vertcat(q1, x2[0], x3[0], x2[1], x3[1], x3[2]), disc

    def _fk_start_expr(self, q: Any) -> tuple[Any, Any]:
        T_h, R_h = self.home
        T_k, R_k = ca.DM(T_h), ca.DM(R_h)
        qh = ca.DM(self.q_home)
        for k in range(1, START_SUBSTEPS + 1):
            q_s = qh + (k / START_SUBSTEPS) * (q - qh)
            for _ in range(START_NEWTON_STEPS):
                T_k, R_k, _ = self._fk_step(T_k, R_k, q_s)
        return T_k, R_k

    # -------------------------------------------------------------- CasADi Functions
    @cached_property
    def fk_start_function(self) -> ca.Function:
        """CasADi Function ``fk_start(q[6]) -> (T0[3], R0[3x3])``: the default FK start.

        Continuation from the home pose, which is the implicit 5-DOF solution
        (``q4 = -q5``, arms 2 and 3 near parallelograms; Dressler (2012), eqs. 4.25-4.26,
        4.32-4.33): the actuator values go from ``q_home`` to ``q`` in
        :data:`START_SUBSTEPS` equal sub-steps, each followed by
        :data:`START_NEWTON_STEPS` Newton steps of the FK (eqs. 4.30-4.31). This defines
        the nominal assembly mode: the one connected to the home pose.

        Returns
        -------
        casadi.Function
        """
        q = ca.MX.sym("q", 6)
        T0, R0 = self._fk_start_expr(q)
        return ca.Function("f1_fk_start", [q], [T0, R0], ["q"], ["T0", "R0"])

    @cached_property
    def ik_start_function(self) -> ca.Function:
        """CasADi Function ``ik_start(T[3], R_T[3x3]) -> (q0[6], disc1)``: the default IK start.

        Continuation from the home pose: the pose goes from ``(T_home, R_home)`` to
        ``(T, R_T)`` in :data:`START_SUBSTEPS` equal sub-steps (straight in ``T``, about a
        fixed axis in orientation, ``R = Rot(s w) R_home`` with ``w`` the rotation vector
        of ``R_T R_home^T``, valid below 180 deg), each followed by
        :data:`START_NEWTON_STEPS` Newton steps of arms 2 and 3 from ``q_home``. This
        defines the nominal IK branch (the one connected to the home pose). ``q1`` is the
        exact closed form of arm 1 (eq. 4.20, ``+`` root: cart joint above the plate joint
        along ``v1``); ``disc1 < 0``: arm 1 cannot reach the pose.

        Returns
        -------
        casadi.Function
        """
        T = ca.MX.sym("T", 3)
        R = ca.MX.sym("R_T", 3, 3)
        q0, disc = self._ik_start_expr(T, R)
        return ca.Function("f1_ik_start", [T, R], [q0, disc], ["T", "R_T"], ["q0", "disc1"])

    def _newton_arm_step(self, arm: int) -> ca.Function:
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        x = ca.SX.sym("x", arm + 1)
        q = ca.SX.zeros(6)
        idx = [1, 3] if arm == 1 else [2, 4, 5]
        for k, i in enumerate(idx):
            q[i] = x[k]
        e = self._arm_residual(arm, q, T, R, squared=True)
        J = ca.jacobian(e, x)
        x_new = x - ca.solve(J, e)
        return ca.Function(f"f1_ik_step_arm{arm + 1}", [x, T, R], [x_new, e], ["x", "T", "R_T"], ["x_next", "e"])

    def ik_function(self, max_iter: int = IK_MAX_ITER) -> ca.Function:
        """CasADi Function of the inverse kinematics with a fixed number of Newton iterations.

        ``ik(T[3], R_T[3x3], q0[6]) -> (q[6], e[6], iterations, status, disc1)``: arm 1 in
        closed form (eq. 4.20, ``+`` root; ``disc1 < 0``: arm 1 cannot reach the pose);
        arms 2 (``q2, q4``) and 3 (``q3, q5, q6``) by ``max_iter`` unrolled Newton steps on
        ``e = L^2 - ||B - A(Q)||^2`` (Dressler (2012), eqs. 4.27-4.29) from ``q0`` (a
        previous sample, or ``ik_start``). ``e`` are the final
        residuals [m^2] of links 1, 2a, 2b, 3a, 3b, 3c; ``iterations`` the Newton steps
        taken before ``max |e|`` fell below :data:`IK_TOLERANCE`; ``status`` 1 when
        converged and arm 1 reaches the pose, else 0. Suitable for C code generation.

        Parameters
        ----------
        max_iter : int, optional
            Number of Newton iterations (unrolled).

        Returns
        -------
        casadi.Function

        Raises
        ------
        InputError
            If ``max_iter`` is not a positive integer.
        """
        n = _check_max_iter(max_iter)
        T = ca.MX.sym("T", 3)
        R = ca.MX.sym("R_T", 3, 3)
        q0 = ca.MX.sym("q0", 6)
        step2, step3 = self._ik_steps
        q1, disc = self._arm1_closed_form(T, R)
        x2 = ca.vertcat(q0[1], q0[3])
        x3 = ca.vertcat(q0[2], q0[4], q0[5])
        iters = 0
        for _ in range(n):
            x2n, e2 = step2(x2, T, R)
            x3n, e3 = step3(x3, T, R)
            iters = iters + (ca.mmax(ca.fabs(ca.vertcat(e2, e3))) > IK_TOLERANCE)
            x2, x3 = x2n, x3n
        q = ca.vertcat(q1, x2[0], x3[0], x2[1], x3[1], x3[2])
        e = ca.vertcat(*[self._arm_residual(a, q, T, R) for a in range(3)])
        ok = ca.logic_and(ca.mmax(ca.fabs(e)) <= IK_TOLERANCE, disc >= 0)
        return ca.Function(
            f"f1_ik_{n}", [T, R, q0], [q, e, iters, ok, disc], ["T", "R_T", "q0"], ["q", "e", "iterations", "status", "disc1"]
        )

    @cached_property
    def _ik_steps(self) -> tuple[ca.Function, ca.Function]:
        return self._newton_arm_step(1), self._newton_arm_step(2)

    @cached_property
    def _fk_step(self) -> ca.Function:
        q = ca.SX.sym("q", 6)
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        w = ca.SX.sym("w", 3)
        Rw = ca.mtimes(rotation_vector_to_rotation(w), R)
        e = ca.vertcat(*[self._arm_residual(a, q, T, Rw, squared=False) for a in range(3)])
        x = ca.vertcat(T, w)
        J = ca.substitute(ca.jacobian(e, x), w, ca.DM.zeros(3))
        e0 = ca.substitute(e, w, ca.DM.zeros(3))
        dx = -ca.solve(J, e0)
        R_next = ca.mtimes(rotation_vector_to_rotation(dx[3:]), R)
        return ca.Function("f1_fk_step", [T, R, q], [T + dx[:3], R_next, e0], ["T", "R_T", "q"], ["T_next", "R_next", "e"])

    @cached_property
    def jacobian_function(self) -> ca.Function:
        """CasADi Function ``jacobian(T, R_T, q) -> (J_X[6x6], J_q[6x6])`` of the link lengths.

        ``J_X``: row ``ij`` is ``d||B_ij - A_ij|| / d(T, w)`` at ``w = 0`` with
        ``R_T <- Rot(w) R_T``, the Stewart-platform inverse Jacobian of Dressler (2012),
        eq. 4.31, ``[AB^T/|AB|, (R_T B0_ij x AB)^T/|AB|]`` (AD of the closure graph; the
        rotation vector ``w`` replaces the ZYZ angles). ``J_q``: ``d||B_ij - A_ij|| / dq``
        (block-diagonal per arm). Along a motion, ``J_X (T_dot, w) + J_q q_dot = 0``.

        Returns
        -------
        casadi.Function
        """
        q = ca.SX.sym("q", 6)
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        w = ca.SX.sym("w", 3)
        Rw = ca.mtimes(rotation_vector_to_rotation(w), R)
        e = ca.vertcat(*[self._arm_residual(a, q, T, Rw, squared=False) for a in range(3)])
        J_X = ca.substitute(ca.jacobian(e, ca.vertcat(T, w)), w, ca.DM.zeros(3))
        J_q = ca.substitute(ca.jacobian(e, q), w, ca.DM.zeros(3))
        return ca.Function("f1_jacobian", [T, R, q], [J_X, J_q], ["T", "R_T", "q"], ["J_X", "J_q"])

    def fk_function(self, max_iter: int = FK_MAX_ITER) -> ca.Function:
        """CasADi Function of the forward kinematics with a fixed number of Newton iterations.

        ``fk(q[6], T0[3], R0[3x3]) -> (T[3], R_T[3x3], e[6], iterations, status)``:
        ``max_iter`` unrolled Newton steps on the link lengths (Dressler (2012),
        eqs. 4.30-4.31) from ``(T0, R0)`` (a previous sample, or ``fk_start``), orientation
        updated as ``R_T <- Rot(dw) R_T``. ``e`` are the final ``||B - A|| - L`` [m];
        ``iterations`` the steps taken before ``max |e|`` fell below :data:`FK_TOLERANCE`;
        ``status`` 1 when converged. Suitable for C code generation.

        Parameters
        ----------
        max_iter : int, optional
            Number of Newton iterations (unrolled).

        Returns
        -------
        casadi.Function

        Raises
        ------
        InputError
            If ``max_iter`` is not a positive integer.
        """
        n = _check_max_iter(max_iter)
        q = ca.MX.sym("q", 6)
        T = ca.MX.sym("T0", 3)
        R = ca.MX.sym("R0", 3, 3)
        T_k, R_k = T, R
        iters = 0
        for _ in range(n):
            T_n, R_n, e = self._fk_step(T_k, R_k, q)
            iters = iters + (ca.mmax(ca.fabs(e)) > FK_TOLERANCE)
            T_k, R_k = T_n, R_n
        e = ca.vertcat(*[self._arm_residual(a, q, T_k, R_k, squared=False) for a in range(3)])
        ok = ca.mmax(ca.fabs(e)) <= FK_TOLERANCE
        return ca.Function(
            f"f1_fk_{n}", [q, T, R], [T_k, R_k, e, iters, ok], ["q", "T0", "R0"], ["T", "R_T", "e", "iterations", "status"]
        )

    # -------------------------------------------------------------- numeric API
    def _mapped_ik(self, n_steps: int) -> _Mapped:
        if n_steps not in self._ik_cache:
            self._ik_cache[n_steps] = _Mapped(self.ik_function(n_steps).expand())
        return self._ik_cache[n_steps]

    def _mapped_fk(self, n_steps: int) -> _Mapped:
        if n_steps not in self._fk_cache:
            self._fk_cache[n_steps] = _Mapped(self.fk_function(n_steps).expand())
        return self._fk_cache[n_steps]

    def _run_ik(self, max_iter: int, T: np.ndarray, Rc: np.ndarray, q0: np.ndarray) -> tuple[np.ndarray, ...]:
        """Newton IK in chunks on the unconverged columns; returns (q, e, iterations, ok, disc1)."""
        N = T.shape[1]
        q, e = np.array(q0, dtype=float), np.full((6, N), np.nan)
        it, ok, disc = np.zeros(N, dtype=int), np.zeros(N, dtype=bool), np.zeros(N)
        active, done = np.arange(N), 0
        while active.size and done < max_iter:
            k = min(_CHUNK, max_iter - done)
            cols = np.concatenate([np.arange(3 * j, 3 * j + 3) for j in active]) if active.size < N else slice(None)
            qn, en, itn, okn, dn = self._mapped_ik(k)(active.size, T[:, active], Rc[:, cols], q[:, active])
            q[:, active], e[:, active], disc[active] = qn, en, dn.ravel()
            it[active] += itn.ravel().astype(int)
            ok[active] = okn.ravel().astype(bool) & np.all(np.isfinite(en), axis=0) & np.all(np.isfinite(qn), axis=0)
            done += k
            active = active[~ok[active] & np.all(np.isfinite(q[:, active]), axis=0) & (disc[active] >= 0)]
        return q, e, it, ok, disc

    def _run_fk(self, max_iter: int, q: np.ndarray, T0: np.ndarray, R0c: np.ndarray) -> tuple[np.ndarray, ...]:
        """Newton FK in chunks on the unconverged columns; returns (T, R cols, e, iterations, ok)."""
        N = q.shape[1]
        T, Rc, e = np.array(T0, dtype=float), np.array(R0c, dtype=float), np.full((6, N), np.nan)
        it, ok = np.zeros(N, dtype=int), np.zeros(N, dtype=bool)
        active, done = np.arange(N), 0
        while active.size and done < max_iter:
            k = min(_CHUNK, max_iter - done)
            cols = np.concatenate([np.arange(3 * j, 3 * j + 3) for j in active]) if active.size < N else slice(None)
            Tn, Rn, en, itn, okn = self._mapped_fk(k)(active.size, q[:, active], T[:, active], Rc[:, cols])
            T[:, active], e[:, active] = Tn, en
            Rc[:, cols] = Rn
            it[active] += itn.ravel().astype(int)
            ok[active] = okn.ravel().astype(bool) & np.all(np.isfinite(en), axis=0)
            done += k
            active = active[~ok[active] & np.all(np.isfinite(T[:, active]), axis=0)]
        return T, Rc, e, it, ok

    @cached_property
    def _fk_start_mapped(self) -> _Mapped:
        return _Mapped(self.fk_start_function.expand())

    @cached_property
    def _ik_start_mapped(self) -> _Mapped:
        return _Mapped(self.ik_start_function.expand())

    @cached_property
    def _jac_mapped(self) -> _Mapped:
        return _Mapped(self.jacobian_function)

    @staticmethod
    def _R_cols(R: np.ndarray) -> np.ndarray:
        """(N, 3, 3) -> (3, 3N) blocks for a mapped Function (column-major 3x3 inputs)."""
        return np.concatenate(list(R), axis=1) if R.shape[0] > 1 else R[0]

    @staticmethod
    def _R_from_cols(M: np.ndarray, n: int) -> np.ndarray:
        return np.asarray(M).reshape(3, n, 3).transpose(1, 0, 2)

    @cached_property
    def home(self) -> tuple[np.ndarray, np.ndarray]:
        """The home pose ``(T_home (3,) [m], R_home (3, 3))``: the FK of ``q_home``.

        Found by Newton's method from the implicit 5-DOF solution (arm 3 a
        parallelogram for the joint-plate angles, position by trilateration of arm 1 and
        the mean joint points of arms 2 and 3, plate below the carts), Dressler (2012),
        eqs. 4.25-4.26, 4.32-4.33. Every default start continues from it.

        Returns
        -------
        tuple of numpy.ndarray
        """
        T0, R0 = self._five_dof_start(self.q_home)
        return self.fk(self.q_home, T0, R0)

    def fk_start(self, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The FK start value (implicit 5-DOF solution), see :attr:`fk_start_function`.

        Parameters
        ----------
        q : array_like, shape (6,) or (N, 6)
            Actuator values [m, rad].

        Returns
        -------
        T0 : numpy.ndarray, shape (3,) or (N, 3)
            Start positions [m].
        R0 : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Start orientations.

        Raises
        ------
        InputError
            Wrong shape or non-finite values.
        """
        qa, single = _as_rows(q, "q", 6)
        T0, R0 = self._fk_start_mapped(qa.shape[0], qa.T)
        T0 = T0.T
        R0 = self._R_from_cols(R0, qa.shape[0])
        return (T0[0], R0[0]) if single else (T0, R0)

    def fk(
        self,
        q: np.typing.ArrayLike,
        T0: np.typing.ArrayLike | None = None,
        R0: np.typing.ArrayLike | None = None,
        max_iter: int = FK_MAX_ITER,
        return_iterations: bool = False,
    ) -> tuple[np.ndarray, ...]:
        """Forward kinematics by Newton's method, Dressler (2012), eqs. 4.30-4.33.

        Parameters
        ----------
        q : array_like, shape (6,) or (N, 6)
            Actuator values [m, rad].
        T0 : array_like, shape (3,) or (N, 3), optional
            Start positions (e.g. the previous sample); default the 5-DOF start
            (:attr:`fk_start_function`), which selects the nominal assembly mode.
        R0 : array_like, shape (3, 3) or (N, 3, 3), optional
            Start orientations; given together with ``T0``.
        max_iter : int, optional
            Newton iteration limit (:data:`FK_MAX_ITER`).
        return_iterations : bool, optional
            Also return the Newton iterations used per pose.

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations ``R_T``.
        iterations : numpy.ndarray of int, shape () or (N,)
            Only with ``return_iterations``.

        Raises
        ------
        ConvergenceError
            If ``max |(||B - A|| - L)|`` does not fall below :data:`FK_TOLERANCE` within
            ``max_iter`` iterations; the message names the first failing row.
        InputError
            Wrong shapes, non-finite values, only one of ``T0``/``R0``, or a bad ``max_iter``.
        """
        n_it = _check_max_iter(max_iter)
        qa, single = _as_rows(q, "q", 6)
        N = qa.shape[0]
        if (T0 is None) != (R0 is None):
            raise InputError("T0 and R0: give both start values or neither")
        if T0 is None:
            T0a, R0m = self._fk_start_mapped(N, qa.T)
        else:
            T0r, _ = _as_rows(T0, "T0", 3)
            if T0r.shape[0] not in (1, N):
                raise InputError(f"T0: expected 1 or {N} rows, got {T0r.shape[0]}")
            T0a = np.broadcast_to(T0r, (N, 3)).T
            R0m = self._R_cols(_as_rotations(R0, N, "R0"))
        T, R, e, it, ok = self._run_fk(n_it, qa.T, T0a, R0m)
        if T0 is None and not np.all(ok) and np.any(ok):
            self._fk_continue(n_it, qa, T, R, e, it, ok)
        if not np.all(ok):
            k = int(np.argmin(ok))
            ek = np.abs(e[:, k])
            resid = f"{np.max(ek):.3g} m" if np.all(np.isfinite(ek)) else "not finite (diverged)"
            raise ConvergenceError(
                f"{self.name}: forward kinematics did not converge for pose row {k} (q = {qa[k].tolist()}): "
                f"max |link length residual| {resid} > {FK_TOLERANCE:g} m after "
                f"{n_it} Newton iterations (no assembly near the start, or max_iter too small); "
                f"{int(np.sum(~ok))} pose(s) failed"
            )
        T = T.T
        R = self._R_from_cols(R, N)
        out = (T[0], R[0], it[0]) if single else (T, R, it)
        return out if return_iterations else out[:2]

    def _fk_continue(self, n_it: int, qa: np.ndarray, T: np.ndarray, Rc: np.ndarray, e: np.ndarray, it: np.ndarray, ok: np.ndarray) -> None:
        """Second start for rows whose default-start FK failed (in place).

        A model far from the one whose home pose the default start follows (e.g. a
        calibration start perturbed by tens of mm) can leave the continuation of
        :attr:`fk_start_function` on some poses. Such a row is reached from the converged
        row nearest in ``q`` (scaled: metres, radians) by :data:`FK_CONTINUATION_STEPS`
        equal steps in ``q``, each a Newton solve started from the previous solution.
        """
        N = qa.shape[0]
        good = np.flatnonzero(ok)
        bad = np.flatnonzero(~ok)
        d = np.linalg.norm(qa[bad, None, :] - qa[None, good, :], axis=2)
        src = good[np.argmin(d, axis=1)]
        Rcols = Rc.reshape(3, N, 3)
        Tb = T[:, src].copy()
        Rb = Rcols[:, src, :].reshape(3, -1)
        fine = np.ones(bad.size, dtype=bool)
        for s in range(1, FK_CONTINUATION_STEPS + 1):
            w = s / FK_CONTINUATION_STEPS
            qs = ((1.0 - w) * qa[src] + w * qa[bad]).T
            Tb, Rb, eb, itb, okb = self._run_fk(n_it, qs, Tb, Rb)
            fine &= okb
            it[bad] += itb
        for j, k in enumerate(bad):
            if fine[j] and np.all(np.isfinite(eb[:, j])):
                T[:, k] = Tb[:, j]
                Rcols[:, k, :] = Rb.reshape(3, bad.size, 3)[:, j, :]
                e[:, k] = eb[:, j]
                ok[k] = True
        Rc[:] = Rcols.reshape(3, -1)

    def ik(
        self,
        T: np.typing.ArrayLike,
        R: np.typing.ArrayLike,
        q0: np.typing.ArrayLike | None = None,
        max_iter: int = IK_MAX_ITER,
        return_iterations: bool = False,
    ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Inverse kinematics, Dressler (2012), eqs. 4.20-4.29.

        Arm 1 in closed form; arms 2 and 3 by Newton's method (see :meth:`ik_function`).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations ``R_T``.
        q0 : array_like, shape (6,) or (N, 6), optional
            Start values (the previous solution in real-time use); default the parallel-arm
            start of :attr:`ik_start_function`.
        max_iter : int, optional
            Newton iteration limit (:data:`IK_MAX_ITER`).
        return_iterations : bool, optional
            Also return the Newton iterations used per pose.

        Returns
        -------
        q : numpy.ndarray, shape (6,) or (N, 6)
            Actuator values [m, rad].
        iterations : numpy.ndarray of int, shape () or (N,)
            Only with ``return_iterations``.

        Raises
        ------
        UnreachablePoseError
            If arm 1 cannot reach a pose (no real root of its quadratic); names the row.
        ConvergenceError
            If Newton's method for arm 2 or 3 does not reach :data:`IK_TOLERANCE` within
            ``max_iter`` iterations (pose out of reach of those arms or ``max_iter`` too
            small); names the first failing row.
        InputError
            Wrong shapes, non-finite values, ``R`` not a rotation, or a bad ``max_iter``.
        """
        n_it = _check_max_iter(max_iter)
        Ta, single = _as_rows(T, "T", 3)
        N = Ta.shape[0]
        Ra = _as_rotations(R, N)
        Rc = self._R_cols(Ra)
        if q0 is None:
            q0a, _ = self._ik_start_mapped(N, Ta.T, Rc)
        else:
            q0r, _ = _as_rows(q0, "q0", 6)
            if q0r.shape[0] not in (1, N):
                raise InputError(f"q0: expected 1 or {N} rows, got {q0r.shape[0]}")
            q0a = np.broadcast_to(q0r, (N, 6)).T
        q, e, it, ok, disc = self._run_ik(n_it, Ta.T, Rc, q0a)
        if np.any(disc < 0):
            k = int(np.argmax(disc < 0))
            raise UnreachablePoseError(
                f"{self.name}: pose row {k} (T = {Ta[k].tolist()}) is unreachable for arm 1: the link-1 sphere about "
                f"B_1 misses guideway 1 (discriminant {disc[k]:.3g} m^2 < 0)"
            )
        if not np.all(ok):
            k = int(np.argmin(ok))
            raise ConvergenceError(
                f"{self.name}: inverse kinematics did not converge for pose row {k} (T = {Ta[k].tolist()}): "
                f"max |L^2 - ||B - A||^2| {np.nanmax(np.abs(e[:, k])):.3g} m^2 > {IK_TOLERANCE:g} m^2 after "
                f"{n_it} Newton iterations (pose out of reach of arm 2 or 3, or max_iter too small); "
                f"{int(np.sum(~ok))} pose(s) failed"
            )
        q = q.T
        out = (q[0], it[0]) if single else (q, it)
        return out if return_iterations else out[0]

    def jacobians(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of the link lengths w.r.t. the pose and the actuators, eq. 4.31.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations.
        q : array_like, shape (6,) or (N, 6)
            Actuator values of the poses [m, rad].

        Returns
        -------
        J_X : numpy.ndarray, shape (6, 6) or (N, 6, 6)
            Stewart-platform inverse Jacobian: rows links 1, 2a, 2b, 3a, 3b, 3c, columns
            ``(T_dot [m/s], w [rad/s])`` with ``R_T_dot = [w]x R_T``.
        J_q : numpy.ndarray, shape (6, 6) or (N, 6, 6)
            Link-length rates per actuator rate (see :attr:`jacobian_function`).

        Raises
        ------
        InputError
            Wrong shapes, non-finite values or ``R`` not a rotation.
        """
        Ta, single = _as_rows(T, "T", 3)
        N = Ta.shape[0]
        qa, _ = _as_rows(q, "q", 6)
        if qa.shape[0] != N:
            raise InputError(f"q: expected {N} rows to match T, got {qa.shape[0]}")
        J_X, J_q = self._jac_mapped(N, Ta.T, self._R_cols(_as_rotations(R, N)), qa.T)
        J_X = np.asarray(J_X).reshape(6, N, 6).transpose(1, 0, 2)
        J_q = np.asarray(J_q).reshape(6, N, 6).transpose(1, 0, 2)
        return (J_X[0], J_q[0]) if single else (J_X, J_q)

    # -------------------------------------------------------------- limits and workspace
    @cached_property
    def _ball_axes(self) -> ca.Function:
        """Home link directions in the frames of the bodies carrying the joints."""
        T_h, R_h = self.home
        qh = ca.DM(self.q_home)
        J2, J3 = (np.asarray(M) for M in self.joint_plate_rotations(self._p_dm, qh))
        carriers = [np.eye(3), J2, J3]
        axes_A, axes_B = [], []
        for arm in range(3):
            A, B, _ = (np.asarray(ca.DM(x)) for x in self.link_points(self._p_dm, qh, ca.DM(T_h), ca.DM(R_h), arm))
            u = (B - A) / np.linalg.norm(B - A, axis=0)
            axes_A.append(carriers[arm].T @ u)
            axes_B.append(R_h.T @ u)
        q = ca.SX.sym("q", 6)
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        J2s, J3s = self.joint_plate_rotations(self._p_dm, q)
        carriers_s = [ca.DM.eye(3), J2s, J3s]
        cos_A, cos_B = [], []
        for arm in range(3):
            A, B, _ = self.link_points(self._p_dm, q, T, R, arm)
            for j in range(A.shape[1]):
                u = (B[:, j] - A[:, j]) / ca.norm_2(B[:, j] - A[:, j])
                cos_A.append(ca.dot(u, ca.mtimes(carriers_s[arm], ca.DM(axes_A[arm][:, j]))))
                cos_B.append(ca.dot(u, ca.mtimes(R, ca.DM(axes_B[arm][:, j]))))
        ang = ca.acos(ca.fmin(ca.fmax(ca.vertcat(ca.horzcat(*cos_A), ca.horzcat(*cos_B)), -1), 1))
        return ca.Function("f1_ball_joint_angles", [T, R, q], [ang], ["T", "R_T", "q"], ["angles"])

    @cached_property
    def _ball_mapped(self) -> _Mapped:
        return _Mapped(self._ball_axes)

    def ball_joint_angles(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Angles of the links to their ball-joint axes [rad].

        The ball-joint axes are not in the source; they are taken as the link directions
        at the home pose, fixed in the body that carries the joint: cart 1, joint plate 2
        (``R1u2 Ry(q4)``), joint plate 3 (``R1u3 Ry(q5) R2u3 Rx(q6)``) on the actuator side,
        the end-effector plate (``R_T``) on the plate side. So every angle is 0 at home and
        the 45-deg limit (Dressler (2012), ch. 5.5) is a cone about that mounting.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations.
        q : array_like, shape (6,) or (N, 6)
            Actuator values of the poses [m, rad].

        Returns
        -------
        numpy.ndarray, shape (2, 6) or (N, 2, 6)
            Row 0: actuator-side joints, row 1: plate-side joints; columns links 1, 2a,
            2b, 3a, 3b, 3c.

        Raises
        ------
        InputError
            Wrong shapes, non-finite values or ``R`` not a rotation.
        """
        Ta, single = _as_rows(T, "T", 3)
        N = Ta.shape[0]
        qa, _ = _as_rows(q, "q", 6)
        if qa.shape[0] != N:
            raise InputError(f"q: expected {N} rows to match T, got {qa.shape[0]}")
        (ang,) = self._ball_mapped(N, Ta.T, self._R_cols(_as_rotations(R, N)), qa.T)
        ang = np.asarray(ang).reshape(2, N, 6).transpose(1, 0, 2)
        return ang[0] if single else ang

    def _require_limits(self, what: str) -> F1Limits:
        if self.limits is None:
            raise InputError(f"{what}: the model has no limits (load it with load_f1 or pass limits=F1Limits(...))")
        return self.limits

    def aspect_signs(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Signs of the Jacobian determinants that separate assembly modes and IK branches.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations.
        q : array_like, shape (6,) or (N, 6)
            Actuator values of the poses [m, rad].

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``sign det`` of ``J_X`` (:meth:`jacobians`; FK or type-II singularities where
            it is 0) and of the blocks of ``J_q`` of arms 2 (``q2, q4``) and 3 (``q3, q5,
            q6``) (IK, type-I singularities). Poses with the signs of the home pose lie
            in its aspect.

        Raises
        ------
        InputError
            Wrong shapes, non-finite values or ``R`` not a rotation.
        """
        J_X, J_q = self.jacobians(T, R, q)
        single = J_X.ndim == 2
        J_X, J_q = (J_X[None], J_q[None]) if single else (J_X, J_q)
        d = np.column_stack([
            np.linalg.det(J_X),
            np.linalg.det(J_q[:, 1:3][:, :, [1, 3]]),
            np.linalg.det(J_q[:, 3:6][:, :, [2, 4, 5]]),
        ])
        sg = np.sign(d)
        return sg[0] if single else sg

    def error_amplification(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Largest TCP errors per link-length error (distance to the FK singularities).

        With ``J`` the pose Jacobian ``J_X`` (:meth:`jacobians`, eq. 4.31), a link-length
        error ``dL`` moves the pose by ``J^-1 dL``; the 2-norms of the position and
        orientation rows of ``J^-1`` are the worst-case amplifications. They grow without
        bound at a type-II singularity.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations.
        q : array_like, shape (6,) or (N, 6)
            Actuator values of the poses [m, rad].

        Returns
        -------
        numpy.ndarray, shape (2,) or (N, 2)
            Position amplification [m/m] and orientation amplification [rad/m]
            (``inf`` at a singular Jacobian).

        Raises
        ------
        InputError
            Wrong shapes, non-finite values or ``R`` not a rotation.
        """
        J = self.jacobians(T, R, q)[0]
        single = J.ndim == 2
        J = J[None] if single else J
        out = np.full((J.shape[0], 2), np.inf)
        regular = np.abs(np.linalg.det(J)) > 0
        if np.any(regular):
            Ji = np.linalg.inv(J[regular])
            out[regular] = np.column_stack([np.linalg.norm(Ji[:, :3], 2, axis=(1, 2)), np.linalg.norm(Ji[:, 3:], 2, axis=(1, 2))])
        return out[0] if single else out

    def joint_plate_amplification(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Largest joint-plate rotation per plate rotation (distance to the IK singularities).

        From ``J_X (T_dot, w) + J_q q_dot = 0`` (:meth:`jacobians`): the 2-norm of
        ``d(q4, q5, q6)/dw = -(J_q^-1 J_X)[3:, 3:]``. It grows without bound at a type-I
        singularity, where the IK of arm 2 or 3 loses a solution (two branches meet).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations.
        q : array_like, shape (6,) or (N, 6)
            Actuator values of the poses [m, rad].

        Returns
        -------
        float or numpy.ndarray, shape (N,)
            [rad/rad]; ``inf`` at a singular ``J_q``.

        Raises
        ------
        InputError
            Wrong shapes, non-finite values or ``R`` not a rotation.
        """
        J_X, J_q = self.jacobians(T, R, q)
        single = J_X.ndim == 2
        J_X, J_q = (J_X[None], J_q[None]) if single else (J_X, J_q)
        out = np.full(J_X.shape[0], np.inf)
        regular = np.abs(np.linalg.det(J_q)) > 0
        if np.any(regular):
            D = -np.linalg.solve(J_q[regular], J_X[regular])
            out[regular] = np.linalg.norm(D[:, 3:, 3:], 2, axis=(1, 2))
        return float(out[0]) if single else out

    def in_workspace(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Whether poses with their IK solutions belong to the workspace.

        A pose belongs to the workspace when its cart positions and joint-plate angles
        lie in ``limits``, every ball joint is within its cone
        (:meth:`ball_joint_angles`), it lies in the aspect of the home pose
        (:meth:`aspect_signs` equal to the home's: no singularity separates it from
        home, so the nominal IK branch and FK mode are the ones connected to home) and
        its error amplification (:meth:`error_amplification`, FK side) and joint-plate
        amplification (:meth:`joint_plate_amplification`, IK side) are below
        ``limits.error_amplification_max`` and ``limits.joint_plate_amplification_max``
        (margins to the singularities).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations.
        q : array_like, shape (6,) or (N, 6)
            Their actuator values (from :meth:`ik`) [m, rad].

        Returns
        -------
        bool or numpy.ndarray of bool, shape (N,)

        Raises
        ------
        InputError
            Wrong shapes, or the model has no limits.
        """
        lim = self._require_limits("in_workspace")
        qa, single = _as_rows(q, "q", 6)
        N = qa.shape[0]
        Ta, _ = _as_rows(T, "T", 3)
        if Ta.shape[0] != N:
            raise InputError(f"T: expected {N} rows to match q, got {Ta.shape[0]}")
        Ra = _as_rotations(R, N)
        rng = np.vstack([lim.cart_travel, lim.joint_plate_range])
        ok = np.all((qa >= rng[:, 0]) & (qa <= rng[:, 1]), axis=1)
        T_h, R_h = self.home
        home_signs = self.aspect_signs(T_h, R_h, self.q_home)
        # the criteria in order of cost, each on the poses still in
        for check in ("ball", "aspect", "amplification", "joint plates"):
            idx = np.flatnonzero(ok)
            if idx.size == 0:
                break
            if check == "ball":
                ang = self.ball_joint_angles(Ta[idx], Ra[idx], qa[idx]).reshape(-1, 12)
                good = np.all(ang <= lim.ball_joint_angle_max, axis=1)
            elif check == "aspect":
                good = np.all(self.aspect_signs(Ta[idx], Ra[idx], qa[idx]).reshape(-1, 3) == home_signs, axis=1)
            elif check == "amplification":
                amp = self.error_amplification(Ta[idx], Ra[idx], qa[idx]).reshape(-1, 2)
                good = np.all(amp <= lim.error_amplification_max, axis=1)
            else:
                good = self.joint_plate_amplification(Ta[idx], Ra[idx], qa[idx]).reshape(-1) <= lim.joint_plate_amplification_max
            ok[idx] = good
        return bool(ok[0]) if single else ok

    def _reach_bounds(self) -> tuple[list[np.ndarray], list[float]]:
        """Per link: the cart's travel segment ``A0_i + [q_min, q_max] v_i`` and the largest
        distance ``L_ij + |offset of A_ij from the guideway line|`` of ``B_ij`` from it."""
        lim = self._require_limits("workspace")
        segments, reach = [], []
        for arm in range(3):
            A0, v = _get(self._p, f"A0_{arm + 1}"), _get(self._p, f"v{arm + 1}")
            seg = np.array([A0 + lim.cart_travel[arm, k] * v for k in range(2)])
            for n in F1_LINKS[arm]:
                r = _get(self._p, f"L_{n}")
                if arm > 0:
                    r += np.linalg.norm(_get(self._p, f"Abj_{n}"))
                if arm == 2:
                    r += np.linalg.norm(_get(self._p, "r3"))
                segments.append(seg)
                reach.append(float(r))
        return segments, reach

    @cached_property
    def _arm1_mapped(self) -> _Mapped:
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        return _Mapped(ca.Function("f1_ik_arm1", [T, R], list(self._arm1_closed_form(T, R)), ["T", "R_T"], ["q1", "disc1"]))

    @cached_property
    def _reach_mapped(self) -> _Mapped:
        segments, reach = self._reach_bounds()
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        B = ca.horzcat(*[self.link_points(self._p_dm, ca.DM.zeros(6), T, R, a)[1] for a in range(3)])
        margins = []
        for j, (seg, r) in enumerate(zip(segments, reach)):
            a, d = ca.DM(seg[0]), ca.DM(seg[1] - seg[0])
            t = ca.fmin(ca.fmax(ca.dot(B[:, j] - a, d) / ca.dot(d, d), 0), 1)
            margins.append(r - ca.norm_2(B[:, j] - a - t * d))
        return _Mapped(ca.Function("f1_reach_margin", [T, R], [ca.vertcat(*margins)], ["T", "R_T"], ["margin"]))

    def _position_box(self) -> tuple[np.ndarray, np.ndarray]:
        """A box containing every TCP position whose joints B_ij are within reach."""
        segments, reach = self._reach_bounds()
        lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
        for j, (seg, r) in enumerate(zip(segments, reach)):
            n = [n for arm in F1_LINKS for n in arm][j]
            grow = r + np.linalg.norm(_get(self._p, f"B0_{n}"))
            lo = np.maximum(lo, seg.min(axis=0) - grow)
            hi = np.minimum(hi, seg.max(axis=0) + grow)
        return lo, hi

    def workspace_grid(
        self,
        step_m: float = 0.25,
        step_deg: float = 10.0,
        reorientation_deg: np.typing.ArrayLike | None = None,
        return_q: bool = False,
    ) -> tuple[np.ndarray, ...]:
        """Poses of a regular 6-D grid inside the workspace (Dressler (2012), ch. 5.5).

        Positions ``T_home + step_m * (i, j, k)`` inside a box that bounds every reachable
        position; orientations ``Rz(c) Ry(b) Rx(a) R_home`` (rotations about the world axes
        from the home orientation) with ``a, b, c`` multiples of ``step_deg`` within the
        reorientation range. A pose is kept when the IK converges (default start), the
        pose is in the workspace (:meth:`in_workspace`: limits, ball joints, aspect of the
        home pose, margins to the singularities) and it is the nominal FK solution of its
        actuator values (the FK from the default start returns it within
        :data:`GRID_FK_TOLERANCE`; this removes 5 of 1251 F1 poses: their path from home
        passes close to a singularity, and the actuator path leads to another assembly
        mode of the same aspect or folds on the way). Two exact pre-filters skip hopeless candidates before Newton: each
        ``B_ij`` within ``L_ij`` plus the joint-plate offset of its cart's travel segment,
        and arm 1's closed-form ``q1`` within travel.

        Parameters
        ----------
        step_m : float, optional
            Position spacing [m].
        step_deg : float, optional
            Orientation spacing [deg].
        reorientation_deg : array_like, shape (3,), optional
            Largest rotation about x, y, z [deg]; default ``limits.reorientation_range``.
        return_q : bool, optional
            Also return the actuator values.

        Returns
        -------
        T : numpy.ndarray, shape (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (N, 3, 3)
            Plate orientations.
        q : numpy.ndarray, shape (N, 6)
            Only with ``return_q``: actuator values [m, rad].

        Raises
        ------
        InputError
            Non-positive steps, a bad range, or the model has no limits.
        """
        lim = self._require_limits("workspace_grid")
        if not (isinstance(step_m, (int, float)) and step_m > 0 and math.isfinite(step_m)):
            raise InputError(f"step_m: expected a positive spacing in m, got {step_m!r}")
        if not (isinstance(step_deg, (int, float)) and step_deg > 0 and math.isfinite(step_deg)):
            raise InputError(f"step_deg: expected a positive spacing in deg, got {step_deg!r}")
        if reorientation_deg is None:
            rng = np.degrees(lim.reorientation_range)
        else:
            rng = np.asarray(reorientation_deg, dtype=float)
            if rng.shape != (3,) or not np.all(np.isfinite(rng)) or np.any(rng < 0) or np.any(rng >= 90):
                raise InputError(f"reorientation_deg: expected three angles in [0, 90) deg, got {reorientation_deg!r}")
        T_h, R_h = self.home
        lo, hi = self._position_box()
        axes = [
            T_h[k] + step_m * np.arange(np.ceil((lo[k] - T_h[k]) / step_m), np.floor((hi[k] - T_h[k]) / step_m) + 1)
            for k in range(3)
        ]
        P = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        angs = [np.radians(step_deg * np.arange(-np.floor(r / step_deg + 1e-9), np.floor(r / step_deg + 1e-9) + 1)) for r in rng]
        O = np.stack(np.meshgrid(*angs, indexing="ij"), axis=-1).reshape(-1, 3)
        Rs = np.array([np.asarray(ca.DM(ca.mtimes([_rot_z(c), _rot_y(b), _rot_x(a)]))) @ R_h for a, b, c in O])
        T = np.repeat(P, len(Rs), axis=0)
        R = np.tile(Rs, (len(P), 1, 1))
        # exact pre-filters: every B_ij within reach of its cart's travel segment, and arm 1
        # (closed form) reaching the pose within its travel
        Rc = self._R_cols(R)
        (margin,) = self._reach_mapped(T.shape[0], T.T, Rc)
        keep = np.all(margin >= 0, axis=0)
        T, R = T[keep], R[keep]
        q1, disc = self._arm1_mapped(T.shape[0], T.T, self._R_cols(R))
        keep = (disc[0] >= 0) & (q1[0] >= lim.cart_travel[0, 0]) & (q1[0] <= lim.cart_travel[0, 1])
        T, R = T[keep], R[keep]
        if T.shape[0] == 0:
            empty = (np.zeros((0, 3)), np.zeros((0, 3, 3)))
            return empty + (np.zeros((0, 6)),) if return_q else empty
        Rc = self._R_cols(R)
        q0, _ = self._ik_start_mapped(T.shape[0], T.T, Rc)
        q, _, _, ok, _ = self._run_ik(IK_MAX_ITER, T.T, Rc, q0)
        T, R, q = T[ok], R[ok], q[:, ok].T
        if T.shape[0]:
            keep = self.in_workspace(T, R, q)
            T, R, q = T[keep], R[keep], q[keep]
        if T.shape[0]:
            # the pose must be the nominal FK solution of its actuator values (the mode the
            # robot reaches from home): the FK from the default start returns it
            T0, R0 = self._fk_start_mapped(T.shape[0], q.T)
            Tf, Rf, _, _, ok = self._run_fk(FK_MAX_ITER, q.T, T0, R0)
            Rf = self._R_from_cols(Rf, T.shape[0])
            ok &= np.linalg.norm(Tf.T - T, axis=1) <= GRID_FK_TOLERANCE
            ok &= np.abs(Rf - R).reshape(-1, 9).max(axis=1) <= GRID_FK_TOLERANCE
            T, R, q = T[ok], R[ok], q[ok]
        return (T, R, q) if return_q else (T, R)



# ------------------------------------------------------------------ parameter file
class _Fields:
    """Field access with messages naming the file and the field."""

    def __init__(self, data: Mapping[str, Any], origin: str, prefix: str = "") -> None:
        self.data, self.origin, self.prefix = data, origin, prefix

    def fail(self, key: str, expected: str, got: Any = None) -> ParameterError:
        what = "" if got is None else f", got {got!r}"
        return ParameterError(f"{self.origin}: field '{self.prefix}{key}': expected {expected}{what}")

    def keys(self, allowed: set[str]) -> None:
        unknown = sorted(set(self.data) - allowed)
        if unknown:
            raise ParameterError(
                f"{self.origin}: unknown field '{self.prefix}{unknown[0]}' (allowed: {', '.join(sorted(allowed))})"
            )

    def table(self, key: str) -> "_Fields":
        if key not in self.data:
            raise ParameterError(f"{self.origin}: missing table '[{self.prefix}{key}]'")
        if not isinstance(self.data[key], Mapping):
            raise self.fail(key, "a table", self.data[key])
        return _Fields(self.data[key], self.origin, f"{self.prefix}{key}.")

    def string(self, key: str, default: str | None = None) -> str:
        if key not in self.data:
            if default is None:
                raise ParameterError(f"{self.origin}: missing field '{self.prefix}{key}'")
            return default
        if not isinstance(self.data[key], str):
            raise self.fail(key, "a string", self.data[key])
        return self.data[key]

    def array(self, key: str, shape: tuple[int, ...]) -> np.ndarray:
        if key not in self.data:
            raise ParameterError(f"{self.origin}: missing field '{self.prefix}{key}'")
        value = self.data[key]
        try:
            arr = np.array(value, dtype=float)
        except (TypeError, ValueError):
            raise self.fail(key, f"an array of numbers of shape {shape}", value) from None
        if arr.shape != shape or not np.all(np.isfinite(arr)):
            raise self.fail(key, f"finite numbers of shape {shape}", value)
        return arr

    def number(self, key: str) -> float:
        if key not in self.data:
            raise ParameterError(f"{self.origin}: missing field '{self.prefix}{key}'")
        value = self.data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(key, "a finite number", value)
        return float(value)

    def vectors(self, key: str, names: tuple[str, ...], size: int) -> dict[str, np.ndarray]:
        t = self.table(key)
        t.keys(set(names))
        return {n: t.array(n, (size,)) for n in names}


def _f1_from_mapping(data: Mapping[str, Any], origin: str) -> F1Closure:
    f = _Fields(data, origin)
    f.keys({"name", "description", "frame", "length_unit", "kinematics", "home", "limits"})
    unit = f.string("length_unit")
    if unit not in ("mm", "m"):
        raise f.fail("length_unit", "'mm' or 'm'", unit)
    s = 1e-3 if unit == "mm" else 1.0
    k = f.table("kinematics")
    k.keys({"source", "links", "L", "A0", "v", "q1u2", "q1u3", "r3", "q2u3", "Abj", "B0"})
    all_links = tuple(n for arm in F1_LINKS for n in arm)
    if "links" in k.data and list(k.data["links"]) != list(all_links):
        raise k.fail("links", f"{list(all_links)}", k.data["links"])
    L = k.array("L", (6,))
    if np.any(L <= 0):
        raise k.fail("L", "positive link lengths", L.tolist())
    A0 = k.vectors("A0", ("arm1", "arm2", "arm3"), 3)
    v = k.vectors("v", ("arm1", "arm2", "arm3"), 3)
    for arm, vv in v.items():
        if not 0.5 < np.linalg.norm(vv) < 2.0:
            raise ParameterError(
                f"{origin}: field 'kinematics.v.{arm}': expected a guideway direction of norm about 1 "
                f"(0.5 < |v| < 2), got {vv.tolist()}"
            )
    quats = {}
    for name in ("q1u2", "q1u3", "q2u3"):
        qv = k.array(name, (4,))
        nrm = np.linalg.norm(qv)
        if not 0.5 < nrm < 2.0:
            raise k.fail(name, "a quaternion (w, x, y, z) of norm about 1 (0.5 < |q| < 2)", qv.tolist())
        quats[name] = qv / nrm  # printed values are not unit: normalised at load
    r3 = k.array("r3", (3,))
    Abj = k.vectors("Abj", ("2a", "2b", "3a", "3b", "3c"), 3)
    B0 = k.vectors("B0", all_links, 3)
    Ld = dict(zip(all_links, L))
    values = {
        "L_1": Ld["1"] * s, "A0_1": A0["arm1"] * s, "v1": v["arm1"], "B0_1": B0["1"] * s,
        "A0_2": A0["arm2"] * s, "v2": v["arm2"], "q1u2": quats["q1u2"],
        "A0_3": A0["arm3"] * s, "v3": v["arm3"], "q1u3": quats["q1u3"], "r3": r3 * s, "q2u3": quats["q2u3"],
    }
    for n in all_links[1:]:
        values[f"L_{n}"] = Ld[n] * s
        values[f"Abj_{n}"] = Abj[n] * s
        values[f"B0_{n}"] = B0[n] * s
    p = np.zeros(_N_PARAMETERS)
    for name, (i, n) in _OFFSET.items():
        p[i:i + n] = values[name]
    h = f.table("home")
    h.keys({"source", "cart_positions", "joint_plate_angles_deg"})
    q_home = np.concatenate([h.array("cart_positions", (3,)) * s, np.radians(h.array("joint_plate_angles_deg", (3,)))])
    lt = f.table("limits")
    lt.keys({"source", "cart_travel", "joint_plate_angles_deg", "ball_joint_angle_max_deg", "reorientation_range_deg",
             "position_error_amplification_max", "orientation_error_amplification_max_deg_per_mm",
             "joint_plate_amplification_max"})
    travel = lt.array("cart_travel", (3, 2)) * s
    plate = np.radians(lt.array("joint_plate_angles_deg", (3, 2)))
    for key, arr in (("cart_travel", travel), ("joint_plate_angles_deg", plate)):
        if np.any(arr[:, 0] >= arr[:, 1]):
            raise lt.fail(key, "rows (min, max) with min < max", lt.data[key])
    ball = lt.number("ball_joint_angle_max_deg")
    if not 0 < ball < 90:
        raise lt.fail("ball_joint_angle_max_deg", "an angle in (0, 90) degrees", ball)
    reo = lt.array("reorientation_range_deg", (3,))
    if np.any(reo < 0) or np.any(reo >= 90):
        raise lt.fail("reorientation_range_deg", "three angles in [0, 90) degrees", reo.tolist())
    amp = np.array([lt.number("position_error_amplification_max"), lt.number("orientation_error_amplification_max_deg_per_mm")])
    if np.any(amp <= 0):
        raise lt.fail("position_error_amplification_max" if amp[0] <= 0 else "orientation_error_amplification_max_deg_per_mm",
                      "a positive number", float(amp[0] if amp[0] <= 0 else amp[1]))
    amp[1] = math.radians(amp[1]) * 1e3  # deg/mm -> rad/m
    plate_amp = lt.number("joint_plate_amplification_max")
    if plate_amp <= 0:
        raise lt.fail("joint_plate_amplification_max", "a positive number", plate_amp)
    rng = np.vstack([travel, plate])
    if np.any(q_home < rng[:, 0]) or np.any(q_home > rng[:, 1]):
        raise ParameterError(f"{origin}: table '[home]': the home actuator values lie outside the limits of '[limits]'")
    limits = F1Limits(cart_travel=travel, joint_plate_range=plate, ball_joint_angle_max=math.radians(ball),
                      reorientation_range=np.radians(reo), error_amplification_max=amp,
                      joint_plate_amplification_max=plate_amp, source=lt.string("source", default=""))
    return F1Closure(p, q_home, limits, name=f.string("name"), source=k.string("source", default=""))


def load_f1(name_or_path: str | Path = "F1") -> F1Closure:
    """Load and validate an F1 parameter file (shipped name ``"F1"`` or a path).

    The shipped :file:`F1.toml` holds Dressler (2012), Table 5.5 in mm as printed
    (``length_unit = "mm"``); lengths are converted to metres and the printed, non-unit
    quaternions normalised at load. ``v`` is kept as printed (``|v| = 0.99``, a
    gear-ratio correction).

    Parameters
    ----------
    name_or_path : str or pathlib.Path, optional
        ``"F1"`` or the path of a TOML file in the same format.

    Returns
    -------
    F1Closure
        The model with its home pose and limits.

    Raises
    ------
    ParameterError
        Unknown name, unreadable file, TOML syntax error, or an invalid field (the
        message names the file and the field).
    """
    text_name = str(name_or_path)
    if isinstance(name_or_path, str) and text_name == "F1":
        resource = resources.files(_DATA_PACKAGE) / "data" / "F1.toml"
        origin = "F1.toml (shipped)"
        data = read_toml(Path(str(resource)), ParameterError, "F1 parameter file", origin, resource.read_text(encoding="utf-8"))
    else:
        path = Path(name_or_path)
        if path.suffix != ".toml" and not path.exists():
            raise ParameterError(f"unknown F1 parameter set {text_name!r}: not 'F1' (shipped) and no such file")
        origin = str(path)
        data = read_toml(path, ParameterError, "F1 parameter file")
    return _f1_from_mapping(data, origin)
