"""The maintainer tools find the checkout from the current folder, not from the module's location
(which is site-packages for an installed package: issue 44, installed = tested)."""

from __future__ import annotations

import pytest

from gtmodel._repository import checkout
from gtmodel.errors import InputError

from .conftest import REPO


@pytest.mark.parametrize("sub", [".", "docs", "tests/report"])
def test_the_checkout_is_found_from_any_folder_in_it(monkeypatch, sub):
    monkeypatch.delenv("GTMODEL_REPOSITORY", raising=False)
    monkeypatch.chdir(REPO / sub)
    assert checkout() == REPO.resolve()


def test_outside_a_checkout_the_current_folder_is_named(monkeypatch, tmp_path):
    monkeypatch.delenv("GTMODEL_REPOSITORY", raising=False)
    monkeypatch.chdir(tmp_path)
    assert checkout() == tmp_path.resolve()


def test_the_environment_names_the_checkout(monkeypatch, tmp_path):
    monkeypatch.setenv("GTMODEL_REPOSITORY", str(tmp_path))
    assert checkout() == tmp_path.resolve()


def test_the_fidelity_report_outside_a_checkout_says_so(monkeypatch, tmp_path):
    from gtmodel.report import fidelity

    monkeypatch.setattr(fidelity, "FIGURES", tmp_path / "docs" / "fidelity_figures.json")
    with pytest.raises(InputError, match="fidelity_figures.json: not found; the fidelity report works on a gtmodel checkout"):
        fidelity.load()
