"""Optimal motion on top of the modelling layer: point-to-point time/energy-optimal motion."""

from gtmodel.trajectory.point_to_point import (
    SAMPLE_TIME,
    PointToPoint,
    PointToPointSolution,
    build_optimization,
    solve_point_to_point,
    trapezoid_profile,
)

__all__ = [
    "SAMPLE_TIME",
    "PointToPoint",
    "PointToPointSolution",
    "build_optimization",
    "solve_point_to_point",
    "trapezoid_profile",
]
