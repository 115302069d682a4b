"""The loop's controllers: tracking (feedforward + TV-LQR) and real-time MPC of any model.

A loop controller follows a reference motion (an optimal control result, a table) at the
loop period (4 ms by default) and is ONE CasADi Function ``control(t, x, u_last, w) ->
(u, w_next, ok)``, the loop step that :mod:`gtmodel.codegen.loop_step` turns into C and the
loop files of :mod:`gtmodel.problems` declare and check.

Modules by job:

* :mod:`~gtmodel.control.problem`: the :class:`TrackingProblem` both controllers build
  from (model, sampled reference, bounds, parameters, scales, weights, prediction step);
* :mod:`~gtmodel.control.reference`: the reference sampled at the loop period and the row
  read at time ``t`` (shared by both controllers);
* :mod:`~gtmodel.control.tracking`: the tracking controller (feedforward plus time-varying
  LQR along the reference, Riccati recursion);
* :mod:`~gtmodel.control.mpc`: the real-time nonlinear MPC (single shooting, SQP with a
  Gauss-Newton Hessian, generated solver inside the Function);
* :mod:`~gtmodel.control.mpc_constraints`: the MPC's state bounds and path constraints,
  soft (exact penalty) or hard;
* :mod:`~gtmodel.control.mpc_fatrop`: the MPC's horizon problem by multiple shooting in
  fatrop's stage order;
* :mod:`~gtmodel.control.bounds`: violations of declared bounds on a closed loop's plant,
  counted by the loop check.
* :mod:`~gtmodel.control.runtime`: the compiled robot runtime (RSI/EGM over UDP, built by
  :mod:`gtmodel.codegen.robot_runtime`) run as a child process, its cycle log and counts read.

The names below are imported on first use (:mod:`gtmodel._lazy`).

Lower layers only: modeling and the base modules.
"""

from gtmodel._lazy import lazy_exports

__all__ = [
    "INDEX_EPS",
    "PERIOD_EPS",
    "FLOAT_PERIOD_LIMIT",
    "MEASUREMENT_LIMIT",
    "MEMORY_LIMIT",
    "SampledReference",
    "hold_input",
    "sampled",
    "sample_reference",
    "period_index",
    "reference_scales",
    "plausible_range",
    "PREDICTION_METHODS",
    "TrackingProblem",
    "tracking_problem",
    "weight_matrix",
    "TrackingController",
    "tracking_controller",
    "dlqr",
    "riccati_gains",
    "saturate",
    "DEFAULT_PENALTY",
    "MPCConstraints",
    "problem_constraints",
    "MPC_METHODS",
    "MPC_SOLVERS",
    "QP_ROW",
    "MPCController",
    "HorizonSolution",
    "mpc_controller",
    "EXCESS_TOLERANCE",
    "BoundExcess",
    "bound_report",
]

# ``mpc_constraints`` (the function) is not exported here: the package attribute of that
# name is the submodule :mod:`gtmodel.control.mpc_constraints`.
__getattr__, __dir__ = lazy_exports(__name__, {
    "INDEX_EPS": "reference", "PERIOD_EPS": "reference", "FLOAT_PERIOD_LIMIT": "reference", "MEASUREMENT_LIMIT": "reference", "MEMORY_LIMIT": "reference", "SampledReference": "reference",
    "hold_input": "reference", "sampled": "reference", "sample_reference": "reference", "period_index": "reference",
    "reference_scales": "reference", "plausible_range": "reference",
    "PREDICTION_METHODS": "problem", "TrackingProblem": "problem", "tracking_problem": "problem", "weight_matrix": "problem",
    "TrackingController": "tracking", "tracking_controller": "tracking", "dlqr": "lqr", "riccati_gains": "lqr",
    "saturate": "tracking",
    "DEFAULT_PENALTY": "mpc_constraints", "MPCConstraints": "mpc_constraints", "problem_constraints": "mpc_constraints",
    "MPC_METHODS": "mpc", "MPC_SOLVERS": "mpc", "QP_ROW": "mpc", "MPCController": "mpc", "mpc_controller": "mpc",
    "HorizonSolution": "mpc_solve",
    "EXCESS_TOLERANCE": "bounds", "BoundExcess": "bounds", "bound_report": "bounds",
})
