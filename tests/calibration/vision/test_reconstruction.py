"""Stereo reconstruction: bundle adjustment, TCP covariance, metric scale.

Independent references: the truth of the synthetic images (true cameras, true TCPs); a
linear DLT triangulation (Hartley and Zisserman, ch. 12.2) of every corner in NumPy from the
true projection matrices ``K [R | -R c]`` (distortion-free cameras), whose corner centroid
is the pattern centre; and a Monte-Carlo study of the pixel noise for the covariance.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.vision import bundle_adjust, reconstruct, scale_from_carts, synthetic_stereo_images
from gtmodel.errors import InputError

from . import _rig

#: Noise-free images: TCP [m] and camera orientation [rad, m] to this.
EXACT_TOL = 1e-9
#: Acceptable 1-sigma coverage over a Monte-Carlo study (nominal 0.683).
COVERAGE = (0.6, 0.76)


def _truth_in_camera_1(cams, T_world):
    return (T_world - cams[0].position) @ cams[0].R.T


def _relative(cams):
    R21 = cams[1].R @ cams[0].R.T
    return R21, cams[1].R @ (cams[0].position - cams[1].position)


def _rotation_angle(R):
    return float(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))


@pytest.fixture(scope="module")
def exact():
    cams = _rig.cameras()
    syn = synthetic_stereo_images(_rig.model(), _rig.poses(), cams, _rig.pattern(), pixel_sigma=0.0)
    rec = reconstruct(syn.images, cams, _rig.pattern(), pixel_sigma=0.3, transmission=_rig.transmission())
    return cams, syn, rec


def test_noise_free_images_give_the_tcp_and_the_camera_orientation(exact):
    cams, syn, rec = exact
    assert rec.success and syn.images.n_poses >= 20
    T_true = _truth_in_camera_1(cams, syn.T[syn.rows])
    assert np.abs(rec.T_metric - T_true).max() < EXACT_TOL
    R21, t21 = _relative(cams)
    # the sin of the angle: arccos loses half the digits near 0
    assert np.linalg.norm(rec.R21 @ R21.T - np.eye(3)) < EXACT_TOL
    assert np.abs(rec.scale * rec.t21 - t21).max() < EXACT_TOL
    assert abs(rec.scale - 1.0) < EXACT_TOL  # the pattern's declared size is its true size here


def _dlt(P1, P2, uv1, uv2):
    A = np.stack([uv1[0] * P1[2] - P1[0], uv1[1] * P1[2] - P1[1], uv2[0] * P2[2] - P2[0], uv2[1] * P2[2] - P2[1]])
    X = np.linalg.svd(A)[2][-1]
    return X[:3] / X[3]


def _projection_matrix(cam):
    K = np.array([[cam.fx, 0, cam.cx], [0, cam.fy, cam.cy], [0, 0, 1]])
    return K @ np.column_stack([cam.R, -cam.R @ cam.position])


@pytest.mark.parametrize("sigma", [0.0, 0.3])
def test_tcp_agrees_with_a_linear_dlt_triangulation(sigma):
    cams = _rig.cameras(distorted=False)
    syn = synthetic_stereo_images(_rig.model(), _rig.poses(), cams, _rig.pattern(), pixel_sigma=sigma, seed=3)
    rec = reconstruct(syn.images, cams, _rig.pattern(), pixel_sigma=max(sigma, 0.1), transmission=_rig.transmission())
    P1, P2 = _projection_matrix(cams[0]), _projection_matrix(cams[1])
    uv = syn.images.uv
    dlt = np.array([np.mean([_dlt(P1, P2, uv[k, 0, j], uv[k, 1, j]) for j in range(uv.shape[2])], axis=0) for k in range(uv.shape[0])])
    T_ba = rec.T_metric @ cams[0].R + cams[0].position  # camera-1 frame -> world
    if sigma == 0.0:
        assert np.abs(T_ba - dlt).max() < EXACT_TOL
    else:  # two estimators of the same point: within a few of the bundle adjustment's sigmas (DLT is worse)
        z = (T_ba - dlt) @ cams[0].R.T / rec.sigma_T_metric
        assert np.sqrt(np.mean(z ** 2)) < 3.0


def _coverage(seeds):
    cams = _rig.cameras()
    hits = []
    for seed in seeds:
        syn = synthetic_stereo_images(_rig.model(), _rig.poses(), cams, _rig.pattern(), pixel_sigma=0.4, seed=seed)
        rec = bundle_adjust(syn.images, cams, _rig.pattern(), pixel_sigma=0.4)
        err = rec.T - _truth_in_camera_1(cams, syn.T[syn.rows])
        hits.append(np.abs(err) <= np.sqrt(np.einsum("nii->ni", rec.cov_T)))
    return float(np.mean(hits))


def test_covariance_is_honest_on_a_few_noise_draws():
    """3 draws (about 330 coordinates): the binomial sd of the coverage is 0.026, so +-4 sd about 0.683."""
    c = _coverage(range(3))
    assert 0.683 - 0.1 <= c <= 0.683 + 0.1, c


@pytest.mark.slow
def test_covariance_is_honest_monte_carlo():
    """1-sigma coverage of the predicted TCP covariance over 40 noise draws (nominal 0.683)."""
    c = _coverage(range(100, 140))
    assert COVERAGE[0] <= c <= COVERAGE[1], c


def test_start_values_are_not_the_answer_with_noise(exact):
    """The bundle adjustment moves away from the homography start (it iterates)."""
    cams, _, _ = exact
    syn = synthetic_stereo_images(_rig.model(), _rig.poses(), cams, _rig.pattern(), pixel_sigma=0.5, seed=7)
    rec = bundle_adjust(syn.images, cams, _rig.pattern(), pixel_sigma=0.5)
    assert rec.success and rec.iterations >= 2 and 0.3 < rec.rms_px < 0.7


def test_scale_from_cart_displacements():
    q = np.array([[0, 0, 0], [0.1, 0.1, 0.1], [0.3, 0.3, 0.3], [0.2, 0.0, 0.1]])
    T = 2.0 * np.array([[0, 0, 0], [0.1, 0, 0], [0.3, 0, 0], [5, 5, 5]])
    lam, pairs, spread = scale_from_carts(q, T)
    assert lam == pytest.approx(0.5, rel=1e-14) and pairs == 3 and spread < 1e-15


@pytest.mark.parametrize("call, match", [
    (lambda im, c, p: bundle_adjust(im, c, p, pixel_sigma=0.0), r"pixel_sigma: expected a positive"),
    (lambda im, c, p: bundle_adjust(im, c, p, pixel_sigma=float("nan")), r"pixel_sigma: expected a positive"),
    (lambda im, c, p: bundle_adjust(im.subset([0]), c, p), r"at least 2 poses"),
    (lambda im, c, p: bundle_adjust(im, c[:1], p), r"cameras: expected 2 cameras"),
    (lambda im, c, p: bundle_adjust(im, c, type(p)(p.corners[:8])), r"20 corners per pose, the pattern has 8"),
    (lambda im, c, p: reconstruct(im, c, p, scale=-1.0), r"scale: expected a positive number"),
    (lambda im, c, p: scale_from_carts(np.eye(3), np.eye(3)), r"no two poses whose carts all moved"),
    (lambda im, c, p: scale_from_carts(im.q, im.q, transmission=0.0), r"transmission: expected a positive"),
])
def test_bad_reconstruction_input(exact, call, match):
    cams, syn, _ = exact
    with pytest.raises(InputError, match=match):
        call(syn.images, cams, _rig.pattern())
