"""Kinematic calibration from closure equations as least-squares NLPs.

The package, one module per job: :mod:`~gtmodel.calibration.kinematic.selection` (free,
fixed and tied parameters), :mod:`~gtmodel.calibration.kinematic.alignment` (Kabsch frame
alignment), :mod:`~gtmodel.calibration.kinematic.data` (measurement checks),
:mod:`~gtmodel.calibration.kinematic.residuals` (CasADi residual/Jacobian graphs and
IPOPT NLPs of a group of arms), :mod:`~gtmodel.calibration.kinematic.lsq` (MINPACK
solve and Gauss-Newton polishing of a group), :mod:`~gtmodel.calibration.kinematic.problem`
(:class:`CalibrationProblem`), :mod:`~gtmodel.calibration.kinematic.start` (what a solve
does before solving: caches per data set, the frame alignment guarded by the cost),
:mod:`~gtmodel.calibration.kinematic.result` (results) and
:mod:`~gtmodel.calibration.kinematic.shortcuts` (:func:`calibrate`,
:func:`analyze_identifiability` with a cache of problems).

The cost is the closure-equation cost of Dressler (2012), eqs. 5.1-5.2,

    V(s) = sum_k w_k sum_(links j) ( ||A_j(q_k, s) - B_j(T_k, R_k, s)||^2 - L_j(s)^2 )^2,

always real-valued (unlike FK/IK residuals), with optional measurement weights ``w_k``
(the residual of pose k is multiplied by ``sqrt(w_k)``). The steps:

1. **Frame alignment** (Dressler (2012), eqs. 5.3-5.4). Parameters are identified in the
   measurement frame, so the start model is moved there first: the rigid transform
   ``(R, t)`` that best maps its FK positions onto the measured TCP positions (orthogonal
   Procrustes/Kabsch by SVD, :func:`fit_rigid_transform`) is applied with
   ``model.transformed(R, t)``. The alignment only sets the start point, so it is guarded
   by the cost: of no transform, the centroid translation and the rigid fit, the one with
   the lowest ``V`` is used (on a small pose cloud with a poor nominal model the fitted
   rotation can be far off). Collinear FK positions give a translation only.
2. **Groups of arms** (Dressler (2012), ch. 5: arms are independent). Arms whose closure
   equations share a free parameter (read with ``model.arm_parameter_indices``, e.g. the
   common ``v`` of the ideal 3-link model, or joined by a tie) form one NLP; the others are
   solved separately. The modified 3-link model (21 parameters) gives three 7-parameter
   problems, the ideal one a single 15-parameter problem.
3. **Parameters**: free, fixed or tied (:class:`ParameterSelection`). Quaternion parameters
   (``model.quaternion_indices()``) are never moved as 4-vectors: the variables are a
   rotation vector ``r`` (3 per quaternion, rad) with ``quat = quat0 * exp(r / 2)``
   (a local parametrisation about the anchor ``quat0``), for both solver families; the
   anchor is re-set to the (normalised) solution after each solve, so the reported
   quaternions have unit norm (the improvement asked for in Dressler (2012), ch. 5.4,
   where unconstrained 4-vectors drifted to norms 0.974-1.003).
4. **Residuals and exact Jacobian** come from one CasADi graph per group: the closure
   residuals of one pose (``model.closure_function``) with their Jacobian with respect to
   the group's variables, mapped over blocks of :data:`CHUNK_SIZE` poses and expanded to
   one SX graph per block, then mapped over the blocks (poses padded with zero weight).
   The graph depends neither on the number of poses nor on the data: re-solving with
   other data or another start re-uses it. Evaluation goes through ``Function.buffer`` on
   NumPy arrays (no conversion to DM, which alone cost ~1 ms per call for 779 poses).
5. **Checks before solving**: shapes and finite data, at least as many residuals as free
   variables per group, and full rank of the Jacobian at the start (a rank-deficient
   problem is a :class:`~gtmodel.errors.ModelError` naming the non-identifiable
   parameters and what they depend on, with the report attached, not a fit).

Measured (``python benchmarks/bench_calibration.py``; CasADi 3.8.2, 2 cores shared with
other jobs, load 3-4, so ranges over five runs; one 7-parameter arm group of the L1, 779
poses, residuals + Jacobian per evaluation):

=================================================  ============  ===========
variant                                             build [s]     eval [ms]
=================================================  ============  ===========
``map`` of the per-pose Function (serial)           0.001         0.26-0.5
one SX graph over all poses (Python loop)           0.15-0.35     0.1-0.23
``map(N).expand()`` (one SX graph per N)            0.013-0.03    0.1-0.23
blocks of 64 poses expanded, then mapped (used)     0.002-0.006   0.1-0.23
=================================================  ============  ===========

The block variant builds once for any number of poses and evaluates at SX speed (the
same speed as one graph over all poses, 2-2.5x faster than the plain ``map``).

Solvers (``solver=``) on the L1 21-parameter problem (779 synthetic laser-tracker poses:
true = Table 5.1 modified model, start = the ideal model, noise 10 um; summed over the
three arm groups; same benchmark):

==============  ==========  ===========  ==========  ==============================
solver          iterations  solve [ms]   build [s]   optimum vs ``"lm"`` (relative)
==============  ==========  ===========  ==========  ==============================
``"lm"``        12          4.5-14       0.03-0.07   (reference)
``"trf"``       14          6.6-28       --          1e-13
``"ipopt"``     9           69-160       0.4-1.0     8e-12
``"ipopt-gn"``  19          76-160       0.01-0.04   7e-14
==============  ==========  ===========  ==========  ==============================

(``"lm"``/``"trf"`` iterations are Jacobian evaluations including the polishing step.)
``"lm"`` -- MINPACK's Levenberg-Marquardt (``lmder``) with the exact CasADi Jacobian,
called through :func:`scipy.optimize.leastsq` exactly as
``least_squares(method="lm", x_scale="jac")`` calls it (same iterates to the last bit,
without its per-evaluation wrappers), plus one Gauss-Newton polishing step (see
:data:`POLISH_STEPS`) -- is the default: fewest evaluations, least overhead. Each
evaluation is one call of the residual + Jacobian graph (the Jacobian MINPACK asks for
next at the same point is the cached one); the polishing step's column-pivoted QR
(LAPACK directly) also gives the rank, singular values and covariance of the report
(:func:`~gtmodel.calibration.identifiability.analyze_qr`), and the alignment and the
start rank check are cached per data set and start, so a repeated call does little
besides the solves. Whole ``calibrate`` call, L1, 779 poses (``bench_calibration.py
--json``, shared 2-core machine at load 4-9, medians of 15 interleaved runs): 4.7 ms
CPU (9 ms wall) against 15-23 ms CPU (33 ms wall) for SciPy's least_squares with its
2-point finite-difference Jacobian on the same residuals (all 21 parameters, one SX
graph of all poses through buffers, 89 residual evaluations): 3-5x. What remains of the
call (CPU, ms): 13 residual + Jacobian evaluations of 779 poses by the CasADi
interpreter 1.5, MINPACK's own work 0.7, the final residuals 0.2, polishing QR and
reports 0.8, data checks, parameters and result 0.5. Evaluating the blocks as compiled
C (:func:`gtmodel._compiler.compiled_function`, bit-identical) made the call 1.3x
faster but the peer, evaluated the same way, 2x faster (ratio 3.5x -> 2.2x), for
~3 s of the C compiler per graph: not used. The ratio moves with the machine's load:
the many small calls of the exact-Jacobian path suffer more from a busy CPU than the
peer's few long ones. IPOPT (exact Hessian
of V, or the Gauss-Newton Hessian ``2 J^T J``) reaches the same optimum with a different
method; it is kept as that independent check and for calibration problems that need
constraints, at ~10x the time here (its per-iteration overhead dominates).

Standard deviations: ``sigma^2 (J^T J)^-1`` restricted to the free variables, with
``sigma^2 = RSS / (m - n)`` per group (m residuals, n variables), propagated to the
parameters through the Jacobian of the parameter map (tied parameters get the
deviation of their source, quaternion components that of the 4-vector).
"""

