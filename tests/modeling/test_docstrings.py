"""Every public function/method of gtmodel.modeling documents all its parameters.

Reference: numpydoc's validator (codes PR01 undocumented, PR02 unknown parameter,
RT01 missing Returns section).
"""

from __future__ import annotations

import inspect

import pytest

numpydoc_validate = pytest.importorskip("numpydoc.validate")

from gtmodel.modeling import collocation, model, optimization, result  # noqa: E402

CHECKED_CODES = {"PR01", "PR02", "RT01", "GL08"}


def _public_names():
    names = []
    for mod in (model, optimization, collocation, result):
        for name in mod.__all__:
            obj = getattr(mod, name)
            names.append(f"{mod.__name__}.{name}")
            if inspect.isclass(obj):
                for attr, val in vars(obj).items():
                    if not attr.startswith("_") and inspect.isfunction(val):
                        names.append(f"{mod.__name__}.{name}.{attr}")
    return names


@pytest.mark.parametrize("qualname", _public_names())
def test_numpydoc(qualname):
    errors = [e for e in numpydoc_validate.validate(qualname)["errors"] if e[0] in CHECKED_CODES]
    assert not errors, errors
