"""What every loop-controller file shares: the model, ``[reference]``, ``[check]``, the plant and the one reader.

A loop-controller file (the MPC file of :mod:`gtmodel.problems.mpc_file`, the tracking
controller file of :mod:`gtmodel.problems.tracking_file`) is a declared kind
(:data:`gtmodel.problems.registry.LOOP_KINDS`, its light schema in
:mod:`gtmodel.problems.kinds.schemas`, ``gtmodel schema --list``): a controller section of
its own and these two tables (:mod:`gtmodel.problems.kinds.schemas.loop`), validated on
load by :func:`read_loop_file` (pydantic, unknown fields refused; every error names the
file and the field, the CLI exits with 2):

``[reference]``
    The motion tracked: ``problem`` (a ``point_to_point`` problem file of the robot, or an
    ``optimal_control`` or ``optimica`` problem file of the user's model, solved first; ``overrides`` its
    dotted fields, e.g. a tighter force limit for the plan than the actuators' bounds; the
    default input bounds are that problem's without the overrides) or ``file`` (a CSV table
    with ``t`` and the model's state and input names, e.g. a result folder's
    ``trajectories.csv`` as written: its ``point`` column and repeated times are read as such,
    its ``summary.json`` gives the solve's status, parameters and bounds); ``settle_time`` [s]
    the end held: its state (the robot at rest) with the input that holds it
    (:func:`~gtmodel.control.reference.hold_input`); ``accept_unverified`` (default false)
    takes a reference whose verification failed or was skipped, which the check's summary
    and verdict repeat (:mod:`gtmodel.problems.loop_bounds`). The declared bounds of the
    model and the reference (states, inputs, algebraic variables and outputs) are carried
    into the controller unless its file overrides them; an input bound declared nowhere is
    named in the summary.
``[check]``
    The closed loop of ``--check`` (:mod:`gtmodel.estimation.closed_loop.controller_loop`):
    ``mass_factor``, ``friction_factor`` (the robot plant; a user model: ``parameter_factor``
    on every parameter, ``parameter_factors`` a table by parameter name replacing it for
    those), ``compliance`` (the robot: the tool structure of eq. 6.14 in the
    plant, the tool position tracked, the controller measuring ``T``, ``T_dot``), ``noise``
    (one standard deviation per state), ``disturbance`` and ``disturbance_time``, ``delay``
    (samples), ``seed``, ``error_states``, ``plant_method`` / ``plant_substeps``, and the
    acceptance: ``max_ratio`` (the RMS ratio to the feedforward below it, default 1) and
    ``max_step_time`` (the 99th-percentile step time at most it, default the period); every
    declared bound is counted on the plant (:func:`gtmodel.problems.loop_check.plant_bounds`).

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

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import casadi as ca
import numpy as np
from pydantic import ValidationError

from gtmodel._tables import read_table
from gtmodel._toml import read_toml
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.estimation.closed_loop.controller_loop import compliant_plant, mismatched_robot
from gtmodel.control.problem import substep_states
from gtmodel.control.reference import hold_input
from gtmodel.modeling import ExplicitODE, explicit_ode
from gtmodel.modeling.simulation.step_stability import step_stability
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.loop_notes import controller_notes, row_points_note
from gtmodel.problems.loop_bounds import DeclaredBounds, input_limits, accept_reference, dae_bounds, input_bounds, summary_bounds
from gtmodel.problems.plan_cache import planned
from gtmodel.problems.loop_limits import (MAX_LOOP_SAMPLES, MAX_MAGNITUDE, MAX_PERIOD_S, MAX_TABLE_NUMBERS, MAX_WEIGHT, MIN_PERIOD_S,
                                          Bounds, Period, StateBounds, Weights, loop_samples)
from gtmodel.problems.references import robot_parameters
from gtmodel.problems.registry import MODEL_OCP_KINDS, get_loop_kind
from gtmodel.problems.run import load_problem, solve_problem
from gtmodel.problems.kinds.schemas.loop import CheckSection, LoopFile, ReferenceSection
from gtmodel.problems.schema import problem_error
from gtmodel.problems.user_model import load_user_model, split_model_reference
from gtmodel.robots.model import gantry_tau_model
from gtmodel.trajectory.point_to_point import solve_point_to_point

__all__ = ["RESULT_TABLE", "LoopFile", "LoopInputs", "LoopModel", "LoopReference", "LoopSetup", "read_loop_file", "loop_inputs", "loop_model", "weight_diagonal",
           "loop_reference", "input_bounds", "loop_setup", "loop_samples", "MIN_PERIOD_S", "MAX_PERIOD_S", "MAX_WEIGHT",
           "MAX_MAGNITUDE", "MAX_LOOP_SAMPLES", "MAX_TABLE_NUMBERS", "Period", "Weights", "Bounds", "StateBounds", "ReferenceSection", "CheckSection"]

#: The table of an ``optimal_control`` result folder (``[reference] file`` may name it as written).
RESULT_TABLE = "trajectories.csv"
_TCP_STATES = ("x", "y", "z", "xd", "yd", "zd")
_TCP_INPUTS = ("tau1", "tau2", "tau3")


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
        The controller (an :class:`~gtmodel.control.mpc.MPCController` or a
        :class:`~gtmodel.control.tracking.TrackingController`: ``t0``, ``dt``,
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
    bounds : DeclaredBounds or None, optional
        The declared bounds the check counts on the plant (states, inputs, algebraic variables
        and outputs; :func:`loop_reference`); None: the input bounds alone.
    names : tuple of list of str, optional
        ``(x_names, u_names, y_names)`` of the plant (the columns of its states, inputs and outputs).
    outputs : casadi.Function or None, optional
        ``h(x, u, p) -> y`` of the plant (its algebraic variables and outputs, for their bounds;
        None: none counted).
    notes : list of str, optional
        What the summary and the verdict repeat (an unverified reference accepted, unknown bounds).
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
    bounds: DeclaredBounds | None = None
    names: tuple = ((), (), ())
    outputs: Any = None
    notes: list[str] = field(default_factory=list)


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


@dataclass
class LoopReference:
    """The reference of ``[reference]`` (:func:`loop_reference`).

    Parameters
    ----------
    t : numpy.ndarray
        ``(M,)`` times [s].
    x, u : numpy.ndarray
        ``(M, nx)``, ``(M, nu)`` the states and inputs in the model's order (the settling hold included).
    limits : numpy.ndarray or None
        ``(2, nu)`` the declared input bounds (the reference problem's, without the overrides, within
        the model's; a result folder's; the model's), None when ``bounds_field`` is None for a user model.
    bounds : DeclaredBounds
        Every declared bound of the model's variables (states, inputs, algebraic variables and
        outputs), :mod:`gtmodel.problems.loop_bounds`.
    notes : list of str
        What the controller's summary repeats (an unverified reference accepted; where the bounds come from).
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    limits: np.ndarray | None
    bounds: DeclaredBounds
    notes: list[str]


