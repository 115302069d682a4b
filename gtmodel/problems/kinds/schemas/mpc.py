"""The schema of an MPC file (light: validated before the MPC is built); the reader is :mod:`gtmodel.problems.mpc_file`.

An MPC file is a :class:`~gtmodel.problems.kinds.schemas.loop.LoopFile` (``name``,
``description``, ``[reference]``, ``[check]``) and its ``[mpc]`` table; the kind is
``mpc`` in :data:`gtmodel.problems.registry.LOOP_KINDS` (``gtmodel schema mpc``), generated
and checked by ``gtmodel codegen``.
"""

from __future__ import annotations

from pydantic import Field

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.problems.kinds.schemas.loop import LoopFile
from gtmodel.problems.loop_limits import MAX_MAGNITUDE, Bounds, Period, StateBounds, Weights
from gtmodel.problems.schema import NonEmptyText, Section, choice, number

__all__ = ["MAX_HORIZON", "MPC_METHOD_NAMES", "MPC_SOLVER_NAMES", "RATE_FACTOR", "MPCSection", "MPCFile"]

#: Longest horizon accepted [periods].
MAX_HORIZON = 1000
#: The prediction steps of :data:`gtmodel.control.mpc.MPC_METHODS` (a test keeps them equal).
MPC_METHOD_NAMES = ("euler", "rk4", "implicit_euler", "radau2")
#: The NLP solvers of :data:`gtmodel.control.mpc.MPC_SOLVERS` (a test keeps them equal).
MPC_SOLVER_NAMES = ("sqpmethod", "fatrop", "hpipm")
#: ``[mpc] input_rate_weights`` when the file gives none (solver ``sqpmethod``, constraint rows: DAQP's QPs):
#: this factor times the input weight ``R`` (move suppression, as MATLAB's MPC weighs the inputs' rates by
#: default). Not without rows (``qrqp``): on ``codegen/mpc/dc_motor_mpc.toml`` the single-precision step's
#: ``qrqp`` then failed one of the check's 200 random inputs. The drive family's MPCs
#: by one recipe (``benchmarks/bench_drive_family_loop.py``, members 0-7, plant 20 % off) held their bounds in
#: 5 of 8 without the term, 7 of 8 with it, their tracking ratios within 6 % of the ones without (10 times: 5.07 %
#: beyond drive0_06's current bound, 100 times: held).
RATE_FACTOR = 100.0


