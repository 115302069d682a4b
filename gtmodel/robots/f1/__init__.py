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

from gtmodel.robots.f1.io import load_f1
from gtmodel.robots.f1.layout import (
    F1_FIXED_FOR_IDENTIFIABILITY,
    F1_LINKS,
    FK_CONTINUATION_STEPS,
    FK_MAX_ITER,
    FK_TOLERANCE,
    GRID_FK_TOLERANCE,
    IK_MAX_ITER,
    IK_TOLERANCE,
    NEWTON_CHUNK,
    ROTATION_TOLERANCE,
    START_NEWTON_STEPS,
    START_SUBSTEPS,
    F1Limits,
)
from gtmodel.robots.f1.model import F1Closure

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
    "NEWTON_CHUNK",
]

