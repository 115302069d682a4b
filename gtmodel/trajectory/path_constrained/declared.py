"""A path-constrained motion problem as one declaration: what, by which method, with which solver.

:class:`PathConstrainedDeclaration` (what the ``path_constrained`` problem kind loads)
holds the TCP path, its limits, the method (``"convex"``: the convex reformulation on a
grid, :func:`~gtmodel.trajectory.solve_path_convex`; ``"collocation"``: direct
collocation with an energy weight, :func:`~gtmodel.trajectory.solve_path_collocation`)
and the solver settings; :meth:`PathConstrainedDeclaration.solve` solves it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.defaults import PATH_METHODS
from gtmodel.robots import RobotParameters
from gtmodel.trajectory.path import Path as TcpPath
from gtmodel.trajectory.path_constrained.collocation import solve_path_collocation
from gtmodel.trajectory.path_constrained.constraints import PathConstraints
from gtmodel.trajectory.path_constrained.convex import solve_path_convex
from gtmodel.trajectory.path_constrained.solution import PathSolution
from gtmodel.modeling.ocp.methods import Collocation, SolverSettings

__all__ = ["PathConstrainedDeclaration", "PATH_METHODS"]

# PATH_METHODS (the methods of kind ``path_constrained``) lives in gtmodel.defaults.


@dataclass(frozen=True)
class PathConstrainedDeclaration:
    """A path-constrained motion problem: the path, its limits, the method and the solver settings.

    Parameters
    ----------
    path : gtmodel.trajectory.Path
        The TCP path (checked inside the workspace).
    robot : RobotParameters
        Parameter set.
    constraints : gtmodel.trajectory.PathConstraints
        Limits along the path.
    method : str
        One of :data:`PATH_METHODS`.
    grid : int
        Grid points of the convex method.
    w : float
        Energy weight of the collocation method's objective
        ``final_time + w * sum_i integral tau_i^2 dt`` [1/N^2].
    configuration : int
        IK configuration.
    viscous_friction : bool
        Include viscous friction.
    collocation : Collocation
        The transcription of method ``"collocation"``.
    final_time_guess : float
        Initial guess of the duration [s] (method ``"collocation"``).
    final_time_bounds : tuple of float
        Bounds of the duration [s] (method ``"collocation"``).
    solver : SolverSettings
        IPOPT's iteration limit and tolerance (method ``"collocation"``).
    """

    path: TcpPath
    robot: RobotParameters
    constraints: PathConstraints
    method: str
    grid: int
    w: float
    configuration: int
    viscous_friction: bool
    collocation: Collocation = Collocation()
    final_time_guess: float = 1.0
    final_time_bounds: tuple[float, float] = (0.05, 10.0)
    solver: SolverSettings = SolverSettings()

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> PathSolution:
        """Solve with the declared method.

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        PathSolution
            Always returned; its ``status`` says whether it is optimal.
        """
        d = self
        if d.method == "convex":
            return solve_path_convex(d.path, d.constraints, robot=d.robot, grid=d.grid, configuration=d.configuration, viscous_friction=d.viscous_friction)
        return solve_path_collocation(
            d.path,
            d.robot,
            d.constraints.force_limit,
            w=d.w,
            configuration=d.configuration,
            viscous_friction=d.viscous_friction,
            elements=d.collocation.elements,
            points=d.collocation.points,
            scheme=d.collocation.scheme,
            final_time_guess=d.final_time_guess,
            final_time_bounds=d.final_time_bounds,
            max_iter=d.solver.max_iter,
            tol=d.solver.tol,
            verbose=verbose,
        )
