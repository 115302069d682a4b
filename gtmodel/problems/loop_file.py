"""What every loop-controller file shares: the model, ``[reference]``, ``[check]`` and the plant.

A loop-controller file (the MPC file of :mod:`gtmodel.problems.mpc_file`, the tracking
controller file of :mod:`gtmodel.problems.tracking_file`) declares a controller section of
its own and these two tables, validated on load (pydantic, unknown fields refused; every
error names the file and the field, the CLI exits with 2):

``[reference]``
    The motion tracked: ``problem`` (a ``point_to_point`` problem file of the robot, or an
    ``optimal_control`` problem file of the user's model, solved first; ``overrides`` its
    dotted fields, e.g. a tighter force limit for the plan than the actuators' bounds; the
    default input bounds are that problem's without the overrides) or ``file`` (a CSV table
    with ``t`` and the model's state and input names); ``settle_time`` [s] the end held: its state (the robot at rest) with the input that holds it (:func:`~gtmodel.estimation.reference.hold_input`).
``[check]``
    The closed loop of ``--check`` (:mod:`gtmodel.estimation.closed_loop.controller_loop`):
    ``mass_factor``, ``friction_factor`` (the robot plant; a user model: ``parameter_factor``
    on every parameter, ``parameter_factors`` a table by parameter name replacing it for
    those), ``compliance`` (the robot: the tool structure of eq. 6.14 in the
    plant, the tool position tracked, the controller measuring ``T``, ``T_dot``), ``noise``
    (one standard deviation per state), ``disturbance`` and ``disturbance_time``, ``delay``
    (samples), ``seed``, ``error_states``, ``plant_method`` / ``plant_substeps``, and the
    acceptance: ``max_ratio`` (the RMS ratio to the feedforward below it, default 1) and
    ``max_step_time`` (the 99th-percentile step time at most it, default the period).

Every number is finite and in a declared range, checked on load before anything is solved,
built or written (the ranges of the tables below and of the controller tables):
``period`` :data:`MIN_PERIOD_S` .. :data:`MAX_PERIOD_S` (1e-5 .. 1 s); weights ``0 ..``
:data:`MAX_WEIGHT` (1e12); input and state bounds, ``noise`` and ``disturbance`` of
magnitude <= :data:`MAX_MAGNITUDE` (1e7), ``noise`` >= 0; ``settle_time`` 0 .. 60 s,
``disturbance_time`` 0 .. 1e4 s; factors in (0, 10]. ``name`` is a C identifier of at most
40 characters (the C prefix ``gt_<name>``); ``reference.overrides`` only with
``reference.problem``. The size is estimated before the reference is sampled
(:func:`loop_samples`): at most :data:`MAX_LOOP_SAMPLES` loop periods (the settling hold
first, the whole reference once its length is known) and :data:`MAX_TABLE_NUMBERS` numbers
in the generated C's tables.

The model is ``"L1"`` (a Gantry-Tau parameter set: its rigid-body dynamics with friction in
TCP states ``T``, ``T_dot`` and input ``tau``, :func:`gtmodel.robots.model.gantry_tau_model`)
or ``"FILE.py:Class"`` (a user's model), reduced to its explicit ODE
(:func:`gtmodel.modeling.explicit_ode`) by :func:`loop_model`; :func:`loop_reference` reads
or solves the reference, :func:`input_bounds` gives the saturation and :func:`loop_setup`
the plant of the check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
from pydantic import Field, ValidationError

from gtmodel._tables import read_table
from gtmodel._toml import read_toml
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.estimation.closed_loop.controller_loop import compliant_plant, mismatched_robot
from gtmodel.estimation.reference import hold_input
from gtmodel.modeling import ExplicitODE, explicit_ode
from gtmodel.modeling.simulation.explicit import STEP_METHODS
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.references import robot_parameters
from gtmodel.problems.run import load_problem, solve_problem
from gtmodel.problems.schema import MAX_FORCE_N, Identifier, NonEmptyText, Section, choice, number, problem_error
from gtmodel.problems.user_model import load_user_model, split_model_reference
from gtmodel.robots.model import gantry_tau_model
from gtmodel.trajectory.point_to_point import solve_point_to_point

__all__ = ["LoopFile", "LoopInputs", "LoopModel", "LoopSetup", "read_loop_file", "loop_inputs", "loop_model", "weight_diagonal",
           "loop_reference", "input_bounds", "loop_setup", "loop_samples", "MIN_PERIOD_S", "MAX_PERIOD_S", "MAX_WEIGHT",
           "MAX_MAGNITUDE", "MAX_LOOP_SAMPLES", "MAX_TABLE_NUMBERS", "Period", "Weights", "Bounds", "StateBounds"]

#: Shortest loop period of a loop-controller file [s] (100 kHz; a shorter one is a unit slip:
#: ``period = 1e-12`` asked numpy for 2.18 TiB of reference samples).
MIN_PERIOD_S = 1e-5
#: Longest loop period [s].
MAX_PERIOD_S = 1.0
#: Largest weight of a weight table (``state_weights``, ``input_weights``, ``terminal_weights``,
#: ``integral_weights``): the shipped files' largest is 1e8 (1 mm of TCP error against 100 N);
#: 1e12 leaves four decades for other units, and keeps the QP's and the Riccati recursion's
#: products of weights and squared scales (``Q`` times ``B^T P B``) far from overflow.
MAX_WEIGHT = 1e12
#: Largest magnitude of a number in the units of the model's states and inputs in a loop file
#: (input bounds, state bounds, noise, disturbance): :data:`~gtmodel.problems.schema.MAX_FORCE_N`.
MAX_MAGNITUDE = MAX_FORCE_N
#: Most loop periods of a loop-controller file's reference (the motion sampled at the period and
#: the settling hold): each is a row of the reference the controller stores, a sample of the
#: generated C's tables and a period of the closed-loop check (400 s at the 4 ms loop, 1 s at
#: :data:`MIN_PERIOD_S`; the shipped files have 132 to 352).
MAX_LOOP_SAMPLES = 100_000
#: Most numbers in the tables the generated C holds (samples times the numbers of each: ``x*``,
#: ``u*``, a tracking controller's gains): about 25 bytes of C source each, 50 MB at the limit.
MAX_TABLE_NUMBERS = 2_000_000

#: A loop period [s] in ``MIN_PERIOD_S .. MAX_PERIOD_S``.
Period = number(ge=MIN_PERIOD_S, le=MAX_PERIOD_S, unit="s", description="loop period")
#: A weight table by variable name: finite weights in ``0 .. MAX_WEIGHT``.
Weights = dict[str, number(ge=0, le=MAX_WEIGHT, description="weight")]
#: Input bounds, one finite number of magnitude <= ``MAX_MAGNITUDE`` per input (None: the default).
Bounds = list[number(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)] | None
#: State bounds by state name, finite numbers of magnitude <= ``MAX_MAGNITUDE``.
StateBounds = dict[str, number(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]

_TCP_STATES = ("x", "y", "z", "xd", "yd", "zd")
_TCP_INPUTS = ("tau1", "tau2", "tau3")


class ReferenceSection(Section):
    """``[reference]``: the motion tracked (exactly one of ``problem`` and ``file``)."""

    problem: NonEmptyText | None = Field(default=None, description="a point_to_point (robot) or optimal_control (user model) problem file, relative to this file, solved first")
    overrides: dict[str, Any] = Field(default_factory=dict, description="dotted fields of that problem replaced, e.g. 'limits.force'")
    file: NonEmptyText | None = Field(default=None, description="a CSV table: t and the model's state and input names")
    settle_time: number(ge=0, le=60.0, unit="s", description="the end state held this long, with the input that holds it") = 0.5


class CheckSection(Section):
    """``[check]``: the closed loop of ``--check``."""

    mass_factor: number(gt=0, le=10.0, description="plant masses / model masses (robot)") = 1.1
    friction_factor: number(gt=0, le=10.0, description="plant friction / model friction (robot)") = 1.1
    parameter_factor: number(gt=0, le=10.0, description="plant parameters / model parameters (user model)") = 1.1
    parameter_factors: dict[str, number(gt=0, le=10.0)] = Field(default_factory=dict, description="plant / model factors of single parameters by name, replacing parameter_factor for them (user model; e.g. a geometry known exactly: 1.0)")
    noise: list[number(ge=0, le=MAX_MAGNITUDE)] = Field(default_factory=list, max_length=10_000,
                                                        description="measurement noise standard deviation per state, each >= 0 (default none)")
    disturbance: list[number(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)] = Field(default_factory=list, max_length=10_000,
                                                                           description="input step disturbance per input (default none)")
    disturbance_time: number(ge=0, le=1e4, unit="s", description="time of the step disturbance") = 0.0
    delay: int = Field(default=1, ge=0, le=100, strict=True, description="input delay [samples]")
    seed: int = Field(default=0, ge=0, le=2**63 - 1, strict=True)
    compliance: bool = Field(default=False, strict=True, description="robot: the tool structure of eq. 6.14 (7.4 / 11.5 Hz modes) in the plant")
    error_states: list[str] = Field(default_factory=list, description="states summarised by the tracking error (default all)")
    plant_method: choice(*STEP_METHODS, description="the plant's fixed step (radau2, implicit_euler: stiff models; not with compliance)") = "rk4"
    plant_substeps: int = Field(default=4, ge=1, le=1000, strict=True, description="plant steps per loop period")
    max_ratio: number(gt=0, le=1.0, description="the check passes with an RMS tracking error below this fraction of the feedforward's alone") = 1.0
    max_step_time: float | None = Field(default=None, gt=0, le=10.0, allow_inf_nan=False,
                                        description="s: the largest 99th-percentile step time of the generated C that passes (default the period)")


@dataclass
class LoopModel:
    """The controller's model and the plant of the check.

    Parameters
    ----------
    ode : ExplicitODE
        The controller's model.
    plant : ExplicitODE
        The plant's model (a robot: masses and friction scaled; a user model: ``ode`` itself).
    plant_p : numpy.ndarray
        ``(np,)`` the plant's parameters.
    robot : bool
        True for a Gantry-Tau parameter set (TCP states), False for a user model.
    parameter_factor : float or numpy.ndarray
        A user model's plant parameters over the model's, one factor or ``(np,)`` per parameter
        (``[check] parameter_factor`` and ``parameter_factors``; applied again when the
        reference problem sets the model's parameters).
    """

    ode: ExplicitODE
    plant: ExplicitODE
    plant_p: np.ndarray
    robot: bool
    parameter_factor: Any = 1.0


@dataclass
class LoopSetup:
    """What a loop-controller file builds: the controller, the plant of the check and the loop options.

    Parameters
    ----------
    name : str
        Controller name.
    controller : Any
        The controller (an :class:`~gtmodel.estimation.mpc.MPCController` or a
        :class:`~gtmodel.estimation.tracking.TrackingController`: ``t0``, ``dt``,
        ``length``, ``u_ref``, ``u_lb``, ``u_ub``).
    plant_step : casadi.Function
        ``step(x, u, p) -> (x_next, ...)`` of the mismatched plant over one period.
    plant_p : numpy.ndarray
        Its parameters.
    t, x_ref, u_ref : numpy.ndarray
        The reference at the loop period (settling included).
    loop : dict
        Keyword arguments of :func:`~gtmodel.estimation.closed_loop.controller_loop.run_controller_loop`.
    plant_x0 : numpy.ndarray
        The plant's initial state (the reference's first state; the structure at rest).
    max_ratio : float, optional
        The check passes with an RMS tracking error below this fraction of the feedforward's
        (``[check] max_ratio``; default 1: better than the feedforward alone).
    max_step_time : float or None, optional
        The largest 99th-percentile step time that passes [s] (``[check] max_step_time``;
        default None: the loop period).
    """

    name: str
    controller: Any
    plant_step: Any
    plant_p: np.ndarray
    t: np.ndarray
    x_ref: np.ndarray
    u_ref: np.ndarray
    loop: dict
    plant_x0: np.ndarray
    max_ratio: float = 1.0
    max_step_time: float | None = None


def loop_model(file: ProblemFile, field: str, model: str, check: CheckSection) -> LoopModel:
    """The model of a loop-controller file and the mismatched plant of its ``[check]``.

    Parameters
    ----------
    file : ProblemFile
        The file (for its folder and its errors).
    field : str
        Dotted name of the model field, e.g. ``"mpc.model"``.
    model : str
        A robot parameter set (``"L1"`` or a TOML file) or ``"FILE.py:Class"``.
    check : CheckSection
        The file's ``[check]`` (its mismatch factors).

    Returns
    -------
    LoopModel

    Raises
    ------
    ProblemError
        Naming the file and ``field``: an unknown parameter set, a model file that cannot be
        loaded or reduced; naming the ``[check]`` field: ``check.noise`` / ``check.disturbance``
        of another length than the model's states / inputs, an unknown ``check.error_states``
        entry or ``check.parameter_factors`` parameter, ``check.compliance`` for a user model.
    """
    if ":" not in model:
        if check.parameter_factors:
            raise file.fail("check.parameter_factors", "no table for a robot (its plant: mass_factor, friction_factor)", check.parameter_factors)
        params = robot_parameters(file, field, model)
        ode = explicit_ode(gantry_tau_model(params, states="tcp"))
        plant = explicit_ode(gantry_tau_model(mismatched_robot(params, check.mass_factor, check.friction_factor), states="tcp"))
        return _checked(file, check, LoopModel(ode=ode, plant=plant, plant_p=plant.p_default, robot=True))
    model_path, cls = split_model_reference(model)
    model_path = Path(file.reference(field, str(model_path)))  # Python the user runs, as optimal_control's model.file (not a data file)
    try:
        ode = explicit_ode(load_user_model(model_path, cls))
    except GtModelError as exc:
        raise file.wrap(field, exc) from None
    factor = np.full(ode.np, float(check.parameter_factor))
    names = ode.dae.p_vars
    for name, value in check.parameter_factors.items():  # each > 0 and <= 10 (the schema)
        if name not in names:
            raise file.fail(f"check.parameter_factors.{name}", f"a parameter of the model ({', '.join(names)})", name)
        factor[names[name]] = value
    return _checked(file, check, LoopModel(ode=ode, plant=ode, plant_p=ode.p_default * factor, robot=False, parameter_factor=factor))


def _checked(file: ProblemFile, check: CheckSection, model: LoopModel) -> LoopModel:
    """``model``, once the ``[check]`` fields that depend on it fit it (before the reference is solved)."""
    ode = model.ode
    names_x = list(ode.x_names)
    for field, v, size, names in (("check.noise", check.noise, ode.nx, names_x), ("check.disturbance", check.disturbance, ode.nu, ode.u_names)):
        if v and len(v) != size:
            raise file.fail(field, f"{size} numbers ({', '.join(names)})", v)
    unknown = [s for s in check.error_states if s not in names_x]
    if unknown:
        raise file.fail(f"check.error_states.{unknown[0]}", f"a state of the model ({', '.join(names_x)})", unknown[0])
    if check.compliance and not model.robot:
        raise file.fail("check.compliance", "false for a user model (the tool structure of eq. 6.14 is the robot's)", True)
    if check.compliance and (check.plant_method, check.plant_substeps) != ("rk4", 4):
        raise file.fail("check.plant_method", "the default rk4 with 4 substeps with check.compliance (the compliant plant has its own step)",
                        check.plant_method)
    return model


def weight_diagonal(file: ProblemFile, field: str, weights: dict[str, float], names: list[str]) -> np.ndarray | None:
    """A weight table by variable name as the diagonal of a weight matrix.

    Parameters
    ----------
    file : ProblemFile
        The file (for its errors).
    field : str
        Dotted name of the table, e.g. ``"controller.state_weights"``.
    weights : dict of str to float
        Weight by variable name (a variable not named weighs 0).
    names : list of str
        The model's variables in order.

    Returns
    -------
    numpy.ndarray or None
        ``(len(names),)``, or None for an empty table (the controller's default).

    Raises
    ------
    ProblemError
        ``<field>.<name>``: a variable the model does not have (the values are the schema's
        :data:`Weights`: finite, in ``0 .. MAX_WEIGHT``).
    """
    if not weights:
        return None
    for key in weights:
        if key not in names:
            raise file.fail(f"{field}.{key}", f"a variable of the model ({', '.join(names)})", key)
    return np.array([float(weights.get(n, 0.0)) for n in names])


def loop_samples(file: ProblemFile, field: str, duration: float, settle_time: float, dt: float, per_sample: int) -> int:
    """The loop periods of a reference, refused above :data:`MAX_LOOP_SAMPLES` and :data:`MAX_TABLE_NUMBERS`.

    The estimate before anything is sampled, built or run: ``floor(duration / dt) + 1 +
    round(settle_time / dt)`` periods (the reference the controller stores, the rows of the
    generated C's tables and the periods of the closed-loop check), each with ``per_sample``
    numbers in the generated C.

    Parameters
    ----------
    file : ProblemFile
        The file (for its errors).
    field : str
        The period's field, e.g. ``"mpc.period"``.
    duration : float
        The reference motion's length [s] (0: the settling hold alone, before it is known).
    settle_time : float
        ``reference.settle_time`` [s].
    dt : float
        Loop period [s].
    per_sample : int
        Numbers of each sample in the generated C (``nx + nu``; a tracking controller's gains
        add ``nu (nx + n_integral)``).

    Returns
    -------
    int
        The number of loop periods.

    Raises
    ------
    ProblemError
        Naming the file and ``field``: more periods or table numbers than the limits (the
        estimate, the limit and the remedy in the message); a duration that is not finite.
    """
    if not (math.isfinite(duration) and duration >= 0):
        raise file.fail("reference", "a reference motion of finite length", duration)
    samples = int(math.floor(duration / dt + 1e-6)) + 1 + int(round(settle_time / dt))
    settle = f" and reference.settle_time = {settle_time:g} s" if settle_time else ""
    what = f"{duration:g} s of motion{settle} at {dt:g} s: {samples} periods"
    remedy = "a longer period, a shorter motion" + (" or settle_time" if settle_time else "")
    if samples > MAX_LOOP_SAMPLES:
        raise file.fail(field, f"a period giving at most {MAX_LOOP_SAMPLES} loop periods over the reference ({what}; each a sample "
                               f"the controller stores and the generated C holds, and a period of the closed-loop check); {remedy}", dt)
    if samples * per_sample > MAX_TABLE_NUMBERS:
        raise file.fail(field, f"a period giving at most {MAX_TABLE_NUMBERS} numbers in the generated C's tables ({what} of "
                               f"{per_sample} numbers each: {samples * per_sample}); {remedy}", dt)
    return samples


def loop_reference(file: ProblemFile, ref: ReferenceSection, model: LoopModel, dt: float, bounds_field: str | None = None,
                   period_field: str = "period", per_sample: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    """The reference motion of ``[reference]``, with the settling hold, and the reference problem's input bounds.

    Parameters
    ----------
    file : ProblemFile
        The file.
    ref : ReferenceSection
        Its ``[reference]``.
    model : LoopModel
        The controller's model.
    dt : float
        Loop period [s] (of the robot's sampled trajectory and the settling hold).
    bounds_field : str, optional
        The controller section whose ``u_lb``, ``u_ub`` are needed from the reference
        problem's ``[bounds]`` (a user model), e.g. ``"mpc"``; None when both are given.
    period_field : str, optional
        The period's dotted field, named when the reference has too many periods
        (:func:`loop_samples`, checked once its length is known, before it is sampled).
    per_sample : int, optional
        Numbers of each sample in the generated C (default ``nx + nu``).

    Returns
    -------
    t : numpy.ndarray
        ``(M,)`` times [s].
    x, u : numpy.ndarray
        ``(M, nx)``, ``(M, nu)`` the states and inputs in the model's order.
    limits : numpy.ndarray or None
        ``(2, nu)`` the reference problem's input bounds (without the overrides), None for
        a table or when ``bounds_field`` is None for a user model.

    Raises
    ------
    ProblemError
        Naming ``reference.problem`` or ``reference.file``: a problem of the wrong kind, one
        that does not solve, a table without the columns; naming ``period_field``: too many
        periods (:func:`loop_samples`). (Neither or both of ``problem`` and ``file``:
        :func:`read_loop_file`.)
    """
    ode, robot = model.ode, model.robot
    width = ode.nx + ode.nu if per_sample is None else per_sample
    if ref.problem is not None:
        # a problem file the user wrote, resolved as a model file is (relative to this file): the shipped loop-controller
        # files in codegen/ name their references in problems/; its data files stay confined when it loads
        source = Path(file.reference("reference.problem", ref.problem))
        try:
            loaded = load_problem(source, dict(ref.overrides))
        except GtModelError as exc:
            raise file.wrap("reference.problem", exc) from None
        wanted = "point_to_point" if robot else "optimal_control"
        if loaded.kind != wanted:
            raise file.fail("reference.problem", f"a problem file of kind {wanted} (for this model)", loaded.kind)
        solution = solve_point_to_point(loaded.declaration) if robot else solve_problem(loaded)
        if not solution.success:
            raise file.fail("reference.problem", f"a problem that solves (status {solution.status})")
        loop_samples(file, period_field, float(solution.result.final_time - solution.result.t[0]) if robot
                     else float(solution.t[-1] - solution.t[0]), ref.settle_time, dt, width)
        if robot:
            tr = solution.trajectory(dt)
            bound = np.asarray(load_problem(source).declaration.force_limit, dtype=float)
            t = tr["t"]
            x = np.column_stack([tr[c] for c in _TCP_STATES])
            u = np.column_stack([tr[c] for c in _TCP_INPUTS])
            limits = np.vstack([-bound, bound])
        else:
            t = np.asarray(solution.t, dtype=float).reshape(-1)
            x = np.column_stack([np.asarray(solution.states[n], dtype=float).reshape(-1) for n in ode.x_names])
            u = np.column_stack([np.asarray(solution.inputs[n], dtype=float).reshape(-1) for n in ode.u_names])
            # the prediction is the model the reference was planned with: the problem's [model.parameters]
            ode.p_default = ode.dae.parameter_vector({k: v for k, v in solution.parameters.items() if k in ode.dae.p_vars})
            model.plant_p = ode.p_default * model.parameter_factor
            limits = None
            if bounds_field is not None:
                declared = load_problem(source).data.get("bounds", {})
                try:
                    limits = np.array([[float(declared.get(n, [-np.inf, np.inf])[i]) for n in ode.u_names] for i in (0, 1)])
                except (TypeError, ValueError, IndexError):
                    raise file.fail("reference.problem", "a problem whose [bounds] of the inputs are [lo, hi] numbers "
                                    f"(else give {bounds_field}.u_lb and {bounds_field}.u_ub)") from None
                limits = np.vstack([np.maximum(limits[0], ode.u_lb), np.minimum(limits[1], ode.u_ub)])  # within the model's declared bounds
    else:
        source = file.data_file("reference.file", ref.file)
        table = read_table(source, "the reference table")
        cols = {n: table.data[:, i] for i, n in enumerate(table.columns)}
        missing = [n for n in ["t", *ode.x_names, *ode.u_names] if n not in cols]
        if missing:
            raise file.fail("reference.file", f"a table with the columns t, {', '.join(ode.x_names + ode.u_names)} (missing {missing[0]!r})")
        t = np.asarray(cols["t"], dtype=float)
        loop_samples(file, period_field, float(t[-1] - t[0]) if t.size else 0.0, ref.settle_time, dt, width)
        x = np.column_stack([cols[n] for n in ode.x_names])
        u = np.column_stack([cols[n] for n in ode.u_names])
        limits = None
    n = int(round(ref.settle_time / dt))
    if n:  # the end held: its state (the robot at rest) and the input that holds it there, not the last (braking) input
        x_end = x[-1] * np.r_[np.ones(3), np.zeros(3)] if robot else x[-1]
        t = np.r_[t, t[-1] + dt * np.arange(1, n + 1)]
        x = np.vstack([x, np.tile(x_end, (n, 1))])
        u = np.vstack([u, np.tile(hold_input(ode.f, x_end, u[-1], ode.p_default), (n, 1))])
    return t, x, u, limits


def input_bounds(file: ProblemFile, section: str, u_lb: list[float] | None, u_ub: list[float] | None,
                 limits: np.ndarray | None, ode: ExplicitODE) -> tuple[np.ndarray, np.ndarray]:
    """The saturation bounds: the file's ``u_lb``/``u_ub``, else the reference problem's, else the model's.

    Parameters
    ----------
    file : ProblemFile
        The file.
    section : str
        The controller section, e.g. ``"mpc"`` (the fields ``<section>.u_lb``, ``<section>.u_ub``).
    u_lb, u_ub : list of float or None
        The file's bounds.
    limits : numpy.ndarray or None
        ``(2, nu)`` the reference problem's (:func:`loop_reference`).
    ode : ExplicitODE
        The model (its declared bounds).

    Returns
    -------
    lb, ub : numpy.ndarray
        ``(nu,)`` each.

    Raises
    ------
    ProblemError
        ``<section>.u_lb`` / ``<section>.u_ub`` of another length than the model's inputs,
        a lower bound above its upper bound (``<section>.u_lb[i]``).
    """
    lb = np.asarray(u_lb, dtype=float) if u_lb is not None else (limits[0] if limits is not None else ode.u_lb)
    ub = np.asarray(u_ub, dtype=float) if u_ub is not None else (limits[1] if limits is not None else ode.u_ub)
    for field, v in ((f"{section}.u_lb", lb), (f"{section}.u_ub", ub)):
        if v.size != ode.nu:
            raise file.fail(field, f"{ode.nu} bounds ({', '.join(ode.u_names)})", v.tolist())
    crossed = np.flatnonzero(~(lb <= ub))
    if crossed.size:
        j = int(crossed[0])
        raise file.fail(f"{section}.u_lb[{j}]", f"a lower bound <= the upper bound {float(ub[j]):g} ({ode.u_names[j]})", float(lb[j]))
    return lb, ub


def loop_setup(file: ProblemFile, name: str, controller: Any, model: LoopModel, check: CheckSection, dt: float) -> LoopSetup:
    """The closed loop of ``[check]`` around a built controller.

    Parameters
    ----------
    file : ProblemFile
        The file.
    name : str
        Controller name.
    controller : Any
        The controller (``t0``, ``dt``, ``length``, ``x_ref``, ``u_ref``, ``u_lb``, ``u_ub``).
    model : LoopModel
        Its model and the plant.
    check : CheckSection
        The file's ``[check]``.
    dt : float
        Loop period [s].

    Returns
    -------
    LoopSetup
        The plant: the mismatched model's ``check.plant_method`` step (default RK4, 4 substeps per period), or with
        ``compliance`` the tool structure of Dressler (2012), eq. 6.14
        (:func:`~gtmodel.estimation.closed_loop.controller_loop.compliant_plant`).

    Notes
    -----
    The ``[check]`` fields that depend on the model (lengths, names, ``compliance``) are
    checked by :func:`loop_model`, before the reference is solved.
    """
    ode, c = model.ode, check
    names_x = list(ode.x_names)
    xs = controller.x_ref
    loop = dict(u_lb=controller.u_lb, u_ub=controller.u_ub, noise_std=np.asarray(c.noise or np.zeros(ode.nx), dtype=float),
                disturbance=np.asarray(c.disturbance, dtype=float) if c.disturbance else None, disturbance_time=c.disturbance_time,
                delay=c.delay, seed=c.seed, error_states=[names_x.index(s) for s in c.error_states] or None)
    grid = controller.t0 + controller.dt * np.arange(controller.length)
    plant_step, plant_x0 = model.plant.step(dt, c.plant_method, substeps=c.plant_substeps), xs[0].copy()
    if c.compliance:
        plant_step, loop["output"], loop["measured"] = compliant_plant(model.plant, dt=dt)
        plant_x0 = np.r_[xs[0], np.zeros(4)]
    return LoopSetup(name=name, controller=controller, plant_step=plant_step, plant_p=model.plant_p,
                     t=grid, x_ref=xs, u_ref=controller.u_ref, loop=loop, plant_x0=plant_x0,
                     max_ratio=c.max_ratio, max_step_time=c.max_step_time)


class LoopFile(Section):
    """The tables every loop-controller file has; each kind adds its controller's table
    (:class:`~gtmodel.problems.mpc_file.MPCFile`, :class:`~gtmodel.problems.tracking_file.TrackingFile`).

    Parameters
    ----------
    name : str
        Name of the controller (the C prefix is ``gt_<name>``).
    description : str
        Free text.
    reference : ReferenceSection
        ``[reference]``.
    check : CheckSection
        ``[check]``.
    """

    name: Identifier
    description: str = ""
    reference: ReferenceSection
    check: CheckSection = CheckSection()


def read_loop_file(path: str | Path, kind: type[LoopFile], what: str) -> tuple[Any, ProblemFile]:
    """Read and validate a loop-controller file (unknown fields refused).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.
    kind : type
        A :class:`LoopFile` subclass.
    what : str
        The kind of file, for messages (``"MPC file"``).

    Returns
    -------
    doc : LoopFile
        The validated document.
    file : ProblemFile
        The file, for errors naming it and for relative references.

    Raises
    ------
    ProblemError
        Unreadable TOML, an unknown or invalid field (naming the file and the field: a
        number not finite or out of its range, a ``name`` that is not a C identifier),
        neither or both of ``reference.problem`` and ``reference.file``,
        ``reference.overrides`` with ``reference.file``.
    """
    path = Path(path)
    data = read_toml(path, ProblemError, what)
    try:
        doc = kind.model_validate(dict(data))
    except ValidationError as exc:
        raise problem_error(path, exc, kind) from None
    file, ref = ProblemFile(path), doc.reference
    if (ref.problem is None) == (ref.file is None):
        raise file.fail("reference", "exactly one of reference.problem (a problem file solved first) and reference.file (a CSV table)")
    if ref.file is not None and ref.overrides:
        raise file.fail("reference.overrides", "no overrides with reference.file (they replace fields of a reference.problem; "
                                               "a table is used as it is)", ref.overrides)
    return doc, file


@dataclass
class LoopInputs:
    """What every controller kind builds from its file before the controller itself.

    Parameters
    ----------
    model : LoopModel
        The controller's model and the plant's.
    Q, R, Qf : numpy.ndarray or None
        Diagonals of the weights by the file's tables (None: the controller's default).
    t : numpy.ndarray
        ``(M,)`` reference times [s].
    x_ref, u_ref : numpy.ndarray
        ``(M, nx)``, ``(M, nu)`` the reference.
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` saturation bounds (:func:`input_bounds`).
    """

    model: LoopModel
    Q: np.ndarray | None
    R: np.ndarray | None
    Qf: np.ndarray | None
    t: np.ndarray
    x_ref: np.ndarray
    u_ref: np.ndarray
    u_lb: np.ndarray
    u_ub: np.ndarray


def loop_inputs(file: ProblemFile, doc: LoopFile, section: str, per_sample: Callable[[ExplicitODE], int] | None = None,
                before_reference: Callable[[LoopModel], None] | None = None) -> LoopInputs:
    """The model, weights, reference and input bounds of a controller's table ``section``.

    Parameters
    ----------
    file : ProblemFile
        The file.
    doc : LoopFile
        Its document; ``getattr(doc, section)`` has ``model``, ``period``,
        ``state_weights``, ``input_weights``, ``terminal_weights``, ``u_lb``, ``u_ub``.
    section : str
        The controller's table (``"mpc"``, ``"controller"``).
    per_sample : callable, optional
        ``per_sample(ode) -> int``: numbers of each reference sample in the generated C
        (default ``nx + nu``), for :func:`loop_samples`.
    before_reference : callable, optional
        ``before_reference(model)``, called once the model is known and before the
        reference is solved (a controller's own size estimate).

    Returns
    -------
    LoopInputs

    Raises
    ------
    ProblemError
        Naming the file and the field: the model, an unknown variable in a weight table,
        too many loop periods (:func:`loop_samples`: the settling hold before the reference
        is solved, the whole reference once its length is known), the reference
        (:func:`loop_reference`), bounds of the wrong length or crossed.
    """
    sec = getattr(doc, section)
    model = loop_model(file, f"{section}.model", sec.model, doc.check)
    ode = model.ode
    width = per_sample(ode) if per_sample is not None else ode.nx + ode.nu
    loop_samples(file, f"{section}.period", 0.0, doc.reference.settle_time, sec.period, width)
    input_bounds(file, section, sec.u_lb, sec.u_ub, None, ode)  # the file's bounds against the model's, before the reference is solved
    if before_reference is not None:
        before_reference(model)
    names_x, names_u = list(ode.x_names), list(ode.u_names)
    Q = weight_diagonal(file, f"{section}.state_weights", sec.state_weights, names_x)
    R = weight_diagonal(file, f"{section}.input_weights", sec.input_weights, names_u)
    Qf = weight_diagonal(file, f"{section}.terminal_weights", sec.terminal_weights, names_x)
    t, x_ref, u_ref, limits = loop_reference(file, doc.reference, model, sec.period,
                                             bounds_field=None if sec.u_lb is not None and sec.u_ub is not None else section,
                                             period_field=f"{section}.period", per_sample=width)
    u_lb, u_ub = input_bounds(file, section, sec.u_lb, sec.u_ub, limits, ode)
    return LoopInputs(model=model, Q=Q, R=R, Qf=Qf, t=t, x_ref=x_ref, u_ref=u_ref, u_lb=u_lb, u_ub=u_ub)
