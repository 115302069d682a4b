"""An MPC file: a declared ``[mpc]`` for ``gtmodel codegen --mpc FILE --out DIR [--check]``.

A TOML file with three tables, validated on load (pydantic, unknown fields refused; every
error names the file and the field, the CLI exits with 2):

``[mpc]``
    ``model`` (a Gantry-Tau parameter set such as ``"L1"``, its rigid-body dynamics with
    friction in TCP states ``T``, ``T_dot`` and input ``tau`` (:func:`gtmodel.robots.model.gantry_tau_model`),
    or ``"FILE.py:Class"`` a user's model), ``horizon`` (periods, >= 1), ``period`` [s]
    (> 0, default the 4 ms loop), ``blocks`` (input blocks, a divisor of the horizon;
    default the horizon), ``sqp_iterations`` (default 1: the real-time iteration),
    ``solver`` (``"sqpmethod"``: CasADi's SQP with ``qrqp``), ``method`` (prediction step),
    ``state_weights`` / ``input_weights`` / ``terminal_weights`` (tables by variable name:
    an unknown variable is refused), ``u_lb`` / ``u_ub`` (default: the reference problem's
    force limits, else the model's declared bounds).
``[reference]``
    The motion tracked: ``problem`` (a ``point_to_point`` problem file of the robot, or an
    ``optimal_control`` problem file of the user's model, solved first; ``overrides`` its
    dotted fields, e.g. a tighter force limit for the plan than the actuators' bounds; the
    default input bounds are that problem's without the overrides) or ``file`` (a CSV table with ``t`` and the model's state and
    input names); ``settle_time`` [s] the last sample held.
``[check]``
    The closed loop of ``--check`` (:mod:`gtmodel.estimation.closed_loop.controller_loop`):
    ``mass_factor``, ``friction_factor`` (the robot plant; a user model: ``parameter_factor``
    on every parameter), ``compliance`` (the robot: the tool structure of eq. 6.14 in the
    plant, the tool position tracked, the controller measuring ``T``, ``T_dot``), ``noise`` (one standard deviation per state), ``disturbance`` and
    ``disturbance_time``, ``delay`` (samples), ``seed``, ``error_states``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import Field, ValidationError

from gtmodel._tables import read_table
from gtmodel._toml import read_toml
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.estimation.closed_loop.controller_loop import compliant_plant, mismatched_robot
from gtmodel.estimation.mpc import MPC_METHODS, MPC_SOLVERS, MPCController, mpc_controller
from gtmodel.modeling import explicit_ode
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.references import robot_parameters
from gtmodel.problems.run import load_problem, solve_problem
from gtmodel.problems.user_model import load_user_model, split_model_reference
from gtmodel.robots.model import gantry_tau_model
from gtmodel.trajectory.point_to_point import solve_point_to_point
from gtmodel.problems.schema import NonEmptyText, Section, choice, number, problem_error

__all__ = ["MPCFile", "MPCSetup", "load_mpc_file"]

#: Longest horizon accepted [periods].
MAX_HORIZON = 1000
_TCP_STATES = ("x", "y", "z", "xd", "yd", "zd")
_TCP_INPUTS = ("tau1", "tau2", "tau3")


class MPCSection(Section):
    """``[mpc]``: the model, the horizon and the weights."""

    model: NonEmptyText = Field(description='a robot parameter set ("L1") or a user model "FILE.py:Class"')
    horizon: int = Field(ge=1, le=MAX_HORIZON, strict=True, description="prediction horizon [periods]")
    period: number(gt=0, le=1.0, unit="s", description="loop period = prediction step") = LOOP_PERIOD_S
    blocks: int | None = Field(default=None, ge=1, strict=True, description="input blocks over the horizon (a divisor; default the horizon)")
    sqp_iterations: int = Field(default=1, ge=1, le=100, strict=True, description="SQP iterations per period (1: real-time iteration)")
    solver: choice(*MPC_SOLVERS, description="NLP solver of the step (qrqp QPs)") = "sqpmethod"
    method: choice(*MPC_METHODS, description="prediction step over one period (euler: cheapest; implicit_euler, radau2: stiff models)") = "rk4"
    substeps: int = Field(default=1, ge=1, le=100, strict=True, description="steps of the method per period")
    state_weights: dict[str, float] = Field(default_factory=dict, description="diagonal of Q by state name (default: Bryson's rule)")
    input_weights: dict[str, float] = Field(default_factory=dict, description="diagonal of R by input name")
    terminal_weights: dict[str, float] = Field(default_factory=dict, description="diagonal of Qf by state name (default Q)")
    u_lb: list[float] | None = Field(default=None, description="input lower bounds")
    u_ub: list[float] | None = Field(default=None, description="input upper bounds")


class ReferenceSection(Section):
    """``[reference]``: the motion tracked (exactly one of ``problem`` and ``file``)."""

    problem: NonEmptyText | None = Field(default=None, description="a point_to_point (robot) or optimal_control (user model) problem file, relative to this file, solved first")
    overrides: dict[str, Any] = Field(default_factory=dict, description="dotted fields of that problem replaced, e.g. 'limits.force'")
    file: NonEmptyText | None = Field(default=None, description="a CSV table: t and the model's state and input names")
    settle_time: number(ge=0, le=60.0, unit="s", description="the last sample held this long") = 0.5


class CheckSection(Section):
    """``[check]``: the closed loop of ``--check``."""

    mass_factor: number(gt=0, le=10.0, description="plant masses / model masses (robot)") = 1.1
    friction_factor: number(gt=0, le=10.0, description="plant friction / model friction (robot)") = 1.1
    parameter_factor: number(gt=0, le=10.0, description="plant parameters / model parameters (user model)") = 1.1
    noise: list[float] = Field(default_factory=list, description="measurement noise standard deviation per state (default none)")
    disturbance: list[float] = Field(default_factory=list, description="input step disturbance (default none)")
    disturbance_time: number(ge=0, le=1e4, unit="s", description="time of the step disturbance") = 0.0
    delay: int = Field(default=1, ge=0, le=100, strict=True, description="input delay [samples]")
    seed: int = Field(default=0, ge=0, strict=True)
    compliance: bool = Field(default=False, strict=True, description="robot: the tool structure of eq. 6.14 (7.4 / 11.5 Hz modes) in the plant")
    error_states: list[str] = Field(default_factory=list, description="states summarised by the tracking error (default all)")


class MPCFile(Section):
    """An MPC file (see the module docstring).

    Parameters
    ----------
    name : str
        Name of the controller (the C prefix is ``gt_<name>``).
    description : str
        Free text.
    mpc : MPCSection
        ``[mpc]``.
    reference : ReferenceSection
        ``[reference]``.
    check : CheckSection
        ``[check]``.
    """

    name: NonEmptyText
    description: str = ""
    mpc: MPCSection
    reference: ReferenceSection
    check: CheckSection = CheckSection()


@dataclass
class MPCSetup:
    """What an MPC file builds: the controller, the plant of the check and the loop options.

    Parameters
    ----------
    name : str
        Controller name.
    controller : MPCController
        The MPC.
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
    """

    name: str
    controller: MPCController
    plant_step: Any
    plant_p: np.ndarray
    t: np.ndarray
    x_ref: np.ndarray
    u_ref: np.ndarray
    loop: dict
    plant_x0: np.ndarray


def _diag(file: ProblemFile, field: str, weights: dict[str, float], names: list[str]) -> np.ndarray | None:
    if not weights:
        return None
    for key, value in weights.items():
        if key not in names:
            raise file.fail(f"{field}.{key}", f"a variable of the model ({', '.join(names)})", key)
        if not (math.isfinite(value) and value >= 0):
            raise file.fail(f"{field}.{key}", "a finite weight >= 0", value)
    return np.array([float(weights.get(n, 0.0)) for n in names])


def _reference(file: ProblemFile, doc: MPCFile, ode: Any, robot: bool, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
    ref = doc.reference
    if (ref.problem is None) == (ref.file is None):
        raise file.fail("reference", "exactly one of reference.problem (a problem file solved first) and reference.file (a CSV table)")
    if ref.problem is not None:
        # a problem file the user wrote, resolved as a model file is (relative to this file): the shipped MPC
        # files in codegen/mpc/ name their references in problems/; its data files stay confined when it loads
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
            declared = {} if doc.mpc.u_lb is not None and doc.mpc.u_ub is not None else load_problem(source).data.get("bounds", {})
            try:
                limits = np.array([[float(declared.get(n, [-np.inf, np.inf])[i]) for n in ode.u_names] for i in (0, 1)])
            except (TypeError, ValueError, IndexError):
                raise file.fail("reference.problem", "a problem whose [bounds] of the inputs are [lo, hi] numbers "
                                "(else give mpc.u_lb and mpc.u_ub)") from None
            limits = np.vstack([np.maximum(limits[0], ode.u_lb), np.minimum(limits[1], ode.u_ub)])  # within the model's declared bounds
    else:
        source = file.data_file("reference.file", ref.file)
        table = read_table(source, "the reference table")
        cols = {n: table.data[:, i] for i, n in enumerate(table.columns)}
        missing = [n for n in ["t", *ode.x_names, *ode.u_names] if n not in cols]
        if missing:
            raise file.fail("reference.file", f"a table with the columns t, {', '.join(ode.x_names + ode.u_names)} (missing {missing[0]!r})")
        t = np.asarray(cols["t"], dtype=float)
        x = np.column_stack([cols[n] for n in ode.x_names])
        u = np.column_stack([cols[n] for n in ode.u_names])
        limits = None
    n = int(round(ref.settle_time / dt))
    t = np.r_[t, t[-1] + dt * np.arange(1, n + 1)]
    x = np.vstack([x, np.tile(x[-1] * np.r_[np.ones(3), np.zeros(3)] if robot else x[-1], (n, 1))]) if n else x
    u = np.vstack([u, np.tile(u[-1], (n, 1))]) if n else u
    return t, x, u, limits


def load_mpc_file(path: str | Path) -> MPCSetup:
    """Read, validate and build an MPC file (see the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.

    Returns
    -------
    MPCSetup

    Raises
    ------
    ProblemError
        Naming the file and the field: unreadable TOML, an unknown or invalid field, a
        horizon < 1, a period <= 0, an unknown variable in a weight table, blocks that do
        not divide the horizon, a reference that cannot be read or solved.
    """
    path = Path(path)
    data = read_toml(path, ProblemError, "MPC file")
    try:
        doc = MPCFile.model_validate(dict(data))
    except ValidationError as exc:
        raise problem_error(path, exc, MPCFile) from None
    file = ProblemFile(path)
    m = doc.mpc

    robot = ":" not in m.model
    if robot:

        params = robot_parameters(file, "mpc.model", m.model)
        ode = explicit_ode(gantry_tau_model(params, states="tcp"))
        plant = explicit_ode(gantry_tau_model(mismatched_robot(params, doc.check.mass_factor, doc.check.friction_factor), states="tcp"))
        plant_p = plant.p_default
    else:

        model_path, cls = split_model_reference(m.model)
        model_path = Path(file.reference("mpc.model", str(model_path)))  # Python the user runs, as optimal_control's model.file (not a data file)
        try:
            ode = explicit_ode(load_user_model(model_path, cls))
        except GtModelError as exc:
            raise file.wrap("mpc.model", exc) from None
        plant = ode
    names_x, names_u = list(ode.x_names), list(ode.u_names)
    Q = _diag(file, "mpc.state_weights", m.state_weights, names_x)
    R = _diag(file, "mpc.input_weights", m.input_weights, names_u)
    Qf = _diag(file, "mpc.terminal_weights", m.terminal_weights, names_x)
    if m.blocks is not None and m.horizon % m.blocks:
        raise file.fail("mpc.blocks", f"a divisor of the horizon {m.horizon}", m.blocks)
    t, x_ref, u_ref, limits = _reference(file, doc, ode, robot, m.period)
    if not robot:
        plant_p = ode.p_default * doc.check.parameter_factor  # after _reference: the reference problem's parameters
    u_lb = np.asarray(m.u_lb, dtype=float) if m.u_lb is not None else (limits[0] if limits is not None else ode.u_lb)
    u_ub = np.asarray(m.u_ub, dtype=float) if m.u_ub is not None else (limits[1] if limits is not None else ode.u_ub)
    for field, v in (("mpc.u_lb", u_lb), ("mpc.u_ub", u_ub)):
        if v.size != ode.nu:
            raise file.fail(field, f"{ode.nu} bounds ({', '.join(names_u)})", v.tolist())
    try:
        controller = mpc_controller(ode, t, x_ref, u_ref, horizon=m.horizon, dt=m.period, Q=Q, R=R, Qf=Qf, u_lb=u_lb, u_ub=u_ub,
                                    method=m.method, substeps=m.substeps, blocks=m.blocks, sqp_iterations=m.sqp_iterations, solver=m.solver)
    except GtModelError as exc:
        raise file.wrap("mpc", exc) from None
    c = doc.check
    for field, v, size in (("check.noise", c.noise, ode.nx), ("check.disturbance", c.disturbance, ode.nu)):
        if v and len(v) != size:
            raise file.fail(field, f"{size} numbers", v)
    unknown = [s for s in c.error_states if s not in names_x]
    if unknown:
        raise file.fail(f"check.error_states.{unknown[0]}", f"a state of the model ({', '.join(names_x)})", unknown[0])
    xs = controller.x_ref
    loop = dict(u_lb=controller.u_lb, u_ub=controller.u_ub, noise_std=np.asarray(c.noise or np.zeros(ode.nx), dtype=float),
                disturbance=np.asarray(c.disturbance, dtype=float) if c.disturbance else None, disturbance_time=c.disturbance_time,
                delay=c.delay, seed=c.seed, error_states=[names_x.index(s) for s in c.error_states] or None)
    grid = controller.t0 + controller.dt * np.arange(controller.length)
    plant_step, plant_x0 = plant.step(m.period, "rk4", substeps=4), xs[0].copy()
    if c.compliance:
        if not robot:
            raise file.fail("check.compliance", "false for a user model (the tool structure of eq. 6.14 is the robot's)", True)
        plant_step, loop["output"], loop["measured"] = compliant_plant(plant, dt=m.period)
        plant_x0 = np.r_[xs[0], np.zeros(4)]
    return MPCSetup(name=doc.name, controller=controller, plant_step=plant_step, plant_p=plant_p,
                    t=grid, x_ref=xs, u_ref=controller.u_ref, loop=loop, plant_x0=plant_x0)
