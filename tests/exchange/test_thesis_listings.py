"""The thesis' two Optimica listings (Dressler (2012), ch. 3.3 and 3.5) run as printed.

``GTPKinCalib`` (problems/optimica/gtp_kin_calib.mop): the kinematic calibration of the L1
from 176 poses (SYNTHETIC: problems/optimica/data/l1_poses_352.csv, every second pose),
loaded by the Optimica front end and solved as a static NLP; the independent check is the
project's own calibration kind on the same poses (problems/optimica/l1_kin_calib_native.toml:
Levenberg-Marquardt on the same closure residuals, another solver on another graph).

``opt_robot`` (problems/optimica/opt_robot.mop): the L1 robot as a Modelica class shipped in
the package (gtmodel/exchange/modelica_library/GantryTau.mo), the cost integrated over a
rest-to-rest motion, the torques bounded; the independent check is the native problem file of
the same task (problems/optimica/opt_robot_native.toml, kind optimal_control on the project's
Python L1 model).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gtmodel.calibration import read_measurements
from gtmodel.exchange.optimica import load_optimica
from gtmodel.exchange.optimica_static import StaticProblemError, solve_static
from gtmodel.problems import load_problem

ROOT = Path(__file__).resolve().parents[2]
OPTICA = ROOT / "problems" / "optimica"
KIN_MOP = OPTICA / "gtp_kin_calib.mop"
KIN_NATIVE = OPTICA / "l1_kin_calib_native.toml"
#: Native parameter names of the 3-link model in the order the listing declares them.
LISTING_TO_NATIVE = {
    **{f"L{i}": [f"L{i}"] for i in (1, 2, 3)},
    **{f"sA{i}": [f"As{i}_{c}" for c in "xyz"] for i in (1, 2, 3)},
    **{f"v{i}": [f"v{i}_{c}" for c in "xyz"] for i in (1, 2, 3)},
}


@pytest.fixture(scope="module")
def kin_listing():
    """The listing loaded and solved by the Optimica front end (static NLP)."""
    return solve_static(load_optimica(KIN_MOP, "GTPKinCalibOpt"))


@pytest.fixture(scope="module")
def kin_native():
    """The project's calibration kind on the same poses: (CalibrationResult, problem declaration)."""
    decl = load_problem(KIN_NATIVE).declaration
    outcome = decl.solve()
    return outcome.results[0][1], outcome


def test_gtp_kin_calib_data_are_the_native_calibration_poses(kin_native):
    """The .mop arrays hold exactly the 176 poses the native kind calibrates on (read from the CSV independently)."""
    _, outcome = kin_native
    cal, _ = read_measurements(OPTICA / "data" / "l1_poses_352.csv").split_alternate()
    opt = load_optimica(KIN_MOP, "GTPKinCalibOpt")
    values = {n: np.ravel(opt.model._vars[n].start) for n in ("q1", "q2", "q3", "X", "Y", "Z")}
    mop = np.column_stack([values[n] for n in ("q1", "q2", "q3", "X", "Y", "Z")])
    assert mop.shape == (176, 6)
    np.testing.assert_array_equal(mop, np.hstack([cal.q, cal.T]))
    np.testing.assert_array_equal(outcome.calibration.T, cal.T)


def test_gtp_kin_calib_cost_agrees_with_native(kin_listing, kin_native):
    """Optimal, and the listing's cost equals the native V (sum of squared closure residuals) to 1e-6 relative."""
    res, _ = kin_native
    assert kin_listing.status == "optimal" and res.status == "optimal"
    assert kin_listing.objective == pytest.approx(res.cost, rel=1e-6)
    assert kin_listing.objective < 0.01 * float(np.sum(res.initial_cost_per_arm))  # the calibration did calibrate


@pytest.mark.parametrize("name", list(LISTING_TO_NATIVE))
def test_gtp_kin_calib_parameters_agree_with_native(kin_listing, kin_native, name):
    """Each calibrated kinematic parameter of the listing equals the native kind's to 1e-6 relative."""
    res, _ = kin_native
    native = np.array([res.parameters[k] for k in LISTING_TO_NATIVE[name]])
    np.testing.assert_allclose(kin_listing.parameters[name], native, rtol=1e-6, atol=1e-9)


def test_gtp_kin_calib_residuals_are_the_listings(kin_listing, kin_native):
    """The listing's f1, f2, f3 at the optimum equal the native weighted closure residuals (eq. 4.9, m^2)."""
    res, _ = kin_native
    listing = np.column_stack([kin_listing.algebraics[f"f{k}"] for k in (1, 2, 3)])
    np.testing.assert_allclose(listing, res.residuals, rtol=1e-6, atol=1e-12)


def test_static_solver_refuses_a_dynamic_problem():
    """solve_static is for problems without states or inputs: a minimum-time problem is refused naming it."""
    opt = load_optimica(OPTICA / "double_integrator_min_time.mop", "DoubleIntegrator.MinTime")
    with pytest.raises(StaticProblemError, match="not a static problem"):
        solve_static(opt)
