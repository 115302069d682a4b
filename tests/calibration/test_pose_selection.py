"""Pose selection (Dressler (2012), eqs. 5.9, 5.14) and simulated calibration (ch. 5.6).

Independent references: eigenvalues from ``numpy.linalg.eigvalsh`` for the secular-equation
roots, a brute-force greedy loop with ``numpy.linalg.cond`` for the selection, a random
choice of the same size as the baseline, hand-computed singular values for eq. 5.14, and
the Monte-Carlo spread of simulated calibrations for the reported standard deviations.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gtmodel.calibration.kinematic import CalibrationProblem
from gtmodel.calibration.pose_selection import (
    ACCEPTANCE_LIMIT,
    _secular_roots,
    acceptance_value,
    scaled_condition_number,
    select_poses,
    select_rows,
    simulate_calibration,
)
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import load_parameters

#: Relative agreement of eigenvalues / condition numbers computed two ways.
EIG_TOL = 1e-9
#: Candidate grid spacing [m] (354 L1 poses).
GRID_STEP = 0.15
#: Poses kept from the grid.
N_KEEP = 100
#: Random subsets drawn for the baseline.
N_RANDOM = 30
#: Laser-tracker noise per coordinate [m].
NOISE = 10e-6
#: Monte-Carlo runs of the simulated calibration.
N_RUNS = 12
#: Accepted ratio of the Monte-Carlo spread to the reported standard deviation (the spread
#: of a standard deviation estimated from 12 runs is ~21 %; 0.5-1.7 is > 2.5 of those).
SPREAD_RATIO = (0.5, 1.7)


@pytest.fixture(scope="module")
def l1():
    return ThreeLinkClosure(load_parameters("L1"))


@pytest.fixture(scope="module")
def candidates(l1):
    T = GantryTau3Kinematics(load_parameters("L1")).workspace_grid(GRID_STEP)
    return l1.ik(T), T


@pytest.fixture(scope="module")
def jacobian(l1, candidates):
    q, T = candidates
    _, J, names = CalibrationProblem(l1).jacobian(l1.parameter_vector(), q, T)
    return J, names


@pytest.mark.parametrize("n", [2, 3, 7, 15])
def test_secular_roots_match_eigvalsh(n):
    """Extreme eigenvalues of G - a a^T for 60 rows a: secular equation vs eigvalsh
    (eigenvalues spread over 6 decades, like a calibration Gram matrix)."""
    rng = np.random.default_rng(n)
    A = rng.standard_normal((300, n)) * np.logspace(0, -3, n)
    G = A.T @ A
    lam, U = np.linalg.eigh(G)
    a = A[:60]
    lo, hi = _secular_roots(lam, (a @ U) ** 2)
    ev = np.linalg.eigvalsh(G[None] - np.einsum("ki,kj->kij", a, a))
    assert lo == pytest.approx(ev[:, 0], rel=EIG_TOL)
    assert hi == pytest.approx(ev[:, -1], rel=EIG_TOL)


def _brute_force(J, n):
    """Greedy removal with numpy.linalg.cond of every candidate subset (eq. 5.9)."""
    N, r, p = J.shape
    Js = J / np.linalg.norm(J.reshape(-1, p), axis=0)
    alive = list(range(N))
    removed = []
    while len(alive) > n:
        conds = [np.linalg.cond(Js[[i for i in alive if i != k]].reshape(-1, p)) for k in alive]
        k = alive[int(np.argmin(conds))]
        alive.remove(k)
        removed.append(k)
    return removed


@pytest.mark.parametrize("model_name", ["L1", "L1_ideal"], ids=["rank-one-blocks", "shared-v"])
def test_greedy_equals_brute_force(model_name, candidates):
    """The removal sequence equals that of a brute-force loop with numpy.linalg.cond, for
    one-row blocks (modified model: secular equation) and three rows per pose sharing v
    (ideal model: batched eigvalsh)."""
    model = ThreeLinkClosure(load_parameters(model_name))
    q, T = candidates
    idx = np.arange(0, len(q), 9)[:40]
    _, J, names = CalibrationProblem(model).jacobian(model.parameter_vector(), q[idx], T[idx])
    res = select_rows(J, 30, names)
    assert res.removed.tolist() == _brute_force(J, 30)


def test_reported_condition_numbers(jacobian):
    """history[-1] and condition_number agree with an SVD of the kept rows (candidate
    scaling); the kept poses are the candidates not removed."""
    J, names = jacobian
    res = select_rows(J, N_KEEP, names)
    Js = J / np.linalg.norm(J.reshape(-1, J.shape[2]), axis=0)
    assert res.condition_number == pytest.approx(np.linalg.cond(Js[res.indices].reshape(-1, J.shape[2])), rel=EIG_TOL)
    assert res.history[-1] == pytest.approx(res.condition_number, rel=EIG_TOL)
    assert sorted(res.indices.tolist() + res.removed.tolist()) == list(range(len(J)))
    assert res.acceptance == pytest.approx(acceptance_value(J[res.indices]))


def test_selection_beats_random_choice(jacobian):
    """Greedy choice of 100 of 354 poses: lower condition number than every one of 30 random
    choices of the same size (seeded baseline), and lower than all candidates together."""
    J, names = jacobian
    res = select_rows(J, N_KEEP, names)
    rng = np.random.default_rng(11)
    Js = J / np.linalg.norm(J.reshape(-1, J.shape[2]), axis=0)
    random = [np.linalg.cond(Js[rng.choice(len(J), N_KEEP, replace=False)].reshape(-1, J.shape[2])) for _ in range(N_RANDOM)]
    assert res.condition_number < min(random)
    assert res.condition_number < res.initial_condition_number


def test_select_poses_on_model(l1, candidates):
    """select_poses evaluates the Jacobian at the model's FK and gives the same selection
    as select_rows on the problem's Jacobian."""
    q, T = candidates
    res = select_poses(l1, q[::4], 30)
    _, J, names = CalibrationProblem(l1).jacobian(l1.parameter_vector(), q[::4], T[::4])
    assert res.indices.tolist() == select_rows(J, 30, names).indices.tolist()
    assert res.names == names


