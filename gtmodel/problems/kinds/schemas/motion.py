"""The tables the motion kinds (``point_to_point``, ``path_constrained``) share, and their closed-loop relatives.

``[motion]``, ``[collocation]``, ``[solver]`` and the robot reference of ``[robot]``
read the same in those kinds. Light (pydantic and :mod:`gtmodel.problems.schema` only), so
that a file is validated before its kind's solvers are imported.
"""

from __future__ import annotations

from pydantic import Field

from gtmodel.defaults import defaults
from gtmodel.problems.schema import MAX_LENGTH_M, Flag, NonEmptyText, Section, choice, integer, number, vector

__all__ = ["MAX_TIME_S", "RobotReference", "MotionSection", "CollocationSection", "RefinementSection", "VerificationSection", "SolverSection", "OcpSolverSection"]

#: Longest final time accepted [s].
MAX_TIME_S = 1.0e4


class RobotReference(Section):
    """``[robot]``: the parameter set and the IK configuration (each kind adds its dynamics options).

    Parameters
    ----------
    parameters : str
        Shipped parameter set name or a TOML path relative to the problem file.
    configuration : int
        IK configuration, 0..7.
    """

    parameters: NonEmptyText = Field(description="shipped parameter set (L1, D1, L1_ideal) or a TOML path relative to the problem file")
    configuration: integer(0, 7, description="IK configuration") = 0


class MotionSection(Section):
    """``[motion]``: rest-to-rest between two TCP positions.

    Parameters
    ----------
    start, end : list of float, shape (3,)
        TCP positions at rest [m].
    """

    start: vector(3, bound=MAX_LENGTH_M, unit="m", description="TCP position at rest at the start")
    end: vector(3, bound=MAX_LENGTH_M, unit="m", description="TCP position at rest at the end")


class CollocationSection(Section):
    """``[collocation]``: the transcription.

    Parameters
    ----------
    elements : int
        Finite elements, 1..10000.
    points : int
        Collocation points per element, 1..9.
    scheme : str
        ``"radau"`` or ``"legendre"``.
    eliminate_algebraics : bool
        Substitute the model's algebraic variables by their expressions of the states,
        inputs and parameters where each block of the algebraic equations is linear with a
        constant Jacobian (the NLP then carries none; the result's are evaluated at the
        solution); false keeps each as an NLP variable at every collocation point.
    """

    elements: integer(1, 10000, description="finite elements") = 50
    points: integer(1, 9, description="collocation points per element") = 3
    scheme: choice("radau", "legendre") = "radau"
    eliminate_algebraics: Flag = Field(True, description="substitute the algebraic variables by their expressions of states, inputs and parameters where each block of the algebraic equations is linear in its own variables with a constant Jacobian (false: each an NLP variable at every collocation point)")


class RefinementSection(Section):
    """``[transcription]``: the verification tolerance and adaptive mesh refinement of a collocation solve.

    Parameters
    ----------
    refine : bool
        Refine the mesh where the solution is least accurate (element defects, input
        switches) until the verification passes or a limit is reached.
    tolerance : float, optional
        Verification tolerance: largest deviation of a state's simulation under the
        optimal inputs from the transcribed state, scaled by ``max(1, max |x|)``; default
        1e-2 (``gtmodel.defaults``).
    max_elements : int, optional
        Limit on the elements of a refined mesh; unset: the most the memory estimate allows
        (``gtmodel.modeling.ocp.budget.max_elements``).
    max_passes : int
        Limit on the solves of the refinement.
    refine_on_failure : bool
        A single solve (``refine = false``) whose verification fails is refined from, within
        the limits (default; as GPOPS-II, which always refines to its mesh tolerance).
    max_cpu_s : float, optional
        CPU-time budget of a refinement [s]; default ``defaults["ocp.refine_max_cpu_s"]``.
    objective_tolerance : float, optional
        A refinement's verified pass with nothing left to split is solved again with every
        element halved, and refined on from there while that improves the objective by more
        than this fraction; 0 ends at the first verified pass; default
        ``defaults["ocp.refine_objective_tolerance"]`` (1e-3).
    regularization : float, optional
        Weight of the input energy a refinement adds to a minimum-time objective from its second pass on, each input
        scaled by its RMS in the previous pass (:mod:`gtmodel.modeling.ocp.regularization`): the minimum time rises by
        about this fraction per input; 0 off; default ``defaults["ocp.input_regularization"]`` (1e-3).
    """

    refine: Flag = Field(False, description="collocation: refine the mesh until the verification passes (h-refinement, switches located; also with [[data]]; not with multiple shooting)")
    tolerance: number(gt=0, lt=1, description="verification tolerance: scaled deviation of the states from their simulation (default 1e-2)") | None = None
    max_elements: integer(1, 20000, description="limit on the elements of a refined mesh (unset: the most the memory estimate allows)") | None = None
    max_passes: integer(1, 100, description="limit on the solves of the refinement") = defaults["ocp.refine_max_passes"]
    refine_on_failure: Flag = Field(True, description="collocation: a single solve whose verification fails is refined from (as refine = true, within max_passes and max_cpu_s); false: it ends check_failed")
    max_cpu_s: number(gt=0, description="CPU-time budget of a mesh refinement, s (default 290): no pass starts once it is spent, the best verified pass is returned") | None = None
    objective_tolerance: number(ge=0, lt=1, description="a refinement's verified pass with nothing left to split is solved again with every element halved, and refined on while that improves the objective by more than this fraction (default 1e-3; 0: no such check)") | None = None
    regularization: number(ge=0, le=0.01, description="a refinement's passes after the first add this weight of input energy (each input scaled by its RMS) to a minimum-time objective, so that inputs a bound arc leaves free do not ring; the minimum time rises by about this fraction per input (default 1e-3; 0: off)") | None = None


