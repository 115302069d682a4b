"""How an optimal control problem is solved, apart from what it is (rockit's split).

A declaration (an :class:`~gtmodel.modeling.Optimization`, or the problems above it:
:class:`~gtmodel.trajectory.PointToPoint`, a path-constrained problem) says *what* is
optimised; small frozen objects, beside the transcriptions they configure, say *how*:

- the method: :class:`Collocation`, the direct-collocation transcription (finite elements,
  collocation points per element, Radau or Legendre points; JModelica's defaults;
  :class:`~gtmodel.modeling.ocp.collocation.CollocationTranscription`), or
  :class:`MultipleShooting` (:class:`~gtmodel.modeling.ocp.shooting.ShootingTranscription`);
- :class:`SolverSettings`, the solver: the NLP solver, its iteration limit and tolerance,
  and whether the NLP derivatives are evaluated through compiled C;
- :class:`Refinement`, the verification and mesh refinement; its
  :attr:`Refinement.verification` (a :class:`VerificationSettings`) is passed to the
  transcription, which verifies with it: a solve never writes its settings onto the
  declaration.

Problem files keep their ``[collocation]``, ``[transcription]``, ``[solver]`` and
``[refinement]`` tables; the problem kinds build these objects from them. The former path
:mod:`gtmodel.trajectory.settings` re-exports them.
"""

from __future__ import annotations

from dataclasses import dataclass

from gtmodel.defaults import defaults
from gtmodel.errors import InputError
from gtmodel.modeling.ocp.regularization import regularization_weight

__all__ = ["Collocation", "MultipleShooting", "SolverSettings", "Refinement", "VerificationSettings", "SCHEMES", "NLP_SOLVERS"]

#: Collocation point families.
SCHEMES = ("radau", "legendre")
#: NLP solvers of the collocation transcriptions: IPOPT (with the project's assembled, compiled
#: derivatives) and fatrop (the NLP ordered stage by stage); the transcription's
#: :data:`gtmodel.modeling.ocp.collocation_stages.SOLVERS` is this tuple.
NLP_SOLVERS = ("ipopt", "fatrop")


def _positive_int(name: str, value: object, hi: int | None = None) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1 or (hi is not None and value > hi):
        span = f"an integer in 1..{hi}" if hi is not None else "a positive integer"
        raise InputError(f"{name}: expected {span}, got {value!r}")


@dataclass(frozen=True)
class Collocation:
    """The method: a direct-collocation transcription.

    Parameters
    ----------
    elements : int
        Finite elements (>= 1).
    points : int
        Collocation points per element, 1..9.
    scheme : str
        ``"radau"`` or ``"legendre"``.
    eliminate_algebraics : bool
        Substitute the algebraic variables by their expressions of the states, inputs and
        parameters where each block of the algebraic equations is linear with a constant
        Jacobian (:mod:`~gtmodel.modeling.ocp.elimination`: the NLP carries none, the
        result's are evaluated at the solution); False keeps each as an NLP variable at
        every collocation point.

    Raises
    ------
    InputError
        A value out of range (naming it).
    """

    elements: int = 50
    points: int = 3
    scheme: str = "radau"
    eliminate_algebraics: bool = True

    def __post_init__(self) -> None:
        _positive_int("elements", self.elements)
        _positive_int("points", self.points, 9)
        if self.scheme not in SCHEMES:
            raise InputError(f"scheme: expected one of {', '.join(SCHEMES)}, got {self.scheme!r}")


@dataclass(frozen=True)
class MultipleShooting:
    """The method: direct multiple shooting (:class:`~gtmodel.modeling.ocp.shooting.ShootingTranscription`).

    Parameters
    ----------
    intervals : int
        Shooting intervals.
    controls : {"constant", "linear"}
        Input parametrisation per interval.
    integrator : str or None
        Integrator (None: rk for an ODE, collocation with algebraic variables: gtmodel's fixed-step
        Radau collocation, the only one of rk, radau and collocation that ended optimal and verified
        on all five shipped drives, ``benchmarks/bench_shooting_integrators.py``).
    steps : int
        Fixed steps per interval of rk/radau/collocation.
    """

    intervals: int = 50
    controls: str = "constant"
    integrator: str | None = None
    steps: int = 4


