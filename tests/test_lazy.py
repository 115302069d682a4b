"""gtmodel._lazy: modules and package exports imported on first use."""

from __future__ import annotations

import sys
from types import ModuleType

import pytest

from gtmodel._lazy import lazy_module


@pytest.fixture
def package(tmp_path, monkeypatch):
    """A fresh package ``lazypkg_<n>`` whose ``__init__`` imports its own submodule (as
    ``gtmodel.robots`` and ``scipy.sparse`` do), removed from sys.modules afterwards."""
    name = f"lazypkg_{len(list(tmp_path.parent.iterdir()))}_{tmp_path.name}".replace("-", "_")
    root = tmp_path / name
    root.mkdir()
    (root / "__init__.py").write_text("from .sub import Thing\nLOADS = 1\n")
    (root / "sub.py").write_text("class Thing:\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield name
    for key in [k for k in sys.modules if k == name or k.startswith(name + ".")]:
        del sys.modules[key]


def test_the_module_is_imported_on_first_attribute_use_only(package):
    mod = lazy_module(package)
    assert package not in sys.modules
    assert isinstance(mod, ModuleType)
    assert mod.LOADS == 1
    assert package in sys.modules and mod.Thing is sys.modules[package].Thing


def test_a_submodule_imported_before_first_use_is_executed_once(package):
    """The standard library's LazyLoader registers its half-loaded package: a later
    ``from package.sub import Thing`` then ran sub.py a second time (two Thing classes,
    ``isinstance`` failing: l1_ilc.toml's "expected a GantryTau3Kinematics, got
    GantryTau3Kinematics"). Checked by class identity against the ordinary import."""
    mod = lazy_module(package)
    sub = __import__(f"{package}.sub", fromlist=["Thing"])
    assert mod.Thing is sub.Thing is sys.modules[f"{package}.sub"].Thing


def test_writes_reach_the_module(package, monkeypatch):
    mod = lazy_module(package)
    monkeypatch.setattr(mod, "LOADS", 2)
    assert sys.modules[package].LOADS == 2 and mod.LOADS == 2


def test_an_imported_module_is_returned_as_it_is():
    assert lazy_module("json") is __import__("json")


def test_a_missing_module_is_refused_by_name():
    with pytest.raises(ModuleNotFoundError, match="no_such_module_xyz"):
        lazy_module("no_such_module_xyz")
