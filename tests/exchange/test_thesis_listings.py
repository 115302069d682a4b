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

from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from gtmodel.calibration import read_measurements
from gtmodel.exchange.modelica import load_modelica
from gtmodel.exchange.optimica import OptimicaError, load_optimica
from gtmodel.exchange.optimica_static import StaticProblemError, solve_static
from gtmodel.modeling import CollocationTranscription, explicit_ode
from gtmodel.problems import load_problem
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematics import GantryTau3Kinematics

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
    assert kin_listing.objective == pytest.approx(9.68496e-7, rel=1e-6)  # the figure docs/optimica.md quotes
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


def test_gtp_kin_calib_by_collocation_gives_the_same_cost(kin_listing):
    """gtmodel solve FILE.mop's path (collocation over the horizon, a static problem repeated) gives the static NLP's cost.

    Independent check: the static NLP (solve_static), which the native kind matches above.
    """
    res = CollocationTranscription(load_optimica(KIN_MOP, "GTPKinCalibOpt"), elements=2, points=1).solve()
    assert res.status == "optimal"
    assert res.objective == pytest.approx(kin_listing.objective, rel=1e-6)
    np.testing.assert_allclose(res.parameters["sA2"], kin_listing.parameters["sA2"], rtol=1e-6)


STATIC_MODEL = """model M
  parameter Real p[2] = {1, 2};
  Real y;
equation
  y = (p[1] - 3)^2 + (p[2] + 1)^2;
end M;
"""


@pytest.mark.parametrize("opt_class, match", [
    ("optimization O (objective = y(finalTime))\n  extends M(p(each free = true, initialGuess = {1, 2, 3}));\nend O;",
     r"s.mop:8: p\(initialGuess\): 3 values for a parameter of 2 elements"),
    ("optimization O (objective = y(finalTime))\n  extends M(p(each free = true));\nconstraint\n  y <= 4;\nend O;",
     r"static problem with constraints"),
], ids=["initialGuess size", "static with constraints"])
def test_static_and_array_parameter_refusals(tmp_path, opt_class, match):
    """An initialGuess of the wrong size names the file, line and sizes; solve_static refuses what it does not map."""
    path = tmp_path / "s.mop"
    path.write_text(STATIC_MODEL + opt_class + "\n", encoding="utf-8")
    with pytest.raises((OptimicaError, StaticProblemError), match=match):
        solve_static(load_optimica(path, "O"))


def test_static_array_parameters_closed_form(tmp_path):
    """A free array parameter (each free = true) of a static problem reaches the closed-form minimum p = (3, -1)."""
    path = tmp_path / "s.mop"
    path.write_text(STATIC_MODEL + "optimization O (objective = y(finalTime))\n"
                    "  extends M(p(each free = true, initialGuess = {0, 0}));\nend O;\n", encoding="utf-8")
    res = solve_static(load_optimica(path, "O"))
    assert res.status == "optimal"
    np.testing.assert_allclose(res.parameters["p"], [3.0, -1.0], atol=1e-8)
    assert res.objective == pytest.approx(0.0, abs=1e-14)


def test_static_solver_refuses_a_dynamic_problem():
    """solve_static is for problems without states or inputs: a minimum-time problem is refused naming it."""
    opt = load_optimica(OPTICA / "double_integrator_min_time.mop", "DoubleIntegrator.MinTime")
    with pytest.raises(StaticProblemError, match="not a static problem"):
        solve_static(opt)


# ----------------------------------------------------------------------------- opt_robot
ROBOT_MOP = OPTICA / "opt_robot.mop"
ROBOT_NATIVE = OPTICA / "opt_robot_native.toml"
#: States of the L1 (TCP [m], velocity [m/s]) and normalised torques where the Modelica class is checked.
ROBOT_POINTS = [
    ([-0.20, 2.75, -0.40], [0.0, 0.0, 0.0], [0.3, 0.2, 0.6]),
    ([0.0, 2.875, -0.50], [0.4, 0.25, -0.2], [-0.5, 0.9, 0.1]),
    ([0.20, 3.00, -0.60], [-0.1, 0.3, 0.15], [0.8, -0.7, -0.2]),
]


@pytest.fixture(scope="module")
def robot_opt():
    """The listing opt_robot loaded by the Optimica front end."""
    return load_optimica(ROBOT_MOP, "opt_robot")


def test_opt_robot_reads_the_robot_as_the_listing_does(robot_opt):
    """robot.tau (an input of the component, unbound) is the problem's input; the TCP, its velocity and cost the states."""
    dae = robot_opt.flat()
    assert dae.u_names == ["robot.tau[0]", "robot.tau[1]", "robot.tau[2]"]
    assert set(dae.x_names) == {"cost", *(f"robot.{n}[{k}]" for n in ("tcp", "vtcp") for k in range(3))}


