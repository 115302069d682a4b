"""What problem files refer to, resolved by the one rule of :class:`~gtmodel.problems.base.ProblemFile`.

Robot parameter sets (``[robot] parameters = "L1"`` or a path), named expression
parameters (``[parameters]``), shared by the kinds that need them.
"""

from __future__ import annotations

import re
from typing import Mapping

from gtmodel._lazy import lazy_module
from gtmodel.errors import ParameterError
from gtmodel.problems.base import ProblemFile

#: The robot models, imported on first use: kinds without a robot (``optimal_control``) do not need them.
robots = lazy_module("gtmodel.robots")

__all__ = ["robot_parameters", "named_parameters"]

_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def robot_parameters(file: ProblemFile, field: str, ref: str) -> robots.RobotParameters:
    """A Gantry-Tau parameter set: a shipped name (``L1``, ``D1``, ...) or a TOML file.

    Parameters
    ----------
    file : ProblemFile
        The problem file.
    field : str
        Dotted field name, e.g. ``"robot.parameters"``.
    ref : str
        Set name or path (relative to the problem file).

    Returns
    -------
    RobotParameters

    Raises
    ------
    ProblemError
        Not a shipped set nor a loadable file (names the field).
    """
    target = file.reference(field, ref, robots.available_parameter_sets())
    try:
        return robots.load_parameters(str(target))
    except ParameterError as exc:
        raise file.wrap(field, exc) from None


def named_parameters(file: ProblemFile, values: Mapping[str, float], reserved: set[str]) -> dict[str, float]:
    """The ``[parameters]`` table: named numbers usable in expressions.

    Parameters
    ----------
    file : ProblemFile
        The problem file.
    values : Mapping[str, float]
        The validated table (values already finite numbers).
    reserved : set of str
        Names the model defines (a parameter may not shadow them).

    Returns
    -------
    dict of str to float

    Raises
    ------
    ProblemError
        A name that is not an identifier or shadows a model name.
    """
    for key in values:
        if not _IDENT.fullmatch(key):
            raise file.fail(f"parameters.{key}", "an identifier (letters, digits, _) as the parameter name", key)
        if key in reserved:
            raise file.fail(f"parameters.{key}", "a name that is not a model variable", key)
    return {k: float(v) for k, v in values.items()}
