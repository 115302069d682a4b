"""Least-squares steps of a calibration group (gtmodel.calibration.kinematic.lsq):
solver "lm" through scipy.optimize.leastsq, the Gauss-Newton polishing step and the
identifiability report from its factorisation (issue 17, item 4)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

from gtmodel.calibration.identifiability import analyze_jacobian
from gtmodel.calibration.kinematic import LSQ_TOLERANCE, MAX_ITER, CalibrationProblem

from ._l1_data import l1_poses, nominal


@pytest.fixture(scope="module")
def data():
    return l1_poses(seed=7)


def test_lm_equals_least_squares(data):
    """Solver "lm" (MINPACK lmder through scipy.optimize.leastsq) takes the iterates of
    least_squares(method="lm", x_scale="jac") with the same tolerances (checked against
    that call on the same residuals: bit-identical point and the same message)."""
    q, T = data
    problem = CalibrationProblem(nominal())
    problem.solve(q, T)
    ev = next(iter(problem._eval_cache.values()))[0]
    ev.set_pb(problem.model.parameter_vector())
    x0 = problem._x_of(problem._anchor(problem.model.parameter_vector()))[problem._groups[0].var_idx] + 1e-3
    sol = scipy.optimize.least_squares(
        ev.residuals, x0, jac=ev.jacobian, method="lm", x_scale="jac",
        ftol=LSQ_TOLERANCE, xtol=LSQ_TOLERANCE, gtol=LSQ_TOLERANCE, max_nfev=MAX_ITER,
    )
    x_ref, n_ref = problem._polish(ev, sol.x)
    x, status, message, iters, _ = problem._solve_minpack(ev, x0, MAX_ITER)
    np.testing.assert_array_equal(x, x_ref)
    assert status == "optimal" and message == sol.message and iters == sol.njev + n_ref


def test_report_from_polishing_step_equals_report_at_solution(data):
    """The identifiability report of each arm group (from the polishing step's
    factorisation) equals analyze_jacobian of the Jacobian evaluated at the calibrated
    parameters (checked against it) to 1e-8 relative."""
    q, T = data
    problem = CalibrationProblem(nominal())
    res = problem.solve(q, T)
    r, J, names = problem.jacobian(res.parameter_vector, q, T)
    std, sv = {}, []
    for g in res.groups:
        cols = [names.index(n) for n in g.variable_names]
        rep = analyze_jacobian(J[:, list(g.arms)][:, :, cols].reshape(-1, len(cols)), g.variable_names,
                               residuals=r[:, list(g.arms)].ravel())
        std.update(rep.std)
        sv.append(rep.singular_values)
    np.testing.assert_allclose(np.sort(res.identifiability.singular_values), np.sort(np.concatenate(sv)), rtol=1e-8)
    np.testing.assert_allclose([res.std[k] for k in std], list(std.values()), rtol=1e-8)
