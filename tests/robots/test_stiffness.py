"""Static stiffness of the 3-link Gantry-Tau (Dressler (2012), ch. 6.3, spec section 4).

Independent references: (1) a finite-difference stiffness of the *nonlinear* elastic
equilibrium of the arms, written here with SciPy's scalar root finder (exact link lengths,
the cart moving along its guideway against its actuator) -- a second method for
``K_x = sum k_i u_i u_i^T``; (2) the inverse Jacobian of eq. 6.5 from the kinematics module
(``K_x = J^-T diag(k_i (u_i . v_i)^2) J^-1``); (3) closed forms: ``trace K_x = sum k_i`` for unit
link vectors, linearity in the force, series/parallel springs for the arm compliance; (4) the
D1's measured TCP stiffness of 2-4 N/um (reference table) for the stated values.
"""

from __future__ import annotations

import tomllib
from importlib import resources

import numpy as np
import pytest
import scipy.optimize

from gtmodel.errors import InputError, ParameterError, UnreachablePoseError
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import available_parameter_sets
from gtmodel.robots.six_link import load_six_link
from gtmodel.report.stiffness import plot_stiffness_map
from gtmodel.robots.stiffness import (
    N_PER_UM,
    GantryTau3Stiffness,
    StiffnessParameters,
    closure_stiffness,
    load_stiffness,
)

from ..conftest import SHARED_REFERENCE

#: Relative agreement of K_x with the finite-difference stiffness of the nonlinear equilibrium
#: (central differences with a 1e-7 m step: truncation ~ (h/L)^2, round-off ~ 1e-9).
FD_RTOL = 1e-5
#: Finite-difference step of the TCP [m].
FD_STEP = 1e-7
#: Agreement of two exact linear-algebra forms of the same matrix (relative).
EXACT_RTOL = 1e-10
#: The stated values must reproduce the D1's measured vertical TCP stiffness band (2-4 N/um)
#: to within this factor at every pose (the values are assumptions, not a fit).
MEASURED_BAND_FACTOR = 1.5
#: Payload of the deflection checks [kg] (a spindle; stated in the problem file).
PAYLOAD_KG = 40.0
SEED = 3
#: Number of random workspace poses of the checks.
N_POSES = 6


@pytest.fixture(scope="module")
def d1():
    return GantryTau3Stiffness("D1", payload_kg=PAYLOAD_KG)


@pytest.fixture(scope="module")
def poses(d1):
    T = d1.kinematics.workspace_grid(0.1)
    rng = np.random.default_rng(SEED)
    return T[rng.choice(len(T), N_POSES, replace=False)]


# ------------------------------------------------------------------ stated values
def test_shipped_values_carry_their_sources():
    """Joints 115 kN/mm (spec section 4); tube and actuator values are labelled assumptions."""
    s = load_stiffness()
    assert s.k_joint == 1.15e8 and s.joints_per_link == 2
    assert tuple(s.links_per_arm) == (1, 2, 3)
    assert "115 kN/mm" in s.sources["joints"]
    assert "ASSUMPTION" in s.sources["links"] and "ASSUMPTION" in s.sources["actuators"]
    assert "stiffness" not in available_parameter_sets()


@pytest.mark.parametrize("i, n", [(0, 1), (1, 2), (2, 3)])
def test_arm_compliance_is_series_and_parallel_springs(d1, i, n):
    """Closed form: cluster of n parallel links, each a tube E A / L in series with two joints."""
    s = d1.stiffness
    A = np.pi / 4 * (s.outer_diameter**2 - s.inner_diameter**2)
    k_link = s.E * A / d1.L[i]
    expected = (1 / k_link + 2 / s.k_joint) / n
    assert d1.c_link[i] == pytest.approx(expected, rel=EXACT_RTOL)


def test_actuator_compliance_is_the_inverse_stiffness(d1):
    np.testing.assert_allclose(d1.c_act, 1 / d1.stiffness.k_actuator, rtol=EXACT_RTOL)


