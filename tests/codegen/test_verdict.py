"""One verdict over generated code (gtmodel.codegen.verdict): check_code returns the shared Status for every source.

References: every source's check reports the shared Status, converged exactly when its
former report passed (CheckReport.passed); the closed loop's own verdict is tested in
tests/codegen/test_closed_loop.py.
"""

from __future__ import annotations

import pytest

from gtmodel.codegen import CheckReport, CodeCheck, Controller, ControllerSource, RobotSource, UserModelSource, check_code, check_generated, generate_code
from gtmodel.errors import InputError
from gtmodel.problems.user_model import load_user_model, split_model_reference
from gtmodel.status import Status

from ..conftest import REPO
from .controller_functions import FILTER_DT, fusion_filter

MODEL = f"{REPO / 'models' / 'cart_pendulum.py'}:CartPendulum"


@pytest.fixture(scope="module")
def robot_code(tmp_path_factory):
    return generate_code(RobotSource("L1", functions=("ik", "fk")), tmp_path_factory.mktemp("robot"))


@pytest.fixture(scope="module")
def filter_code(tmp_path_factory):
    return generate_code(ControllerSource(Controller(dt=FILTER_DT, kf_step=fusion_filter(False).step_function())),
                         tmp_path_factory.mktemp("filter"))


@pytest.fixture(scope="module")
def model_code(tmp_path_factory):
    model = load_user_model(*split_model_reference(MODEL))
    return generate_code(UserModelSource(model, functions=("ode", "step_rk4")), tmp_path_factory.mktemp("model"))


def test_a_plant_is_refused_for_code_that_is_no_loop_step(robot_code):
    with pytest.raises(InputError, match="plant: a closed loop applies to a loop controller"):
        check_code(robot_code, plant=object())


@pytest.mark.slow
@pytest.mark.parametrize("which", ["robot", "filter", "model"])
def test_each_check_returns_a_status(which, robot_code, filter_code, model_code):
    generated = {"robot": robot_code, "filter": filter_code, "model": model_code}[which]
    result = check_code(generated, n=50)
    assert isinstance(result, CodeCheck) and isinstance(result.status, Status)
    assert result.status is Status.CONVERGED and result.passed and result.failures() == []
    report = check_generated(generated, n=50) if which != "filter" else check_generated(generated)
    assert isinstance(report, CheckReport) and report.status is (Status.CONVERGED if report.passed else Status.CHECK_FAILED)


def test_the_check_package_is_not_shadowed_by_a_function():
    """``import gtmodel.codegen.check.closed_loop`` works (a function named ``check`` in ``gtmodel.codegen`` hid the package)."""
    import importlib

    module = importlib.import_module("gtmodel.codegen.check.closed_loop")
    import gtmodel.codegen

    assert gtmodel.codegen.check is importlib.import_module("gtmodel.codegen.check") and callable(module.closed_loop_check)