from gtmodel.calibration.kinematic.alignment import COLLINEAR_TOLERANCE, align_model, fit_rigid_transform
from gtmodel.calibration.kinematic.shortcuts import PROBLEM_CACHE_SIZE, analyze_identifiability, calibrate
from gtmodel.calibration.kinematic.problem import (
    DEFAULT_SOLVER,
    LSQ_TOLERANCE,
    MAX_ITER,
    MAX_REANCHOR,
    POLISH_MAX_STEP,
    POLISH_STEPS,
    REANCHOR_ANGLE,
    SOLVERS,
    CalibrationProblem,
)
from gtmodel.calibration.kinematic.residuals import CHUNK_SIZE, IPOPT_TOLERANCE
from gtmodel.calibration.kinematic.result import CalibrationResult, GroupResult
from gtmodel.calibration.kinematic.selection import ParameterSelection
from gtmodel.calibration.kinematic.start import FK_CACHE_SIZE

__all__ = [
    "ParameterSelection",
    "CalibrationProblem",
    "CalibrationResult",
    "GroupResult",
    "calibrate",
    "analyze_identifiability",
    "fit_rigid_transform",
    "align_model",
    "SOLVERS",
    "DEFAULT_SOLVER",
    "MAX_ITER",
    "LSQ_TOLERANCE",
    "IPOPT_TOLERANCE",
    "CHUNK_SIZE",
    "REANCHOR_ANGLE",
    "MAX_REANCHOR",
    "COLLINEAR_TOLERANCE",
    "POLISH_STEPS",
    "FK_CACHE_SIZE",
    "PROBLEM_CACHE_SIZE",
    "POLISH_MAX_STEP",
]
