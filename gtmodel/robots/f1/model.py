"""The F1 model class: parameters, the closure graph (eqs. 4.19-4.24), frame changes.

:class:`F1Closure` joins the parameter interface of
:class:`~gtmodel.robots.closure.ClosureModel` with the graphs
(:mod:`~gtmodel.robots.f1.graphs`), the numeric kinematics
(:mod:`~gtmodel.robots.f1.solve`) and the workspace (:mod:`~gtmodel.robots.f1.workspace`).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rotations
from gtmodel._geometry import quaternion_to_rotation, rot_x, rot_y, rotation_to_quaternion
from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel
from gtmodel.robots.f1.graphs import F1Graphs
from gtmodel.robots.f1.layout import _N_PARAMETERS, _NAMES, _OFFSET, F1_LINKS, ROTATION_TOLERANCE, F1Limits, _get
from gtmodel.robots.f1.solve import F1Solvers
from gtmodel.robots.f1.workspace import F1Workspace
from gtmodel.robots.mapped import MappedFunction

__all__ = ["F1Closure"]


# ------------------------------------------------------------------ the model
class F1Closure(F1Graphs, F1Solvers, F1Workspace, ClosureModel):
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
        self._fk_cache: dict[int, MappedFunction] = {}
        self._ik_cache: dict[int, MappedFunction] = {}

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
        J2 = ca.mtimes(quaternion_to_rotation(_get(p, "q1u2")), rot_y(q[3]))
        R1u3, R2u3 = quaternion_to_rotation(_get(p, "q1u3")), quaternion_to_rotation(_get(p, "q2u3"))
        J3 = ca.mtimes([R1u3, rot_y(q[4]), R2u3, rot_x(q[5])])
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
                R1u3_Rq5 = ca.mtimes(quaternion_to_rotation(_get(p, "q1u3")), rot_y(q[4]))
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
        Rm = as_rotations(R, 1, "R", ROTATION_TOLERANCE)[0]
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