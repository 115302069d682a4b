"""The L1 MPC file as generated C in closed loop (slow: the reference solve and the compile take ~15 s).

References: the feedforward alone on the same plant (masses and friction 10 % off, noise,
a 20 N step disturbance, one-sample delay: the MPC must halve its RMS tracking error); the
input bounds; the horizon problem solved to convergence by IPOPT at states of the closed
loop (the SQP iterated there agrees to 1e-6); the step contract (a failed solve returns a
status and the last input, saturated, never NaN).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.problems.mpc_check import build_mpc, closed_loop_check, compiled_step, ipopt_agreement
from gtmodel.problems.mpc_file import load_mpc_file

from ..conftest import REPO

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def l1(tmp_path_factory):
    setup = load_mpc_file(REPO / "codegen" / "mpc" / "l1_mpc.toml")
    generated, library = build_mpc(setup, tmp_path_factory.mktemp("l1_mpc"))
    return setup, generated, library, closed_loop_check(setup, generated, library)


def test_l1_mpc_halves_the_feedforward_error_without_bound_violations(l1):
    setup, _, _, check = l1
    assert setup.controller.horizon >= 20 and setup.controller.dt == 0.004
    assert check.ratio_to_feedforward <= 0.5
    assert check.mpc.bound_violations == 0
    assert check.mpc.status_counts == {"GT_OK": setup.t.size}


def test_agreement_refuses_a_reference_ipopt_did_not_solve(l1, monkeypatch):
    from gtmodel.control.mpc import MPCController
    from gtmodel.control.mpc_solve import HorizonSolution
    from gtmodel.errors import SolverError
    from gtmodel.status import Status

    setup, _, _, check = l1
    failed = HorizonSolution(u=np.zeros(setup.controller.nu), w=np.zeros(setup.controller.nw), status=Status.MAX_ITERATIONS,
                             message="Maximum_Iterations_Exceeded", plugin="ipopt")
    monkeypatch.setattr(MPCController, "solve", lambda *a, **k: failed)
    with pytest.raises(SolverError, match=r"IPOPT, the reference, did not solve the horizon problem at t = .* max_iterations "
                                          r"\(Maximum_Iterations_Exceeded\)"):
        ipopt_agreement(setup, check.mpc, samples=1)


def test_converged_rti_agrees_with_ipopt_near_the_reference(l1):
    # states 1 mm and 10 mm/s off the reference while every axis moves (the plant's state is the
    # tool's with the compliance model; the MPC's is T, T_dot); 40 SQP iterations: on the refined
    # reference plan (61 elements, 0.6715 s) the third state needs more than 20 (1.1e-6 after 20,
    # 2e-11 after 40)
    setup, _, _, check = l1
    near = dataclasses.replace(check.mpc, x=check.mpc.x_ref + np.array([1e-3, -1e-3, 1e-3, 0.01, -0.01, 0.01]))
    assert np.max(ipopt_agreement(setup, near, samples=3, iterations=40, min_speed=0.2)) <= 1e-6


@pytest.mark.parametrize("bad", [np.full(6, 100.0), np.r_[1e300, 0, 0, 0, 0, 0]], ids=["out of the workspace", "overflow"])
def test_failed_solve_returns_a_status_and_the_last_input_saturated(l1, bad):
    setup, generated, library, _ = l1
    controller, reset, _ = compiled_step(generated, library)
    status, u_ok = controller(0.1, setup.x_ref[25])
    assert status == 0
    status, u = controller(0.104, bad)
    assert status != 0
    assert np.all(np.isfinite(u))
    if status == STATUS_CODES["GT_MEASUREMENT_REJECTED"][0]:  # a non-finite measurement, with the estimator's memory (the
        # rows' back-off): the state the memory predicts replaces it and the step runs on, its input within the bounds
        assert setup.controller.estimates and np.all((setup.controller.u_lb <= u) & (u <= setup.controller.u_ub))
    else:  # a solve that failed: the last input, saturated
        np.testing.assert_array_equal(u, np.clip(u_ok, setup.controller.u_lb, setup.controller.u_ub))
