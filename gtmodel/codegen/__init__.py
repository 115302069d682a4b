"""C code generation from the CasADi model, compilation and self-check.

``generate`` writes C and a header for model functions (``ik``, ``fk``, ``jacobian``,
``inverse_dynamics``); ``compile_shared`` builds a shared library with the system C
compiler; ``check`` compares the compiled C with the Python evaluation.
"""

from __future__ import annotations

from gtmodel.codegen.build import CompiledLibrary, compile_shared, find_compiler, load_library
from gtmodel.codegen.check import CheckReport, FunctionCheck, StatusProbe, check

from gtmodel.codegen.generate import GeneratedCode, generate, parameter_hash
from gtmodel.codegen.specs import FUNCTION_SPECS, FunctionSpec

__all__ = [
    "generate",
    "compile_shared",
    "find_compiler",
    "load_library",
    "check",
    "GeneratedCode",
    "CheckReport",
    "FunctionCheck",
    "StatusProbe",
    "CompiledLibrary",
    "FunctionSpec",
    "FUNCTION_SPECS",
    "parameter_hash",
]
