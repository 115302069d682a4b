"""The schema of an ``optimal_control`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.optimal_control`; the field reference is
``docs/problem_files.md``.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field
from pydantic_core import PydanticCustomError

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.motion import MAX_TIME_S, CollocationSection, RefinementSection, SolverSection, VerificationSection
from gtmodel.problems.schema import MAX_NAMED_NUMBER, Expressions, Flag, NonEmptyText, ProblemSchema, Section, Text, choice, integer, number, vector

__all__ = [
    "BoundPair", "ModelSection", "FinalTimeSection", "OptimizationSection", "BoundarySection", "InitialGuessSection",
    "TranscriptionSection", "DataSection", "BenchmarkSection", "OptimalControlFile", "MAX_VALUE",
]


#: Largest magnitude of a parameter, boundary value, bound or nominal value in the file
#: (SI units; keeps 1e308 out of the solver).
MAX_VALUE = 1.0e9

_INF = {"inf": math.inf, "+inf": math.inf, "-inf": -math.inf}
#: A bound of at least this magnitude means infinite (IPOPT's ``nlp_upper_bound_inf``
#: convention: ``1e20`` is written for "no bound").
INFINITE_BOUND = 1.0e19


def _bound_pair(v: Any) -> Any:
    """``[lo, hi]``: numbers (``inf``/``-inf`` leave a side open), ``"inf"``/``"-inf"`` or expressions of parameters."""
    what = ('a list [lo, hi] of numbers (|x| <= 1e+09, or -inf/inf, |x| >= 1e19, for an open side), "inf"/"-inf" or '
            'expressions of parameters')
    if not isinstance(v, list) or len(v) != 2:
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": what})
    out = []
    for x in v:
        if isinstance(x, str) and x.strip().lower() in _INF:
            x = _INF[x.strip().lower()]
        if isinstance(x, bool) or not isinstance(x, (int, float, str)) or (isinstance(x, str) and not x.strip()):
            raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": what})
        if isinstance(x, (int, float)):
            if math.isfinite(x) and abs(x) >= INFINITE_BOUND:
                x = math.copysign(math.inf, x)
            if math.isnan(x) or (math.isfinite(x) and abs(x) > MAX_VALUE):
                raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": what})
            x = float(x)
        out.append(x)
    lo, hi = out
    if lo == -math.inf and hi == math.inf:
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": "a bound on at least one side ([-inf, inf] bounds nothing: leave the entry out)"})
    if lo == math.inf or hi == -math.inf:
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": "lo < inf and hi > -inf"})
    return out


def _guess_value(v: Any) -> Any:
    if isinstance(v, bool) or not isinstance(v, (int, float, str)) or (isinstance(v, str) and not v.strip()) or (
            isinstance(v, (int, float)) and not (math.isfinite(v) and abs(v) <= MAX_VALUE)):
        raise PydanticCustomError("gtmodel", "expected {expected}", {"expected": "a finite number (|x| <= 1e+09) or an expression of time"})
    return float(v) if not isinstance(v, str) else v


#: A guess: a number or an expression of ``time``, ``final_time`` and parameters.
GuessValue = Annotated[float | str, BeforeValidator(_guess_value)]

#: ``[lo, hi]`` of a bound: numbers (``inf``, ``-inf``, ``"inf"``, ``"-inf"`` for an open
#: side, not both) or expressions of parameters (``"-F_max"``).
BoundPair = Annotated[
    list[float | str],
    BeforeValidator(_bound_pair),
    Field(min_length=2, max_length=2, description='[lo, hi]: numbers, -inf/inf (or "-inf"/"inf", or a magnitude >= 1e19 such as 1e20) for an open side, or expressions of parameters such as "-F_max"'),
]


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
    objective, minimize, maximize : str, optional
        The objective over the model's names, minimised (``objective`` or ``minimize``)
        or maximised (``maximize``); exactly one of them (none with ``[[data]]`` only).
    constraints : list of str
        Path and point constraints.
    start_time : float
        Start time [s].
    final_time : FinalTimeSection
        Fixed or free final time.
    """

    objective: NonEmptyText | None = Field(None, description='objective to minimise over the model\'s names, e.g. "final_time + w * integral(F^2)"')
    minimize: NonEmptyText | None = Field(None, description="objective to minimise (the same as objective)")
    maximize: NonEmptyText | None = Field(None, description='objective to maximise, e.g. "h(final_time)"')
    constraints: Expressions = Field(default_factory=list, description='path/point constraints, e.g. ["abs(s) <= 1", "theta(final_time) == pi"]')
    start_time: number(ge=-MAX_TIME_S, le=MAX_TIME_S, unit="s") = 0.0
    final_time: FinalTimeSection


