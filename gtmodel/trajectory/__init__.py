"""Optimal motion on top of the modelling layer: point-to-point time/energy-optimal motion."""

from gtmodel.trajectory.point_to_point import (
    SAMPLE_TIME,
    PointToPoint,
    PointToPointSolution,
    build_optimization,
    solve_point_to_point,
    trapezoid_profile,
)
from gtmodel.trajectory.point_to_point_resolve import point_to_point_function, resolve_point_to_point
from gtmodel.trajectory.path import Path, Polyline, SplinePath, StraightLine
from gtmodel.trajectory.path_constrained import (
    PathConstrainedProblem,
    PathConstraints,
    PathSolution,
    solve_path_collocation,
    solve_path_convex,
)
from gtmodel.trajectory.milling import MillingProcess, SpindleAngleResult, optimise_spindle_angle

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
]