@dataclass(frozen=True)
class SolverSettings:
    """The solver: which NLP solver, how long, how tight, and how derivatives are evaluated.

    Parameters
    ----------
    name : str
        The NLP solver, one of :data:`NLP_SOLVERS` (``"ipopt"`` or ``"fatrop"``).
    max_iter : int
        Iteration limit (>= 1).
    tol : float
        Convergence tolerance (> 0).
    jit : bool
        Evaluate the constraint Jacobian and Lagrangian Hessian through C generated from
        their CasADi graph, compiled once and cached (the interpreter without a compiler).

    Raises
    ------
    InputError
        A value out of range (naming it).
    """

    name: str = "ipopt"
    max_iter: int = 3000
    tol: float = 1e-8
    jit: bool = True

    def __post_init__(self) -> None:
        if self.name not in NLP_SOLVERS:
            raise InputError(f"name: expected one of {', '.join(NLP_SOLVERS)}, got {self.name!r}")
        _positive_int("max_iter", self.max_iter)
        if isinstance(self.tol, bool) or not isinstance(self.tol, (int, float)) or not 0 < self.tol < float("inf"):
            raise InputError(f"tol: expected a positive finite number, got {self.tol!r}")


@dataclass(frozen=True)
class VerificationSettings:
    """How a transcription verifies its solution by simulation (:func:`gtmodel.modeling.ocp.verification.verify`).

    Passed to the transcription (``verification=``), never written onto the declaration;
    a field left None falls back to the declaration's own value
    (:attr:`~gtmodel.modeling.Optimization.verification_tolerance`,
    ``verification_rtol``, ``verification_integrator``), then to the default.

    Parameters
    ----------
    tolerance : float or None
        Verification tolerance (scaled deviation of the states from their simulation);
        None: the declaration's, else ``defaults["ocp.verification_tolerance"]``.
    rtol : float or None
        Relative tolerance of the verifying integrator; None: the declaration's, else
        :func:`gtmodel.modeling.ocp.verification.integrator_rtol` of the tolerance.
    integrator : str or None
        ``"cvodes"`` or ``"idas"``; None: the declaration's, else CVODES for an ODE, IDAS
        with algebraic variables.
    """

    tolerance: float | None = None
    rtol: float | None = None
    integrator: str | None = None

    def over(self, optimization: object) -> "VerificationSettings":
        """These settings, each None field taken from ``optimization``'s declared value.

        Parameters
        ----------
        optimization : Optimization
            The declaration (its ``verification_tolerance``, ``verification_rtol`` and
            ``verification_integrator``; read, not changed).

        Returns
        -------
        VerificationSettings
            The settings the verification uses (None where neither says: the default).
        """
        return VerificationSettings(
            self.tolerance if self.tolerance is not None else getattr(optimization, "verification_tolerance", None),
            self.rtol if self.rtol is not None else getattr(optimization, "verification_rtol", None),
            self.integrator if self.integrator is not None else getattr(optimization, "verification_integrator", None),
        )


