"""Self-checks of generated C: compiled functions against the Python evaluation.

- :mod:`~gtmodel.codegen.check.run`: the one helper that writes, compiles (with the
  library's build flags), runs and parses a C program, and the timing programs;
- :mod:`~gtmodel.codegen.check.report`: the comparison against a tolerance
  (:func:`~gtmodel.codegen.check.report.within`) and the reports;
- :mod:`~gtmodel.codegen.check.compare`: inputs, Python references, comparisons and
  edge-case probes of the robot functions;
- :mod:`~gtmodel.codegen.check.robot`: :func:`check` of the robot functions and their timing;
- :mod:`~gtmodel.codegen.check.harness`: the C unit tests of the hand-written harness;
- :mod:`~gtmodel.codegen.check.controller`: :func:`check_controller` over a run of the 4 ms loop;
- :mod:`~gtmodel.codegen.check.filter`: the KF/EKF steps over a measurement record;
- :mod:`~gtmodel.codegen.check.loop_step`: a loop controller's step against Python and its contract;
- :mod:`~gtmodel.codegen.check.closed_loop`, :mod:`~gtmodel.codegen.check.mpc`: a loop
  controller (the MPC's with its IPOPT agreement) in closed loop against a plant simulated in
  Python, beside the feedforward alone, in the library's real type.

Every report has a ``status``, the shared :class:`~gtmodel.status.Status`;
:func:`gtmodel.codegen.check_code` joins them. The C is called through the library's one
ctypes owner, :class:`gtmodel.codegen.build.CompiledLibrary`.
"""

from __future__ import annotations

from gtmodel.codegen.check.compare import sample_inputs
from gtmodel.codegen.check.harness import HARNESS_FILES, HARNESS_FUNCTIONS, harness_applies, harness_dir, run_harness_unit_tests
from gtmodel.codegen.check.report import FLOAT_RELATIVE_TOLERANCE, SENTINEL, CheckReport, FunctionCheck, StatusProbe, within
from gtmodel.codegen.check.robot import check, time_functions, timed_rows
from gtmodel.codegen.declarations import FK_TOLERANCE, IK_TOLERANCE, INVERSE_DYNAMICS_TOLERANCE, JACOBIAN_TOLERANCE

__all__ = [
    "IK_TOLERANCE",
    "FK_TOLERANCE",
    "JACOBIAN_TOLERANCE",
    "INVERSE_DYNAMICS_TOLERANCE",
    "FLOAT_RELATIVE_TOLERANCE",
    "SENTINEL",
    "FunctionCheck",
    "StatusProbe",
    "CheckReport",
    "within",
    "sample_inputs",
    "timed_rows",
    "time_functions",
    "run_harness_unit_tests",
    "harness_dir",
    "harness_applies",
    "HARNESS_FILES",
    "HARNESS_FUNCTIONS",
    "check",
]
