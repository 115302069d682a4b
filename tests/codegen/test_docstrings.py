"""Every public function/class/method of gtmodel.codegen documents all its parameters.

Reference: numpydoc's validator (codes PR01 undocumented, PR02 unknown parameter,
RT01 missing Returns section, GL08 no docstring).
"""

from __future__ import annotations

import importlib
import inspect

import pytest

numpydoc_validate = pytest.importorskip("numpydoc.validate")

# the package re-exports functions named like their modules, so import the modules by path
MODULES = [importlib.import_module(f"gtmodel.codegen.{m}") for m in ("generate", "build", "check", "specs")]

CHECKED_CODES = {"PR01", "PR02", "RT01", "GL08"}


def _public_names():
    names = []
    for mod in MODULES:
        for name in mod.__all__:
            obj = getattr(mod, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue  # constants
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