# ------------------------------------------------------------------ K_x: second methods
def _nonlinear_plate_force(model: GantryTau3Stiffness, T: np.ndarray, dT: np.ndarray) -> np.ndarray:
    """External plate force holding the TCP at T + dT: exact link lengths, carts in equilibrium
    along their guideways (independent of the module: SciPy brentq per arm)."""
    q = model.kinematics.ik(T)
    P = T + dT
    F = np.zeros(3)
    for i in range(3):
        A = model.As[i] + q[i] * model.v[i]
        w = model.v[i] / np.linalg.norm(model.v[i])
        L0 = np.linalg.norm(T - A)

        def tension(s):
            d = P - A - s * w
            return (np.linalg.norm(d) - L0) / model.c_link[i], d / np.linalg.norm(d)

        def balance(s):
            f, u = tension(s)
            return s - model.c_act[i] * f * (u @ w)

        s = scipy.optimize.brentq(balance, -1e-3, 1e-3, xtol=1e-22, rtol=1e-15)
        f, u = tension(s)
        F += f * u
    return F


@pytest.mark.parametrize("n", range(N_POSES))
def test_cartesian_stiffness_matches_finite_differences_of_the_nonlinear_equilibrium(d1, poses, n):
    """K_x (eq. 1) equals d F / d T of the nonlinear elastic equilibrium (central differences)."""
    T = poses[n]
    K = d1.cartesian_stiffness(T)
    K_fd = np.column_stack(
        [(_nonlinear_plate_force(d1, T, FD_STEP * e) - _nonlinear_plate_force(d1, T, -FD_STEP * e)) / (2 * FD_STEP) for e in np.eye(3)]
    )
    np.testing.assert_allclose(K, K_fd, rtol=FD_RTOL, atol=FD_RTOL * np.abs(K).max())
    np.testing.assert_allclose(K, K.T, rtol=EXACT_RTOL)


@pytest.mark.parametrize("n", range(N_POSES))
def test_cartesian_stiffness_is_the_inverse_jacobian_form(d1, poses, n):
    """K_x = J^-T diag(k_i (u_i . v_i)^2) J^-1 with J^-1 of eq. 6.5 (kinematics module)."""
    kin: GantryTau3Kinematics = d1.kinematics
    Jinv = kin.jacobian_inverse(poses)
    cos = np.cos(kin.link_angles(poses))
    k = d1.arm_stiffness(poses)
    uv = cos * np.linalg.norm(d1.v, axis=1)
    K = d1.cartesian_stiffness(poses)
    expected = Jinv[n].T @ np.diag(k[n] * uv[n] ** 2) @ Jinv[n]
    np.testing.assert_allclose(K[n], expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())


def test_trace_is_the_sum_of_arm_stiffnesses(d1, poses):
    """Closed form: trace(sum k_i u_i u_i^T) = sum k_i for unit vectors u_i."""
    np.testing.assert_allclose(np.trace(d1.cartesian_stiffness(poses), axis1=1, axis2=2), d1.arm_stiffness(poses).sum(axis=1), rtol=EXACT_RTOL)


def test_arm_stiffness_depends_on_the_link_angle_through_the_actuator(d1, poses):
    """Eq. 2: 1/k_i = c_link + c_act cos^2(link angle to the guideway)."""
    cos = np.cos(d1.kinematics.link_angles(poses))
    np.testing.assert_allclose(1 / d1.arm_stiffness(poses), d1.c_link + d1.c_act * cos**2, rtol=EXACT_RTOL)


# ------------------------------------------------------------------ loads and deflections
@pytest.mark.parametrize("n", range(N_POSES))
def test_link_forces_balance_the_plate_load(d1, poses, n):
    """sum_i f_i u_i = F (statics of the plate); u_i from the IK of eq. 4.9."""
    F = np.array([120.0, -50.0, -300.0])
    f = d1.link_forces(poses, F)
    q = d1.kinematics.ik(poses)
    T = poses[n]
    A = d1.As + q[n][:, None] * d1.v
    U = (T - A) / np.linalg.norm(T - A, axis=1)[:, None]
    np.testing.assert_allclose(U.T @ f[n], F, rtol=1e-10, atol=1e-9)


