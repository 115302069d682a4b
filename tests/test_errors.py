"""Every gtmodel exception derives from GtModelError and from the matching builtin, so
``except ValueError`` / ``except OSError`` in callers that do not know gtmodel keeps working."""

from __future__ import annotations

import pytest

import gtmodel.errors as errors

BUILTIN = {
    "InputError": ValueError, "ParameterError": ValueError, "ProblemError": ValueError, "ModelError": ValueError,
    "UnreachablePoseError": ValueError, "SingularConfigurationError": ValueError, "ConvergenceError": RuntimeError,
    "SolverError": RuntimeError, "CodegenError": RuntimeError, "CompilerNotFoundError": RuntimeError,
    "ResultWriteError": OSError,
}


@pytest.mark.parametrize("name", sorted(set(errors.__all__) - {"GtModelError"}))
def test_error_derives_from_gtmodel_error_and_its_builtin(name):
    cls = getattr(errors, name)
    assert issubclass(cls, errors.GtModelError)
    assert issubclass(cls, BUILTIN[name])
