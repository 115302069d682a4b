"""Parameter estimation in Python: fit_data, least_squares, estimate_statistics.

Reference: the decay ``x' = -k x`` from a fixed ``x(0) = 2`` fitted to exact samples of
``2 exp(-1.3 t)``: the estimate is 1.3 and the residuals vanish; with weights (no
standard deviations) the covariance is scaled by the residual variance, so zero residuals
give zero standard deviation. Two rates entering only as their sum cannot be told apart:
the reduced Gauss-Newton Hessian is singular, reported as not identifiable (NaN).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.ocp.estimation import estimate_statistics, fit_data, least_squares

T = np.linspace(0.2, 2.0, 10)


def _decay(rates=("k",)):
    m = Model("decay")
    x = m.state("x", start=2.0)
    ks = [m.parameter(k, 1.0) for k in rates]
    m.equation(m.der(x), -sum(ks) * x)
    opt = Optimization(m, final_time=2.0)
    opt.add_point_constraint(x, at="start", lb=2.0, ub=2.0)
    for k in rates:
        opt.free_parameter(k, 0.0, 5.0)
    return opt, x


def test_exact_data_recovers_the_rate():
    opt, x = _decay()
    fit_data(opt, x, T, 2.0 * np.exp(-1.3 * T), name="x")
    opt.set_objective(mayer=least_squares(opt))
    tr = CollocationTranscription(opt, elements=20)
    r = tr.solve()
    st = estimate_statistics(tr, r)
    assert st["estimates"]["k"]["value"] == pytest.approx(1.3, rel=1e-6)
    assert st["residuals"]["x"]["max_abs"] < 1e-6 and st["n_data"] == 10 and st["n_parameters"] == 1
    assert st["estimates"]["k"]["std"] < 1e-5 and st["identifiable"]


def test_rates_seen_only_as_their_sum_are_not_identifiable():
    opt, x = _decay(("k1", "k2"))
    fit_data(opt, x, T, 2.0 * np.exp(-1.3 * T), std=0.01)
    opt.set_objective(mayer=least_squares(opt))
    tr = CollocationTranscription(opt, elements=10)
    st = estimate_statistics(tr, tr.solve())
    assert not st["identifiable"] and np.isnan(st["estimates"]["k1"]["std"])


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"times": [0.5, 1.0], "values": [1.0]}, InputError, "same non-zero length"),
    ({"times": [0.5], "values": [np.nan]}, InputError, "finite numbers"),
    ({"times": [0.5], "values": [1.0], "std": 0.0}, InputError, "std must be positive"),
    ({"times": [0.5], "values": [1.0], "std": 1.0, "weight": 1.0}, InputError, "std or weight, not both"),
    ({"times": [2.5], "values": [1.0]}, ModelError, r"outside the horizon \[0, 2\] s"),
])
def test_bad_data(kwargs, exc, match):
    opt, x = _decay()
    with pytest.raises(exc, match=match):
        fit_data(opt, x, **kwargs)
