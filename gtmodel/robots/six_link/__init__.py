"""The six-link kinematic error model of the Gantry-Tau, Dressler (2012), eqs. 4.14-4.15.

Every one of the six links (arm 1: link ``1``; arm 2: ``2a, 2b``; arm 3: ``3a, 3b, 3c``)
has its own length ``L_ij``, cart-side joint point ``A0_ij`` at ``q_i = 0``, guideway
direction ``v_ij`` (or one ``v_i`` per arm) and plate-side joint point ``B0_ij`` in the
plate frame (Dressler (2012), eq. 4.14)::

    L_ij^2 = || A_ij(q_i) - B_ij(T, R_T) ||^2,   A_ij = A0_ij + q_i v_ij,
                                                 B_ij = T + R_T B0_ij

With imperfect parallelograms the plate orientation ``R_T`` is no longer constant: the six
closure equations determine the six pose unknowns ``(T, R_T)``.

Inverse kinematics stays closed form per link (a quadratic in ``q_i``, one root sign per
arm: the IK configuration, as for the 3-link model). Forward kinematics is Newton's
method on the minimal pose ``X = (T, alpha, beta, gamma)`` (Dressler (2012), eq. 4.15)::

    X_{k+1} = X_k + (d f_ik / dX)^-1 (q - f_ik(X_k))

where ``f_ik(X)`` stacks the six per-link IK values ``q_ij`` and ``q`` repeats the cart
position of arm ``i`` for each of its links. The Jacobian comes from CasADi's automatic
differentiation of the same IK expression.

Orientation parametrisation
---------------------------
ZYZ Euler angles have a gimbal lock at ``beta = 0`` (and ``pi``). They are therefore taken
relative to a reference: ``R_T = R_ref Rz(alpha) Ry(beta) Rz(gamma)`` with
``R_ref = R0 Ry(-pi/2)``, where ``R0`` is the model's nominal plate orientation. At the
nominal orientation ``X = (T, 0, pi/2, 0)``, as far from the lock as possible, for any
``R0`` (identity included). For the D1 the absolute ZYZ angles of ``R0`` are
(85.1, 100.7, -88.5) deg, so the absolute angles would also be safe there; the reference
keeps the method safe for every parameter set. Results are reported as rotation matrices;
absolute ZYZ angles via :func:`gtmodel.robots.closure.rotation_to_zyz`.

Nominal orientation ``R0``
--------------------------
``B0_ij`` is given in the plate frame, ``A0_ij`` and ``v_ij`` in the base (tracker)
frame. In a parallelogram cluster ``A0_ij - A0_ik = R_T (B0_ij - B0_ik)``, so the plate
orientation of the nominal assembly is the rotation that best maps the within-arm
differences of ``B0`` onto those of ``A0`` (:func:`estimate_nominal_orientation`,
orthogonal Procrustes / Kabsch). The model carries it as ``R0``: it is the start of the
FK iteration (with the start position from the closed-form 3-link trilateration of the
links ``1, 2a, 3a`` with ``As_i = A0_i1 - R0 B0_i1``) and the default orientation of the
IK. Moving the model into another frame (:meth:`SixLinkClosure.transformed`,
``x' = R x + t``) rotates and translates ``A0``, rotates ``v``, leaves ``B0`` unchanged
(plate frame) and turns the nominal orientation into ``R R0``.
"""


from gtmodel.robots.six_link.io import load_six_link
from gtmodel.robots.six_link.layout import (
    FK_MAX_ITER,
    FK_TOLERANCE,
    FK_UNROLLED_ITER,
    ROTATION_TOLERANCE,
    SIX_LINKS,
    SixLinkFKResult,
    estimate_nominal_orientation,
)
from gtmodel.robots.six_link.model import SixLinkClosure

__all__ = [
    "SixLinkClosure",
    "SixLinkFKResult",
    "estimate_nominal_orientation",
    "load_six_link",
    "SIX_LINKS",
    "FK_TOLERANCE",
    "FK_MAX_ITER",
    "FK_UNROLLED_ITER",
    "ROTATION_TOLERANCE",
]
