"""The carts' transverse compliance of the synthetic D1 (gtmodel.calibration.cart_compliance).

Independent references: the defining relation of the first-order model (each arm's length unchanged:
``u_i . dT = u_i . d_i`` with ``d_i`` the cart's displacement), recomputed here with numpy from the link
directions; zero compliance moves nothing; the displacement is linear in the compliance; the calibration kind
refuses a compliance on the F1 or below zero.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration import grid_poses
from gtmodel.calibration.cart_compliance import cart_compliance_offsets, transverse_forces
from gtmodel.errors import InputError
from gtmodel.problems import run_problem
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.stiffness import GantryTau3Stiffness


@pytest.fixture(scope="module")
def poses():
    model = ThreeLinkClosure("D1")
    q = grid_poses(model, 0.4)
    T, _ = model.fk(q)
    return T, q


def test_each_arm_keeps_its_length_to_first_order(poses):
    T, q = poses
    c = np.array([2e-6, 1e-6, 0.5e-6])
    dT = cart_compliance_offsets(T, q, c)
    st = GantryTau3Stiffness("D1")
    u = np.stack([T - (st.As[i] + q[:, i:i + 1] * st.v[i]) for i in range(3)], axis=1)
    u /= np.linalg.norm(u, axis=2, keepdims=True)
    d = c[None, :, None] * transverse_forces(T, q)
    assert np.einsum("nij,nj->ni", u, dT) == pytest.approx(np.einsum("nij,nij->ni", u, d), abs=1e-12)


def test_transverse_force_is_across_the_guideway(poses):
    T, q = poses
    st = GantryTau3Stiffness("D1")
    v = st.v / np.linalg.norm(st.v, axis=1, keepdims=True)
    assert np.einsum("nij,ij->ni", transverse_forces(T, q), v) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("scale", [0.0, 1.0, 3.0])
def test_linear_in_the_compliance(poses, scale):
    T, q = poses
    base = cart_compliance_offsets(T, q, [1e-6, 1e-6, 1e-6])
    assert cart_compliance_offsets(T, q, [scale * 1e-6] * 3) == pytest.approx(scale * base, abs=1e-15)


@pytest.mark.parametrize("c, match", [([1e-6, 1e-6], "three compliances"), ([-1e-6, 0.0, 0.0], "three compliances >= 0")])
def test_bad_compliance(poses, c, match):
    with pytest.raises(InputError, match=match):
        cart_compliance_offsets(*poses, c)


F1 = """name = "f1_compliant"
kind = "calibration"
[truth]
model = "f1"
parameters = "F1"
cart_compliance = [1e-6, 1e-6, 1e-6]
random_poses = 10
[[models]]
type = "f1"
start = "truth"
"""


@pytest.mark.parametrize("text, match", [
    (F1, "truth.cart_compliance"),
    (F1.replace('model = "f1"', 'model = "three_link"').replace('"F1"', '"D1"').replace("[1e-6, 1e-6, 1e-6]", "[-1e-6, 0, 0]"), "cart_compliance"),
], ids=["f1", "negative"])
def test_the_kind_refuses(tmp_path, text, match):
    path = tmp_path / "p.toml"
    path.write_text(text)
    res = run_problem(path, tmp_path / "out", plots=False)
    assert res.exit_code == 2 and match in (tmp_path / "out" / "summary.json").read_text()
