"""The Gantry-Tau robots as Modelica classes: the package ``GantryTau`` gtmodel ships.

``modelica_library/GantryTau.mo`` declares ``GantryTau.L1``, the L1 Gantry-Tau's 3-link model
in the structure of the thesis' ``robotmodel`` (Dressler (2012), ch. 3.3): TCP position and
velocity as states, the normalised actuator torques as inputs, the cart positions from the
inverse kinematics, the closure differentiated once and twice, and the force balance of the
carts and the plate with Coulomb (smooth) and viscous friction; the values are those of
``gtmodel/robots/data/L1.toml``. A ``.mo`` or ``.mop`` file that names ``GantryTau.`` (and
declares no package ``GantryTau`` itself) gets the package added to its classes, as the MSL
subset is added for ``Modelica.`` (:mod:`gtmodel.exchange.msl`).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from gtmodel.exchange import msl

__all__ = ["ROBOT_SOURCE", "uses_robots", "extend"]

#: The shipped Modelica source of the package ``GantryTau``.
ROBOT_SOURCE = Path(__file__).parent / "modelica_library" / "GantryTau.mo"
_REF_RE = re.compile(r"(?<![\w.])GantryTau\s*\.\s*[A-Za-z_]")
_OWN_RE = re.compile(r"\bpackage\s+GantryTau\b")


def uses_robots(code: str) -> bool:
    """Whether a Modelica text names a class under ``GantryTau.`` (and declares no package ``GantryTau`` itself).

    Parameters
    ----------
    code : str
        The text, comments and strings blanked (:func:`gtmodel.exchange.msl.code_only`).

    Returns
    -------
    bool
    """
    return msl.names_library(code, _REF_RE, _OWN_RE)


def extend(parser: Any, ast: Any) -> None:
    """Add the shipped package ``GantryTau`` to a parsed file's classes (pymoca's tree, in place).

    Parameters
    ----------
    parser : module
        ``pymoca.parser``.
    ast : pymoca.tree.Tree
        The file's parsed classes.
    """
    msl.add_library(parser, ast, ROBOT_SOURCE, "Gantry-Tau robot")
