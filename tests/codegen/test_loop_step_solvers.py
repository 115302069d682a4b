"""The loop step's safe-input contract for every MPC solver, as generated C (slow: three compiles).

Reference: the contract of :mod:`gtmodel.codegen.loop_step`: a failed solve returns a failure
status and the last input, saturated, never NaN. The failure is forced by a hard state bound
that the start cannot meet (the double integrator at 5 m/s, 5 cm before a position bound,
cannot stop in time under |u| <= 50) for the QP solvers with constraints (DAQP, fatrop), and
by a state whose prediction overflows for the unconstrained qrqp step.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.codegen.build import load_library
from gtmodel.codegen.build import compile_shared
from gtmodel.codegen.loop_step import generate_loop_step, mpc_step
from gtmodel.control.mpc import mpc_controller
from gtmodel.modeling import explicit_ode
from gtmodel.problems.mpc_check import compiled_step

from ..modeling._builders import double_integrator

pytestmark = pytest.mark.slow

DT = 0.004
CASES = [("sqpmethod", {}, [1e300, 1e300]), ("sqpmethod", {"x_ub": {"x": 0.5}, "hard_constraints": True}, [0.45, 5.0]),
         ("fatrop", {"x_ub": {"x": 0.5}, "hard_constraints": True}, [0.45, 5.0]), ("hpipm", {}, [1e300, 1e300])]


def _double_integrator_step(tmp_path, solver, kwargs):
    """The reference times and the generated MPC step of the double integrator, rest to 1 in 0.2 s."""
    ode = explicit_ode(double_integrator()[0])
    t = DT * np.arange(101)
    x_ref = np.column_stack([np.minimum(t / 0.2, 1.0), np.where(t < 0.2, 5.0, 0.0)])
    c = mpc_controller(ode, t, x_ref, np.zeros((101, 1)), horizon=20, Q=[1.0, 0.0], R=[1e-4], u_lb=[-50.0], u_ub=[50.0],
                       method="euler", solver=solver, **kwargs)
    return t, generate_loop_step(mpc_step(c, "di"), tmp_path, prefix="gt_di")


@pytest.mark.parametrize("solver, kwargs, bad", CASES, ids=["qrqp overflow", "daqp infeasible", "fatrop infeasible", "hpipm overflow"])
def test_failed_step_returns_the_last_input_saturated(tmp_path, solver, kwargs, bad):
    t, generated = _double_integrator_step(tmp_path, solver, kwargs)
    controller, _, _ = compiled_step(generated, compile_shared(generated, tmp_path / "build"))
    status, u_ok = controller(t[40], [0.3, 1.0])
    assert status == 0 and np.all(np.isfinite(u_ok))
    status, u = controller(t[41], bad)
    assert status != 0
    np.testing.assert_array_equal(u, np.clip(u_ok, -50.0, 50.0))


@pytest.mark.parametrize("solver, kwargs, bad", [CASES[0], CASES[3]], ids=["qrqp overflow", "hpipm overflow"])
def test_failed_step_leaves_no_trace_in_the_next(tmp_path, solver, kwargs, bad):
    # reference: a second controller of the same library (its own memory, the same thread) that never saw the failure;
    # the failed step keeps the memory, so the next good step must be the same to the bit (the hpipm step keeps
    # HPIPM's memory per thread across QPs: gtmodel.codegen.hpipm_source.patch_hpipm_memory)
    t, generated = _double_integrator_step(tmp_path, solver, kwargs)
    library = compile_shared(generated, tmp_path / "build")
    failed, _, _ = compiled_step(generated, library)
    clean, _, _ = compiled_step(generated, library)
    first = [failed(t[40], [0.3, 1.0]), clean(t[40], [0.3, 1.0])]
    status, _ = failed(t[41], bad)
    assert status != 0
    after = [failed(t[42], [0.32, 0.9]), clean(t[42], [0.32, 0.9])]
    assert [s for s, _ in first + after] == [0, 0, 0, 0]
    np.testing.assert_array_equal(after[0][1], after[1][1])
