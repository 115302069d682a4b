"""Static stiffness of the 3-link (translational) Gantry-Tau model, in CasADi.

Dressler (2012), ch. 6.3 and 2.1 (spec section 4): for a parallel kinematic machine whose
links carry axial forces only, the Cartesian stiffness at the TCP is

    K_x(T) = sum_i k_i u_i u_i^T = U^T diag(k) U,                                   (1)

``u_i = (T - A_i) / |T - A_i|`` the unit link vector of arm ``i`` (rows of ``U``),
``A_i = As_i + q_i v_i`` its cart joint (eq. 4.9), and ``k_i`` the effective axial stiffness
of the arm. Since row ``i`` of the inverse Jacobian (eq. 6.5) is ``u_i^T / (u_i . v_i)``,
(1) is the familiar ``K_x = J^-T diag(k_i (u_i . v_i)^2) J^-1`` form.

Derivation of ``k_i`` (each arm a series chain)
------------------------------------------------
Arm ``i`` is a cluster of ``n_i`` parallel links (the 3-2-1 configuration: ``n = (1, 2, 3)``),
each link a tube of axial stiffness ``k_l = E A / L_i`` with a spherical joint of stiffness
``k_j`` (115 kN/mm) at each end, and the cart is held along its guideway by the actuator with
stiffness ``k_a`` (rigid across the guideway). Let ``f_i`` be the axial (tension-positive)
force of the arm, shared equally by its links (parallelogram clusters, rigid plate).

- The links and joints lengthen by ``dL_i = f_i (1/k_l + 2/k_j) / n_i``.
- The cart carries the component ``f_i (u_i . w_i)`` of the link force along the unit guideway
  direction ``w_i = v_i / |v_i|`` and moves by ``ds_i = f_i (u_i . w_i) / k_a`` along ``w_i``.
- To first order the distance between the cart joint and the TCP changes by
  ``u_i . (dT - ds_i w_i)``, so the TCP displacement along the link is
  ``u_i . dT = dL_i + ds_i (u_i . w_i) = c_i f_i`` with the arm compliance

      c_i = 1/k_i = (1/k_l + 2/k_j) / n_i + (u_i . w_i)^2 / k_a.                     (2)

  The actuator's share depends on the pose through the link angle to the guideway.

Statics of the plate: an external force ``F`` on the plate (gravity, a process force at the
TCP) is balanced by the arm forces, ``sum_i f_i u_i = U^T f = F``, so

    f = U^-T F,     u_i . dT = c_i f_i  =>  U dT = C U^-T F  =>  K_x dT = F,           (3)

with ``K_x = U^T C^-1 U``, i.e. (1). The plate's orientation is held by the parallelograms
(the translational model: no rotation compliance); gravity on the plate is
``F_g = -g (m_p + m_payload + sum_i m_a,i / 2) e_z``, the plate's share of ``G`` in eq. 6.7.
The geometric stiffness of the pre-loaded links (``f_i / L_i (I - u_i u_i^T)``, ~50 N/m for
100 N links) is neglected against ``K_x`` (~1e6 N/m).

:func:`closure_stiffness` is the general form for any closure model (the six-link geometry,
Dressler (2012), eq. 4.14): the link lengths are differentiated with respect to the plate's
position and rotation and the cart displacements, ``C^T diag(k_l) C`` plus the actuators is
assembled and the carts (and, for a force at the TCP, the plate rotation) are condensed out.
For the 3-link model it reproduces (1)-(2) exactly; for the six-link D1 the free plate
rotation makes the TCP 5-10 % softer.

Every expression is written once here in CasADi; :class:`GantryTau3Stiffness` wraps them in
:class:`casadi.Function` objects mapped over poses, and the elasto-geometric calibration
(:mod:`gtmodel.calibration.elasto_geometric`) builds its closure equations from the same
expressions. Stiffness values with their sources and assumptions are in the data file
``gtmodel/robots/data/stiffness.toml`` (:func:`load_stiffness`).

Modules: :mod:`.parameters` (stiffness values and their file), :mod:`.expressions` (the
equations in CasADi), :mod:`.gantry_tau3` (:class:`GantryTau3Stiffness`, workspace maps),
:mod:`.closure` (:func:`closure_stiffness` for any closure model). The colour map of a
workspace section is drawn by :func:`gtmodel.report.stiffness.plot_stiffness_map`.
"""

from gtmodel.robots.stiffness.parameters import MEASURED_D1_N_PER_UM, N_PER_UM, StiffnessParameters, load_stiffness
from gtmodel.robots.stiffness.expressions import (
    arm_compliance_expression,
    cartesian_stiffness_expression,
    deflection_expression,
    link_forces_expression,
    link_unit_vectors_expression,
)
from gtmodel.robots.stiffness.gantry_tau3 import GantryTau3Stiffness, StiffnessMap
from gtmodel.robots.stiffness.closure import ClosureStiffness, closure_stiffness

__all__ = [
    "StiffnessParameters",
    "StiffnessMap",
    "GantryTau3Stiffness",
    "load_stiffness",
    "link_unit_vectors_expression",
    "arm_compliance_expression",
    "cartesian_stiffness_expression",
    "link_forces_expression",
    "deflection_expression",
    "ClosureStiffness",
    "closure_stiffness",
    "MEASURED_D1_N_PER_UM",
    "N_PER_UM",
]
