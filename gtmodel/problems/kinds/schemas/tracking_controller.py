"""The schema of a tracking-controller file (light: validated before the controller is built); the reader is :mod:`gtmodel.problems.tracking_file`.

A tracking-controller file is a :class:`~gtmodel.problems.kinds.schemas.loop.LoopFile`
(``name``, ``description``, ``[reference]``, ``[check]``) and its ``[controller]`` table
(feedforward plus time-varying LQR, :func:`gtmodel.control.tracking.tracking_controller`);
the kind is ``tracking_controller`` in :data:`gtmodel.problems.registry.LOOP_KINDS`
(``gtmodel schema tracking_controller``), generated and checked by ``gtmodel codegen``.
:class:`TrackingFile` is the one class of that name (the L1 replay kind's schema is
:class:`~gtmodel.problems.kinds.schemas.replay.ReplayFile`).
"""

from __future__ import annotations

from pydantic import Field

from gtmodel.defaults import LOOP_PERIOD_S, NOISE_GAIN_LIMIT
from gtmodel.problems.kinds.schemas.loop import STEP_METHOD_NAMES, LoopFile
from gtmodel.problems.loop_limits import MAX_MAGNITUDE, MAX_WEIGHT, Bounds, Period, Weights
from gtmodel.problems.schema import NonEmptyText, Section, choice, number

__all__ = ["ControllerSection", "TrackingFile"]


class ControllerSection(Section):
    """``[controller]``: the model, the period, the weights and the bounds of the tracking controller.

    Parameters
    ----------
    model : str
        A robot parameter set ("L1") or a user model "FILE.py:Class".
    period : float, optional
        Loop period [s].
    method : str, optional
        The fixed step linearised along the reference.
    substeps : int, optional
        Steps of the method per period.
    state_weights : dict, optional
        Diagonal of Q by state name (default: Bryson's rule).
    input_weights : dict, optional
        Diagonal of R by input name (default 1 / (half the bound range)^2).
    terminal_weights : dict, optional
        Diagonal of Qf by state name (default: the stationary Riccati solution at the held end).
    u_lb : list of float, optional
        Input lower bounds.
    u_ub : list of float, optional
        Input upper bounds.
    time_varying : bool, optional
        Time-varying LQR along the reference (false: the held end's time-invariant LQR).
    input_delay : int, optional
        Input delay [periods] the law compensates by predicting the state one period ahead (0 or 1).
    integral_weights : dict, optional
        Integral action on these states: the weight (> 0) of each one's integrated error (default none).
    hold_state_bounds : bool, optional
        Hold the declared state bounds over the period each input acts (the input projected, then saturated;
        default true).
    measurement_noise : list of float, optional
        The sensors' noise standard deviation per state (state units, each >= 0), which the step's extended Kalman
        filter of the measurement assumes (default: ``[check] noise``; all zeros or an empty list: no filter).
    noise_gain_limit : float, optional
        The largest response of an input to a one-sigma error of the measured states (``measurement_noise``), as a
        fraction of its half range: each period's gain rows above it scaled down to it (0: no limit; default 0.1).
    """

    model: NonEmptyText = Field(description='a robot parameter set ("L1") or a user model "FILE.py:Class"')
    period: Period = LOOP_PERIOD_S
    method: choice(*STEP_METHOD_NAMES, description="the fixed step linearised along the reference") = "rk4"
    substeps: int = Field(default=1, ge=1, le=100, strict=True, description="steps of the method per period")
    state_weights: Weights = Field(default_factory=dict, description="diagonal of Q by state name (default: Bryson's rule)")
    input_weights: Weights = Field(default_factory=dict, description="diagonal of R by input name (default 1 / (half the bound range)^2)")
    terminal_weights: Weights = Field(default_factory=dict, description="diagonal of Qf by state name (default: the stationary Riccati solution at the held end)")
    u_lb: Bounds = Field(default=None, description="input lower bounds")
    u_ub: Bounds = Field(default=None, description="input upper bounds")
    time_varying: bool = Field(default=True, strict=True, description="time-varying LQR along the reference (false: the held end's time-invariant LQR)")
    input_delay: int = Field(default=0, ge=0, le=1, strict=True, description="input delay [periods] the law compensates by predicting the state one period ahead (0 or 1)")
    integral_weights: dict[str, number(gt=0, le=MAX_WEIGHT)] = Field(default_factory=dict, description="integral action on these states: the weight (> 0) of each one's integrated error (default none)")
    hold_state_bounds: bool = Field(default=True, strict=True, description="hold the declared state bounds (a current limit) over the period each input acts: the law's input projected onto the inputs that keep the bounded states within them at every substep, then saturated (default true)")
    measurement_noise: list[number(ge=0, le=MAX_MAGNITUDE)] | None = Field(default=None, max_length=10_000, description="the sensors' noise standard deviation per state, which the step's extended Kalman filter of the measurement assumes (default: [check] noise; all zeros or []: no filter)")
    noise_gain_limit: number(ge=0, le=1) = Field(default=NOISE_GAIN_LIMIT, description="the largest response of an input to a one-sigma error of the measured states (measurement_noise), as a fraction of its half range: each period's gain rows above it scaled down to it (0: no limit)")


class TrackingFile(LoopFile):
    """A tracking-controller file (:mod:`gtmodel.problems.tracking_file`): :class:`~gtmodel.problems.kinds.schemas.loop.LoopFile` and its controller's table.

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
    controller : ControllerSection
        ``[controller]``.
    """

    controller: ControllerSection
