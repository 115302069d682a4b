"""The module paths README, docs/ and the notebooks show stay importable after the move into rooms."""

from __future__ import annotations

import importlib

import pytest

import gtmodel.modeling

#: (module path the docs name, names imported from it there, the module it now is).
DOC_PATHS = [
    ("gtmodel.modeling.linear", ["linearize", "Linearization"], "gtmodel.modeling.simulation.linear"),
    ("gtmodel.modeling.expressions", ["parse_expression", "parse_objective", "parse_constraint"], "gtmodel.modeling.ocp.expressions"),
    ("gtmodel.modeling.collocation", ["solve", "CollocationTranscription"], "gtmodel.modeling.ocp.collocation"),
    ("gtmodel.modeling.discontinuities", ["sign_modes"], "gtmodel.modeling.structure.discontinuities"),
    ("gtmodel.modeling.structure", ["scalarize", "eliminate_aliases", "check_structure"], "gtmodel.modeling.structure"),
    ("gtmodel.modeling.library.drive", ["CompliantDriveAxis"], "gtmodel.modeling.library.drive"),
    ("gtmodel.modeling.library.friction", ["MassWithStopAndFriction"], "gtmodel.modeling.library.friction"),
]


@pytest.mark.parametrize(("path", "names", "module"), DOC_PATHS, ids=[p for p, _, _ in DOC_PATHS])
def test_doc_path_is_importable_and_is_the_room_module(path, names, module):
    mod = importlib.import_module(path)
    assert mod is importlib.import_module(module)
    assert [n for n in names if not hasattr(mod, n)] == []


def test_package_exports_resolve():
    assert [n for n in gtmodel.modeling.__all__ if not hasattr(gtmodel.modeling, n)] == []