def test_the_robot_class_is_package_data():
    """GantryTau.mo sits beside the MSL subset, which pyproject.toml's package-data ships ("modelica_library/*.mo")."""
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert '"modelica_library/*.mo"' in text
    assert resources.files("gtmodel.exchange").joinpath("modelica_library/GantryTau.mo").is_file()


@pytest.mark.parametrize("T, T_dot, tau", ROBOT_POINTS)
def test_the_modelica_l1_is_the_native_l1(robot_opt, T, T_dot, tau):
    """At a state and torque, the Modelica class's acceleration and carts equal the native model's forward dynamics and IK.

    Independent check: :class:`gtmodel.robots.dynamics.GantryTau3Dynamics` (eqs. 6.7-6.8, the
    Lagrange terms in TCP coordinates) on the L1 parameter file, against the Modelica class's
    implicit equations (closure differentiated twice, cart and plate force balances with
    multipliers) solved by Newton.
    """
    dae = robot_opt.flat()
    x = np.zeros(dae.x.numel())
    for k in range(3):
        x[dae.x_names.index(f"robot.tcp[{k}]")] = T[k]
        x[dae.x_names.index(f"robot.vtcp[{k}]")] = T_dot[k]
    g = ca.Function("g", [dae.z], [ca.substitute(dae.alg_expr, ca.vertcat(dae.t, dae.x, dae.u, dae.p),
                                                  ca.vertcat(0.0, x, tau, dae.p_value))])
    z0 = np.zeros(dae.z.numel())
    z0[[dae.z_names.index(f"robot.q[{k}]") for k in range(3)]] = T[0]  # the carts near the TCP's x
    z = np.ravel(np.asarray(ca.rootfinder("z", "newton", g, {"abstol": 1e-13})(z0), dtype=float))
    atcp = z[[dae.z_names.index(f"robot.atcp[{k}]") for k in range(3)]]
    q = z[[dae.z_names.index(f"robot.q[{k}]") for k in range(3)]]
    dyn = GantryTau3Dynamics("L1", friction="tanh", friction_width=0.01)
    np.testing.assert_allclose(atcp, dyn.forward_dynamics(T, T_dot, 450.0 * np.asarray(tau)), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(q, GantryTau3Kinematics("L1").ik(T), rtol=1e-12, atol=1e-12)


@pytest.mark.slow
def test_opt_robot_solves_optimal_verified_and_agrees_with_native(robot_opt):
    """opt_robot (50 elements, Radau 3, JModelica.org's defaults) is optimal and verified; its objective equals the native file's to 1e-6.

    Independent check: problems/optimica/opt_robot_native.toml (kind point_to_point on the
    Python L1 model, cart forces in N, the cost the integral of (tau_i / 450 N)^2). About 30 CPU-s.
    """
    res = CollocationTranscription(robot_opt, elements=50, points=3).solve()
    native = load_problem(ROBOT_NATIVE).declaration.solve().result
    assert res.status == "optimal" and native.status == "optimal"
    assert res.verification is not None and res.verification.passed
    assert res.objective == pytest.approx(native.objective, rel=1e-6)
    assert res.objective == pytest.approx(1.286974, abs=1e-6)  # the figure docs/optimica.md quotes
    assert np.max(np.abs(res.inputs["robot.tau"])) <= 1 + 1e-6  # the printed bounds hold


@pytest.mark.parametrize("T, T_dot, tau", ROBOT_POINTS)
def test_a_modelica_file_extending_the_shipped_l1_is_the_native_l1(tmp_path, T, T_dot, tau):
    """A plain ``.mo`` file (``load_modelica``, not the Optimica loader) names ``GantryTau.L1`` and gets the shipped class.

    Independent check: the explicit ODE's acceleration (the index reduction of the class's implicit
    equations) against :class:`gtmodel.robots.dynamics.GantryTau3Dynamics`' forward dynamics (eqs. 6.7-6.8).
    """
    path = tmp_path / "robot.mo"
    path.write_text("model Robot\n  extends GantryTau.L1;\nend Robot;\n", encoding="utf-8")
    ode = explicit_ode(load_modelica(path))
    assert ode.u_names == ["tau[0]", "tau[1]", "tau[2]"]
    xdot = np.ravel(np.asarray(ode.f(np.r_[T, T_dot], tau, ode.p_default), dtype=float))
    dyn = GantryTau3Dynamics("L1", friction="tanh", friction_width=0.01)
    np.testing.assert_allclose(xdot, np.r_[T_dot, dyn.forward_dynamics(T, T_dot, 450.0 * np.asarray(tau))], rtol=1e-9, atol=1e-9)
