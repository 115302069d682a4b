"""Complementary filter (Dressler (2012), eq. 7.17).

Independent references: the specification (-3 dB at the cut-off), checked by
:func:`scipy.signal.sosfreqz` and by the amplitude of a filtered sine read with a
least-squares fit (a second method); the closed-form discretisation error of the double
integral; lifted matrices against the operator on random signals.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.filters.complementary import THESIS_CUTOFFS_HZ, ComplementaryFilter, forward_backward_design_hz

DT = 0.004
#: The specification: zero-phase magnitude -3 dB at the cut-off within 0.1 dB.
DB_TOLERANCE = 0.1
#: Operations on O(1) signals (a few hundred filter passes of rounding).
ROUNDING = 1e-12


def _fit_amplitude(y: np.ndarray, t: np.ndarray, f: float) -> float:
    basis = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)])
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return float(np.hypot(*coef))


@pytest.mark.parametrize("order", [1, 2, 4])
@pytest.mark.parametrize("cutoff", [0.5, 2.63, 4.50, 40.0, 120.0])
def test_minus_3_db_at_cutoff(cutoff, order):
    """Zero-phase magnitude |H|^2 at the cut-off is -3 dB (checked with scipy.signal.sosfreqz)."""
    f = ComplementaryFilter([cutoff], DT, order)
    db = 20 * np.log10(f.magnitude([cutoff])[0, 0])
    assert abs(db + 3.0103) < DB_TOLERANCE
    assert f.design_hz[0] < 0.5 / DT


@pytest.mark.parametrize("j", [0, 1])
def test_minus_3_db_by_filtering_a_sine(j):
    """Second method: the amplitude of a filtered sine at the cut-off (least-squares fit in the middle of the record)."""
    f = ComplementaryFilter()
    fc = THESIS_CUTOFFS_HZ[j]
    t = np.arange(5000) * DT
    x = np.zeros((t.size, 2))
    x[:, j] = np.sin(2 * np.pi * fc * t)
    y = f.low_pass(x)[1000:-1000, j]
    db = 20 * np.log10(_fit_amplitude(y, t[1000:-1000], fc))
    assert abs(db + 3.0103) < DB_TOLERANCE


def test_design_frequency_closed_form():
    """n = 2: f_d = atan(tan(pi f_c dt) / (sqrt(2) - 1)^(1/4)) / (pi dt) (closed form, about 1.25 f_c)."""
    fd = forward_backward_design_hz(4.5, DT, 2)
    assert fd == pytest.approx(np.arctan(np.tan(np.pi * 4.5 * DT) / (np.sqrt(2) - 1) ** 0.25) / (np.pi * DT), rel=1e-15)
    assert 1.2 < fd / 4.5 < 1.3


def test_low_pass_plus_high_pass_is_identity():
    """LP + HP = identity on a signal (to rounding)."""
    x = np.random.default_rng(1).normal(size=(400, 2))
    f = ComplementaryFilter()
    np.testing.assert_allclose(f.low_pass(x) + f.high_pass(x), x, rtol=0, atol=ROUNDING)


def test_exact_complementarity_on_a_second_difference():
    """z_kin = x and a_m = central second difference of x (x at rest at 0 before the record): z_hat = x to rounding."""
    rng = np.random.default_rng(2)
    x = np.zeros((600, 2))
    x[1:] = np.cumsum(np.cumsum(rng.normal(size=(599, 2)), axis=0), axis=0) * 1e-6
    padded = np.vstack([np.zeros((1, 2)), x, x[-1:]])  # x[-1] = 0; the last acceleration is not used
    a = (padded[2:] - 2 * padded[1:-1] + padded[:-2]) / DT**2
    f = ComplementaryFilter()
    np.testing.assert_allclose(f.double_integral(a), x, rtol=0, atol=ROUNDING * np.abs(x).max())
    np.testing.assert_allclose(f.estimate(x, a), x, rtol=0, atol=ROUNDING * np.abs(x).max())


def test_perfect_estimate_for_consistent_measurements():
    """z_kin = z and a_m = z'' (analytic) of a smooth signal not at rest: z_hat ~ z.

    The tolerance is the closed form of the only error left once the end effects have
    died out (the padding is long enough for that): the double integral inverts the
    central second difference, whose gain at angular frequency w is (2 - 2 cos(w dt)) /
    dt^2 instead of w^2; the relative error 1 - (w dt)^2 / (2 - 2 cos(w dt)) of each sine
    passes through HP = 1 - |H|^2 (checked inside the record, 400 samples from the ends). The
    line z(0) + v(0) t that I(a) misses is removed by HP. Near the ends the odd extension
    continues the sinusoidal error point-symmetrically (|2 e[0] - e[k]| <= 3 max |e|), so
    there the bound is 3 times the closed form.
    """
    t = np.arange(1500) * DT
    comps = [(0.01, 0.7, 0.3), (0.003, 3.0, 1.0)]  # amplitude [m], frequency [Hz], phase
    z = 0.02 * t + sum(A * np.sin(2 * np.pi * fr * t + ph) for A, fr, ph in comps)
    a = sum(-A * (2 * np.pi * fr) ** 2 * np.sin(2 * np.pi * fr * t + ph) for A, fr, ph in comps)
    f = ComplementaryFilter()
    z2, a2 = np.column_stack([z, z]), np.column_stack([a, a])
    residual = np.abs(f.estimate(z2, a2) - z2)
    err, interior = residual.max(axis=0), residual[400:-400].max(axis=0)
    w = np.array([2 * np.pi * fr for _, fr, _ in comps])
    rel = np.abs(1 - (w * DT) ** 2 / (2 - 2 * np.cos(w * DT)))
    amp = np.array([A for A, _, _ in comps])
    bound = ((1 - f.magnitude(w / (2 * np.pi))) * amp * rel).sum(axis=1)
    np.testing.assert_array_less(interior, 1.01 * bound)
    np.testing.assert_array_less(err, 3 * bound)
    assert err.max() < 1e-6  # below the 1 um gauge resolution


@pytest.mark.parametrize("n", [1, 2, 50, 400])
def test_lifted_matrices_equal_the_operator(n):
    """F_kin z_kin + F_acc a_m equals estimate(z_kin, a_m) on random signals (to rounding)."""
    f = ComplementaryFilter()
    rng = np.random.default_rng(n)
    zk, am = rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    f_kin, f_acc = f.lifted(n)
    assert f_kin.shape == f_acc.shape == (2, n, n)
    lifted = np.column_stack([f_kin[j] @ zk[:, j] + f_acc[j] @ am[:, j] for j in range(2)])
    np.testing.assert_allclose(lifted, f.estimate(zk, am), rtol=0, atol=ROUNDING * max(1.0, n * DT**2))


def test_accelerometer_bias_is_removed_inside_the_record():
    """A constant accelerometer bias (a parabola after I) leaves the interior unchanged: HP passes nothing of a
    degree-2 polynomial (|H|^2 = 1 - O(f^4)); near the ends the odd extension does not continue a parabola."""
    n = 1500
    f = ComplementaryFilter()
    bias = np.full((n, 2), 0.01)
    out = f.estimate(np.zeros((n, 2)), bias)
    interior = np.abs(out[400:-400]).max()
    assert interior < 1e-9  # 0.5 b t^2 reaches 0.18 m at the end of the record
    assert 0.5 * 0.01 * (n * DT) ** 2 > 0.1


BAD = [
    (dict(cutoff_hz=[125.0, 2.0]), "cutoff_hz.*entry 0"),
    (dict(cutoff_hz=[4.5, 300.0]), "cutoff_hz.*entry 1.*Nyquist"),
    (dict(cutoff_hz=[0.0]), "cutoff_hz"),
    (dict(cutoff_hz=[-1.0]), "cutoff_hz"),
    (dict(cutoff_hz=[[1.0, 2.0]]), "cutoff_hz.*1-D"),
    (dict(cutoff_hz=[]), "cutoff_hz"),
    (dict(cutoff_hz=[np.nan]), "cutoff_hz"),
    (dict(cutoff_hz="fast"), "cutoff_hz"),
    (dict(dt=0.0), "dt"),
    (dict(dt=-0.004), "dt"),
    (dict(order=0), "order"),
    (dict(order=2.5), "order"),
    (dict(cutoff_hz=[60.0], dt=0.01), "cutoff_hz.*Nyquist"),
]


@pytest.mark.parametrize("kwargs, match", BAD)
def test_bad_construction(kwargs, match):
    with pytest.raises(InputError, match=match):
        ComplementaryFilter(**kwargs)


BAD_SIGNALS = [
    (np.zeros((10, 3)), np.zeros((10, 2)), "z_kin.*shape"),
    (np.zeros(10), np.zeros((10, 2)), "z_kin.*shape"),
    (np.zeros((0, 2)), np.zeros((0, 2)), "z_kin.*N >= 1"),
    (np.zeros((10, 2)), np.zeros((9, 2)), "a_m.*10 samples"),
    (np.zeros((10, 2)), np.zeros((10, 1)), "a_m.*shape"),
    (np.full((10, 2), np.inf), np.zeros((10, 2)), "z_kin.*sample 0, column 0"),
    (np.zeros((10, 2)), [[0.0, 0.0]] * 5 + [[0.0, np.nan]] * 5, "a_m.*sample 5, column 1"),
    ("x", np.zeros((10, 2)), "z_kin"),
]


@pytest.mark.parametrize("z_kin, a_m, match", BAD_SIGNALS)
def test_bad_signals(z_kin, a_m, match):
    with pytest.raises(InputError, match=match):
        ComplementaryFilter().estimate(z_kin, a_m)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda f: f.lifted(0), "n"),
        (lambda f: f.magnitude([200.0]), "f_hz.*Nyquist"),
        (lambda f: f.magnitude([-1.0]), "f_hz"),
        (lambda f: f.low_pass(np.zeros((5, 3))), "x.*shape"),
        (lambda f: forward_backward_design_hz(200.0, DT, 2), "cutoff_hz"),
    ],
)
def test_bad_method_arguments(call, match):
    with pytest.raises(InputError, match=match):
        call(ComplementaryFilter())
