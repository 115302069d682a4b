"""The codegen front door (gtmodel.codegen.sources): one generate_code over every source.

References: the former front door generate("L1", ...) writes the same files as the robot
source does (compared byte for byte); the robot source's Python reference round-trips
(ik then fk gives the pose back); the dispatch table of as_source against the declared types.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.codegen import CodeSource, Controller, ControllerSource, RobotSource, UserModelSource, generate, generate_code
from gtmodel.codegen.check import sample_inputs
from gtmodel.codegen.sources import as_source, source_of
from gtmodel.errors import InputError
from gtmodel.problems.user_model import load_user_model, split_model_reference

from ..conftest import REPO
from .controller_functions import FILTER_DT, fusion_filter

MODEL = f"{REPO / 'models' / 'cart_pendulum.py'}:CartPendulum"


@pytest.fixture(scope="module")
def model():
    return load_user_model(*split_model_reference(MODEL))


@pytest.fixture(scope="module")
def robot_code(tmp_path_factory):
    return generate_code(RobotSource("L1", functions=("ik", "fk")), tmp_path_factory.mktemp("robot"))


@pytest.fixture(scope="module")
def filter_code(tmp_path_factory):
    return generate_code(ControllerSource(Controller(dt=FILTER_DT, kf_step=fusion_filter(False).step_function())),
                         tmp_path_factory.mktemp("filter"))


@pytest.fixture(scope="module")
def model_code(model, tmp_path_factory):
    return generate_code(UserModelSource(model, functions=("ode", "step_rk4")), tmp_path_factory.mktemp("model"))


def test_every_source_is_a_code_source(model):
    sources = [RobotSource("L1"), UserModelSource(model), ControllerSource(Controller(dt=FILTER_DT, kf_step=fusion_filter(False).step_function()))]
    assert all(isinstance(s, CodeSource) for s in sources)
    assert [s.kind for s in sources] == ["robot", "model", "controller"]
    assert all(s.summary() and "\n" not in s.summary() for s in sources)


def test_the_robot_source_writes_what_the_former_front_door_writes(robot_code, tmp_path):
    former = generate("L1", tmp_path, functions=["ik", "fk"])
    assert former.functions == robot_code.functions == ("ik", "fk")
    assert former.source.read_text() == robot_code.source.read_text()
    assert former.header.read_text() == robot_code.header.read_text()


def test_source_of_gives_the_source_back(robot_code, filter_code, model_code):
    assert isinstance(source_of(robot_code), RobotSource) and source_of(robot_code).functions == ("ik", "fk")
    assert isinstance(source_of(filter_code), ControllerSource)
    assert isinstance(source_of(model_code), UserModelSource)


def test_the_robot_reference_round_trips(robot_code):
    """ik then fk of the source's Python reference gives the pose back on one of fk's two solutions (a round trip)."""
    src = source_of(robot_code)
    ik = sample_inputs(robot_code, n=20, seed=1)["ik"]
    q = src.reference("ik", ik)["q"]
    err = [np.linalg.norm(src.reference("fk", {"q": q, "solution": np.full(len(q), k)})["T"] - ik["T"], axis=1) for k in (-1, 1)]
    assert np.max(np.fmin(*err)) < 1e-9


@pytest.mark.parametrize("bad, match", [
    ("L1", "expected a CodeSource"),
    (3.0, "expected a CodeSource"),
    (None, "expected a CodeSource"),
])
def test_as_source_refuses_what_is_no_source(bad, match):
    with pytest.raises(InputError, match=match):
        as_source(bad)


@pytest.mark.parametrize("name, match", [
    ("jacobian", "expected one of the generated functions ik, fk, got 'jacobian'"),
    ("kf_step", "expected one of the generated functions ik, fk"),
])
def test_reference_names_a_function_the_source_does_not_generate(robot_code, name, match):
    with pytest.raises(InputError, match=match):
        source_of(robot_code).reference(name, {"q": np.zeros((1, 3))})


@pytest.mark.parametrize("route", ["alone", "in a robot source"])
def test_a_bundle_function_is_checked_over_a_run_by_either_route(filter_code, route):
    """The bundle's kf_step has no row-by-row reference (check_controller runs it): said alike alone and inside a robot's library."""
    alone = source_of(filter_code)
    src = alone if route == "alone" else RobotSource("L1", functions=("fk",), controller=alone.controller)
    with pytest.raises(InputError, match="kf_step: the function is checked over a run"):
        src.reference("kf_step", sample_inputs(filter_code, n=4, seed=3)["kf_step"])
