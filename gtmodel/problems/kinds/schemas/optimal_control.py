"""The schema of an ``optimal_control`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.optimal_control`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.motion import MAX_TIME_S, CollocationSection, SolverSection
from gtmodel.problems.schema import MAX_NAMED_NUMBER, Expressions, Flag, NonEmptyText, ProblemSchema, Section, choice, number, vector

__all__ = ["ModelSection", "FinalTimeSection", "OptimizationSection", "BoundarySection", "InitialGuessSection", "OptimalControlFile", "MAX_VALUE"]


#: Largest magnitude of a parameter, boundary value, bound or nominal value in the file
#: (SI units; keeps 1e308 out of the solver).
MAX_VALUE = 1.0e9


class ModelSection(Section):
    """``[model]``: the user's model file, its class and parameter overrides.

    Parameters
    ----------
    file : str
        Python file, relative to the problem file.
    class_ : str
        ``class`` in the file: the class whose instance is, or builds, a Model.
    parameters : dict of str to float
        Overrides of the model's (scalar) parameters by name.
    """

    file: NonEmptyText = Field(description='Python file of the model, relative to the problem file, e.g. "../models/cart_pendulum.py"')
    class_: NonEmptyText = Field(alias="class", description="class in the file whose instance is, or builds (build()/to_model()), a gtmodel.modeling.Model")
    parameters: dict[str, number(ge=-MAX_VALUE, le=MAX_VALUE)] = Field(default_factory=dict, description="overrides of model parameters by name, e.g. m_pole = 0.3")


class FinalTimeSection(Section):
    """``[optimization.final_time]``: free (with bounds) or fixed (with a value).

    Parameters
    ----------
    free : bool
        Free final time (needs ``bounds``) or fixed (needs ``value``).
    initial_guess : float, optional
        Guess of a free final time [s].
    bounds : list of float, shape (2,), optional
        ``[lo, hi]`` of a free final time [s].
    value : float, optional
        The fixed final time [s].
    """

    free: Flag = Field(description="free final time (needs bounds) or fixed (needs value)")
    initial_guess: number(gt=0, le=MAX_TIME_S, unit="s", description="initial guess of a free final time") | None = None
    bounds: vector(2, nonnegative=True, bound=MAX_TIME_S, unit="s", description="[lo, hi] of a free final time") | None = None
    value: number(gt=0, le=MAX_TIME_S, unit="s", description="the fixed final time") | None = None


class OptimizationSection(Section):
    """``[optimization]``: objective and constraints in the problem language, the horizon.

    Parameters
    ----------
    objective : str
        Objective over the model's names.
    constraints : list of str
        Path and point constraints.
    start_time : float
        Start time [s].
    final_time : FinalTimeSection
        Fixed or free final time.
    """

    objective: NonEmptyText = Field(description='objective over the model\'s names, e.g. "final_time + w * integral(F^2)"')
    constraints: Expressions = Field(default_factory=list, description='path/point constraints, e.g. ["abs(s) <= 1", "theta(final_time) == pi"]')
    start_time: number(ge=-MAX_TIME_S, le=MAX_TIME_S, unit="s") = 0.0
    final_time: FinalTimeSection


class BoundarySection(Section):
    """``[boundary]``: values of states (inputs, algebraics) at the start and final time.

    Parameters
    ----------
    start, final : dict of str to float
        Variable name -> value (each an equality point constraint).
    """

    start: dict[str, number(ge=-MAX_VALUE, le=MAX_VALUE)] = Field(default_factory=dict, description="name -> value at the start time, e.g. theta = 0.0")
    final: dict[str, number(ge=-MAX_VALUE, le=MAX_VALUE)] = Field(default_factory=dict, description="name -> value at the final time, e.g. theta = 3.141592653589793")


class InitialGuessSection(Section):
    """``[initial_guess]``: how the NLP is started.

    Parameters
    ----------
    method : str
        ``"linear"``: states (and other variables with both boundary values) interpolated
        linearly between their start and final values, others at their start values;
        ``"start"``: every variable at the model's start value.
    """

    method: choice("linear", "start", description="linear between the boundary values, or the model's start values") = "linear"


@fill_doc(**KIND_DOCS)
class OptimalControlFile(ProblemSchema):
    """An ``optimal_control`` problem file.

    Parameters
    ----------
    {header_fields}
    model : ModelSection
        ``[model]``: file, class, parameter overrides.
    parameters : dict of str to float
        ``[parameters]``: named numbers of the expressions, each within +-:data:`~gtmodel.problems.schema.MAX_NAMED_NUMBER`.
    optimization : OptimizationSection
        ``[optimization]``: objective, constraints, horizon.
    boundary : BoundarySection
        ``[boundary]``: start and final values.
    bounds : dict of str to list of float
        ``[bounds]``: ``name = [lo, hi]`` for states, inputs, algebraics.
    free_parameters : dict of str to list of float
        ``[free_parameters]``: ``name = [lo, hi]``, model parameters optimised too.
    nominal : dict of str to float
        ``[nominal]``: magnitudes for scaling (variables, ``final_time``).
    initial_guess : InitialGuessSection
        ``[initial_guess]``: how the NLP is started.
    collocation : CollocationSection
        ``[collocation]``: the transcription.
    solver : SolverSection
        ``[solver]``: IPOPT settings.
    """

    kind: Literal["optimal_control"]
    model: ModelSection
    parameters: dict[str, number(ge=-MAX_NAMED_NUMBER, le=MAX_NAMED_NUMBER)] = Field(
        default_factory=dict, description="named numbers of the expressions, e.g. w = 0.001 (|value| <= 1e6)")
    optimization: OptimizationSection
    boundary: BoundarySection = BoundarySection()
    bounds: dict[str, vector(2, bound=MAX_VALUE)] = Field(default_factory=dict, description="name = [lo, hi] for states, inputs, algebraics (overrides the model's)")
    free_parameters: dict[str, vector(2, bound=MAX_VALUE)] = Field(default_factory=dict, description="name = [lo, hi]: model parameters optimised with the trajectory, started at their value")
    nominal: dict[str, number(gt=0, le=MAX_VALUE)] = Field(default_factory=dict, description="nominal magnitudes for scaling, e.g. F = 10.0 (variables, final_time)")
    initial_guess: InitialGuessSection = InitialGuessSection()
    collocation: CollocationSection = CollocationSection()
    solver: SolverSection = SolverSection()
