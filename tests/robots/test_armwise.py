"""``ArmwiseClosure``: arms of different closure models joined (Dressler (2012), Table 5.3, model 5).

Independent references: each source's own closure equations and FK (the joined model must
reproduce arm i of source i exactly, and one model joined with itself must be that model).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.robots import load_six_link
from gtmodel.robots.armwise import ArmwiseClosure
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.pose_rank import POSE_RANK_RTOL, closure_inverse_condition

Q = np.array([[0.0, 0.0, 0.0], [0.2, -0.1, 0.3], [-0.4, -0.3, -0.2]])


@pytest.fixture(scope="module")
def d1():
    base = ThreeLinkClosure("D1")
    other = base.with_parameters(base.parameter_vector() + 1e-4 * np.arange(base.n_parameters) / base.n_parameters)
    return base, other


def test_a_model_joined_with_itself_is_that_model(d1):
    base, _ = d1
    joined = ArmwiseClosure([base, base, base])
    assert dict(zip(joined.parameter_names(), joined.parameter_vector())) == dict(zip(base.parameter_names(), base.parameter_vector()))
    T0, _ = base.fk(Q)
    T1, _ = joined.fk(Q)
    assert np.abs(T1 - T0).max() < 1e-9


@pytest.mark.parametrize("arm", [0, 1, 2])
def test_each_arm_has_its_source_closure(d1, arm):
    base, other = d1
    sources = [base, base, base]
    sources[arm] = other
    joined = ArmwiseClosure(sources)
    T = np.array([0.1, 2.5, -0.4])
    quat = np.array([1.0, 0.0, 0.0, 0.0])
    r_joined = [np.array(joined.closure_function(a)(joined.parameter_vector(), Q[1], T, quat)).ravel() for a in range(3)]
    r_src = [np.array(sources[a].closure_function(a)(sources[a].parameter_vector(), Q[1], T, quat)).ravel() for a in range(3)]
    assert np.concatenate(r_joined) == pytest.approx(np.concatenate(r_src), abs=1e-15)
    r_base = np.array(base.closure_function(arm)(base.parameter_vector(), Q[1], T, quat)).ravel()
    assert not np.allclose(r_joined[arm], r_base, rtol=0, atol=1e-12)  # the swapped arm is the other model's


def test_with_parameters_and_transformed_keep_the_arms(d1):
    base, other = d1
    joined = ArmwiseClosure([base, other, base])
    p = joined.parameter_vector()
    again = joined.with_parameters(p)
    assert np.array_equal(again.parameter_vector(), p)
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    moved = joined.transformed(R, [0.1, 0.2, 0.3])
    assert np.array_equal(moved.sources[1].parameter_vector(), other.transformed(R, [0.1, 0.2, 0.3]).parameter_vector())


@pytest.mark.parametrize("sources, match", [
    (lambda b: [b, b], r"sources: expected 3 closure models"),
    (lambda b: [b, b, "D1"], r"sources: expected 3 closure models"),
    (lambda b: [b, b, load_six_link("D1_six_link")], r"same number of actuators and the same orientation flag"),
])
def test_bad_sources(d1, sources, match):
    with pytest.raises(InputError, match=match):
        ArmwiseClosure(sources(d1[0]))


def test_with_parameters_checks_the_size(d1):
    with pytest.raises(InputError, match=r"p: expected 21 finite values"):
        ArmwiseClosure([d1[0]] * 3).with_parameters(np.zeros(3))


def _coincident_links(model):
    """The model with every link of an arm on its first link (joint points and length): what a free-B0
    six-link calibration converges to, as each link's least-squares problem is the same function of
    the same data (problems/thesis/d1_error_models_thesis.toml, model 3)."""
    names = model.parameter_names()
    v = dict(zip(names, model.parameter_vector()))
    for first, link in (("2a", "2b"), ("3a", "3b"), ("3a", "3c")):
        v.update({n: v[n.replace(f"_{link}", f"_{first}")] for n in names if f"_{link}" in n})
    return model.with_parameters([v[n] for n in names])


def test_a_source_with_coincident_links_leaves_the_joined_pose_to_the_determined_one():
    """Independent checks: the singular values of the closure Jacobian (numpy's SVD); the pose is the
    same under 1e-10 of parameter rounding (what another BLAS kernel changes). Plain Newton from the
    same start meets the singular Jacobian: NaN on one machine, an arbitrary finite orientation on a
    fresh CI environment, so it is not asserted."""
    d1 = load_six_link("D1_six_link")
    p = d1.parameter_vector()
    flat, other = _coincident_links(d1), d1.with_parameters(p + 2e-4 * np.sin(np.arange(p.size)))
    q = np.vstack([Q, [0.3, 0.3, -0.3]])
    assert np.all(closure_inverse_condition(flat, q, *flat.fk(q)) < POSE_RANK_RTOL)
    assert np.all(closure_inverse_condition(d1, q, *d1.fk(q)) > 1e-2)  # condition ~19
    joined = ArmwiseClosure([flat, other, flat])
    T, R = joined.fk(q)
    pj = joined.parameter_vector()
    rounded = joined.with_parameters(pj * (1 + 1e-10 * np.random.default_rng(0).standard_normal(pj.size)))
    assert np.abs(rounded.fk(q)[0] - T).max() < 1e-8
    T0, R0 = other.fk(q)
    # the nearest assembly to the determined source's pose: its orientation (which the flat arms leave free)
    assert np.abs(R - R0).max() < 2e-4 and np.abs(T - T0).max() < 5e-4
