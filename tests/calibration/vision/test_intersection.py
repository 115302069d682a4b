"""TCP by intersection of the rays (the pattern's shape unused) against the truth and the bundle adjustment.

Independent references: the synthetic truth, and the bundle adjustment's TCP (which uses the
pattern's shape); a second intersection from the linear DLT start alone (noise free).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.vision import bundle_adjust, intersect, intersect_tcp, synthetic_stereo_images
from gtmodel.errors import InputError

from . import _rig


@pytest.mark.parametrize("sigma", [0.0, 0.4])
def test_intersection_tcp(sigma):
    cams = _rig.cameras()
    syn = synthetic_stereo_images(_rig.model(), _rig.poses(), cams, _rig.pattern(), pixel_sigma=sigma, seed=2)
    rec = bundle_adjust(syn.images, cams, _rig.pattern(), pixel_sigma=max(sigma, 0.1))
    T, cov = intersect_tcp(syn.images, cams, _rig.pattern(), rec.R21, rec.t21, max(sigma, 0.1))
    T_true = (syn.T[syn.rows] - cams[0].position) @ cams[0].R.T
    if sigma == 0.0:
        assert np.abs(T - T_true).max() < 1e-9
    else:  # two estimates of one TCP: their difference within the combined predicted sigmas
        z = (T - rec.T) / np.sqrt(np.einsum("nii->ni", cov + rec.cov_T))
        assert np.sqrt(np.mean(z ** 2)) < 1.5


def test_tcp_away_from_the_centroid_needs_the_pattern_orientation():
    cams = _rig.cameras()
    syn = synthetic_stereo_images(_rig.model(), _rig.poses()[:6], cams, _rig.pattern())
    with pytest.raises(InputError, match=r"give R_pattern"):
        intersect_tcp(syn.images, cams, _rig.pattern(), np.eye(3), [1.0, 0, 0], 0.3, tcp_in_pattern=[0, 0, 0.05])


@pytest.mark.parametrize("args, match", [
    ((np.zeros((3, 2)), np.zeros((2, 2))), r"expected uv1 and uv2 of one shape"),
    ((np.zeros((3, 2)), np.zeros((3, 2)), 0.0), r"pixel_sigma: expected a positive"),
])
def test_bad_intersection_input(args, match):
    uv1, uv2, *rest = args
    with pytest.raises(InputError, match=match):
        intersect(uv1, uv2, _rig.cameras(), np.eye(3), [1.0, 0, 0], rest[0] if rest else 0.3)
