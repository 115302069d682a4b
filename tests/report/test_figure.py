"""The one figure helper takes its style from gtmodel.defaults (gtmodel.report._figure)."""

from __future__ import annotations

import pytest
from PIL import Image

from gtmodel import defaults as gd
from gtmodel.errors import InputError
from gtmodel.report._figure import new_figure, panel_size, save


@pytest.fixture(autouse=True)
def _reset():
    yield
    gd.reset_defaults()


@pytest.mark.parametrize("size, expected", [(None, "plot.figsize"), ("plot.wide", "plot.wide"), ((3.0, 2.0), (3.0, 2.0))])
def test_sizes_from_defaults_or_given(size, expected):
    fig, ax = new_figure(size=size)
    want = gd.defaults[expected] if isinstance(expected, str) else expected
    assert tuple(fig.get_size_inches()) == pytest.approx(want)
    assert fig.get_layout_engine() is not None


@pytest.mark.parametrize("dpi", [50, 110])
def test_png_resolution_is_the_default_dpi(tmp_path, dpi):
    gd.defaults["plot.dpi"] = dpi
    fig, _ = new_figure(size=(2.0, 1.0))
    assert save(fig, tmp_path / "f.png") is fig
    assert Image.open(tmp_path / "f.png").size == (2 * dpi, 1 * dpi)


def test_no_file_without_path(tmp_path):
    fig, _ = new_figure()
    assert save(fig, None) is fig and not list(tmp_path.iterdir())


def test_panel_size():
    assert panel_size(3, 2, (1.0, 2.0), extra=0.5) == (3.0, 4.5)
    assert panel_size(2) == (2 * gd.defaults["plot.panel"][0], gd.defaults["plot.panel"][1])


@pytest.mark.parametrize("size", ["figsize", "loop.period", (1.0,), (1.0, -2.0)])
def test_bad_size(size):
    with pytest.raises(InputError, match="size"):
        new_figure(size=size)
