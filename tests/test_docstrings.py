"""Every public function, class and method of gtmodel documents all its parameters.

Reference: numpydoc's validator. Checked codes: PR01 (parameter not documented), PR02
(documented parameter that does not exist), RT01 (no Returns section), GL08 (no
docstring). Public = listed in a module's ``__all__``.
"""

from __future__ import annotations

import enum
import importlib
import inspect
import pkgutil

import numpydoc.validate
import pytest

import gtmodel

CHECKED_CODES = {"PR01", "PR02", "RT01", "GL08"}


def _modules():
    names = [gtmodel.__name__] + [m.name for m in pkgutil.walk_packages(gtmodel.__path__, "gtmodel.")]
    return [importlib.import_module(n) for n in sorted(names)]


def _public_names():
    out = []
    for mod in _modules():
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue  # constants
            if getattr(obj, "__module__", None) != mod.__name__:
                continue  # re-export: checked where it is defined
            out.append(f"{mod.__name__}.{name}")
            if inspect.isclass(obj):
                for attr, val in vars(obj).items():
                    if not attr.startswith("_") and inspect.isfunction(val):
                        out.append(f"{mod.__name__}.{name}.{attr}")
    return out


PUBLIC = _public_names()


def test_there_is_a_public_api():
    assert len(PUBLIC) > 50


def _constructed_by_the_language(qualname: str) -> bool:
    """Enums (built from their values) and Protocols (never instantiated) have no call
    signature of their own to document."""
    module, _, name = qualname.rpartition(".")
    obj = getattr(importlib.import_module(module), name, None) if module in {m.__name__ for m in _modules()} else None
    return inspect.isclass(obj) and (issubclass(obj, enum.Enum) or getattr(obj, "_is_protocol", False))


@pytest.mark.parametrize("qualname", PUBLIC)
def test_numpydoc(qualname):
    codes = CHECKED_CODES - {"PR01"} if _constructed_by_the_language(qualname) else CHECKED_CODES
    errors = [e for e in numpydoc.validate.validate(qualname)["errors"] if e[0] in codes]
    assert not errors, errors
