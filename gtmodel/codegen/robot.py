"""The robot model code is generated from: loading, kind, parameter hash.

:class:`RobotModel` wraps a 3-link parameter set (its kinematics and dynamics), the
six-link error model or the F1 model; the declarations of :mod:`gtmodel.codegen.specs`
build their CasADi Functions from its public members and the closure models' public
graphs (:meth:`~gtmodel.robots.closure.ClosureModel.graphs`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.errors import ParameterError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.f1 import F1Closure, load_f1
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import RobotParameters, load_parameters
from gtmodel.robots.six_link import SixLinkClosure, load_six_link

__all__ = ["ROBOT_KINDS", "RobotModel", "load_robot", "parameter_hash"]

#: Robot kinds and what loads them.
ROBOT_KINDS = ("three_link", "six_link", "f1")

def _canonical(obj):
    if dataclasses.is_dataclass(obj):
        return {f.name: _canonical(getattr(obj, f.name)) for f in dataclasses.fields(obj) if f.name not in ("path",)}
    if isinstance(obj, np.ndarray):
        return [_canonical(x) for x in obj.tolist()] if obj.ndim else float(obj)
    if isinstance(obj, (list, tuple)):
        return [_canonical(x) for x in obj]
    if isinstance(obj, float):
        return float.hex(obj)  # exact
    return obj


def parameter_hash(parameters: RobotParameters) -> str:
    """Short hash identifying the numbers of a parameter set.

    Parameters
    ----------
    parameters : RobotParameters
        The parameter set.

    Returns
    -------
    str
        First 16 hex digits of the SHA-256 of a canonical (exact, order-fixed) encoding
        of every field except the file path.
    """
    text = json.dumps(_canonical(parameters), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]



# ----------------------------------------------------------------------------- model
def _vector_hash(name: str, arrays: list[np.ndarray]) -> str:
    text = json.dumps([name] + [[float.hex(float(x)) for x in np.ravel(a)] for a in arrays])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class RobotModel:
    """The symbolic robot model the C functions are generated from.

    Parameters
    ----------
    robot : RobotParameters or SixLinkClosure or F1Closure
        A 3-link parameter set (``GantryTau3Kinematics``/``GantryTau3Dynamics``), the
        six-link error model of Dressler (2012), eq. 4.14, or the F1 model (eqs. 4.16-4.33).
        Values are embedded as constants.
    friction : str, optional
        Form of the friction sign for the dynamics (``"exact"``, ``"tanh"``, ``"piecewise"``).
    """

    def __init__(self, robot: Any, friction: str = "exact") -> None:
        self.robot = robot
        self.friction = friction
        if isinstance(robot, RobotParameters):
            self.kind = "three_link"
            self.parameters: RobotParameters | None = robot
        elif isinstance(robot, SixLinkClosure):
            self.kind = "six_link"
            self.parameters = None
        elif isinstance(robot, F1Closure):
            self.kind = "f1"
            self.parameters = None
        else:
            raise ParameterError(f"robot: expected a 3-link parameter set, a six-link or an F1 model, got {type(robot).__name__}")
        self.name = str(robot.name)

    @cached_property
    def kinematics(self) -> GantryTau3Kinematics:
        """The 3-link kinematics (:class:`GantryTau3Kinematics`)."""
        return GantryTau3Kinematics(self.parameters)

    @cached_property
    def dynamics(self):
        """The rigid-body dynamics with friction (``GantryTau3Dynamics``)."""
        return GantryTau3Dynamics(self.parameters, friction=self.friction)

    @property
    def closure(self):
        """The six-link or F1 closure model (``SixLinkClosure`` / ``F1Closure``)."""
        return self.robot

    def parameter_hash(self) -> str:
        """Short hash of the numbers of the model (first 16 hex digits of a SHA-256).

        Returns
        -------
        str
            For a 3-link set :func:`parameter_hash`; for the
            closure models the hash of the name, the parameter vector and the reference
            orientation / home actuator values.
        """
        if self.kind == "three_link":
            return parameter_hash(self.parameters)
        extra = self.robot.R0 if self.kind == "six_link" else self.robot.q_home
        return _vector_hash(self.name, [self.robot.parameter_vector(), extra])

    @property
    def description(self) -> str:
        """One line describing the robot model."""
        if self.kind == "three_link":
            return str(self.parameters.description)
        if self.kind == "six_link":
            return f"{self.name}: six-link kinematic error model (Dressler (2012), eqs. 4.14, 4.15)"
        return f"{self.name}: F1 6-DOF Gantry-Tau (Dressler (2012), eqs. 4.16-4.33)"


def load_robot(robot: Any) -> Any:
    """Load a robot for code generation: a 3-link set, the six-link or the F1 model.

    Parameters
    ----------
    robot : str or pathlib.Path or RobotParameters or SixLinkClosure or F1Closure
        A loaded model, a shipped name (``"L1"``, ``"D1"``, ``"L1_ideal"``, ``"D1_six_link"``,
        ``"F1"``) or a TOML path (a 3-link set such as a calibration's
        ``parameters.toml``, a six-link or an F1 parameter file; tried in this order).

    Returns
    -------
    RobotParameters or SixLinkClosure or F1Closure
        The model.

    Raises
    ------
    ParameterError
        No model of any kind could be loaded (the message of the 3-link attempt).
    """
    if isinstance(robot, (RobotParameters, SixLinkClosure, F1Closure)):
        return robot
    first: ParameterError | None = None
    for loader in (load_parameters, load_six_link, load_f1):
        try:
            return loader(robot)
        except ParameterError as exc:
            first = first or exc
    if isinstance(robot, (str, Path)) and not Path(robot).exists():
        raise ParameterError(
            f"unknown robot {str(robot)!r}: not a shipped set (3-link: L1, D1, L1_ideal; six-link: D1_six_link; F1) "
            "and no such file"
        )
    raise first  # type: ignore[misc]