def test_acceptance_value_hand_computed():
    """Unit columns at angle 60 deg: sigma = sqrt(3/2), sqrt(1/2), so
    sigma_max^2 / sigma_min = (3/2) / sqrt(1/2) (eq. 5.14, unit-column scaling); scaling the
    columns does not change it; a rank-deficient set gives inf."""
    c, s = 0.5, math.sqrt(3) / 2
    J = np.array([[1.0, c], [0.0, s], [0.0, 0.0]])
    assert acceptance_value(J) == pytest.approx(1.5 / math.sqrt(0.5), rel=1e-12)
    assert acceptance_value(J * [10.0, 0.1]) == pytest.approx(1.5 / math.sqrt(0.5), rel=1e-12)
    assert scaled_condition_number(J) == pytest.approx(math.sqrt(3), rel=1e-12)
    assert acceptance_value([[1.0, 2.0], [2.0, 4.0]]) == math.inf
    assert ACCEPTANCE_LIMIT == 200.0


def test_simulated_calibration_spread(l1, candidates):
    """Simulated calibration (ch. 5.6) of the L1 on 100 grid poses with 10 um noise: the
    Monte-Carlo spread of every parameter agrees with the standard deviation the
    calibrations report, the bias is within the spread, and the expected TCP error is
    below the measurement noise."""
    q, _ = candidates
    nominal = ThreeLinkClosure(load_parameters("L1_ideal"), model="modified")
    sim = simulate_calibration(l1, nominal, q[::3][:100], NOISE, N_RUNS, seed=5, q_eval=q)
    assert all(s == "optimal" for s in sim.statuses)
    ratio = sim.parameter_std / sim.predicted_std
    assert np.all((ratio > SPREAD_RATIO[0]) & (ratio < SPREAD_RATIO[1])), np.round(ratio, 2)
    assert np.all(np.abs(sim.parameter_bias) < 4 * sim.predicted_std / math.sqrt(N_RUNS) + 1e-12)
    assert np.all(sim.tcp_error_mean < NOISE)
    assert np.all(sim.tcp_error_max >= sim.tcp_error_mean)


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    "J, n, match",
    [
        (np.ones((5, 7)), 3, r"J: expected shape \(N, rows_per_pose, n_parameters\)"),
        (np.ones((5, 1, 2)), 0, r"n: expected an integer in 1..5"),
        (np.ones((5, 1, 2)), 6, r"n: expected an integer in 1..5"),
        (np.ones((5, 1, 3)), 2, r"n: 2 poses give 2 residuals for 3 parameters; keep at least 3"),
        (np.full((5, 1, 2), np.nan), 3, r"J: non-finite entries"),
        (np.ones((5, 1, 2)), 3, r"do not identify every parameter: p1 \(depends on p0: 1\)"),
    ],
    ids=["2-D", "n-zero", "n-large", "too-few-rows", "nan", "rank-deficient"],
)
def test_select_rows_bad_input(J, n, match):
    with pytest.raises((InputError, ModelError), match=match):
        select_rows(J, n)


def test_select_poses_on_a_line_refused(l1):
    """Candidates on one line do not identify the 21 parameters (test_identifiability):
    ModelError listing them, not a selection."""
    s = np.linspace(-0.3, 0.3, 40)
    T = np.array([-0.6, 3.0, -0.6]) + s[:, None] * np.array([0.6, 0.64, 0.48])
    with pytest.raises(ModelError, match=r"candidate poses do not identify every parameter: .*depends on"):
        select_poses(l1, l1.ik(T), 30, T)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"noise_sigma": -1e-6}, r"noise_sigma: expected a non-negative noise level"),
        ({"n_runs": 1}, r"n_runs: expected an integer >= 2"),
        ({"orientation_noise": -1.0}, r"orientation_noise: expected a non-negative angle"),
    ],
    ids=["noise", "runs", "orientation"],
)
def test_simulate_bad_input(l1, candidates, kwargs, match):
    q, _ = candidates
    args = {"noise_sigma": NOISE, "n_runs": 3, "seed": 0} | kwargs
    with pytest.raises(InputError, match=match):
        simulate_calibration(l1, l1, q[:50], **args)
