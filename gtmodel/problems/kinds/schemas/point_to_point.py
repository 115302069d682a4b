"""The schema of a ``point_to_point`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.point_to_point`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.defaults import DEFAULT_FRICTION_WIDTH, FRICTION_FORMS
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.motion import MAX_TIME_S, CollocationSection, MotionSection, OcpSolverSection, RefinementSection, RobotReference
from gtmodel.problems.schema import MAX_FORCE_N, MAX_NAMED_NUMBER, Expressions, Flag, NonEmptyText, ProblemSchema, Section, choice, number, vector

__all__ = ["PointToPointFile"]


class RobotSection(RobotReference):
    """``[robot]``: the parameter set and the dynamics options."""

    friction: choice(*FRICTION_FORMS, description="friction form of the dynamics") = "tanh"
    friction_width: number(gt=0, le=10.0, unit="m/s", description="velocity scale of the smooth friction forms") = DEFAULT_FRICTION_WIDTH


class LimitsSection(Section):
    """``[limits]``: actuator and TCP bounds."""

    force: vector(3, positive=True, bound=MAX_FORCE_N, unit="N", description="|tau_i| <= force_i")
    cart_velocity: vector(3, positive=True, bound=1e3, unit="m/s", description="|qd_i| <= cart_velocity_i") | None = None
    cart_acceleration: vector(3, positive=True, bound=1e5, unit="m/s^2", description="|qdd_i| bound") | None = None
    tcp_velocity: number(gt=0, le=1e3, unit="m/s", description="||T_dot|| bound") | None = None
    joint_angle_deg: number(gt=0, lt=90, unit="deg", what="an angle below 90 degrees", description="spherical-joint angle limit (default: the robot's)") | None = None


class FinalTimeSection(Section):
    """``[optimization.final_time]``: free (with bounds) or fixed (with a value)."""

    free: Flag = Field(description="free final time (needs bounds) or fixed (needs value)")
    initial_guess: number(gt=0, le=MAX_TIME_S, unit="s", description="initial guess of a free final time") | None = None
    bounds: vector(2, nonnegative=True, bound=MAX_TIME_S, unit="s", description="[lo, hi] of a free final time") | None = None
    value: number(gt=0, le=MAX_TIME_S, unit="s", description="the fixed final time") | None = None


class OptimizationSection(Section):
    """``[optimization]``: the objective and constraints in the problem language."""

    objective: NonEmptyText = Field(description='objective, e.g. "final_time + w * integral(tau1^2 + tau2^2 + tau3^2)"')
    constraints: Expressions = Field(default_factory=list, description='extra path/point constraints, e.g. ["abs(qd1) <= 1.2"]')
    start_time: number(ge=-MAX_TIME_S, le=MAX_TIME_S, unit="s") = 0.0
    final_time: FinalTimeSection


class InitialGuessSection(Section):
    """``[initial_guess]``: how the NLP is started."""

    method: choice("trapezoid", "bang_bang", "file") = "trapezoid"
    file: NonEmptyText | None = Field(default=None, description='trajectory CSV when method = "file" (relative to the problem file)')


@fill_doc(**KIND_DOCS)
class PointToPointFile(ProblemSchema):
    """A ``point_to_point`` problem file.

    Parameters
    ----------
    {header_fields}
    robot : RobotSection
        ``[robot]``: parameter set, IK configuration, friction model.
    motion : MotionSection
        ``[motion]``: start and end positions [m].
    limits : LimitsSection
        ``[limits]``: actuator and TCP bounds.
    parameters : dict of str to float
        ``[parameters]``: named numbers of the expressions, each within +-:data:`~gtmodel.problems.schema.MAX_NAMED_NUMBER`.
    optimization : OptimizationSection
        ``[optimization]``: objective, constraints, final time.
    initial_guess : InitialGuessSection
        ``[initial_guess]``: how the NLP is started.
    collocation : CollocationSection
        ``[collocation]``: the transcription.
    transcription : RefinementSection
        ``[transcription]``: verification tolerance and mesh refinement.
    solver : OcpSolverSection
        ``[solver]``: IPOPT settings.
    """

    kind: Literal["point_to_point"]
    robot: RobotSection
    motion: MotionSection
    limits: LimitsSection
    parameters: dict[str, number(ge=-MAX_NAMED_NUMBER, le=MAX_NAMED_NUMBER)] = Field(
        default_factory=dict, description="named numbers of the expressions, e.g. w = 0.001 (|value| <= 1e6)")
    optimization: OptimizationSection
    initial_guess: InitialGuessSection = InitialGuessSection()
    collocation: CollocationSection = CollocationSection()
    transcription: RefinementSection = RefinementSection()
    solver: OcpSolverSection = OcpSolverSection()