class VerificationSection(Section):
    """``[verification]``: how a solution is verified by simulation (:mod:`gtmodel.modeling.ocp.verification`).

    The tolerance of the check itself is ``[transcription] tolerance`` (mesh refinement
    uses it too).

    Parameters
    ----------
    enabled : bool
        Verify the solution (default). Off, the summary's ``verification`` block says
        ``"status": "skipped"`` (never passed) and the CLI prints ``skipped``.
    integrator : str
        ``"auto"`` (CVODES for an ODE, IDAS with algebraic variables), ``"cvodes"`` or
        ``"idas"``: SUNDIALS BDF with Newton iterations on the model's Jacobian.
    rtol : float, optional
        Relative tolerance of the integrator (absolute: ``1e-2 rtol``); default ``1e-3``
        times the verification tolerance within ``[1e-10, 1e-6]``.
    """

    enabled: Flag = Field(True, description="verify the solution by simulation (off: the summary says skipped, never verified)")
    integrator: choice("auto", "cvodes", "idas", description="SUNDIALS integrator; auto: cvodes (BDF where the model is stiff along the solution, else Adams) for ODEs and for algebraic variables eliminated symbolically, idas for a nonlinear algebraic loop") = "auto"
    rtol: number(gt=0, lt=1, description="relative tolerance of the integrator (default 1e-3 x the verification tolerance, within [1e-10, 1e-6])") | None = None


class SolverSection(Section):
    """``[solver]``: IPOPT settings.

    Parameters
    ----------
    max_iter : int
        IPOPT iteration limit.
    tol : float
        IPOPT tolerance.
    """

    max_iter: integer(1, 10**6, description="IPOPT iteration limit") = 3000
    tol: number(gt=0, le=1.0, description="IPOPT tolerance") = 1e-8


class OcpSolverSection(SolverSection):
    """``[solver]`` of a collocation OCP: the NLP solver and how its derivatives are evaluated.

    Parameters
    ----------
    max_iter : int
        IPOPT iteration limit.
    tol : float
        IPOPT tolerance.
    name : str
        The NLP solver: ``"ipopt"`` (IPOPT with MUMPS, the project's assembled
        derivatives, default) or ``"fatrop"`` (the NLP ordered stage by stage, one stage
        per element; given the same assembled derivatives as IPOPT, ``jit`` applies to both).
    jit : bool
        Evaluate the constraint Jacobian and Lagrangian Hessian through C generated from
        their CasADi graph, compiled once with the system compiler and cached (the same
        values, about 5x faster per evaluation); the interpreter without a compiler.
    """

    name: choice("ipopt", "fatrop", description="NLP solver (fatrop: stage-wise interior point)") = "ipopt"
    jit: Flag = Field(default=True, description="compiled (cached) C for the NLP derivatives")
