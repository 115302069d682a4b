"""MPC files of users' models (``tests/fixtures/user_models``): what the prediction and the bounds are taken from.

The reference problem's ``[model.parameters]`` are the prediction's (and, scaled by
``[check] parameter_factor``, the plant's); the input bounds are the reference problem's
``[bounds]`` within the model's declared ones (docs/model_in_the_loop.md, section 3).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.modeling import explicit_ode
from gtmodel.problems.mpc_file import load_mpc_file
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO

USER_MODELS = REPO / "tests" / "fixtures" / "user_models"


def test_user_model_mpc_keeps_the_models_declared_input_bounds():
    # cart_move.toml has no [bounds]: the bounds are the model's push.f in [-8, 8] N (they were -inf, inf)
    setup = load_mpc_file(USER_MODELS / "cart_mpc.toml")
    assert (setup.controller.u_lb.tolist(), setup.controller.u_ub.tolist()) == ([-8.0], [8.0])


def test_user_model_mpc_predicts_with_the_reference_problems_parameters():
    # keyword_move.toml sets k_1 = 2, double = 0.8 (the model's defaults are 4, 0.5): the prediction
    # and the plant were built on the defaults; reference: the model's own RK4 step with the file's values
    setup = load_mpc_file(USER_MODELS / "keyword_mpc.toml")
    ode = explicit_ode(load_user_model(USER_MODELS / "keyword_names.py", "Plant2In3Out"))
    p = ode.dae.parameter_vector({"k_1": 2.0, "double": 0.8})
    np.testing.assert_allclose(setup.plant_p, 1.1 * p, rtol=1e-15)  # parameter_factor 1.1
    x, u = np.array([0.3, -0.2, 0.1]), np.array([1.5, -0.5])
    expected = np.asarray(ode.step(0.004, "rk4", substeps=1)(x, u, p)[0]).ravel()
    np.testing.assert_allclose(np.asarray(setup.controller.step(x, u)).ravel(), expected, rtol=1e-12, atol=1e-15)
    assert np.abs(expected - np.asarray(ode.step(0.004, "rk4", substeps=1)(x, u, ode.p_default)[0]).ravel()).max() > 1e-6
