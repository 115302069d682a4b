"""An MPC file: a declared ``[mpc]`` for ``gtmodel codegen --mpc FILE --out DIR [--check]``.

A TOML file with three tables, validated on load (pydantic, unknown fields refused; every
error names the file and the field, the CLI exits with 2):

``[mpc]``
    ``model`` (a Gantry-Tau parameter set such as ``"L1"``, its rigid-body dynamics with
    friction in TCP states ``T``, ``T_dot`` and input ``tau`` (:func:`gtmodel.robots.model.gantry_tau_model`),
    or ``"FILE.py:Class"`` a user's model), ``horizon`` (periods, 1 .. 1000; with the
    model's sizes at most :data:`MAX_QP_ENTRIES` entries of the horizon problem,
    :func:`qp_entries`, and at most :data:`MAX_CODE_BYTES` of generated C, :func:`code_bytes`), ``period`` [s] (1e-5 .. 1, default the 4 ms loop), ``blocks``
    (input blocks, a divisor of the horizon; default the horizon), ``sqp_iterations`` (default 1: the real-time iteration),
    ``solver`` (``"sqpmethod"``: single shooting, real-time iterations, QPs by ``qrqp`` or DAQP), ``method`` (prediction step),
    ``state_weights`` / ``input_weights`` / ``terminal_weights`` / ``input_rate_weights`` (tables by variable name:
    an unknown variable is refused; each weight 0 .. 1e12; the last weighs each input's change per period,
    :attr:`gtmodel.control.mpc.MPCController.R_rate`, default :data:`RATE_FACTOR` times the input weights
    with ``solver = "sqpmethod"`` and constraint rows, 0 for every input: none), ``u_lb`` / ``u_ub`` (default: the declared input bounds,
    :mod:`gtmodel.problems.loop_bounds`: the reference problem's force limits or ``[bounds]``
    over the model's, a result folder's recorded ones, else the model's; one declared nowhere is
    named in the summary); the state bounds and path constraints
    on the predicted states (:mod:`gtmodel.control.mpc_constraints`): the reference
    problem's as its file declares them (``problem_constraints``, default true: the states'
    ``[bounds]`` and ``[optimization] constraints`` of an ``optimal_control`` file, the cart
    travel, joint-angle and velocity limits of a ``point_to_point`` one; a table's: the
    declared state bounds), the declared bounds of algebraic variables and outputs as rows of
    the model's ``h(x, u)``, tightened by
    ``state_lb`` / ``state_ub`` (tables by state name), soft by default (an exact penalty
    with slacks, weight ``constraint_weight``) or ``hard_constraints = true``, on every
    predicted state or every ``constraint_every``-th and the last, and at the states after the
    prediction's substeps inside those periods (``constraint_substeps``, default true); ``disturbance_gain``
    (default 0; in ``[0, 1]``: offset-free MPC, an input disturbance estimated from the
    one-period prediction error, :attr:`gtmodel.control.mpc.MPCController.disturbance_gain`); ``constraint_backoff``
    (default on with rows: the rows tightened by that error, :func:`gtmodel.control.mpc_memory.row_backoff`).
``[reference]``, ``[check]``
    The motion tracked and the closed loop of ``--check``: the tables shared by every
    loop-controller file, :mod:`gtmodel.problems.loop_file`.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
from gtmodel.errors import GtModelError
from gtmodel.control.mpc import mpc_controller
from gtmodel.control.mpc_constraints import problem_constraints
from gtmodel.control.problem import substep_states
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.loop_bounds import DeclaredBounds
from gtmodel.problems.kinds.schemas.mpc import MAX_HORIZON, RATE_FACTOR, MPCFile, MPCSection
from gtmodel.problems.loop_filter import with_measurement_filter
from gtmodel.problems.loop_file import LoopModel, LoopSetup, loop_inputs, loop_setup, read_loop_file, weight_diagonal
from gtmodel.problems.run import load_problem
from gtmodel.trajectory.point_to_point import build_optimization

__all__ = ["MPCFile", "MPCSection", "MPCSetup", "load_mpc_file", "qp_entries", "code_bytes", "MAX_HORIZON", "MAX_QP_ENTRIES",
           "MAX_CODE_BYTES", "RATE_FACTOR"]


#: Most entries of the dense parts of the horizon problem (:func:`qp_entries`): the generated C
#: grows with them, about 64 bytes each beyond a base of about 0.5 MB (measured on the composed
#: motor, nx = 3, nu = 1, blocks = horizon: horizon 20: 0.68 MB, 100: 3.97 MB, 200: 12.8 MB,
#: 400: 46 MB of C, before compiling); the limit, about 15 MB of C, admits the motor's horizon
#: up to 223 with one block per period, the L1's (nx = 6, nu = 3) up to 83, or 1000 with 5 blocks.
MAX_QP_ENTRIES = 250_000


def qp_entries(horizon: int, blocks: int, nx: int, nu: int, solver: str) -> int:
    """The entries of the dense parts of the MPC's horizon problem, estimated before it is built.

    ``sqpmethod`` (single shooting): the Jacobian of the ``horizon (nx + nu)`` residuals by
    the ``nu blocks`` inputs (every predicted state depends on every earlier input) and the
    Gauss-Newton Hessian ``(nu blocks)^2``; ``fatrop`` and ``hpipm`` (multiple shooting in stage order):
    ``horizon (nx + nu)^2``, one stage's blocks per period.

    Parameters
    ----------
    horizon, blocks : int
        Periods predicted and input blocks.
    nx, nu : int
        States and inputs of the model.
    solver : str
        :data:`~gtmodel.control.mpc.MPC_SOLVERS`.

    Returns
    -------
    int
    """
    if solver in ("fatrop", "hpipm"):
        return horizon * (nx + nu) ** 2
    n = nu * blocks
    return horizon * (nx + nu) * n + n * n


#: Largest generated C of an MPC step estimated by :func:`code_bytes` before it is built: 16 MB. The
#: compiler takes minutes on code this large (a 100-substep MPC with hard rows: 38.7 MB of C, refused
#: by the compiler's time-out after 437 s, issue 67); the shipped MPC files need at most 1.4 MB.
MAX_CODE_BYTES = 16_000_000
#: :func:`code_bytes`' coefficients [bytes]: per operation of the prediction step and period, per
#: operation, period and input direction of the Jacobian, and the base. Fitted on the composed DC motor
#: (nx = 3, nu = 1, rk4, blocks = horizon) when the step's Jacobian was CasADi's ``jacobian()`` of the whole
#: prediction: horizon 20, 100, 200, 400 with 2 substeps (0.73, 4.07, 12.8, 46 MB of C) and horizon 20 with 10
#: and 20 substeps and hard rows (1.80, 3.60 MB), within 20 %. Since the chain rule of the stages' Jacobians
#: (:mod:`gtmodel.control.mpc_nlp`) the same MPCs need 0.42 to 4.11 MB and 1.66, 3.02 MB: the estimate is an upper
#: bound there, 1.3 to 3.2 times the code (tests/problems/test_loop_file.py). It does not count the constraint rows
#: (the flexible-joint drive's 160: 1.02 MB for 0.41 MB estimated).
CODE_PER_OPERATION, CODE_PER_DIRECTION, CODE_BASE = 5.6, 0.11, 300_000


def code_bytes(step_operations: int, horizon: int, blocks: int, nx: int, nu: int, solver: str) -> int:
    """The generated C of the MPC's step, estimated before it is built [bytes].

    The code is the prediction unrolled over the horizon and its Jacobian by the inputs: about
    ``horizon * step_operations * (CODE_PER_OPERATION + CODE_PER_DIRECTION * directions)`` plus a
    base, with ``directions = nu * blocks`` (``sqpmethod``, single shooting: every predicted state
    depends on every earlier input) or ``nx + nu`` (``fatrop``, ``hpipm``: one stage's).

    Parameters
    ----------
    step_operations : int
        Operations of one period's prediction step with all its substeps
        (``substep_states(...).n_instructions()``).
    horizon, blocks : int
        Periods predicted and input blocks.
    nx, nu : int
        States and inputs of the model.
    solver : str
        :data:`~gtmodel.control.mpc.MPC_SOLVERS`.

    Returns
    -------
    int
    """
    directions = nx + nu if solver in ("fatrop", "hpipm") else nu * blocks
    return int(CODE_BASE + horizon * step_operations * (CODE_PER_OPERATION + CODE_PER_DIRECTION * directions))


#: What an MPC file builds (:class:`~gtmodel.problems.loop_file.LoopSetup` with an
#: :class:`~gtmodel.control.mpc.MPCController` as its controller).
MPCSetup = LoopSetup


def _constraints(file: ProblemFile, doc: MPCFile, ode: Any, robot: bool, declared: DeclaredBounds) -> dict[str, Any]:
    """The state bounds and path constraints of the MPC: the reference problem's (as its file declares them,
    without the overrides of the plan) or, for a table, the declared bounds (a result folder's summary, the
    model's); the declared bounds of the model's algebraic variables and outputs as rows of ``h(x, u)``;
    tightened by ``mpc.state_lb`` / ``mpc.state_ub``."""
    m = doc.mpc
    names_x, names_u = list(ode.x_names), list(ode.u_names)
    x_lb, x_ub, out = np.full(len(names_x), -np.inf), np.full(len(names_x), np.inf), {}
    if m.problem_constraints and doc.reference.problem is not None:
        source = Path(file.reference("reference.problem", doc.reference.problem))
        loaded = load_problem(source)
        opt = build_optimization(loaded.declaration)[0] if robot else loaded.declaration.optimization
        try:
            x_lb, x_ub, path, lb, ub, names = problem_constraints(opt, names_x, names_u)
        except GtModelError as exc:
            raise file.wrap("mpc.problem_constraints", exc) from None
        out = dict(path=path, path_lb=lb, path_ub=ub, path_names=names)
    elif m.problem_constraints and not robot:
        x_lb, x_ub = declared.vectors(names_x)
    outputs = [n for n in ode.y_names if n in declared.lb] if m.problem_constraints and not robot else []
    if outputs:  # bounds of algebraic variables and outputs (e.g. a resistor's current): rows of y = h(x, u)
        try:
            h = ode.h
        except GtModelError as exc:
            raise file.wrap("mpc.problem_constraints", exc) from None
        xs, us = ca.SX.sym("x", len(names_x)), ca.SX.sym("u", len(names_u))
        y = h(xs, us, ode.p_default)
        rows = ca.vertcat(*[y[list(ode.y_names).index(n)] for n in outputs])
        lo, hi = declared.vectors(outputs)
        if out.get("path") is not None:
            rows = ca.vertcat(out["path"](xs, us), rows)
            lo, hi, outputs = np.r_[out["path_lb"], lo], np.r_[out["path_ub"], hi], list(out["path_names"]) + outputs
        out = dict(path=ca.Function("path", [xs, us], [rows], ["x", "u"], ["h"]), path_lb=lo, path_ub=hi, path_names=outputs)
    for field, table, pick in (("mpc.state_lb", m.state_lb, np.maximum), ("mpc.state_ub", m.state_ub, np.minimum)):
        for key, value in table.items():
            if key not in names_x:
                raise file.fail(f"{field}.{key}", f"a state of the model ({', '.join(names_x)})", key)
            bound = x_lb if field.endswith("lb") else x_ub
            bound[names_x.index(key)] = pick(bound[names_x.index(key)], value)
    bad = np.flatnonzero(x_lb > x_ub)
    if bad.size:
        raise file.fail(f"mpc.state_lb.{names_x[bad[0]]}", "a lower bound <= the upper bound", float(x_lb[bad[0]]))
    return dict(out, x_lb=x_lb, x_ub=x_ub)


def load_mpc_file(path: str | Path, replan: bool = False) -> MPCSetup:
    """Read, validate and build an MPC file (see the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.
    replan : bool, optional
        Solve ``[reference] problem`` even when its plan is cached (``--replan``,
        :mod:`~gtmodel.problems.plan_cache`).

    Returns
    -------
    MPCSetup

    Raises
    ------
    ProblemError
        Naming the file and the field: unreadable TOML, an unknown or invalid field (a
        number not finite or out of its documented range, e.g. a horizon outside 1..1000, a
        period outside 1e-5..1 s, a weight above 1e12), an unknown variable in a weight table,
        blocks that do not divide the horizon, a horizon problem above
        :data:`MAX_QP_ENTRIES` (:func:`qp_entries`, before the reference is solved), generated C
        estimated above :data:`MAX_CODE_BYTES` (:func:`code_bytes`, naming ``mpc.substeps``, or
        ``mpc.horizon`` with one substep), too many
        loop periods (:func:`~gtmodel.problems.loop_file.loop_samples`), a reference that
        cannot be read or solved.
    """
    doc, file = read_loop_file(path, "mpc")
    m = doc.mpc
    if m.blocks is not None and m.horizon % m.blocks:
        raise file.fail("mpc.blocks", f"a divisor of the horizon {m.horizon}", m.blocks)
    if any(m.input_rate_weights.values()) and m.solver != "sqpmethod":  # before the reference is planned
        raise file.fail("mpc.input_rate_weights", f"none with solver {m.solver} (the rate term is built for sqpmethod)", m.input_rate_weights)

    def qp_size(model: LoopModel) -> None:
        blocks = m.horizon if m.blocks is None else m.blocks
        entries = qp_entries(m.horizon, blocks, model.ode.nx, model.ode.nu, m.solver)
        if entries > MAX_QP_ENTRIES:
            raise file.fail("mpc.horizon", f"a horizon problem of at most {MAX_QP_ENTRIES} entries (horizon {m.horizon}, blocks {blocks}, "
                                           f"{model.ode.nx} states, {model.ode.nu} inputs, solver {m.solver}: about {entries}; the generated C "
                                           "grows with them, about 64 bytes each); fewer periods or input blocks", m.horizon)
        operations = substep_states(model.ode, m.period, m.method, m.substeps).n_instructions()
        size = code_bytes(operations, m.horizon, blocks, model.ode.nx, model.ode.nu, m.solver)
        if size > MAX_CODE_BYTES:
            field = "mpc.substeps" if m.substeps > 1 else "mpc.horizon"
            raise file.fail(field, f"generated C of at most {MAX_CODE_BYTES / 1e6:.0f} MB (estimated before building: about {size / 1e6:.1f} MB "
                                   f"for horizon {m.horizon}, {m.substeps} {m.method} substeps per period ({operations} operations), "
                                   f"blocks {blocks}, solver {m.solver}); fewer substeps, a shorter horizon or fewer input blocks",
                            getattr(m, field.split(".")[1]))

    i = loop_inputs(file, doc, "mpc", before_reference=qp_size, replan=replan)
    ode = i.model.ode
    cons = _constraints(file, doc, ode, i.model.robot, i.bounds)
    R_rate = weight_diagonal(file, "mpc.input_rate_weights", m.input_rate_weights, list(ode.u_names))
    try:
        controller = mpc_controller(ode, i.t, i.x_ref, i.u_ref, horizon=m.horizon, dt=m.period, Q=i.Q, R=i.R, Qf=i.Qf, u_lb=i.u_lb,
                                    u_ub=i.u_ub, method=m.method, substeps=m.substeps, blocks=m.blocks, sqp_iterations=m.sqp_iterations,
                                    solver=m.solver, hard_constraints=m.hard_constraints, constraint_weight=m.constraint_weight,
                                    constraint_every=m.constraint_every,
                                    constraint_substeps=m.constraint_substeps, delay=m.input_delay, disturbance_gain=float(m.disturbance_gain),
                                    constraint_backoff=m.constraint_backoff, R_rate=R_rate, **cons)
    except GtModelError as exc:
        fields = {"disturbance_gain": "mpc.disturbance_gain", "constraint_backoff": "mpc.constraint_backoff", "R_rate": "mpc.input_rate_weights"}
        raise file.wrap(next((f for k, f in fields.items() if k in str(exc)), "mpc"), exc) from None
    if R_rate is None and m.solver == "sqpmethod" and controller.constraints is not None:  # the default (RATE_FACTOR)
        controller = replace(controller, R_rate=RATE_FACTOR * controller.R)
    controller = with_measurement_filter(file, "mpc.measurement_noise", controller, m.measurement_noise, doc.check.noise, ode)
    return loop_setup(file, doc.name, controller, i.model, doc.check, m.period, bounds=i.bounds, notes=i.notes)
