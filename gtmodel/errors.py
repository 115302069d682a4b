"""Exceptions raised by gtmodel.

Every exception derives from :class:`GtModelError`; each subclass also inherits the
matching builtin (``ValueError``, ``RuntimeError``, ...), so ``except ValueError``
keeps working for callers that do not know gtmodel.
"""

from __future__ import annotations

__all__ = [
    "GtModelError",
    "InputError",
    "ParameterError",
    "ProblemError",
    "ModelError",
    "UnreachablePoseError",
    "SingularConfigurationError",
    "ConvergenceError",
    "SolverError",
    "CodegenError",
    "CompilerNotFoundError",
    "ResultWriteError",
]


class GtModelError(Exception):
    """Base class of every error raised by gtmodel."""


class InputError(GtModelError, ValueError):
    """A function argument has the wrong shape, type or value."""


class ParameterError(GtModelError, ValueError):
    """A robot parameter set (file or mapping) is invalid; the message names file and field."""


class ProblemError(GtModelError, ValueError):
    """A problem file is invalid; the message names the file and the field."""


class ModelError(GtModelError, ValueError):
    """A model or optimisation declaration is inconsistent (modelling layer)."""


class UnreachablePoseError(GtModelError, ValueError):
    """A pose or a set of actuator positions has no kinematic solution; the message names the arm."""


class SingularConfigurationError(GtModelError, ValueError):
    """The Jacobian is singular (or numerically so) at the requested pose."""


class ConvergenceError(GtModelError, RuntimeError):
    """An iterative method (Newton, integrator) did not converge within its limits."""


class SolverError(GtModelError, RuntimeError):
    """A numerical solver could not be set up or run (not a non-optimal status, which is a result)."""


class CodegenError(GtModelError, RuntimeError):
    """C code generation, compilation or its self-check failed."""


class CompilerNotFoundError(CodegenError):
    """No C compiler was found; the message says how to install one."""


class ResultWriteError(GtModelError, OSError):
    """A result file or folder cannot be written; the message names the path (exit code 2)."""
