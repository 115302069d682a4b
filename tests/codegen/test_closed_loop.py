"""The closed-loop check of a loop controller's C (gtmodel.codegen.check.closed_loop), in double and in float.

References: the float32 step and the double step of the same tracking controller (the shipped
DC motor file) on the same plant, noise and disturbance, each beside the feedforward alone:
both pass the file's criteria (no divergence, bounds held, no failed step, RMS ratio to the
feedforward below its limit); the library's one ctypes owner (CompiledLibrary) gives the memory
struct the C declares (float32 reals) and the smaller stack work of float reals.
"""

from __future__ import annotations

import ctypes

import pytest

from gtmodel.codegen import check_code
from gtmodel.codegen.build import load_library
from gtmodel.codegen.check.closed_loop import LoopCheck
from gtmodel.codegen.loop_step import build_step, tracking_step
from gtmodel.problems.tracking_file import load_tracking_file
from gtmodel.status import Status

from ..conftest import REPO


@pytest.fixture(scope="module")
def motor():
    return load_tracking_file(REPO / "codegen" / "controllers" / "dc_motor_tracking.toml")


@pytest.fixture(scope="module")
def runs(motor, tmp_path_factory):
    out = {}
    for real in ("double", "float"):
        generated, _ = build_step(tracking_step(motor.controller, motor.name), tmp_path_factory.mktemp(real), "gt_motor", real=real)
        out[real] = (generated, check_code(generated, n=200, plant=motor, label="tracking controller"))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("real", ["double", "float"])
def test_the_closed_loop_runs_and_passes_in_both_real_types(runs, real):
    generated, result = runs[real]
    loop = result.reports[-1]
    assert isinstance(loop, LoopCheck) and loop.real == real
    assert result.status is Status.CONVERGED, result.summary_lines()
    assert loop.closed.t.size == loop.feedforward.t.size > 100  # the whole motion ran
    assert ("float32 step" in "\n".join(result.summary_lines())) == (real == "float")


@pytest.mark.slow
def test_the_float_step_tracks_as_well_as_the_double_step(runs):
    """The float32 step reads the row of its period (PERIOD_EPS covers float32's round-off of
    (t - t0) / dt): its tracking RMS equals the double step's to 1 % (0.9756 against 0.221 when
    a slack of 1e-6 periods read row k - 1 at half the grid times)."""
    rms = {real: runs[real][1].reports[-1].closed.rms_error for real in ("double", "float")}
    assert rms["float"] == pytest.approx(rms["double"], rel=1e-2)


@pytest.mark.slow
def test_the_float_memory_has_float32_reals(runs):
    generated, result = runs["float"]
    library = load_library(generated, result.reports[0].library)
    memory, _, _ = library.loop_interface()
    step = generated.parameters
    assert ctypes.sizeof(memory) >= ctypes.sizeof(ctypes.c_float) * (step.nu + max(step.nw, 1))
    assert library.real_type is ctypes.c_float
    assert library.work_bytes("control") < load_library(runs["double"][0], runs["double"][1].reports[0].library).work_bytes("control")


def test_the_loop_reports_its_periods_while_it_runs(monkeypatch):
    """With the interval at 0 every period reports; the count is the calls made (the law's own result unchanged)."""
    import numpy as np

    from gtmodel.codegen.check import closed_loop

    monkeypatch.setattr(closed_loop, "PROGRESS_INTERVAL_S", 0.0)
    lines: list[str] = []
    law = closed_loop._reporting(lambda t, x: (0, np.array([t])), "closed loop, generated C MPC", 3, lines.append)
    results = [law(0.5 * k, np.zeros(1)) for k in range(3)]
    assert [r[1][0] for r in results] == [0.0, 0.5, 1.0]
    assert [line.rsplit(": ", 1)[1].split(",")[0] for line in lines] == ["1 of 3 periods", "2 of 3 periods", "3 of 3 periods"]


@pytest.fixture(scope="module")
def mpc_runs(tmp_path_factory):
    from gtmodel.codegen.check.mpc import build_mpc
    from gtmodel.problems.mpc_file import load_mpc_file

    setup = load_mpc_file(REPO / "codegen" / "mpc" / "dc_motor_mpc.toml")
    out = {}
    for real in ("double", "float"):
        generated, _ = build_mpc(setup, tmp_path_factory.mktemp(f"mpc_{real}"), real=real)
        out[real] = (generated, check_code(generated, n=200, plant=setup, label="MPC"))
    return setup, out


#: Found 2026-11-29, not fixed: the float32 step's qrqp stops at its iteration limit where the QP's gradient is large
#: (its round-off above the absolute 1e-4 tolerance, QP_FLOAT_TOLERANCE): the contract probe "a valid state after
#: init" (a random state, the first warm start) returns GT_NUMERIC_ERROR. Until the first warm start became the
#: reference's inputs (MPCController.w_initial) the probe's QP converged and the loop's first one did not; the loop
#: now tracks as the double step does (the test below). A tolerance scaled to the gradient would loosen the C-Python
#: comparison to volts (2 tau / lambda_min(H)). Not strict: another compiler's float rounding may converge there.
FLOAT_QP_STALL = "the float32 qrqp stalls at its iteration limit on the contract probe's cold start (see FLOAT_QP_STALL)"


@pytest.mark.slow
@pytest.mark.parametrize("real", ["double", pytest.param("float", marks=pytest.mark.xfail(strict=False, reason=FLOAT_QP_STALL))])
def test_the_mpc_passes_its_check_in_both_real_types(mpc_runs, real):
    """The shipped MPC: C equal to Python within its real type's tolerance (float: derived from the
    QP's conditioning, MPCController.float_tolerance; before, 2.6e-3 V failed the fixed 1e-4) and the
    99th-percentile step within the 4 ms period (float: 9.7 ms with qrqp's 1e-8 tolerances)."""
    setup, runs = mpc_runs
    generated, result = runs[real]
    assert result.status is Status.CONVERGED, result.summary_lines()
    control = result.reports[0].functions[0]
    assert control.name == "control" and control.within_tolerance
    loop = result.reports[-1]
    assert loop.real == real and loop.step_p99_s <= setup.controller.dt


@pytest.mark.slow
def test_the_float_mpc_tracks_as_well_as_the_double_one(mpc_runs):
    rms = {real: mpc_runs[1][real][1].reports[-1].closed.rms_error for real in ("double", "float")}
    assert rms["float"] == pytest.approx(rms["double"], rel=1e-2)
