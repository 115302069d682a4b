"""Optimal motion on top of the modelling layer: point-to-point time/energy-optimal motion.

Point-to-point and path-constrained motion of the robots, paths, milling, exports, and the
``optimal_control`` declaration of a user's model (:mod:`~gtmodel.trajectory.model_ocp`). The
method objects (:class:`Collocation`, :class:`MultipleShooting`, :class:`SolverSettings`,
:class:`Refinement`) live beside the transcriptions in :mod:`gtmodel.modeling.ocp.methods`
and are re-exported here.

The names below are imported on first use (:mod:`gtmodel._lazy`): a problem that needs only
:mod:`gtmodel.trajectory.model_ocp` does not import the robot models and path planners.
"""

from gtmodel._lazy import lazy_exports

__all__ = [
    "SAMPLE_TIME",
    "PointToPoint",
    "PointToPointSolution",
    "build_optimization",
    "solve_point_to_point",
    "trapezoid_profile",
    "resolve_point_to_point",
    "point_to_point_function",
    "Path",
    "StraightLine",
    "Polyline",
    "SplinePath",
    "PathConstraints",
    "PathConstrainedProblem",
    "PathSolution",
    "solve_path_convex",
    "solve_path_collocation",
    "MillingProcess",
    "SpindleAngleResult",
    "optimise_spindle_angle",
    "Collocation",
    "MultipleShooting",
    "SolverSettings",
    "Refinement",
    "OptimalControl",
]

__getattr__, __dir__ = lazy_exports(__name__, {
    "SAMPLE_TIME": "point_to_point", "PointToPoint": "point_to_point", "PointToPointSolution": "point_to_point", "build_optimization": "point_to_point", "solve_point_to_point": "point_to_point", "trapezoid_profile": "point_to_point",
    "point_to_point_function": "point_to_point_resolve", "resolve_point_to_point": "point_to_point_resolve",
    "Path": "path", "Polyline": "path", "SplinePath": "path", "StraightLine": "path",
    "PathConstrainedProblem": "path_constrained", "PathConstraints": "path_constrained", "PathSolution": "path_constrained", "solve_path_collocation": "path_constrained", "solve_path_convex": "path_constrained",
    "MillingProcess": "milling", "SpindleAngleResult": "milling", "optimise_spindle_angle": "milling",
    # the method objects live in gtmodel.modeling.ocp.methods, re-exported by trajectory.settings
    "Collocation": "settings", "MultipleShooting": "settings", "SolverSettings": "settings", "Refinement": "settings",
    "OptimalControl": "model_ocp",
})
