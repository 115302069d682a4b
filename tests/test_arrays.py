"""The scalar check of gtmodel._arrays (``finite_float``): every refusal names the argument, the unit and the value."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel._arrays import finite_float
from gtmodel.errors import InputError


@pytest.mark.parametrize("value, kwargs, match", [
    (True, {}, r"k: expected a finite value \[N/m\], got True"),
    ("1", {}, r"k: expected a finite value \[N/m\], got '1'"),
    (float("nan"), {}, r"k: expected a finite value"),
    (0.0, {"positive": True}, r"k: expected a finite positive value \[N/m\], got 0.0"),
    (-1, {"nonnegative": True}, r"k: expected a finite non-negative value \[N/m\], got -1"),
])
def test_finite_float_refuses(value, kwargs, match):
    with pytest.raises(InputError, match=match):
        finite_float(value, "k", "N/m", **kwargs)


@pytest.mark.parametrize("value, kwargs", [(0, {"nonnegative": True}), (np.float32(2.5), {"positive": True}), (-3, {})])
def test_finite_float_accepts(value, kwargs):
    assert finite_float(value, "k", **kwargs) == float(value)