class BoundarySection(Section):
    """``[boundary]``: values of states (inputs, algebraics) at the start and final time.

    Parameters
    ----------
    start, final : dict of str to float
        Variable name -> value (each an equality point constraint). The model's fixed
        starts (``Mass(s=3)``) are initial conditions too; a ``start`` entry takes the
        place of the fixed start of its variable when it has the same value, and is an
        error naming the variable when it differs.
    """

    start: dict[str, number(ge=-MAX_VALUE, le=MAX_VALUE)] = Field(default_factory=dict, description="name -> value at the start time, e.g. theta = 0.0 (the model's fixed starts hold too; a different value for one is an error)")
    final: dict[str, number(ge=-MAX_VALUE, le=MAX_VALUE)] = Field(default_factory=dict, description="name -> value at the final time, e.g. theta = 3.141592653589793")


class InitialGuessSection(Section):
    """``[initial_guess]``: how the NLP is started.

    Parameters
    ----------
    method : str
        ``"linear"``: states (and other variables with both boundary values) interpolated
        linearly between their start and final values, others at their start values;
        ``"start"``: every variable at the model's start value; ``"simulation"``: the
        model simulated from its start values (``[boundary.start]``) under ``inputs``;
        ``"file"``: the trajectory in ``file``.
    file : str, optional
        With ``method = "file"``: a CSV (time column and columns named as the model's
        variables) or an earlier result folder (its ``trajectories.csv``), relative to
        the problem file; interpolated linearly onto the mesh. With a free final time the
        table's last time is the guess of the final time (unless
        ``optimization.final_time.initial_guess`` is given).
    time_column : str
        The time column of ``file`` [s].
    values : dict of str to float or str
        Per-variable guesses overriding the method: a number or an expression of
        ``time``, ``final_time`` and parameters.
    inputs : dict of str to float or str
        With ``method = "simulation"``: the inputs of the simulation, numbers or
        expressions of ``time`` (default the model's input start values).
    """

    method: choice("linear", "start", "simulation", "file", description="linear between the boundary values, the model's start values, a simulation of the model under inputs, or the trajectory in file") = "linear"
    file: NonEmptyText | None = Field(None, description='method "file": a CSV with a time column, or an earlier result folder (its trajectories.csv), relative to this file')
    time_column: NonEmptyText = Field("t", description="time column of file [s]")
    values: dict[str, GuessValue] = Field(default_factory=dict, description='per-variable guesses: numbers or expressions of time, e.g. theta = "pi * time / final_time"')
    inputs: dict[str, GuessValue] = Field(default_factory=dict, description='method "simulation": inputs as numbers or expressions of time, e.g. F = "5 * sin(time)"')


class DataSection(Section):
    """``[[data]]``: measurements of the model for parameter estimation (a least-squares objective).

    Parameters
    ----------
    file : str
        CSV file of the measurements (relative to the problem file), read with
        ``gtmodel._tables.read_table``: a time column and one column per measured name.
    time_column : str
        The time column [s].
    measures : list of str
        Model names measured (outputs, states, algebraic variables).
    columns : list of str, optional
        The CSV column of each measured name; default the names themselves.
    std : list of float, optional
        Standard deviations of the measurements, one per measured name (or one for all);
        weights ``1 / std^2``.
    weights : list of float, optional
        Weights of the squared residuals instead of ``std``; default 1.
    """

    file: NonEmptyText = Field(description="CSV of the measurements, relative to this file")
    time_column: NonEmptyText = Field("t", description="time column of the CSV [s]")
    measures: list[NonEmptyText] = Field(min_length=1, description='model names measured, e.g. ["x", "v"] (outputs, states, algebraics)')
    columns: list[NonEmptyText] | None = Field(None, description="CSV column of each measured name (default: the names)")
    std: vector(None, positive=True, bound=MAX_VALUE, description="standard deviations, one per measured name or one for all") | None = None
    weights: vector(None, positive=True, bound=MAX_VALUE, description="weights of the squared residuals instead of std") | None = None