def test_deflection_is_linear_and_solves_K_dT_equals_F(d1, poses):
    F = np.array([0.0, 200.0, -500.0])
    dT = d1.deflection(poses, F)
    np.testing.assert_allclose(d1.deflection(poses, 2 * F), 2 * dT, rtol=EXACT_RTOL)
    K = d1.cartesian_stiffness(poses)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", K, dT), np.broadcast_to(F, dT.shape), rtol=1e-9, atol=1e-6)


def test_gravity_load_and_deflection(d1, poses):
    """Plate load = g (m_p + payload + sum m_a / 2) (eq. 6.7's G); with a 40 kg payload the
    deflection is well above the 10 um tracker noise (100-300 um)."""
    d = d1.parameters.dynamics
    assert d1.gravity_force[2] == pytest.approx(-d.g * (d.m_p + PAYLOAD_KG + d.m_a.sum() / 2))
    dT = d1.gravity_deflection(poses)
    np.testing.assert_allclose(dT, d1.deflection(poses, d1.gravity_force), rtol=EXACT_RTOL)
    assert np.all(dT[:, 2] < 0)
    assert 100e-6 < np.linalg.norm(dT, axis=1).min() and np.linalg.norm(dT, axis=1).max() < 300e-6


def test_stated_values_give_the_measured_d1_stiffness_band(d1):
    """Dressler (2012), ch. 6.3: the D1 measured 2-4 N/um at the TCP. With the stated values the
    model's vertical stiffness over the D1 workspace lies in that band (within the factor)."""
    ref = tomllib.loads((SHARED_REFERENCE / "gantry_tau_D1_F1.toml").read_text())["D1"]["stiffness_tcp_N_per_um"]
    smap = d1.stiffness_map(d1.kinematics.workspace_grid(0.15))
    kz = smap.axis_stiffness[:, 2] / N_PER_UM
    assert ref[0] / MEASURED_BAND_FACTOR <= kz.min() and kz.max() <= ref[1] * MEASURED_BAND_FACTOR
    s = smap.summary()
    assert s["measured_D1_N_per_um"] == ref
    assert s["min_eigenvalue_N_per_um"][0] <= s["axis_N_per_um"]["z"][0]


def test_stiffness_map_plot(d1, tmp_path):
    P = d1.section_grid(step=0.1)
    fig = plot_stiffness_map(d1.stiffness_map(P), tmp_path / "map.png", quantity="z", title="D1")
    assert (tmp_path / "map.png").stat().st_size > 0
    assert "115" in fig.axes[0].get_title()  # the stated joint stiffness is on the figure


# ------------------------------------------------------------------ bad input
def _params(**kw):
    base = dict(k_joint=1.15e8, E=1e11, outer_diameter=0.04, inner_diameter=0.034, k_actuator=[1.5e7] * 3, links_per_arm=[1, 2, 3])
    base.update(kw)
    return base


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(k_joint=0.0), r"k_joint: expected positive"),
        (dict(k_joint=-1e8), r"k_joint: expected positive"),
        (dict(E=float("nan")), r"E: expected positive"),
        (dict(k_actuator=[1e7, 0.0, 1e7]), r"k_actuator: expected positive"),
        (dict(k_actuator=[1e7, 1e7]), r"k_actuator: expected shape \(3,\)"),
        (dict(inner_diameter=0.05), r"inner_diameter: expected 0 <= inner_diameter < outer_diameter"),
        (dict(links_per_arm=[1, 2.5, 3]), r"links_per_arm: expected positive integers"),
    ],
    ids=["zero_joint", "negative_joint", "nan_modulus", "zero_actuator", "actuator_shape", "inner_too_big", "fractional_links"],
)
def test_bad_stiffness_values(kw, match):
    with pytest.raises(InputError, match=match):
        StiffnessParameters(**_params(**kw))