def _result_summary(table: Path) -> dict[str, Any] | None:
    """The ``summary.json`` beside a table when the table is an ``optimal_control`` result folder's ``trajectories.csv``."""
    summary_file = table.parent / "summary.json"
    if table.name != RESULT_TABLE or not summary_file.is_file():
        return None
    try:
        summary = json.loads(summary_file.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return summary if isinstance(summary, dict) and summary.get("kind") in MODEL_OCP_KINDS else None


def loop_reference(file: ProblemFile, ref: ReferenceSection, model: LoopModel, dt: float, bounds_field: str | None = None,
                   period_field: str = "period", per_sample: int | None = None, replan: bool = False) -> LoopReference:
    """The reference motion of ``[reference]``, with the settling hold, its declared bounds and whether it was verified.

    A reference problem solved here, or a result folder's ``trajectories.csv`` (as gtmodel
    writes it: the text column ``point``, a time written twice at an element boundary), is
    taken when verified, or unverified through ``[reference] accept_unverified = true``
    (:func:`~gtmodel.problems.loop_bounds.accept_reference`); a result folder's table also
    gives the solve's parameter values (the prediction's) and the bounds its ``summary.json``
    records.

    Parameters
    ----------
    file : ProblemFile
        The file.
    ref : ReferenceSection
        Its ``[reference]``.
    model : LoopModel
        The controller's model (its parameter defaults set to the reference's).
    dt : float
        Loop period [s] (of the robot's sampled trajectory and the settling hold).
    bounds_field : str, optional
        The controller section whose ``u_lb``, ``u_ub`` are needed from the declared bounds
        (a user model), e.g. ``"mpc"``; None when both are given.
    period_field : str, optional
        The period's dotted field, named when the reference has too many periods
        (:func:`loop_samples`, checked once its length is known, before it is sampled).
    per_sample : int, optional
        Numbers of each sample in the generated C (default ``nx + nu``).
    replan : bool, optional
        Solve a user model's reference problem even when its plan is cached (:mod:`~gtmodel.problems.plan_cache`).

    Returns
    -------
    LoopReference

    Raises
    ------
    ProblemError
        Naming ``reference``, ``reference.problem`` or ``reference.file``: neither or both,
        a problem of the wrong kind, one that does not solve, an unverified one without
        ``accept_unverified``, a table without the columns; naming ``period_field``: too many
        periods (:func:`loop_samples`).
    """
    ode, robot = model.ode, model.robot
    width = ode.nx + ode.nu if per_sample is None else per_sample
    names = list(ode.x_names) + list(ode.u_names) + list(ode.y_names)
    notes: list[str] = []
    if (ref.problem is None) == (ref.file is None):
        raise file.fail("reference", "exactly one of reference.problem (a problem file solved first) and reference.file (a CSV table)")
    if ref.problem is not None:
        # a problem file the user wrote, resolved as a model file is (relative to this file): the shipped loop-controller
        # files in codegen/ name their references in problems/; its data files stay confined when it loads
        source = Path(file.reference("reference.problem", ref.problem))
        try:
            loaded = load_problem(source, dict(ref.overrides))
        except GtModelError as exc:
            raise file.wrap("reference.problem", exc) from None
        wanted = "point_to_point" if robot else "optimal_control"
        if loaded.kind != wanted and (robot or loaded.kind not in MODEL_OCP_KINDS):
            raise file.fail("reference.problem", f"a problem file of kind {wanted} (for this model)", loaded.kind)
        solution = solve_point_to_point(loaded.declaration) if robot else planned(loaded, lambda: solve_problem(loaded), replan,
                                                                                  [*ode.x_names, *ode.u_names])
        if robot:
            if not solution.success:
                raise file.fail("reference.problem", f"a problem that solves (status {solution.status})")
            loop_samples(file, period_field, float(solution.result.final_time - solution.result.t[0]), ref.settle_time, dt, width)
            tr = solution.trajectory(dt)
            bound = np.asarray(load_problem(source).declaration.force_limit, dtype=float)
            t = tr["t"]
            x = np.column_stack([tr[c] for c in _TCP_STATES])
            u = np.column_stack([tr[c] for c in _TCP_INPUTS])
            limits = np.vstack([-bound, bound])
            bounds = DeclaredBounds(source="the reference problem's force limits")
            for j, n in enumerate(ode.u_names):
                bounds.add(n, -bound[j], bound[j])
        else:
            note = accept_reference(file, "reference.problem", solution.status, getattr(solution, "verification", None), ref.accept_unverified)
            notes += [note] if note else []
            loop_samples(file, period_field, float(solution.t[-1] - solution.t[0]), ref.settle_time, dt, width)
            t = np.asarray(solution.t, dtype=float).reshape(-1)
            x = np.column_stack([np.asarray(solution.states[n], dtype=float).reshape(-1) for n in ode.x_names])
            u = np.column_stack([np.asarray(solution.inputs[n], dtype=float).reshape(-1) for n in ode.u_names])
            # the prediction is the model the reference was planned with: the problem's [model.parameters]
            ode.p_default = ode.dae.parameter_vector({k: v for k, v in solution.parameters.items() if k in ode.dae.p_vars})
            model.plant_p = ode.p_default * model.parameter_factor
            opt = load_problem(source).declaration.optimization  # as the file declares it: without the plan's overrides
            bounds = dae_bounds(opt.flat(), opt, source="the reference problem's [bounds] over the model's").restricted(names)
            limits = input_limits(bounds, ode)
    else:
        source = file.data_file("reference.file", ref.file)
        table = read_table(source, "the reference table", text_columns=("point",))
        cols = {n: table.data[:, i] for i, n in enumerate(table.columns)}
        missing = [n for n in ["t", *ode.x_names, *ode.u_names] if n not in cols]
        if missing:
            raise file.fail("reference.file", f"a table with the columns t, {', '.join(ode.x_names + ode.u_names)} (missing {missing[0]!r})")
        t = np.asarray(cols["t"], dtype=float)
        loop_samples(file, period_field, float(t[-1] - t[0]) if t.size else 0.0, ref.settle_time, dt, width)
        keep = np.append(np.diff(t) > 0, True) if t.size else np.zeros(0, bool)  # a mesh time written twice (element boundary): the later row
        t = t[keep]
        x = np.column_stack([cols[n][keep] for n in ode.x_names])
        u = np.column_stack([cols[n][keep] for n in ode.u_names])
        bounds = dae_bounds(ode.dae)
        summary = _result_summary(source)
        if summary is not None:  # a result folder's own table: its solve's verification, parameters and bounds
            note = accept_reference(file, "reference.file", summary.get("status", ""), summary.get("verification"), ref.accept_unverified)
            notes += [note] if note else []
            values = {k: v for k, v in (summary.get("model_parameters") or {}).items() if k in ode.dae.p_vars}
            if values and not robot:
                ode.p_default = ode.dae.parameter_vector(values)
                model.plant_p = ode.p_default * model.parameter_factor
            recorded = summary_bounds(summary, source=f"the result's summary.json ({source.parent.name})")
            for n in recorded.names:
                bounds.add(n, recorded.lb[n], recorded.ub[n])
            bounds.source = recorded.source if recorded.names else bounds.source
        else:
            notes.append(f"reference: the table {source.name} (not a result folder's: no verification to check)")
        bounds = bounds.restricted(names)
        limits = input_limits(bounds, ode)
    unknown = bounds.unknown(list(ode.u_names))
    if unknown and bounds_field is not None:
        notes.append(f"input bounds unknown: {', '.join(unknown)} (declared by neither the model nor the reference; "
                     f"give {bounds_field}.u_lb / {bounds_field}.u_ub): their violations are not counted")
    n = int(round(ref.settle_time / dt))
    if n:  # the end held: its state (the robot at rest) and the input that holds it there, not the last (braking) input,
        # from just after the end on (a loop sample after the end reads the hold, not the plan's last input interpolated
        # towards it: a minimum-time drive's final voltage spike held a period drove the belt drive's current to 9.7 A of 8)
        x_end = x[-1] * np.r_[np.ones(3), np.zeros(3)] if robot else x[-1]
        t = np.r_[t, t[-1] + 1e-9 * dt, t[-1] + dt * np.arange(1, n + 1)]
        x = np.vstack([x, np.tile(x_end, (n + 1, 1))])
        u = np.vstack([u, np.tile(hold_input(ode.f, x_end, u[-1], ode.p_default), (n + 1, 1))])
    return LoopReference(t=t, x=x, u=u, limits=limits, bounds=bounds, notes=notes)


def loop_setup(file: ProblemFile, name: str, controller: Any, model: LoopModel, check: CheckSection, dt: float,
               bounds: DeclaredBounds | None = None, notes: list[str] | None = None) -> LoopSetup:
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
    bounds : DeclaredBounds, optional
        The declared bounds the check counts on the plant (:attr:`LoopReference.bounds`);
        default the controller's input bounds alone.
    notes : list of str, optional
        What the summary and the verdict repeat (:attr:`LoopReference.notes`).

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
                delay=c.delay, seed=c.seed, error_states=[names_x.index(s) for s in c.error_states] or None, state_names=names_x)
    if c.delay and getattr(controller, "u_initial", None) is not None:  # before the first computed input arrives: the C memory's u_last
        loop["u_before"] = np.asarray(controller.u_initial, dtype=float)
    grid = controller.t0 + controller.dt * np.arange(controller.length)
    plant_step, plant_x0 = model.plant.step(dt, c.plant_method, substeps=c.plant_substeps), xs[0].copy()
    if not c.compliance and model.plant.nx == xs.shape[1]:
        # the plant's own step must follow the mismatched model: an unstable RK4 plant diverges (or decays wrongly) under
        # any controller, and the verdict would blame the controller (a held-out drive with L/R = 0.2 ms, issue 49)
        stability = step_stability(model.plant.f, dt, c.plant_method, c.plant_substeps, xs, controller.u_ref, model.plant_p, t=grid)
        if stability is not None and not stability.stable:
            raise file.fail("check.plant_substeps", "a stable plant step: " + stability.message(
                "the check's plant step (plant_method, plant_substeps)", "plant_substeps = {n}"), c.plant_substeps)
    if c.compliance:
        plant_step, loop["output"], loop["measured"] = compliant_plant(model.plant, dt=dt)
        plant_x0 = np.r_[xs[0], np.zeros(4)]
    elif c.plant_substeps > 1:  # its states at the step's substeps: the declared bounds counted between the samples too
        loop["interior"] = _interior_states(model.plant, dt, c.plant_method, c.plant_substeps)
        notes = list(notes or []) + row_points_note(controller, c.plant_substeps)
    counted = DeclaredBounds(source="the controller's input bounds") if bounds is None else bounds.restricted(bounds.names)
    for j, n in enumerate(ode.u_names):  # an input without a declared bound: the controller's saturation
        if n not in counted.lb:
            counted.add(n, controller.u_lb[j], controller.u_ub[j])
    notes = list(notes or []) + controller_notes(controller)
    outputs = None
    if not c.compliance and ode.y_names and any(n in counted.lb for n in ode.y_names):
        try:
            outputs = model.plant.h
        except GtModelError:  # a model of the time: its outputs are not counted
            outputs = None
    return LoopSetup(name=name, controller=controller, plant_step=plant_step, plant_p=model.plant_p,
                     t=grid, x_ref=xs, u_ref=controller.u_ref, loop=loop, plant_x0=plant_x0,
                     max_ratio=c.max_ratio, max_step_time=c.max_step_time, bounds=counted,
                     names=(list(ode.x_names), list(ode.u_names), list(ode.y_names)), outputs=outputs, notes=list(notes or []))