class TranscriptionSection(RefinementSection):
    """``[transcription]``: the transcription method, the verification tolerance and mesh refinement.

    Parameters
    ----------
    method : str
        ``"collocation"`` (direct collocation, settings in ``[collocation]``) or
        ``"multiple_shooting"`` (direct multiple shooting, a CasADi integrator per interval).
    intervals : int
        Shooting intervals (multiple shooting).
    controls : str
        ``"constant"`` or ``"linear"``: inputs piecewise constant or piecewise linear
        over the shooting intervals.
    integrator : str, optional
        ``"rk"`` (fixed-step RK4) and ``"radau"`` (fixed-step 2-stage Radau IIA, implicit,
        for stiff models) on the explicit form (the algebraic variables eliminated
        symbolically, as codegen does), ``"collocation"`` (fixed-step Radau IIA collocation,
        a Newton rootfinder per step started from a simulation of the guess; DAEs),
        ``"cvodes"`` / ``"idas"`` (SUNDIALS, variable step); default rk for ODEs,
        collocation for DAEs (measured: ``benchmarks/bench_shooting_integrators.py``).
    steps : int
        Fixed integrator steps per interval (rk, radau, collocation); rk and radau impose
        the bounds and path constraints at every step's end, collocation at every stage point.
    refine : bool
        Collocation: refine the mesh where the solution is least accurate (element
        defects, input switches) until the verification passes or a limit is reached
        (also with ``[[data]]``: the statistics are those of the final mesh); refused
        with multiple shooting.
    tolerance : float, optional
        Verification tolerance (collocation and multiple shooting): largest deviation of
        a state's simulation under the optimal inputs from the transcribed state, scaled
        by ``max(1, max |x|)``; default 1e-2 (``gtmodel.defaults``).
    max_elements : int, optional
        Limit on the elements of a refined mesh; unset: the most the memory estimate allows.
    max_passes : int
        Limit on the solves of the refinement.
    refine_on_failure : bool
        A single collocation solve whose verification fails is refined from (default).
    max_cpu_s : float, optional
        CPU-time budget of a refinement [s]; default ``defaults["ocp.refine_max_cpu_s"]``. With multiple
        shooting, the budget of the whole solve, its continuation over smoothing widths included (IPOPT's
        ``max_cpu_time``, what is left of it per solve); unset there: none (``[solver] max_iter`` alone).
    objective_tolerance : float, optional
        A refinement's verified pass with nothing left to split is solved again with every
        element halved, and refined on from there while that improves the objective by more
        than this fraction; 0 ends at the first verified pass; default 1e-3.
    regularization : float, optional
        Weight of the input energy a refinement adds to a minimum-time objective from its second pass on, each input
        scaled by its RMS in the previous pass (:mod:`gtmodel.modeling.ocp.regularization`); 0 off; default 1e-3.
    """

    method: choice("collocation", "multiple_shooting", description="direct collocation ([collocation]) or direct multiple shooting") = "collocation"
    intervals: integer(1, 10000, description="multiple shooting: number of intervals") = 50
    controls: choice("constant", "linear", description="multiple shooting: inputs piecewise constant or piecewise linear") = "constant"
    integrator: choice("rk", "radau", "collocation", "cvodes", "idas", description="multiple shooting: integrator per interval (default rk for ODEs, collocation for DAEs: Radau IIA collocation, its rootfinder started from a simulation of the guess)") | None = None
    steps: integer(1, 1000, description="multiple shooting: fixed integrator steps per interval (rk, radau, collocation); rk and radau impose the bounds at every step's end, collocation at every stage point") = 4
    max_cpu_s: number(gt=0, description="CPU-time budget, s: of a mesh refinement (default 290: no pass starts once it is spent, the best verified pass is returned); with multiple shooting, of the whole solve, its continuation included (unset: none)") | None = None


class BenchmarkSection(Section):
    """``[benchmark]``: the published optimum a benchmark problem is checked against.

    Parameters
    ----------
    source : str
        Where the value is published (author, year, problem number).
    published : float
        The published optimum.
    quantity : str
        What the value is (``"final time [s]"``, ``"objective"``).
    sign : float
        ``objective = sign * published`` (``-1`` where a maximum is written as the
        minimum of its negative).
    tolerance : float
        Largest relative error to the published value; beyond it the result is printed
        and flagged (a warning in the CLI and the summary's ``warnings``).
    """

    source: NonEmptyText = Field(description='where the value is published, e.g. "COPS 3.0, problem 4 (Dolan, More, Munson 2004)"')
    published: number(description="the published optimum")
    quantity: Text = Field("objective", description='what the value is, e.g. "final time [s]"')
    sign: number(ge=-1, le=1, description="objective = sign * published: 1, or -1 for a maximum written as minimise its negative") = 1.0
    tolerance: number(gt=0, lt=1, description="largest relative error to the published value; beyond it the result is flagged") = 1e-4