def test_bad_stiffness_file_names_the_field(tmp_path):
    text = (resources.files("gtmodel.robots") / "data" / "stiffness.toml").read_text()
    f = tmp_path / "s.toml"
    f.write_text(text.replace("k_joint = 1.15e8", "k_joint = -1.0"))
    with pytest.raises(ParameterError, match=r"s\.toml: field 'joints\.k_joint': expected positive"):
        load_stiffness(f)


@pytest.mark.parametrize(
    "call, err, match",
    [
        (lambda m: m.cartesian_stiffness([0.0, 0.0]), InputError, r"T: expected shape"),
        (lambda m: m.cartesian_stiffness([np.nan, -4.4, 0.1]), InputError, r"T: row 0 is not finite"),
        (lambda m: m.deflection([-1.27, -4.36, 0.16], [0.0, 1.0]), InputError, r"F: expected a force of shape"),
        (lambda m: m.deflection([[-1.27, -4.36, 0.16]] * 2, np.zeros((3, 3))), InputError, r"F: expected a force of shape"),
        (lambda m: m.link_forces([-1.27, -4.36, 0.16], [0.0, np.inf, 0.0]), InputError, r"F: row 0 is not finite"),
        (lambda m: m.cartesian_stiffness([10.0, 0.0, 0.0]), UnreachablePoseError, r"arm"),
        (lambda m: m.cartesian_stiffness([-0.4, -4.36, 0.16]), UnreachablePoseError, r"outside the workspace"),
        (lambda m: GantryTau3Stiffness("D1", payload_kg=-1.0), InputError, r"payload_kg"),
        (lambda m: plot_stiffness_map(m.stiffness_map([[-1.27, -4.36, 0.16]]), quantity="w"), InputError, r"quantity"),
    ],
    ids=["short_T", "nan_T", "short_F", "F_rows", "inf_F", "unreachable", "outside_limits", "negative_payload", "bad_quantity"],
)
def test_bad_input(d1, call, err, match):
    with pytest.raises(err, match=match):
        call(d1)


# ------------------------------------------------------------------ any closure model (condensation)
#: Six-link with the plate rotation held vs the 3-link translational model (parallel links of a
#: cluster are nearly parallel, the plate offsets small): relative agreement of K.
SIX_LINK_RTOL = 0.05


@pytest.mark.parametrize("n", range(3))
def test_condensed_three_link_closure_equals_the_series_formula(d1, poses, n):
    """Third method: differentiate the closure link lengths w.r.t. TCP and cart displacements,
    condense the carts (K_xx - K_xs K_ss^-1 K_sx): equals eqs. 1-2 (series arm compliance)."""
    model = ThreeLinkClosure(d1.parameters)
    T = poses[n]
    cs = closure_stiffness(model, d1.kinematics.ik(T), d1.stiffness)
    np.testing.assert_allclose(cs.T, T, atol=1e-9)
    np.testing.assert_allclose(cs.K, d1.cartesian_stiffness(T), rtol=1e-9, atol=1e-9 * np.abs(cs.K).max())


def test_six_link_plate_rotation_lowers_the_stiffness(d1, poses):
    """Six-link D1 (Table 5.9 geometry): with the rotation held it is the translational model;
    letting the plate rotate under a TCP force can only soften it (K_locked - K_free >= 0)."""
    six = load_six_link("D1_six_link")
    T = poses[0]
    cs = closure_stiffness(six, d1.kinematics.ik(T), d1.stiffness)
    assert cs.K.shape == (6, 6) and cs.k_links.shape == (6,)
    K3 = d1.cartesian_stiffness(cs.T)
    np.testing.assert_allclose(cs.K_locked, K3, rtol=SIX_LINK_RTOL, atol=SIX_LINK_RTOL * np.abs(K3).max())
    assert np.linalg.eigvalsh(cs.K_locked - cs.K_free).min() > -1e-6 * np.abs(K3).max()
    assert np.linalg.eigvalsh(cs.K_free).min() < np.linalg.eigvalsh(cs.K_locked).min()


def test_closure_stiffness_refuses_other_models():
    with pytest.raises(InputError, match="3 linear actuators"):
        closure_stiffness("L1", [0.0, 0.0, 0.0])
