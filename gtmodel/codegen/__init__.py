"""C code generation from the CasADi model, compilation and self-check.

The front door (:mod:`gtmodel.codegen.sources`): every kind of code is a ``CodeSource``
(``RobotSource``, ``UserModelSource``, the loop step ``LoopStep`` of a tracking controller or
an MPC, ``ControllerSource``) that supplies its declarations, its Python reference and its
writer; ``generate_code(source, out_dir)`` writes it, ``check_code(generated)`` checks it
(C against Python, the closed loop of a loop controller) with one shared ``Status``.
``generate`` and ``check_generated`` below take a source too (``check_generated`` was ``check``,
which shadowed the package :mod:`gtmodel.codegen.check`).

``generate`` writes C and a header for the model functions of a robot (3-link sets: ``ik``,
``fk``, ``jacobian``, ``jacobian_inverse``, ``acceleration``, ``inverse_dynamics``,
``gravity``; the six-link ``fk``/``ik``; the F1 Newton ``ik``/``fk``) and, with an
``EstimatorILCBundle`` (formerly ``Controller``), the Kalman step, the ILC correction and the KF/EKF
steps of the laser tracker + IMU fusion (:mod:`gtmodel.codegen.specs.filter`), with
``retime_n_max`` the online re-timing along a path (:mod:`gtmodel.codegen.retime`);
``compile_shared``
builds a shared library with the system C compiler; ``check_generated`` compares the compiled C with
the Python evaluation, probes the edge cases and times every function. The hand-written
harness (Makefile, 4 ms loop, C unit tests) is in ``codegen/`` at the top of the repository.

The stages, each importing only those below it (an import-linter contract):

- :mod:`~gtmodel.codegen.declarations`, :mod:`~gtmodel.codegen.robot`: what a generated
  function is (``FunctionSpec``) and the robot models;
- :mod:`~gtmodel.codegen.specs`: the declarations per robot kind and of the filter steps;
- :mod:`~gtmodel.codegen.controller`: the ``Controller`` and its declarations;
- :mod:`~gtmodel.codegen.emit`: the C, one ``Fragment`` (header lines, source lines, specs)
  per part, the hand-written C in template files of ``harness/``;
- :mod:`~gtmodel.codegen.writer`: the one library writer (``write_library``, ``GeneratedCode``),
  over the generic emitter :mod:`~gtmodel.codegen.emit.wrapper`;
- :mod:`~gtmodel.codegen.generate`: the robot's writer, the four files of its library from the fragments;
- :mod:`~gtmodel.codegen.build`, :mod:`~gtmodel.codegen.retime`,
  :mod:`~gtmodel.codegen.controller_file`: compiling and loading, calling the re-timing,
  controller files;
- :mod:`~gtmodel.codegen.check`: the self-checks, with one helper that writes, compiles,
  runs and parses a C program;
- :mod:`~gtmodel.codegen.model_code`: the same for a user's model (its explicit ODE and
  fixed steps);
- :mod:`~gtmodel.codegen.sources`, :mod:`~gtmodel.codegen.verdict`: the front door over all of
  the above (``generate_code``, ``check_code``);
- :mod:`~gtmodel.codegen.loop_step`: the one step interface of the loop's controllers
  (``<prefix>_init``, ``<prefix>_step`` on a caller-owned memory) around one CasADi Function
  (the tracking controller; an MPC);
- :mod:`~gtmodel.codegen.robot_runtime`: a loop step behind KUKA RSI or ABB EGM over UDP
  (``RobotRuntime``, a ``CodeSource``; ``build_runtime`` compiles the one executable that
  :func:`gtmodel.control.runtime.run_loop` runs), just below the front door.
"""

from __future__ import annotations

from gtmodel.codegen.build import CompiledLibrary, compile_shared, find_compiler, load_library
from gtmodel.codegen.check import CheckReport, FunctionCheck, StatusProbe
from gtmodel.codegen.check.controller import ControllerCheckReport, check_controller
from gtmodel.codegen.controller import Controller, EstimatorILCBundle
from gtmodel.codegen.controller_file import load_controller, save_controller
from gtmodel.codegen.declarations import FunctionSpec, NewtonLoop
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.codegen.model_code import check_model, generate_model
from gtmodel.codegen.check.loop_step import check_loop_step
from gtmodel.codegen.loop_step import LoopStep, generate_loop_step
from gtmodel.codegen.robot import load_robot, parameter_hash
from gtmodel.codegen.specs import FUNCTION_SPECS
from gtmodel.codegen.sources import CodeSource, ControllerSource, RobotSource, UserModelSource, generate, generate_code
from gtmodel.codegen.verdict import CodeCheck, check_code, check_generated

__all__ = [
    "CodeSource",
    "RobotSource",
    "UserModelSource",
    "ControllerSource",
    "CodeCheck",
    "generate_code",
    "check_code",
    "generate",
    "generate_model",
    "check_model",
    "LoopStep",
    "generate_loop_step",
    "check_loop_step",
    "compile_shared",
    "find_compiler",
    "load_library",
    "check_generated",
    "EstimatorILCBundle",
    "Controller",
    "check_controller",
    "ControllerCheckReport",
    "load_controller",
    "save_controller",
    "GeneratedCode",
    "CheckReport",
    "FunctionCheck",
    "StatusProbe",
    "CompiledLibrary",
    "FunctionSpec",
    "FUNCTION_SPECS",
    "NewtonLoop",
    "load_robot",
    "parameter_hash",
]