def _interior_states(plant: ExplicitODE, dt: float, method: str, substeps: int) -> ca.Function:
    """``interior(x, u, p) -> (nx, substeps - 1)``: the plant step's states after each of its substeps but the last.

    A held-out drive's MPC passed its check at 5.028 A of 5 (0.57 %) counted at the 4 ms samples, and reached 5.087 A
    (1.74 %) between them (issue 49's loop trial): the plant's own substeps are where it is between the samples.
    """
    states = substep_states(plant, dt, method, substeps)
    x, u, p = ca.SX.sym("x", plant.nx), ca.SX.sym("u", plant.nu), ca.SX.sym("p", plant.np)
    return ca.Function("interior", [x, u, p], [states(x, u, p)[:, :-1]], ["x", "u", "p"], ["x_interior"])


def read_loop_file(path: str | Path, kind: type[LoopFile] | str, what: str | None = None) -> tuple[Any, ProblemFile]:
    """Read and validate a loop-controller file (unknown fields refused): the one reader of every loop kind.

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.
    kind : str or type
        A loop-controller file kind of :data:`gtmodel.problems.registry.LOOP_KINDS`
        (``"mpc"``, ``"tracking_controller"``: its declared schema), or a :class:`LoopFile`
        subclass.
    what : str, optional
        The kind of file, for messages (default the declared kind's, ``"MPC file"``).

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
    if isinstance(kind, str):
        declared = get_loop_kind(kind)
        kind, what = declared.schema_class(), what or declared.what
    data = read_toml(path, ProblemError, what or "loop-controller file")
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
    bounds : DeclaredBounds
        Every declared bound (:attr:`LoopReference.bounds`).
    notes : list of str
        What the summary repeats (:attr:`LoopReference.notes`).
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
    bounds: DeclaredBounds = field(default_factory=DeclaredBounds)
    notes: list[str] = field(default_factory=list)


def loop_inputs(file: ProblemFile, doc: LoopFile, section: str, per_sample: Callable[[ExplicitODE], int] | None = None,
                before_reference: Callable[[LoopModel], None] | None = None, replan: bool = False) -> LoopInputs:
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
    replan : bool, optional
        Solve the reference problem even when its plan is cached (:func:`loop_reference`).

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
    ref = loop_reference(file, doc.reference, model, sec.period, bounds_field=None if sec.u_lb is not None and sec.u_ub is not None else section,
                         period_field=f"{section}.period", per_sample=width, replan=replan)
    u_lb, u_ub = input_bounds(file, section, sec.u_lb, sec.u_ub, ref.limits, ode)
    return LoopInputs(model=model, Q=Q, R=R, Qf=Qf, t=ref.t, x_ref=ref.x, u_ref=ref.u, u_lb=u_lb, u_ub=u_ub, bounds=ref.bounds, notes=ref.notes)
