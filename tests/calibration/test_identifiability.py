"""Identifiability analysis: rank, dependencies, observability indices, standard deviations.

References used as independent checks (named in each test): hand-computed singular values
and QR dependencies of small matrices, the closed-form covariance of linear least squares,
and the algebra of the closure equations (a plate offset shifts every joint point; poses
on a line reach only five parameter combinations per arm).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

from gtmodel.calibration.kinematic import analyze_identifiability, calibrate
from gtmodel.calibration.identifiability import (
    RANK_TOLERANCE,
    analyze_jacobian,
    analyze_qr,
    combine_reports,
    numerical_rank,
    observability_indices,
    scale_columns,
)
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import KinematicParameters, load_parameters

#: Agreement of hand-computed numbers (round-off only).
EXACT = 1e-12
#: Agreement of dependency coefficients computed from a Jacobian at the model's values.
DEPENDENCY_TOL = 1e-6
#: Grid spacing of the "rich" L1 pose set [m].
GRID_STEP = 0.15


class PlateOffsetClosure(ThreeLinkClosure):
    """3-link model with a plate offset ``b``: ``B_i = T + b`` (not identifiable from positions).

    ``d r_i / d b_c = -d r_i / d As_i_c``, so the column of ``b_c`` is minus the sum of the
    columns of ``As1_c, As2_c, As3_c`` (Dressler (2012), ch. 5.1: the plate offset is
    absorbed in ``As_i``).
    """

    def __init__(self, kinematics: KinematicParameters, b=(0.0, 0.0, 0.0)) -> None:
        super().__init__(kinematics)
        self.b = np.asarray(b, dtype=float).reshape(3)
        self.name = f"{self.name}_plate_offset"

    def parameter_names(self):
        return super().parameter_names() + ("b_x", "b_y", "b_z")

    def parameter_vector(self):
        return np.concatenate([super().parameter_vector(), self.b])

    def link_points(self, p, q, T, R, arm):
        A, B, L = super().link_points(p, q, T, R, arm)
        return A, B + p[-3:], L

    def with_parameters(self, p):
        pa = np.asarray(p, dtype=float).ravel()
        base = ThreeLinkClosure(self.kinematics).with_parameters(pa[:-3])
        return PlateOffsetClosure(base.kinematics, pa[-3:])

    def transformed(self, R, t):
        base = ThreeLinkClosure(self.kinematics).transformed(R, t)
        return PlateOffsetClosure(base.kinematics, np.asarray(R, dtype=float) @ self.b)

    def fk(self, q):
        T, R = super().fk(q)
        return T - self.b, R


@pytest.fixture(scope="module")
def l1():
    return ThreeLinkClosure(load_parameters("L1"))


@pytest.fixture(scope="module")
def grid(l1):
    kin = GantryTau3Kinematics(load_parameters("L1"))
    T = kin.workspace_grid(GRID_STEP)
    return l1.ik(T), T


# ------------------------------------------------------------------ hand-computed examples
def test_observability_indices_hand_computed():
    """O1-O5 of singular values (3, 2, 1) with m = 4 rows, computed by hand.

    O1 = 6^(1/3)/2, O2 = 1/3, O3 = 1, O4 = 1/3, O5 = 1/(1 + 1/2 + 1/3) = 6/11
    (definitions of Sun and Hollerbach 2008).
    """
    obs = observability_indices([1.0, 3.0, 2.0], 4)
    assert obs["O1"] == pytest.approx(6 ** (1 / 3) / 2, rel=EXACT)
    assert obs["O2"] == pytest.approx(1 / 3, rel=EXACT)
    assert obs["O3"] == pytest.approx(1.0, rel=EXACT)
    assert obs["O4"] == pytest.approx(1 / 3, rel=EXACT)
    assert obs["O5"] == pytest.approx(6 / 11, rel=EXACT)


def test_observability_of_a_jacobian_hand_computed():
    """Unit columns at 60 deg: J^T J = [[1, c], [c, 1]], singular values sqrt(1 +- c), c = 1/2.

    The columns already have unit norm, so the scaling leaves them; the indices follow
    from sigma = sqrt(3/2), sqrt(1/2) by hand.
    """
    c, s = 0.5, math.sqrt(3) / 2
    J = np.array([[1.0, c], [0.0, s], [0.0, 0.0]])
    rep = analyze_jacobian(J, ["a", "b"])
    s1, s2 = math.sqrt(1.5), math.sqrt(0.5)
    assert rep.singular_values == pytest.approx([s1, s2], rel=EXACT)
    assert rep.condition_number == pytest.approx(math.sqrt(3), rel=EXACT)
    assert rep.observability["O1"] == pytest.approx(math.sqrt(s1 * s2) / math.sqrt(3), rel=EXACT)
    assert rep.observability["O2"] == pytest.approx(s2 / s1, rel=EXACT)
    assert rep.observability["O3"] == pytest.approx(s2, rel=EXACT)
    assert rep.observability["O4"] == pytest.approx(s2**2 / s1, rel=EXACT)
    assert rep.observability["O5"] == pytest.approx(1 / (1 / s1 + 1 / s2), rel=EXACT)
    assert rep.full_rank and rep.rank == 2


def test_dependency_coefficients_hand_computed():
    """j3 = 3 j1 - 2 j2 with j1 = e1, j2 = 2 e2, j3 = 3 e1 - 4 e2: p2 depends on p0 (3), p1 (-2).

    Scaled columns e1, e2, (3 e1 - 4 e2)/5: the pivoted QR takes e1, then e2 (residual
    norm 1 > 4/5), so p2 is the dependent one; the coefficients in the parameters' units
    are those of the construction.
    """
    J = np.array([[1.0, 0.0, 3.0], [0.0, 2.0, -4.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    rep = analyze_jacobian(J, ["p0", "p1", "p2"])
    assert rep.rank == 2
    assert rep.identifiable == ("p0", "p1")
    deps = rep.non_identifiable["p2"]["depends_on"]
    assert deps == pytest.approx({"p0": 3.0, "p1": -2.0}, rel=EXACT)
    assert rep.condition_number == math.inf
    assert all(v == 0.0 for v in rep.observability.values())
    assert "p2 (depends on" in rep.describe()


def test_zero_column_is_non_identifiable_without_dependencies():
    """A parameter that does not enter the residuals (zero column): rank 1, no dependencies."""
    J = np.array([[1.0, 0.0], [2.0, 0.0], [0.5, 0.0]])
    rep = analyze_jacobian(J, ["a", "unused"])
    assert rep.rank == 1
    assert rep.non_identifiable == {"unused": {"depends_on": {}}}
    assert "does not affect the residuals" in rep.describe()


def test_standard_deviations_equal_linear_least_squares_formula():
    """std = sqrt(diag(sigma^2 (J^T J)^-1)), sigma^2 = RSS/(m - n): the textbook formula with
    an explicit inverse (independent of the QR route of analyze_jacobian)."""
    rng = np.random.default_rng(3)
    J = rng.standard_normal((50, 3)) * np.array([1.0, 10.0, 0.01])
    r = rng.standard_normal(50)
    rep = analyze_jacobian(J, ["a", "b", "c"], residuals=r)
    sigma2 = r @ r / (50 - 3)
    cov = sigma2 * np.linalg.inv(J.T @ J)
    assert [rep.std[k] for k in "abc"] == pytest.approx(np.sqrt(np.diag(cov)), rel=1e-10)
    assert rep.covariance == pytest.approx(cov, rel=1e-9)


def test_scale_columns_gives_unit_norms():
    """Every non-zero column gets unit norm; the norms are returned (definition)."""
    Js, norms = scale_columns([[3.0, 0.0], [4.0, 0.0]])
    assert norms == pytest.approx([5.0, 0.0])
    assert Js[:, 0] == pytest.approx([0.6, 0.8])
    assert np.all(Js[:, 1] == 0.0)


def test_combined_report_equals_block_diagonal_analysis():
    """Reports of two blocks combined = the analysis of the block-diagonal Jacobian
    (singular values, rank, O1-O5, condition number), computed directly."""
    rng = np.random.default_rng(4)
    A, B = rng.standard_normal((30, 3)), rng.standard_normal((20, 2)) * 5.0
    B = np.column_stack([B, B[:, 0] - B[:, 1]])  # one dependency in block B
    ra, rb = analyze_jacobian(A, ["a0", "a1", "a2"]), analyze_jacobian(B, ["b0", "b1", "b2"])
    J = np.block([[A, np.zeros((30, 3))], [np.zeros((20, 3)), B]])
    direct = analyze_jacobian(J, ["a0", "a1", "a2", "b0", "b1", "b2"])
    comb = combine_reports([ra, rb])
    assert comb.rank == direct.rank == 5 == numerical_rank(J)
    assert comb.singular_values == pytest.approx(direct.singular_values, rel=1e-10, abs=1e-12)
    assert comb.observability == pytest.approx(direct.observability, rel=1e-10, abs=1e-12)
    assert set(comb.non_identifiable) == set(direct.non_identifiable)
    assert comb.condition_number == direct.condition_number == math.inf


# ------------------------------------------------------------------ robot models
def test_ideal_model_rich_data_full_rank(grid):
    """Ideal 15-parameter L1 model on a workspace grid: all parameters identifiable
    (Dressler (2012), ch. 5.1: 3-D positions identify the 15 parameters)."""
    q, T = grid
    ideal = ThreeLinkClosure(load_parameters("L1_ideal"))
    kin = GantryTau3Kinematics(load_parameters("L1_ideal"))
    T = kin.workspace_grid(GRID_STEP)
    rep = analyze_identifiability(ideal, ideal.ik(T), T)
    assert rep.n_parameters == 15
    assert rep.full_rank, rep.describe()
    assert rep.condition_number < 1.0 / RANK_TOLERANCE


def test_modified_model_rich_data_full_rank(l1, grid):
    """Modified 21-parameter model on the grid: full rank (ch. 5.1)."""
    q, T = grid
    rep = analyze_identifiability(l1, q, T)
    assert rep.n_parameters == 21 and rep.full_rank


def test_plate_offset_reported_with_its_dependencies(l1, grid):
    """Plate offset b (3 extra parameters): rank 21 of 24; per axis c one of
    {b_c, As1_c, As2_c, As3_c} is not identifiable and depends on the other three with
    coefficient -1 (column algebra in PlateOffsetClosure's docstring)."""
    q, T = grid
    model = PlateOffsetClosure(l1.kinematics)
    rep = analyze_identifiability(model, q, T)
    assert rep.rank == 21 and rep.n_parameters == 24
    assert len(rep.non_identifiable) == 3
    bad = [c for c in "xyz" if not _plate_axis_ok(rep, c)]
    assert not bad, (bad, rep.describe())  # axes whose dependency family is wrong


def _plate_axis_ok(rep, c):
    """Axis c: exactly one of {b_c, As1_c, As2_c, As3_c} is non-identifiable, depending on the
    other three with coefficient -1."""
    family = {f"b_{c}", f"As1_{c}", f"As2_{c}", f"As3_{c}"}
    nonid = [k for k in rep.non_identifiable if k in family]
    if len(nonid) != 1:
        return False
    deps = rep.non_identifiable[nonid[0]]["depends_on"]
    return set(deps) == family - set(nonid) and list(deps.values()) == pytest.approx(
        [-1.0] * 3, abs=DEPENDENCY_TOL
    )


def test_calibrate_refuses_non_identifiable_request(l1, grid):
    """calibrate() on the plate-offset model: ModelError naming the parameters and their
    dependencies, with the report attached (not a fit)."""
    q, T = grid
    model = PlateOffsetClosure(l1.kinematics)
    with pytest.raises(ModelError, match=r"singular at the start \(rank 21 of 24\); not identifiable: .*depends on") as exc:
        calibrate(model, q, T)
    rep = exc.value.report
    assert len(rep.non_identifiable) == 3
    # fixing the offset makes it solvable (its columns are the dependent ones)
    res = calibrate(model, q, T, fixed=["b_*"])
    assert res.success and res.cost < 1e-20


def test_poses_on_a_line_rank_deficient(l1):
    """Poses on one straight line: per arm the residual |As - T0 + q v - s u|^2 - L^2 depends
    on the parameters only through |As - T0|^2 - L^2, |v|^2, u.(As - T0), v.(As - T0) and
    v.u, so the rank is at most 5 per arm (15 of 21); every missing parameter is reported
    with dependencies."""
    s = np.linspace(-0.3, 0.3, 40)
    T = np.array([-0.6, 3.0, -0.6]) + s[:, None] * np.array([0.6, 0.64, 0.48])
    q = l1.ik(T)
    rep = analyze_identifiability(l1, q, T)
    assert rep.rank <= 15
    assert len(rep.non_identifiable) == 21 - rep.rank
    assert all(info["depends_on"] for info in rep.non_identifiable.values())


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    "J, kwargs, match",
    [
        (np.ones(3), {}, r"J: expected a 2-D Jacobian"),
        (np.array([[1.0, np.nan]]), {}, r"J: non-finite entries in row\(s\) \[0\]"),
        (np.eye(3), {"names": ["a", "b"]}, r"names: expected 3 names"),
        (np.eye(3), {"residuals": np.ones(2)}, r"residuals: expected 3 values"),
        (np.eye(3), {"tolerance": 0.0}, r"tolerance and threshold must be positive"),
        (np.zeros((0, 2)), {}, r"at least one row and one column"),
    ],
    ids=["1-D", "nan", "names", "residuals", "tolerance", "empty"],
)
def test_analyze_jacobian_bad_input(J, kwargs, match):
    with pytest.raises(InputError, match=match):
        analyze_jacobian(J, **kwargs)


