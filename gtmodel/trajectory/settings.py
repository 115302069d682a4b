"""How an optimal-motion problem is solved, apart from what it is (rockit's split).

A declaration (:class:`~gtmodel.trajectory.PointToPoint`, a path-constrained problem)
says *what* is optimised; two small objects say *how*:

- :class:`Collocation`, the method: the direct-collocation transcription (finite elements,
  collocation points per element, Radau or Legendre points; JModelica's defaults);
- :class:`SolverSettings`, the solver: the NLP solver, its iteration limit and tolerance,
  and whether the NLP derivatives are evaluated through compiled C.

Problem files keep their ``[collocation]`` and ``[solver]`` tables; the problem kinds
build these objects from them.
"""

from __future__ import annotations

from dataclasses import dataclass

from gtmodel.errors import InputError

__all__ = ["Collocation", "SolverSettings", "Refinement", "SCHEMES", "NLP_SOLVERS"]

#: Collocation point families.
SCHEMES = ("radau", "legendre")
#: NLP solvers the transcriptions offer through the project's assembled derivatives.
NLP_SOLVERS = ("ipopt",)


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

    Raises
    ------
    InputError
        A value out of range (naming it).
    """

    elements: int = 50
    points: int = 3
    scheme: str = "radau"

    def __post_init__(self) -> None:
        _positive_int("elements", self.elements)
        _positive_int("points", self.points, 9)
        if self.scheme not in SCHEMES:
            raise InputError(f"scheme: expected one of {', '.join(SCHEMES)}, got {self.scheme!r}")


@dataclass(frozen=True)
class SolverSettings:
    """The solver: which NLP solver, how long, how tight, and how derivatives are evaluated.

    Parameters
    ----------
    name : str
        The NLP solver (``"ipopt"``).
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
    max_elements : int
        Limit on the elements of a refined mesh.
    max_passes : int
        Limit on the solves of the refinement.

    Raises
    ------
    InputError
        A value out of range (naming it).
    """

    refine: bool = False
    tolerance: float | None = None
    max_elements: int = 400
    max_passes: int = 10

    def __post_init__(self) -> None:
        _positive_int("max_elements", self.max_elements)
        _positive_int("max_passes", self.max_passes)
        if self.tolerance is not None and not (isinstance(self.tolerance, (int, float)) and 0 < self.tolerance < 1):
            raise InputError(f"tolerance: expected a number in (0, 1), got {self.tolerance!r}")
