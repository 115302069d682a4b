"""The public header of a robot's (or a controller bundle's) library; the generic writer is :mod:`gtmodel.codegen.emit.wrapper`.

:func:`header_text` fills ``harness/template_header.h`` with the robot's description, its
tolerance and Newton-loop macros and the prototypes of the wrapped functions. The names
:func:`functions_fragment` and :func:`wrapper_text` (the generic writer, former home here) are
re-exported from :mod:`gtmodel.codegen.emit.wrapper`.
"""

from __future__ import annotations

from typing import Sequence

from gtmodel.codegen.declarations import CONTROLLER_KIND, THRESHOLD_MACROS
from gtmodel.codegen.emit import c_float as _c_float
from gtmodel.codegen.emit import Fragment, fill, header_guard
from gtmodel.codegen.emit.wrapper import _arg_size, _check_every, _out_function, functions_fragment, wrapper_text
from gtmodel.codegen.robot import RobotModel
from gtmodel._escape import c_comment, c_string

__all__ = ["functions_fragment", "header_text", "wrapper_text"]

_ = (_arg_size, _check_every, _out_function)  # former names of this module


def header_text(gen_prefix: str, functions: Fragment, version: str, phash: str, model: RobotModel, friction: str, real: str,
                newton: dict, extra: Sequence[str] = ()) -> str:
    """The public header ``<prefix>.h`` of a robot's (or a controller's) library.

    Parameters
    ----------
    gen_prefix : str
        C prefix (``gt_L1``).
    functions : Fragment
        The wrapped functions (:func:`functions_fragment`).
    version : str
        Version string of the library.
    phash : str
        Parameter (or controller) hash.
    model : RobotModel
        The robot (named unless every function is a controller's).
    friction : str
        Friction form of the dynamics.
    real : {"double", "float"}
        Floating-point type.
    newton : dict
        ``{name: (tolerance, max_iter)}`` of the Newton loops.
    extra : sequence of str, optional
        Header lines of the other fragments (controller, re-timing), after the prototypes.

    Returns
    -------
    str
        The header (``harness/template_header.h`` filled).
    """
    P = gen_prefix.upper()
    robot = any(spec.kind != CONTROLLER_KIND for spec in functions.specs)
    robot_doc = [
        f" * Robot: {c_comment(model.description)}",
        f" * Friction form of the dynamics: {friction}" if model.kind == "three_link" else " * Kinematics only.",
    ] if robot else []
    tolerances = [
        "/* Smallest accepted |cos| of the link-to-guideway angle; below it GT_SINGULAR. */",
        f"#define {P}_SINGULARITY_TOLERANCE {_c_float(THRESHOLD_MACROS['SINGULARITY_TOLERANCE'])}",
        "/* Smallest accepted distance [m] of sphere centre 3 from the line through 1 and 2 (FK). */",
        f"#define {P}_DEGENERACY_TOLERANCE {_c_float(THRESHOLD_MACROS['DEGENERACY_TOLERANCE'])}",
    ] if robot else []
    newton_defines = []
    for name, (tol, max_iter) in newton.items():
        N = f"{P}_{name.upper()}"
        newton_defines += [
            f"/* Newton loop of {gen_prefix}_{name}: convergence tolerance and iteration limit (generation options). */",
            f"#define {N}_TOLERANCE {_c_float(tol)}",
            f"#define {N}_MAX_ITER {int(max_iter)}",
        ]
    names = dict(VERSION=version, WHAT=f"the {model.name} Gantry-Tau model." if robot else "gtmodel controller functions (no robot model).")
    return fill(
        "template_header.h", names, GP=gen_prefix, P=P, HASH=phash, REAL=real, IS_FLOAT=1 if real == "float" else 0,
        SOURCE="the CasADi model" if robot else "the controller's CasADi Functions",
        ROBOT_DOC="\n".join(robot_doc), ROBOT_DEFINE=f'#define {P}_ROBOT {c_string(model.name)}' if robot else "",
        OPEN=header_guard(P)[0], CLOSE=header_guard(P)[1],
        ROBOT_TOLERANCES="\n".join(tolerances), NEWTON_DEFINES="\n".join(newton_defines),
        PROTOTYPES="\n".join(functions.header), EXTRA="\n".join(extra),
    )