@pytest.mark.parametrize(
    "sv, m, match",
    [([], 3, "singular_values"), ([1.0, -1.0], 3, "singular_values"), ([1.0], 0, "n_residuals")],
    ids=["empty", "negative", "rows"],
)
def test_observability_bad_input(sv, m, match):
    with pytest.raises(InputError, match=match):
        observability_indices(sv, m)


def _dependent_jacobian() -> np.ndarray:
    J = np.random.default_rng(5).standard_normal((40, 4)) * [1.0, 1e-3, 10.0, 1.0]
    J[:, 3] = 2.0 * J[:, 0] - 0.5 * J[:, 2]  # column 3 a combination of 0 and 2
    return J


@pytest.mark.parametrize(
    "J", [np.random.default_rng(4).standard_normal((30, 5)) * [1.0, 1e3, 1e-2, 1.0, 5.0], _dependent_jacobian()],
    ids=["full_rank", "rank_deficient"],
)
def test_analyze_qr_equals_analyze_jacobian(J):
    """The report from a pivoted QR computed elsewhere (the calibration's polishing step)
    equals analyze_jacobian's report of the same Jacobian (checked against it: a second
    route through the same factorisation)."""
    r = np.random.default_rng(6).standard_normal(J.shape[0])
    names = [f"x{i}" for i in range(J.shape[1])]
    ref = analyze_jacobian(J, names, residuals=r)
    Js, norms = scale_columns(J)
    R, piv = scipy.linalg.qr(Js, mode="r", pivoting=True)
    rep = analyze_qr(R, piv, norms, J.shape[0], names, rss=float(r @ r))
    assert (rep.rank, rep.identifiable, rep.n_residuals) == (ref.rank, ref.identifiable, ref.n_residuals)
    assert rep.non_identifiable.keys() == ref.non_identifiable.keys()
    np.testing.assert_allclose(rep.singular_values, ref.singular_values, rtol=EXACT)
    np.testing.assert_allclose(list(rep.std.values()), list(ref.std.values()), rtol=EXACT)
    np.testing.assert_allclose(list(rep.observability.values()), list(ref.observability.values()), rtol=EXACT)