@dataclass(frozen=True)
class Refinement:
    """Verification and adaptive mesh refinement of a collocation solution.

    Parameters
    ----------
    refine : bool
        Refine the mesh (:func:`gtmodel.modeling.ocp.refinement.solve_refined`) until the
        verification passes, or solve once on the given mesh (verified all the same).
    tolerance : float or None
        Verification tolerance (scaled deviation of the states from their simulation,
        :mod:`gtmodel.modeling.ocp.verification`); None for the default
        ``defaults["ocp.verification_tolerance"]``.
    max_elements : int or None
        Limit on the elements of a refined mesh; None (default): the most the memory estimate
        allows (:func:`gtmodel.modeling.ocp.budget.max_elements`).
    max_passes : int
        Limit on the solves of the refinement.
    verify : bool
        Verify the solution by simulation (default); off, nothing is verified and the
        result's ``verification`` is None (its summary block says ``skipped``); refused with
        ``refine`` (refinement is driven by the verification).
    integrator : str or None
        The verifying integrator, ``"cvodes"`` or ``"idas"``; None: CVODES for an ODE,
        IDAS with algebraic variables.
    rtol : float or None
        Relative tolerance of the verifying integrator; None for
        :func:`gtmodel.modeling.ocp.verification.integrator_rtol` of the tolerance.
    on_failure : bool
        Without ``refine``, a solve whose verification fails is refined from
        (:func:`gtmodel.modeling.ocp.refinement.solve_refined` with ``start``), within the
        limits; default True.
    max_cpu_s : float or None
        CPU-time budget of a refinement [s]; None for
        ``defaults["ocp.refine_max_cpu_s"]``. Multiple shooting
        (:meth:`gtmodel.trajectory.model_ocp.OptimalControl.solve`) takes it as the budget of
        its whole solve, continuation included; None there: no budget.
    objective_tolerance : float or None
        A refinement's verified pass with nothing left to split is solved again with every
        element halved, and refined on from there while that improves the objective by more
        than this fraction; 0: no such check; None for
        ``defaults["ocp.refine_objective_tolerance"]``.
    regularization : float or None
        Weight of the input energy a refinement adds to a minimum-time objective from its second pass on
        (:mod:`gtmodel.modeling.ocp.regularization`); 0 off; None for ``defaults["ocp.input_regularization"]``.

    Raises
    ------
    InputError
        A value out of range (naming it).
    """

    refine: bool = False
    tolerance: float | None = None
    max_elements: int | None = None
    max_passes: int = defaults["ocp.refine_max_passes"]
    verify: bool = True
    integrator: str | None = None
    rtol: float | None = None
    on_failure: bool = True
    max_cpu_s: float | None = None
    objective_tolerance: float | None = None
    regularization: float | None = None

    def __post_init__(self) -> None:
        if self.regularization is not None:
            regularization_weight(self.regularization)  # the one check of a weight
        if self.max_elements is not None:
            _positive_int("max_elements", self.max_elements)
        if self.max_cpu_s is not None and not (isinstance(self.max_cpu_s, (int, float)) and self.max_cpu_s > 0):
            raise InputError(f"max_cpu_s: expected a positive number of seconds, got {self.max_cpu_s!r}")
        _positive_int("max_passes", self.max_passes)
        if self.objective_tolerance is not None and (isinstance(self.objective_tolerance, bool) or not isinstance(
                self.objective_tolerance, (int, float)) or not 0 <= self.objective_tolerance < 1):
            raise InputError(f"objective_tolerance: expected a number in [0, 1) (0: no objective check), got {self.objective_tolerance!r}")
        if self.tolerance is not None and not (isinstance(self.tolerance, (int, float)) and 0 < self.tolerance < 1):
            raise InputError(f"tolerance: expected a number in (0, 1), got {self.tolerance!r}")
        if self.refine and not self.verify:
            raise InputError("verify: mesh refinement (refine = true) is driven by the verification; it cannot be off")
        if self.integrator not in (None, "cvodes", "idas"):
            raise InputError(f"integrator: expected 'cvodes' or 'idas', got {self.integrator!r}")
        if self.rtol is not None and not (isinstance(self.rtol, (int, float)) and 0 < self.rtol < 1):
            raise InputError(f"rtol: expected a number in (0, 1), got {self.rtol!r}")

    @property
    def verification(self) -> VerificationSettings:
        """The verification's settings (tolerance, integrator and its rtol), passed to the transcription."""
        return VerificationSettings(self.tolerance, self.rtol, self.integrator)