class MPCSection(Section):
    """``[mpc]``: the model, the horizon and the weights.

    Parameters
    ----------
    model : str
        A robot parameter set ("L1") or a user model "FILE.py:Class".
    horizon : int
        Prediction horizon [periods].
    period : float, optional
        Loop period [s].
    blocks : int, optional
        Input blocks over the horizon (a divisor; default the horizon).
    sqp_iterations : int, optional
        SQP iterations per period (1: real-time iteration).
    solver : str, optional
        NLP solver of the step (qrqp QPs).
    method : str, optional
        Prediction step over one period (euler: cheapest; implicit_euler, radau2: stiff models).
    substeps : int, optional
        Steps of the method per period.
    state_weights : dict, optional
        Diagonal of Q by state name (default: Bryson's rule).
    input_weights : dict, optional
        Diagonal of R by input name.
    input_rate_weights : dict, optional
        Weight of each input's change per period by input name (move suppression; sqpmethod only; default with constraint rows RATE_FACTOR = 100 times input_weights, 0: none).
    terminal_weights : dict, optional
        Diagonal of Qf by state name (default Q).
    u_lb : list of float, optional
        Input lower bounds.
    u_ub : list of float, optional
        Input upper bounds.
    state_lb : dict, optional
        Lower bounds of the predicted states by state name (with the reference problem's).
    state_ub : dict, optional
        Upper bounds of the predicted states by state name (with the reference problem's).
    problem_constraints : bool, optional
        Impose the reference problem's state bounds and path constraints on the horizon.
    hard_constraints : bool, optional
        State and path constraints hard (default soft: an exact penalty with slacks).
    constraint_weight : float, optional
        Constraint_weight.
    input_delay : int, optional
        Input delay [periods] the step compensates by predicting the state one period ahead (0 or 1).
    constraint_every : int, optional
        Constrain every k-th predicted state and the last (1: all).
    constraint_substeps : bool, optional
        Also constrain the states after each of the prediction's substeps within the constrained periods (between the samples).
    disturbance_gain : float, optional
        Offset-free MPC: the gain of the input-disturbance estimate per period (0: none).
    constraint_backoff : bool, optional
        Tighten the constraint rows by the prediction's one-period error measured in the loop (default: on with
        rows and sqpmethod or hpipm).
    measurement_noise : list of float, optional
        The sensors' noise standard deviation per state (state units, each >= 0), which the step's extended Kalman
        filter of the measurement assumes (default: ``[check] noise``; all zeros or an empty list: no filter).
    """

    model: NonEmptyText = Field(description='a robot parameter set ("L1") or a user model "FILE.py:Class"')
    horizon: int = Field(ge=1, le=MAX_HORIZON, strict=True, description="prediction horizon [periods]")
    period: Period = LOOP_PERIOD_S
    blocks: int | None = Field(default=None, ge=1, le=MAX_HORIZON, strict=True, description="input blocks over the horizon (a divisor; default the horizon)")
    sqp_iterations: int = Field(default=1, ge=1, le=100, strict=True, description="SQP iterations per period (1: real-time iteration)")
    solver: choice(*MPC_SOLVER_NAMES, description="NLP solver of the step: sqpmethod (single shooting, qrqp or DAQP QPs), fatrop or hpipm (multiple shooting, one input per period, constraints of the states only)") = "sqpmethod"
    method: choice(*MPC_METHOD_NAMES, description="prediction step over one period (euler: cheapest; implicit_euler, radau2: stiff models)") = "rk4"
    substeps: int = Field(default=1, ge=1, le=100, strict=True, description="steps of the method per period")
    state_weights: Weights = Field(default_factory=dict, description="diagonal of Q by state name (default: Bryson's rule)")
    input_weights: Weights = Field(default_factory=dict, description="diagonal of R by input name")
    input_rate_weights: Weights = Field(default_factory=dict, description="weight of each input's change per period by input name, sum_j R_rate (u_j - u_{j-1})^2 with u_{-1} the input acting before the horizon (move suppression; sqpmethod only; default with constraint rows " f"{RATE_FACTOR:g} times input_weights, 0 for every input: none)")
    terminal_weights: Weights = Field(default_factory=dict, description="diagonal of Qf by state name (default Q)")
    u_lb: Bounds = Field(default=None, description="input lower bounds")
    u_ub: Bounds = Field(default=None, description="input upper bounds")
    state_lb: StateBounds = Field(default_factory=dict, description="lower bounds of the predicted states by state name (with the reference problem's)")
    state_ub: StateBounds = Field(default_factory=dict, description="upper bounds of the predicted states by state name (with the reference problem's)")
    problem_constraints: bool = Field(default=True, strict=True, description="impose the reference problem's state bounds and path constraints on the horizon")
    hard_constraints: bool = Field(default=False, strict=True, description="state and path constraints hard (default soft: an exact penalty with slacks)")
    constraint_weight: number(gt=0, le=1e30, description="penalty weight rho of the soft constraints (default 100 H max_i Q_ii scale_i^2)") | None = None
    input_delay: int = Field(default=0, ge=0, le=1, strict=True, description="input delay [periods] the step compensates by predicting the state one period ahead (0 or 1)")
    constraint_every: int = Field(default=1, ge=1, le=MAX_HORIZON, strict=True, description="constrain every k-th predicted state and the last (1: all)")
    constraint_substeps: bool = Field(default=True, strict=True, description="also constrain the states after each of the prediction's substeps within the constrained periods (between the samples)")
    disturbance_gain: number(ge=0, le=1.0, description="offset-free MPC: the gain of the input-disturbance estimate per period (0: none)") = 0.0
    constraint_backoff: bool | None = Field(default=None, strict=True, description="tighten the constraint rows by the prediction's one-period error measured in the loop, carried to each bounded quantity (a bound never loosened; default: on with constraint rows and solver sqpmethod or hpipm)")
    measurement_noise: list[number(ge=0, le=MAX_MAGNITUDE)] | None = Field(default=None, max_length=10_000, description="the sensors' noise standard deviation per state, which the step's extended Kalman filter of the measurement assumes (default: [check] noise; all zeros or []: no filter)")


class MPCFile(LoopFile):
    """An MPC file (:mod:`gtmodel.problems.mpc_file`): :class:`~gtmodel.problems.kinds.schemas.loop.LoopFile` and its controller's table.

    Parameters
    ----------
    name : str
        Name of the controller, a C identifier of at most 40 characters (the C prefix is ``gt_<name>``).
    description : str
        Free text.
    reference : ReferenceSection
        ``[reference]``.
    check : CheckSection
        ``[check]``.
    mpc : MPCSection
        ``[mpc]``.
    """

    mpc: MPCSection