class OutputSection(Section):
    """``[output]``: what the result folder shows besides the solution's own variables.

    Parameters
    ----------
    variables : list of str
        Variables of the model (states, algebraic variables, inputs, outputs, the aliases a
        reduction eliminated) plotted in ``variables.png``; every variable is a column of
        ``trajectories.csv``. Default: for a model reduced to index 1, the states of the
        model as written (``load.phi``, not only the states the reduction chose).
    """

    variables: list[NonEmptyText] = Field(default_factory=list, description='variables plotted in variables.png, e.g. ["load.phi", "load.w"]; default for a reduced model: its states as written')


class ModelSolverSection(SolverSection):
    """``[solver]`` of an ``optimal_control`` problem: the NLP solver, its limits, how derivatives are evaluated.

    Parameters
    ----------
    max_iter : int
        IPOPT iteration limit.
    tol : float
        IPOPT tolerance.
    name : str
        ``"ipopt"`` (default) or ``"fatrop"`` (collocation only: the NLP ordered stage by stage; multiple
        shooting is refused, saying so).
    jit : bool
        Compile the NLP's derivatives to C (cached; default false for a user's model: its first solve then
        pays the compilation).
    """

    name: choice("ipopt", "fatrop", description="NLP solver (fatrop: stage-wise interior point, collocation only)") = "ipopt"
    jit: Flag = Field(default=False, description="compiled (cached) C for the NLP derivatives")


class ContinuationSection(Section):
    """``[continuation]``: the continuation over the model's smoothing widths (non-smooth elements).

    Parameters
    ----------
    enabled : bool
        Continue over the widths when the model declares any (default true).
    start_factor : float
        The first solve's widths are the declared ones times this (default 100).
    step : float
        Each solve divides the widths by this (default 10), down to the declared ones.
    """

    enabled: Flag = Field(default=True, description="continue over the model's smoothing widths (when it declares any)")
    start_factor: number(gt=1, le=1e6, description="first widths: the declared ones times this") = 100.0
    step: number(gt=1, le=1e6, description="each step divides the widths by this") = 10.0


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
    data : list of DataSection
        ``[[data]]``: measurements fitted by least squares (parameter estimation).
    transcription : TranscriptionSection
        ``[transcription]``: collocation or multiple shooting, verification tolerance and
        mesh refinement.
    verification : VerificationSection
        ``[verification]``: whether and with which integrator the solution is verified.
    collocation : CollocationSection
        ``[collocation]``: the collocation mesh.
    benchmark : BenchmarkSection, optional
        ``[benchmark]``: a published optimum to compare with (benchmark problems).
    solver : ModelSolverSection
        ``[solver]``: the NLP solver and its settings.
    continuation : ContinuationSection
        ``[continuation]``: the continuation over the model's smoothing widths.
    output : OutputSection
        ``[output]``: the variables plotted in ``variables.png``.
    """

    kind: Literal["optimal_control"]
    model: ModelSection
    parameters: dict[str, number(ge=-MAX_NAMED_NUMBER, le=MAX_NAMED_NUMBER)] = Field(
        default_factory=dict, description="named numbers of the expressions, e.g. w = 0.001 (|value| <= 1e6)")
    optimization: OptimizationSection
    boundary: BoundarySection = BoundarySection()
    bounds: dict[str, BoundPair] = Field(default_factory=dict, description="name = [lo, hi] for states, inputs, algebraics (overrides the model's); inf for an open side, expressions of parameters allowed")
    free_parameters: dict[str, BoundPair] = Field(default_factory=dict, description="name = [lo, hi]: model parameters optimised with the trajectory, started at their value")
    nominal: dict[str, number(gt=0, le=MAX_VALUE)] = Field(default_factory=dict, description="nominal magnitudes for scaling, e.g. F = 10.0 (variables, final_time)")
    initial_guess: InitialGuessSection = InitialGuessSection()
    data: list[DataSection] = Field(default_factory=list, description="[[data]] tables: measurements fitted by least squares (parameter estimation)")
    transcription: TranscriptionSection = TranscriptionSection()
    verification: VerificationSection = VerificationSection()
    collocation: CollocationSection = CollocationSection()
    benchmark: BenchmarkSection | None = None
    solver: ModelSolverSection = ModelSolverSection()
    continuation: ContinuationSection = ContinuationSection()
    output: OutputSection = OutputSection()
