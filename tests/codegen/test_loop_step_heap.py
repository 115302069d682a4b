"""The heap arena of a loop step whose QP solver allocates (DAQP), as generated C (slow: two compiles).

References: the allocator calls themselves, counted by the arena (``<prefix>_heap_stats``): the
peak use is non-zero only if DAQP's mallocs reached the arena (the ``--wrap`` link took effect),
and an arena made too small at compile time (``-DGT_HEAP_ARENA_BYTES=64``) passes exactly those
calls to the heap, which the closed-loop verdict names; a qrqp step (no allocating solver) has no
arena at all.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.codegen.build import compile_shared
from gtmodel.codegen.loop_step import HEAP_ARENA_BYTES, generate_loop_step, mpc_step, uses_heap_arena
from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.control.mpc import mpc_controller
from gtmodel.modeling import explicit_ode
from gtmodel.problems.loop_check import LoopCheck, compiled_step, heap_stats

from ..modeling._builders import double_integrator

pytestmark = pytest.mark.slow

DT = 0.004
T = DT * np.arange(101)
X_REF = np.column_stack([np.minimum(T / 0.2, 1.0), np.where(T < 0.2, 5.0, 0.0)])


def _generated(tmp_path, **kwargs):
    ode = explicit_ode(double_integrator()[0])
    c = mpc_controller(ode, T, X_REF, np.zeros((101, 1)), horizon=20, Q=[1.0, 0.0], R=[1e-4], u_lb=[-50.0], u_ub=[50.0],
                       method="euler", **kwargs)
    return generate_loop_step(mpc_step(c, "di"), tmp_path, prefix="gt_di")


def _run(generated, library, steps=60):
    controller, _, _ = compiled_step(generated, library)
    statuses = [controller(T[k], X_REF[k] + [0.01, 0.0])[0] for k in range(steps)]
    return statuses, heap_stats(generated, library)


@pytest.mark.parametrize("flags, in_heap", [((), False), (("-DGT_HEAP_ARENA_BYTES=64",), True)], ids=["arena", "arena too small"])
def test_daqp_allocations_go_to_the_arena(tmp_path, flags, in_heap):
    generated = _generated(tmp_path, x_ub={"x": 2.0})  # a constraint row: DAQP
    assert uses_heap_arena(generated.casadi_source)
    assert "_heap_stats(unsigned long *peak_bytes" in generated.header.read_text()
    statuses, (peak, calls, size) = _run(generated, compile_shared(generated, tmp_path / "build", extra_flags=flags))
    assert statuses == [0] * len(statuses)
    assert size == (64 if in_heap else HEAP_ARENA_BYTES)
    assert (calls > 0) == in_heap
    assert 0 < peak <= size if not in_heap else peak == 0
    check = LoopCheck(closed=_trivial_loop(0.1), feedforward=_trivial_loop(0.5), memory_bytes=0, work_bytes=0, heap=(peak, calls, size))
    assert [f for f in check.failures() if "on the heap" in f] == ([f"{calls} allocations of the QP solver on the heap (its arena of 64 bytes too small)"]
                                                                   if in_heap else [])


def _trivial_loop(u):
    """x_{k+1} = x_k + u from 1 against the reference 1: an otherwise passing loop."""
    x, v, p = ca.SX.sym("x"), ca.SX.sym("u"), ca.SX.sym("p", 0)
    step = ca.Function("step", [x, v, p], [x + v])
    return run_controller_loop(lambda t, y: (0, [u]), step, [1.0], np.arange(8.0), np.ones((8, 1)), [-1.0], [1.0], delay=0)


def test_qrqp_step_has_no_arena(tmp_path):
    generated = _generated(tmp_path)
    assert not uses_heap_arena(generated.casadi_source)
    _, stats = _run(generated, compile_shared(generated, tmp_path / "build"), steps=3)
    assert stats is None
