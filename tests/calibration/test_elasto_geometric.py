"""Elasto-geometric calibration (Dressler (2012), ch. 5.3 next step; eqs. 4.9, 5.1-5.5).

Synthetic truth: the L1 (Table 5.1 modified) with the stated stiffness values, measured TCP
``FK(q) + K_x^-1 F_g`` (stiffness model) plus laser-tracker noise. Independent references:
the true model's validation error on the same noisy poses (the noise floor, as the L1
kinematic calibration test uses), the true compliances that generated the data, the linear
deflection of the stiffness model against Newton's method on the loaded closure equations
(second method, agreement to second order), the rigid 3-link closure for zero compliance,
and exact dependencies in pose sets built to have them (pure translation along the guideway).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.elasto_geometric import (
    calibrate_elasto_geometric,
    compliance_identifiability,
    compliance_selection,
    compliant_measurements,
    elasto_geometric_study,
    explain_identifiability,
)
from gtmodel.calibration.evaluation import evaluate
from gtmodel.calibration.measurements import MeasurementSet, read_measurements
from gtmodel.calibration.poses import grid_poses
from gtmodel.calibration.synthetic import NO_NOISE
from gtmodel.errors import InputError
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.elasto_geometric import COMPLIANCE_NAMES, ElastoGeometricClosure
from gtmodel.robots.stiffness import GantryTau3Stiffness

#: Payload of the compliant truth [kg] (a spindle: deflections ~100-200 um).
PAYLOAD_KG = 40.0
#: Grid step of the study [m] (~250 L1 poses: the test stays fast).
GRID_STEP = 0.17
#: Validation mean error of the elasto-geometric model vs the true model's (noise floor).
NOISE_FLOOR_RATIO = 1.05
#: The geometric-only model on two-load data must be at least this much worse than the floor.
GEOMETRIC_RATIO = 3.0
#: Calibrated compliances within this many reported standard deviations of the truth.
N_SIGMA = 3.0
#: Newton FK on the loaded closure vs FK + K_x^-1 F: second-order terms |dT|^2 / L ~ 1e-8 m.
SECOND_ORDER_TOL = 1e-7
SEED = 0


@pytest.fixture(scope="module")
def truth():
    return GantryTau3Stiffness("L1", payload_kg=PAYLOAD_KG)


@pytest.fixture(scope="module")
def q(truth):
    return grid_poses(ThreeLinkClosure("L1"), GRID_STEP)


@pytest.fixture(scope="module")
def start():
    return ThreeLinkClosure("L1_ideal", model="modified")


@pytest.fixture(scope="module")
def two_loads(truth, start, q):
    return elasto_geometric_study(truth, start, q, payloads_kg=[0.0, PAYLOAD_KG], seed=SEED)


# ------------------------------------------------------------------ the model
def test_loaded_closure_fk_matches_linear_deflection_of_the_stiffness_model(truth, q):
    """Newton on eq. 2 (loaded link lengths) = rigid FK + K_x^-1 F_g (stiffness model), to
    second order; two independent solution methods of the same physics."""
    model = ElastoGeometricClosure.from_stiffness(truth)
    data = compliant_measurements(truth, q[:40], noise=NO_NOISE)
    T_newton, _ = model.fk(q[:40])
    np.testing.assert_allclose(T_newton, data.T, atol=SECOND_ORDER_TOL)
    assert np.linalg.norm(T_newton - truth.kinematics.fk(q[:40]), axis=1).min() > 100e-6  # it does deflect


def test_per_pose_loads_give_the_same_deflection(truth, q):
    """A load carried with the pose (MeasurementSet.load) acts like the constant load: the
    stiffness model's gravity force, and Newton's FK on eq. 2 against the linear deflection."""
    loaded = ElastoGeometricClosure.from_stiffness(truth, per_pose_load=True)
    data = compliant_measurements(truth, q[:20], noise=NO_NOISE, payloads_kg=np.full(20, PAYLOAD_KG))
    assert data.n_q == 3 and data.has_load
    np.testing.assert_allclose(data.load, np.broadcast_to(truth.gravity_force, (20, 3)), rtol=1e-12)
    np.testing.assert_allclose(loaded.fk(loaded.pose_inputs(data))[0], data.T, atol=SECOND_ORDER_TOL)
    np.testing.assert_allclose(evaluate(loaded, data).errors, 0.0, atol=SECOND_ORDER_TOL)


def test_load_survives_the_csv_file(truth, start, q, tmp_path):
    """Two-load data written to CSV (F_x_N..F_z_N columns) and read back calibrate to the same
    parameters as the data in memory (the file carries the load exactly)."""
    rows = np.repeat(np.arange(12), 2)
    data = compliant_measurements(truth, q[rows], seed=SEED, payloads_kg=np.tile([0.0, PAYLOAD_KG], 12))
    back = read_measurements(data.to_csv(tmp_path / "two_loads.csv"))
    np.testing.assert_array_equal(back.load, data.load)
    el = ElastoGeometricClosure(start, per_pose_load=True)
    a = calibrate_elasto_geometric(el, data, free_compliance="c_l*", max_iter=20)
    b = calibrate_elasto_geometric(el, back, free_compliance="c_l*", max_iter=20)
    np.testing.assert_allclose(b.model.parameter_vector(), a.model.parameter_vector(), rtol=0, atol=1e-12)


def test_zero_compliance_is_the_rigid_closure(q):
    """Eq. 2 with c = 0 is eq. 4.9 of the geometric model."""
    geo = ThreeLinkClosure("L1")
    el = ElastoGeometricClosure(geo, F=[0.0, 0.0, -500.0])
    T = geo.fk(q[:5])[0]
    values = [
        (
            arm,
            k,
            float(geo.closure_function(arm)(geo.parameter_vector(), q[k], T[k], [1, 0, 0, 0])),
            float(el.closure_function(arm)(el.parameter_vector(), q[k], T[k], [1, 0, 0, 0])),
        )
        for arm in range(3)
        for k in range(5)
    ]
    bad = [(arm, k, a, b) for arm, k, a, b in values if a != pytest.approx(b, abs=1e-15)]
    assert not bad, bad  # (arm, pose, rigid residual, elasto-geometric residual)


def test_transform_rotates_the_load():
    from gtmodel.robots.closure import rotation_vector_to_rotation

    el = ElastoGeometricClosure(ThreeLinkClosure("L1"), F=[0.0, 0.0, -500.0])
    R = rotation_vector_to_rotation([0.1, -0.2, 0.3])
    moved = el.transformed(R, [0.1, 0.2, 0.3])
    np.testing.assert_allclose(moved.F, R @ el.F)
    assert moved.parameter_names() == el.parameter_names()


# ------------------------------------------------------------------ calibration
def test_elasto_geometric_calibration_reaches_the_noise_floor(two_loads):
    """Two loads per pose: the elasto-geometric model validates at the true model's error on
    the same noisy poses; the geometric-only model cannot (same q, two TCPs)."""
    st = two_loads
    assert st.status == "optimal"
    floor = st.noise_floor.mean_error
    assert st.elasto_report.mean_error <= NOISE_FLOOR_RATIO * floor, (st.elasto_report.mean_error, floor)
    assert st.geometric_report.mean_error >= GEOMETRIC_RATIO * floor
    assert st.deflection.max() > 10 * 10e-6  # far above the tracker noise


def test_compliances_within_three_std_of_the_truth(two_loads):
    st = two_loads
    assert st.identifiability.full_rank and st.identifiability.n_parameters == 21 + 6
    bad = [row for row in st.compliance_table() if not abs(row["z"]) < N_SIGMA]
    assert not bad, bad
    assert st.load_identifiability.full_rank  # known load changes make the constant load separable too


def test_single_load_is_absorbed_by_the_geometry(truth, start, q):
    """One constant load: the arm forces barely vary, so the geometric model absorbs most of
    the deflection (validation close to the floor) and the compliances are poorly determined;
    with the load free, the load and the compliances are not separable."""
    st = elasto_geometric_study(truth, start, q, seed=SEED)
    floor = st.noise_floor.mean_error
    assert st.elasto_report.mean_error <= 1.2 * floor
    assert st.geometric_report.mean_error <= 1.2 * floor
    std = np.array([st.elasto.std[n] for n in COMPLIANCE_NAMES])
    true = np.concatenate([st.true_model.c_link, st.true_model.c_act])
    assert np.all(std > 0.5 * true)
    rep = st.load_identifiability
    assert rep.rank == rep.n_parameters - 1
    assert any("products c_i f_i" in e for e in explain_identifiability(rep))


def test_compliance_not_separable_from_length_on_a_pure_translation(truth):
    """Poses moved along the (common) guideway direction keep every link direction, hence every
    arm force: c_l,i f_i is a constant length change, not separable from L_i (QR dependency)."""
    ideal = ThreeLinkClosure("L1_ideal", model="ideal")
    model = ElastoGeometricClosure(ideal, truth.c_link, truth.c_act, truth.gravity_force)
    q0 = ideal.ik(truth.kinematics.workspace_grid(0.3)[0])
    q = q0 + np.linspace(-0.3, 0.3, 20)[:, None] * np.ones(3)
    T, _ = model.fk(q)
    rep = compliance_identifiability(model, q, T, free_compliance="c_l*", fixed=("As*", "v*"))
    assert rep.rank == 3
    bad = [
        i
        for i in (1, 2, 3)
        if not (
            f"L{i}" in rep.non_identifiable.get(f"c_l{i}", {}).get("depends_on", {})
            or f"c_l{i}" in rep.non_identifiable.get(f"L{i}", {}).get("depends_on", {})
        )
    ]
    assert not bad, (bad, rep.describe())  # arms whose c_l,i is not tied to L_i
    text = explain_identifiability(rep)
    assert len(text) == 3 and all("not separable from the link length" in t for t in text)


# ------------------------------------------------------------------ bad input
#: Poses without a load (for the per-pose-load bad-input rows).
_POSES = MeasurementSet(q=np.zeros((2, 3)), T=np.ones((2, 3)), source="no load")


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda t: ElastoGeometricClosure("L1"), r"geometric: expected a ThreeLinkClosure"),
        (lambda t: ElastoGeometricClosure(ThreeLinkClosure("L1"), c_link=[1e-8, 1e-8]), r"c_link: expected 3 finite"),
        (lambda t: ElastoGeometricClosure(ThreeLinkClosure("L1"), F=[0.0, np.nan, 0.0]), r"F: expected 3 finite"),
        (lambda t: ElastoGeometricClosure(ThreeLinkClosure("L1")).with_parameters(np.zeros(5)), r"expected 30 finite"),
        (lambda t: ElastoGeometricClosure(ThreeLinkClosure("L1")).fk(np.zeros((2, 6))), r"expected 3 columns"),
        (lambda t: compliant_measurements(t, np.zeros((4, 2))), r"q: expected finite cart positions"),
        (lambda t: compliant_measurements(t, np.zeros((2, 3)), payloads_kg=[1.0, -1.0]), r"payloads_kg"),
        (lambda t: compliant_measurements("L1", np.zeros((2, 3))), r"stiffness: expected a GantryTau3Stiffness"),
        (lambda t: compliance_selection("c_x*"), r"free_compliance: 'c_x\*' matches no compliance"),
        (lambda t: ElastoGeometricClosure(ThreeLinkClosure("L1"), per_pose_load=True).pose_inputs(_POSES), r"holds no plate load"),
        (lambda t: ElastoGeometricClosure(ThreeLinkClosure("L1"), per_pose_load=True).pose_inputs(_POSES.q), r"measurements: expected a MeasurementSet"),
        (lambda t: calibrate_elasto_geometric(ElastoGeometricClosure(ThreeLinkClosure("L1"), per_pose_load=True), _POSES), r"holds no plate load"),
        (lambda t: evaluate(ElastoGeometricClosure(ThreeLinkClosure("L1"), per_pose_load=True), _POSES), r"holds no plate load"),
        (lambda t: ElastoGeometricClosure(ThreeLinkClosure("L1")).pose_inputs(MeasurementSet(np.zeros((2, 6)), np.zeros((2, 3)))), r"6 actuator columns"),
    ],
    ids=["not_closure", "c_shape", "nan_load", "p_size", "fk_columns", "q_shape", "negative_payload", "not_stiffness", "bad_pattern",
         "no_load", "not_a_set", "calibrate_no_load", "evaluate_no_load", "f1_columns"],
)
def test_bad_input(truth, call, match):
    with pytest.raises(InputError, match=match):
        call(truth)
