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
``[reference]``, ``[check]``
    The motion tracked and the closed loop of ``--check``: the tables shared by every
    loop-controller file, :mod:`gtmodel.problems.loop_file`.
"""

from __future__ import annotations

from pathlib import Path

from pydantic import Field, ValidationError

from gtmodel._toml import read_toml
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.estimation.mpc import MPC_METHODS, MPC_SOLVERS, mpc_controller
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.loop_file import CheckSection, LoopSetup, ReferenceSection, input_bounds, loop_model, loop_reference, loop_setup, weight_diagonal
from gtmodel.problems.schema import NonEmptyText, Section, choice, number, problem_error

__all__ = ["MPCFile", "MPCSetup", "load_mpc_file"]

#: Longest horizon accepted [periods].
MAX_HORIZON = 1000


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


#: What an MPC file builds (:class:`~gtmodel.problems.loop_file.LoopSetup` with an
#: :class:`~gtmodel.estimation.mpc.MPCController` as its controller).
MPCSetup = LoopSetup


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
    model = loop_model(file, "mpc.model", m.model, doc.check)
    ode = model.ode
    names_x, names_u = list(ode.x_names), list(ode.u_names)
    Q = weight_diagonal(file, "mpc.state_weights", m.state_weights, names_x)
    R = weight_diagonal(file, "mpc.input_weights", m.input_weights, names_u)
    Qf = weight_diagonal(file, "mpc.terminal_weights", m.terminal_weights, names_x)
    if m.blocks is not None and m.horizon % m.blocks:
        raise file.fail("mpc.blocks", f"a divisor of the horizon {m.horizon}", m.blocks)
    t, x_ref, u_ref, limits = loop_reference(file, doc.reference, model, m.period,
                                             bounds_field=None if m.u_lb is not None and m.u_ub is not None else "mpc")
    u_lb, u_ub = input_bounds(file, "mpc", m.u_lb, m.u_ub, limits, ode)
    try:
        controller = mpc_controller(ode, t, x_ref, u_ref, horizon=m.horizon, dt=m.period, Q=Q, R=R, Qf=Qf, u_lb=u_lb, u_ub=u_ub,
                                    method=m.method, substeps=m.substeps, blocks=m.blocks, sqp_iterations=m.sqp_iterations, solver=m.solver)
    except GtModelError as exc:
        raise file.wrap("mpc", exc) from None
    return loop_setup(file, doc.name, controller, model, doc.check, m.period)
