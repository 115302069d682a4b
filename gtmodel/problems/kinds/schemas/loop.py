"""The schema of every loop-controller file's shared tables, ``[reference]`` and ``[check]`` (light).

A loop-controller file (an MPC file, :mod:`gtmodel.problems.kinds.schemas.mpc`; a
tracking-controller file, :mod:`gtmodel.problems.kinds.schemas.tracking_controller`) is a
:class:`LoopFile`: these tables, ``name`` and ``description``, and its controller's table.
The kinds are declared in :data:`gtmodel.problems.registry.LOOP_KINDS`; the fields' meaning
is the reader's, :mod:`gtmodel.problems.loop_file`. Imports only pydantic and the light
modules (validated before any solver is imported).
"""

from __future__ import annotations

from typing import Any

from pydantic import Field

from gtmodel.problems.loop_limits import MAX_MAGNITUDE
from gtmodel.problems.schema import Identifier, NonEmptyText, Section, choice, number

__all__ = ["STEP_METHOD_NAMES", "ReferenceSection", "CheckSection", "LoopFile"]

#: The fixed steps of :meth:`gtmodel.modeling.ExplicitODE.step` (``STEP_METHODS``; a test keeps them equal).
STEP_METHOD_NAMES = ("rk4", "implicit_euler", "radau2")


class ReferenceSection(Section):
    """``[reference]``: the motion tracked (exactly one of ``problem`` and ``file``).

    Parameters
    ----------
    problem : str, optional
        A point_to_point (robot) or optimal_control (user model) problem file, relative to this file, solved
        first.
    overrides : dict, optional
        Dotted fields of that problem replaced, e.g. 'limits.force'.
    file : str, optional
        A CSV table: t and the model's state and input names.
    settle_time : float, optional
        The end state held this long, with the input that holds it [s].
    accept_unverified : bool, optional
        Track a reference whose verification failed or was skipped (default false: refused); the summary and
        the verdict repeat it.
    """

    problem: NonEmptyText | None = Field(default=None, description="a point_to_point (robot) or optimal_control (user model) problem file, relative to this file, solved first")
    overrides: dict[str, Any] = Field(default_factory=dict, description="dotted fields of that problem replaced, e.g. 'limits.force'")
    file: NonEmptyText | None = Field(default=None, description="a CSV table: t and the model's state and input names")
    settle_time: number(ge=0, le=60.0, unit="s", description="the end state held this long, with the input that holds it") = 0.5
    accept_unverified: bool = Field(default=False, strict=True, description="track a reference whose verification failed or was skipped "
                                    "(default false: refused); the summary and the verdict repeat it")


class CheckSection(Section):
    """``[check]``: the closed loop of ``--check``.

    Parameters
    ----------
    mass_factor : float, optional
        Plant masses / model masses (robot).
    friction_factor : float, optional
        Plant friction / model friction (robot).
    parameter_factor : float, optional
        Plant parameters / model parameters (user model).
    parameter_factors : dict, optional
        Plant / model factors of single parameters by name, replacing parameter_factor for them (user model;
        e.g. a geometry known exactly: 1.0).
    noise : list of float, optional
        Measurement noise standard deviation per state, each >= 0 (default none).
    disturbance : list of float, optional
        Input step disturbance per input (default none).
    disturbance_time : float, optional
        Time of the step disturbance [s].
    delay : int, optional
        Input delay [samples].
    seed : int, optional
        Seed.
    compliance : bool, optional
        Robot: the tool structure of eq. 6.14 (7.4 / 11.5 Hz modes) in the plant.
    error_states : list, optional
        States summarised by the tracking error (default all).
    plant_method : str, optional
        The plant's fixed step (radau2, implicit_euler: stiff models; not with compliance).
    plant_substeps : int, optional
        Plant steps per loop period.
    max_ratio : float, optional
        The check passes with an RMS tracking error below this fraction of the feedforward's alone.
    max_step_time : float, optional
        S: the largest 99th-percentile step time of the generated C that passes (default the period).
    """

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
    plant_method: choice(*STEP_METHOD_NAMES, description="the plant's fixed step (radau2, implicit_euler: stiff models; not with compliance)") = "rk4"
    plant_substeps: int = Field(default=4, ge=1, le=1000, strict=True, description="plant steps per loop period")
    max_ratio: number(gt=0, le=1.0, description="the check passes with an RMS tracking error below this fraction of the feedforward's alone") = 1.0
    max_step_time: float | None = Field(default=None, gt=0, le=10.0, allow_inf_nan=False,
                                        description="s: the largest 99th-percentile step time of the generated C that passes (default the period)")


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
