"""The schema of a ``path_constrained`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.path_constrained`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BeforeValidator, Field
from pydantic_core import PydanticCustomError

from gtmodel._docstrings import fill_doc
from gtmodel.defaults import PATH_METHODS
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.motion import MAX_TIME_S, CollocationSection, MotionSection, RobotReference, SolverSection
from gtmodel.problems.schema import MAX_FORCE_N, MAX_LENGTH_M, Flag, ProblemSchema, Section, choice, integer, number, vector

__all__ = ["MAX_GRID_POINTS", "MAX_VIA_POINTS", "PathConstrainedFile"]

#: Most grid points of the convex method (20000 solve in about a second, 250 MB).
MAX_GRID_POINTS = 20000
#: Most via points of a path.
MAX_VIA_POINTS = 1000
#: Smallest velocity limit accepted [m/s]: slower limits make motions of hours, whose
#: 4 ms samples would not fit in memory.
MIN_VELOCITY_M_S = 1e-2
#: Smallest acceleration limit accepted [m/s^2] (same reason).
MIN_ACCELERATION_M_S2 = 1e-2
#: Shortest duration accepted [s] (the guess and bounds of method "collocation").
MIN_TIME_S = 1e-3
#: Largest energy weight accepted [1/N^2] (w = 1 already makes the duration irrelevant).
MAX_ENERGY_WEIGHT = 1e3


def _at_least(minimum: float, unit: str) -> AfterValidator:
    """Every entry of a (validated) vector at least ``minimum``."""

    def check(v: list[float]) -> list[float]:
        if any(x < minimum for x in v):
            raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": f"numbers >= {minimum:g} {unit}"})
        return v

    return AfterValidator(check)


def _limit(unit: str, minimum: float, bound: float, description: str) -> Any:
    return Annotated[vector(3, positive=True, bound=bound, unit=unit, description=description), _at_least(minimum, unit)]


def _via_list(v: Any) -> Any:
    if not isinstance(v, list) or len(v) > MAX_VIA_POINTS:
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": f"a list of at most {MAX_VIA_POINTS} [x, y, z] points [m]"})
    return v


#: Via points of a path: ``[[x, y, z], ...]`` [m].
ViaPoints = Annotated[
    list[vector(3, bound=MAX_LENGTH_M, unit="m", description="a via point [x, y, z]")],
    BeforeValidator(_via_list),
    Field(max_length=MAX_VIA_POINTS, description='points between motion.start and motion.end, e.g. [[0.0, 2.9, -0.5]] [m]'),
]


class RobotSection(RobotReference):
    """``[robot]``: the parameter set and the friction model (exact Coulomb friction always)."""

    viscous_friction: Flag = Field(default=True, description="include viscous friction")


class PathSection(Section):
    """``[path]``: the TCP path from motion.start to motion.end."""

    shape: choice("line", "polyline", "spline", description='"line", or a "polyline"/"spline" through via points') = "line"
    via: ViaPoints = []


class LimitsSection(Section):
    """``[limits]``: bounds along the path (at least one; method "collocation": force only)."""

    force: vector(3, positive=True, bound=MAX_FORCE_N, unit="N", description="|tau_i| <= force_i") | None = None
    cart_velocity: _limit("m/s", MIN_VELOCITY_M_S, 1e3, "|qd_i| <= cart_velocity_i") | None = None
    cart_acceleration: _limit("m/s^2", MIN_ACCELERATION_M_S2, 1e5, "|qdd_i| <= cart_acceleration_i") | None = None
    tcp_velocity: _limit("m/s", MIN_VELOCITY_M_S, 1e3, "per axis |T_dot_j| <= tcp_velocity_j") | None = None
    tcp_speed: number(ge=MIN_VELOCITY_M_S, le=1e3, unit="m/s", description="||T_dot|| <= tcp_speed") | None = None
    tcp_acceleration: _limit("m/s^2", MIN_ACCELERATION_M_S2, 1e5, "per axis |T_ddot_j| <= tcp_acceleration_j") | None = None


class MethodSection(Section):
    """``[method]``: how the problem is solved."""

    name: choice(*PATH_METHODS, description='"convex" (Verscheure et al. 2009) or "collocation" (Dressler 2012, IPOPT)') = "convex"
    grid: integer(2, MAX_GRID_POINTS, description='grid points of method "convex"') = 500
    w: number(ge=0, le=MAX_ENERGY_WEIGHT, unit="1/N^2", description='energy weight of method "collocation": final_time + w * sum_i integral tau_i^2 dt') = 0.0
    final_time_guess: number(ge=MIN_TIME_S, le=MAX_TIME_S, unit="s", description='initial guess of the duration, within final_time_bounds (method "collocation")') = 1.0
    final_time_bounds: Annotated[
        vector(2, positive=True, bound=MAX_TIME_S, unit="s", description='[lo, hi] of the duration (method "collocation")'), _at_least(MIN_TIME_S, "s")
    ] = [0.05, 10.0]


@fill_doc(**KIND_DOCS)
class PathConstrainedFile(ProblemSchema):
    """A ``path_constrained`` problem file.

    Parameters
    ----------
    {header_fields}
    robot : RobotSection
        ``[robot]``: parameter set, IK configuration, viscous friction.
    motion : MotionSection
        ``[motion]``: start and end positions [m].
    path : PathSection
        ``[path]``: shape and via points.
    limits : LimitsSection
        ``[limits]``: bounds along the path.
    method : MethodSection
        ``[method]``: convex or collocation and their settings.
    collocation : CollocationSection
        ``[collocation]``: mesh of method ``"collocation"``.
    solver : SolverSection
        ``[solver]``: IPOPT settings.
    """

    kind: Literal["path_constrained"]
    robot: RobotSection
    motion: MotionSection
    path: PathSection = PathSection()
    limits: LimitsSection
    method: MethodSection = MethodSection()
    collocation: CollocationSection = CollocationSection()
    solver: SolverSection = SolverSection()
