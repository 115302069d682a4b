"""Limits and workspace of the F1 model, Dressler (2012), ch. 5.5.

Ball-joint angles, aspect signs, the margins to the singularities, the workspace test
and the 6-D workspace grid.
"""

from __future__ import annotations

import math
from functools import cached_property

import casadi as ca
import numpy as np

from gtmodel._arrays import as_rotations, as_rows
from gtmodel._geometry import rot_x, rot_y, rot_z
from gtmodel._docstrings import fill_doc
from gtmodel.errors import InputError
from gtmodel.robots.f1.layout import (
    POSE_DOCS,
    pose_rows,
    F1_LINKS,
    FK_MAX_ITER,
    GRID_FK_TOLERANCE,
    IK_MAX_ITER,
    ROTATION_TOLERANCE,
    F1Limits,
    _get,
)
from gtmodel.robots.mapped import MappedFunction
from gtmodel.robots.workspace import in_ranges

__all__ = ["F1Workspace"]


class F1Workspace:
    """Limits, singularity margins and workspace of :class:`~gtmodel.robots.f1.F1Closure` (a mixin of it)."""

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
    def _ball_mapped(self) -> MappedFunction:
        return MappedFunction(self._ball_axes)

    @fill_doc(**POSE_DOCS)
    def ball_joint_angles(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Angles of the links to their ball-joint axes [rad].

        The ball-joint axes are not in the source; they are taken as the link directions
        at the home pose, fixed in the body that carries the joint: cart 1, joint plate 2
        (``R1u2 Ry(q4)``), joint plate 3 (``R1u3 Ry(q5) R2u3 Rx(q6)``) on the actuator side,
        the end-effector plate (``R_T``) on the plate side. So every angle is 0 at home and
        the 45-deg limit (Dressler (2012), ch. 5.5) is a cone about that mounting.

        Parameters
        ----------
        {pose_args}

        Returns
        -------
        numpy.ndarray, shape (2, 6) or (N, 2, 6)
            Row 0: actuator-side joints, row 1: plate-side joints; columns links 1, 2a,
            2b, 3a, 3b, 3c.

        {pose_raises}
        """
        Ta, Rs, qa, single = pose_rows(T, R, q)
        N = Ta.shape[0]
        (ang,) = self._ball_mapped(Ta.T, self._R_cols(Rs), qa.T, n=N)
        ang = np.asarray(ang).reshape(2, N, 6).transpose(1, 0, 2)
        return ang[0] if single else ang

    def _require_limits(self, what: str) -> F1Limits:
        if self.limits is None:
            raise InputError(f"{what}: the model has no limits (load it with load_f1 or pass limits=F1Limits(...))")
        return self.limits

    @fill_doc(**POSE_DOCS)
    def aspect_signs(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Signs of the Jacobian determinants that separate assembly modes and IK branches.

        Parameters
        ----------
        {pose_args}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``sign det`` of ``J_X`` (:meth:`jacobians`; FK or type-II singularities where
            it is 0) and of the blocks of ``J_q`` of arms 2 (``q2, q4``) and 3 (``q3, q5,
            q6``) (IK, type-I singularities). Poses with the signs of the home pose lie
            in its aspect.

        {pose_raises}
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

    @fill_doc(**POSE_DOCS)
    def error_amplification(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Largest TCP errors per link-length error (distance to the FK singularities).

        With ``J`` the pose Jacobian ``J_X`` (:meth:`jacobians`, eq. 4.31), a link-length
        error ``dL`` moves the pose by ``J^-1 dL``; the 2-norms of the position and
        orientation rows of ``J^-1`` are the worst-case amplifications. They grow without
        bound at a type-II singularity.

        Parameters
        ----------
        {pose_args}

        Returns
        -------
        numpy.ndarray, shape (2,) or (N, 2)
            Position amplification [m/m] and orientation amplification [rad/m]
            (``inf`` at a singular Jacobian).

        {pose_raises}
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

    @fill_doc(**POSE_DOCS)
    def joint_plate_amplification(self, T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> np.ndarray:
        """Largest joint-plate rotation per plate rotation (distance to the IK singularities).

        From ``J_X (T_dot, w) + J_q q_dot = 0`` (:meth:`jacobians`): the 2-norm of
        ``d(q4, q5, q6)/dw = -(J_q^-1 J_X)[3:, 3:]``. It grows without bound at a type-I
        singularity, where the IK of arm 2 or 3 loses a solution (two branches meet).

        Parameters
        ----------
        {pose_args}

        Returns
        -------
        float or numpy.ndarray, shape (N,)
            [rad/rad]; ``inf`` at a singular ``J_q``.

        {pose_raises}
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
        qa, single = as_rows(q, "q", 6)
        N = qa.shape[0]
        Ta, _ = as_rows(T, "T", 3)
        if Ta.shape[0] != N:
            raise InputError(f"T: expected {N} rows to match q, got {Ta.shape[0]}")
        Ra = as_rotations(R, N, "R", ROTATION_TOLERANCE)
        ok = in_ranges(qa, np.vstack([lim.cart_travel, lim.joint_plate_range]))
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
    def _arm1_mapped(self) -> MappedFunction:
        return MappedFunction(self.arm1_function)

    @cached_property
    def _reach_mapped(self) -> MappedFunction:
        segments, reach = self._reach_bounds()
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        B = ca.horzcat(*[self.link_points(self._p_dm, ca.DM.zeros(6), T, R, a)[1] for a in range(3)])
        margins = []
        for j, (seg, r) in enumerate(zip(segments, reach)):
            a, d = ca.DM(seg[0]), ca.DM(seg[1] - seg[0])
            t = ca.fmin(ca.fmax(ca.dot(B[:, j] - a, d) / ca.dot(d, d), 0), 1)
            margins.append(r - ca.norm_2(B[:, j] - a - t * d))
        return MappedFunction(ca.Function("f1_reach_margin", [T, R], [ca.vertcat(*margins)], ["T", "R_T"], ["margin"]))

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
        Rs = np.array([np.asarray(ca.DM(ca.mtimes([rot_z(c), rot_y(b), rot_x(a)]))) @ R_h for a, b, c in O])
        T = np.repeat(P, len(Rs), axis=0)
        R = np.tile(Rs, (len(P), 1, 1))
        # exact pre-filters: every B_ij within reach of its cart's travel segment, and arm 1
        # (closed form) reaching the pose within its travel
        Rc = self._R_cols(R)
        (margin,) = self._reach_mapped(T.T, Rc, n=T.shape[0])
        keep = np.all(margin >= 0, axis=0)
        T, R = T[keep], R[keep]
        q1, disc = self._arm1_mapped(T.T, self._R_cols(R), n=T.shape[0])
        keep = (disc[0] >= 0) & (q1[0] >= lim.cart_travel[0, 0]) & (q1[0] <= lim.cart_travel[0, 1])
        T, R = T[keep], R[keep]
        if T.shape[0] == 0:
            empty = (np.zeros((0, 3)), np.zeros((0, 3, 3)))
            return empty + (np.zeros((0, 6)),) if return_q else empty
        Rc = self._R_cols(R)
        q0, _ = self._ik_start_mapped(T.T, Rc, n=T.shape[0])
        q, _, _, ok, _ = self._run_ik(IK_MAX_ITER, T.T, Rc, q0)
        T, R, q = T[ok], R[ok], q[:, ok].T
        if T.shape[0]:
            keep = self.in_workspace(T, R, q)
            T, R, q = T[keep], R[keep], q[keep]
        if T.shape[0]:
            # the pose must be the nominal FK solution of its actuator values (the mode the
            # robot reaches from home): the FK from the default start returns it
            T0, R0 = self._fk_start_mapped(q.T, n=T.shape[0])
            Tf, Rf, _, _, ok = self._run_fk(FK_MAX_ITER, q.T, T0, R0)
            Rf = self._R_from_cols(Rf, T.shape[0])
            ok &= np.linalg.norm(Tf.T - T, axis=1) <= GRID_FK_TOLERANCE
            ok &= np.abs(Rf - R).reshape(-1, 9).max(axis=1) <= GRID_FK_TOLERANCE
            T, R, q = T[ok], R[ok], q[ok]
        return (T, R, q) if return_q else (T, R)


