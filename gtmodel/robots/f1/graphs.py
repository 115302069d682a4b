"""Symbolic graphs of the F1 model: closure residuals, Newton steps, unrolled IK/FK, starts.

Every numeric method of :class:`~gtmodel.robots.f1.F1Closure` and the generated C code
evaluate these CasADi graphs (Dressler (2012), eqs. 4.20-4.33); :meth:`F1Graphs.graphs`
publishes the ones the code generator and solvers use.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import positive_int
from gtmodel._geometry import rotation_log, rotation_vector_to_rotation
from gtmodel.robots.f1.layout import (
    F1_LINKS,
    FK_MAX_ITER,
    FK_TOLERANCE,
    IK_MAX_ITER,
    IK_TOLERANCE,
    START_NEWTON_STEPS,
    START_SUBSTEPS,
    _get,
)
from gtmodel.robots.kinematic_expressions import fk_expression, ik_expression

__all__ = ["F1Graphs"]


class F1Graphs:
    """The CasADi graphs of :class:`~gtmodel.robots.f1.F1Closure` (a mixin of it)."""

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
        w = rotation_log(ca.mtimes(R, ca.DM(R_h).T))
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
        n = positive_int(max_iter, "max_iter")
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
        n = positive_int(max_iter, "max_iter")
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
    # -------------------------------------------------------------- the public graph interface
    @cached_property
    def arm1_function(self) -> ca.Function:
        """CasADi Function ``ik_arm1(T[3], R_T[3x3]) -> (q1, disc1)``: arm 1 in closed form.

        Eq. 4.20, the ``+`` root (cart joint above the plate joint along ``v1``); ``q1`` [m],
        ``disc1`` [m^2] the discriminant, negative where arm 1 cannot reach the pose.

        Returns
        -------
        casadi.Function
        """
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R_T", 3, 3)
        return ca.Function("f1_ik_arm1", [T, R], list(self._arm1_closed_form(T, R)), ["T", "R_T"], ["q1", "disc1"])

    @cached_property
    def ik_step_function(self) -> ca.Function:
        """CasADi Function ``ik_step(x[5], T[3], R[3x3]) -> (x_next[5], residual)``: one IK Newton step.

        One Newton step of arms 2 and 3 at once on ``e = L^2 - ||B - A(Q)||^2``
        (Dressler (2012), eqs. 4.27-4.29), the iterate packed as ``x = (q2, q4, q3, q5,
        q6)`` [m, rad]; ``residual = max |e|`` [m^2] at ``x`` (before the step). Arm 1 is
        in closed form (:attr:`arm1_function`). :meth:`ik` runs exactly these steps.

        Returns
        -------
        casadi.Function
        """
        step2, step3 = self._ik_steps
        x, T, R = ca.SX.sym("x", 5), ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
        x2n, e2 = step2(x[0:2], T, R)
        x3n, e3 = step3(x[2:5], T, R)
        return ca.Function(
            "f1_ik_step", [x, T, R], [ca.vertcat(x2n, x3n), ca.mmax(ca.fabs(ca.vertcat(e2, e3)))],
            ["x", "T", "R"], ["x_next", "residual"],
        )

    @cached_property
    def fk_step_function(self) -> ca.Function:
        """CasADi Function ``fk_step(x[12], q[6]) -> (x_next[12], residual)``: one FK Newton step.

        One Newton step on the link lengths (Dressler (2012), eqs. 4.30-4.31) with the
        multiplicative orientation update; the iterate packed as ``x = (T [m], vec(R_T))``
        (``R_T`` column-major); ``residual = max | ||B - A|| - L |`` [m] at ``x`` (before the
        step). :meth:`fk` runs exactly these steps.

        Returns
        -------
        casadi.Function
        """
        x, q = ca.SX.sym("x", 12), ca.SX.sym("q", 6)
        T_n, R_n, e = self._fk_step(x[:3], ca.reshape(x[3:], 3, 3), q)
        return ca.Function(
            "f1_fk_step", [x, q], [ca.vertcat(T_n, ca.vec(R_n)), ca.mmax(ca.fabs(e))], ["x", "q"], ["x_next", "residual"]
        )

    def graphs(self) -> dict[str, ca.Function]:
        """The CasADi Functions of the model used by solvers and the code generator, by name.

        Parameters are embedded as constants. Besides the closure Functions of
        :meth:`ClosureModel.graphs <gtmodel.robots.closure.ClosureModel.graphs>`:

        ``"ik_start"``
            :attr:`ik_start_function`: ``(T[3] [m], R_T[3x3]) -> (q0[6] [m, rad], disc1 [m^2])``.
        ``"ik_arm1"``
            :attr:`arm1_function`: ``(T, R_T) -> (q1 [m], disc1 [m^2])``.
        ``"ik_step"``
            :attr:`ik_step_function`: ``(x[5], T, R) -> (x_next[5], residual [m^2])``,
            ``x = (q2, q4, q3, q5, q6)``.
        ``"fk_start"``
            :attr:`fk_start_function`: ``q[6] -> (T0[3] [m], R0[3x3])``.
        ``"fk_step"``
            :attr:`fk_step_function`: ``(x[12], q[6]) -> (x_next[12], residual [m])``,
            ``x = (T, vec(R_T))``.
        ``"jacobian"``
            :attr:`jacobian_function`: ``(T, R_T, q) -> (J_X[6x6], J_q[6x6])``.

        Returns
        -------
        dict of str to casadi.Function
        """
        return {
            **super().graphs(),  # type: ignore[misc]
            "ik_start": self.ik_start_function,
            "ik_arm1": self.arm1_function,
            "ik_step": self.ik_step_function,
            "fk_start": self.fk_start_function,
            "fk_step": self.fk_step_function,
            "jacobian": self.jacobian_function,
        }
