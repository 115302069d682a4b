"""A glitch in the measurement or the memory of the generated MPC step, in closed loop (slow: the
reference solve and the compile of the motor MPC take ~20-40 s, once for the module).

The motor MPC of ``codegen/mpc/dc_motor_mpc.toml`` (offset-free: its memory holds the warm start,
the disturbance estimate, the last state and input) runs as generated C against the file's
mismatched, noisy plant. Reference: the spike-free run of the same step on the same plant and
noise (the input computed at every period); a single glitch must leave the input within 1 % of
the input bound (24 V) of that run from 5 periods after it on, with a status that is not
``GT_OK`` where the glitch was met, and every input finite and inside the bounds.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest

from gtmodel.codegen.build import load_library
from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.codegen.loop_step import load_loop_step
from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.problems.loop_check import STATUS_NAMES
from gtmodel.problems.mpc_check import build_mpc
from gtmodel.problems.mpc_file import load_mpc_file

from ..conftest import REPO

pytestmark = pytest.mark.slow

OK, BAD, RESET, REJECTED = (STATUS_CODES[k][0] for k in ("GT_OK", "GT_BAD_ARGUMENT", "GT_MEMORY_RESET", "GT_MEASUREMENT_REJECTED"))
#: The period of the glitch (mid-motion: the input is off its bounds) and the periods allowed to recover.
K, RECOVER = 60, 5


class Step:
    """The compiled step with its memory in reach (to write a glitch into it)."""

    def __init__(self, generated, library):
        self.memory, self.init, self.step = load_loop_step(generated, load_library(generated, library))
        self.mem = self.memory()
        self.x, self.u = (ctypes.c_double * 3)(), (ctypes.c_double * 1)()

    def __call__(self, t, x):
        self.x[:] = [float(v) for v in x]
        return self.step(ctypes.byref(self.mem), t, self.x, self.u), np.array(self.u[:])


@pytest.fixture(scope="module")
def motor(tmp_path_factory):
    setup = load_mpc_file(REPO / "codegen" / "mpc" / "dc_motor_mpc.toml")
    generated, library = build_mpc(setup, tmp_path_factory.mktemp("motor_mpc"))
    step = Step(generated, library)
    free = _run(setup, step)
    return setup, step, free


def _run(setup, step, glitch=None):
    """The closed loop with ``glitch(k, x) -> x`` applied before the step's k-th call: the statuses and computed inputs."""
    step.init(ctypes.byref(step.mem))
    calls = []

    def controller(t, x):
        x = x if glitch is None else glitch(len(calls), np.array(x, dtype=float))
        status, u = step(t, x)
        calls.append((status, u[0]))
        return status, u

    run_controller_loop(controller, setup.plant_step, setup.plant_x0, setup.t, setup.x_ref,
                        **dict(setup.loop, plant_p=setup.plant_p, status_names=STATUS_NAMES))
    status, u = (np.array(v) for v in zip(*calls))
    return status, u


def _spike(value, index=0):
    def glitch(k, x):
        if k == K:
            x[index] = value
        return x
    return glitch


def _poison(step, **entries):
    """Values written into the step's memory before its K-th call (``u_last``, ``w`` by index)."""
    def glitch(k, x):
        if k == K:
            for name, values in entries.items():
                for i, v in values.items():
                    getattr(step.mem, name)[i] = v
        return x
    return glitch


def _recovered(setup, u, free_u):
    """The first period after the glitch from which the input stays within 1 % of the bound of the spike-free run's."""
    off = np.abs(u - free_u) > 0.01 * float(np.max(np.abs(np.r_[setup.controller.u_lb, setup.controller.u_ub])))
    late = np.flatnonzero(off[K:])
    return 0 if late.size == 0 else int(late[-1]) + 1


def test_spike_free_run_is_ok(motor):
    setup, _, (status, u) = motor
    assert np.all(status == OK) and status.size == setup.t.size
    assert np.all(np.abs(u[K:K + 10]) < 24.0)  # off its bounds where the glitch comes


@pytest.mark.parametrize("value", [1e20, 1e50, 1e150, math.nan], ids=["1e20", "1e50", "1e150", "nan"])
def test_single_measurement_spike_is_rejected_and_the_input_recovers(motor, value):
    # x[0] (the current) absurd or NaN: the state the memory predicts replaces it (GT_MEASUREMENT_REJECTED)
    setup, step, (_, free_u) = motor
    status, u = _run(setup, step, _spike(value))
    assert status[K] == REJECTED and np.all(status[K + 1:] == OK) and np.all(status[:K] == OK)
    assert np.all(np.isfinite(u)) and np.all(np.abs(u) <= 24.0)
    assert _recovered(setup, u, free_u) <= RECOVER


@pytest.mark.parametrize("entries", [
    {"w": {0: math.nan}},               # the warm start
    {"w": {20: math.nan}},              # the disturbance estimate
    {"w": {0: 1e150, 5: -1e150}},       # the warm start absurd (1e150 V)
    {"w": {20: 1e150}},                 # the estimate absurd
    {"u_last": {0: math.nan}, "w": {21: math.nan}},  # the last input and the last state
], ids=["nan warm start", "nan estimate", "absurd warm start", "absurd estimate", "nan last input and state"])
def test_poisoned_memory_is_reset(motor, entries):
    # written into the memory from outside: the next step resets it to the reference's (GT_MEMORY_RESET) with a valid input
    setup, step, (_, free_u) = motor
    status, u = _run(setup, step, _poison(step, **entries))
    assert status[K] == RESET and np.all(status[K + 1:] == OK)
    assert np.all(np.isfinite(u)) and np.all(np.abs(u) <= 24.0)
    assert _recovered(setup, u, free_u) <= 2 * RECOVER  # the estimate starts again from zero (gain 0.3 per period)


def test_spike_below_the_measurement_limit_is_rejected_by_its_effect(motor):
    # a current of 1e6 A is inside the limit (1e6 state scales), but the estimate it drives is absurd:
    # the measurement is judged absurd too and the prediction replaces it on the same step
    setup, step, (_, free_u) = motor
    status, u = _run(setup, step, _spike(1e6))
    assert status[K] == REJECTED and np.all(status[K + 1:] == OK)
    assert np.all(np.isfinite(u)) and np.all(np.abs(u) <= 24.0)
    assert _recovered(setup, u, free_u) <= RECOVER


def test_spike_with_a_poisoned_memory_waits_for_the_next_measurement(motor):
    # neither the measurement nor the memory to use: the safe input, and the reset at the next valid measurement
    setup, step, _ = motor
    poison = _poison(step, w={20: math.nan})
    status, u = _run(setup, step, lambda k, x: _spike(math.nan)(k, poison(k, x)))
    assert status[K] == BAD and u[K] == u[K - 1] and status[K + 1] == RESET and np.all(status[K + 2:] == OK)
