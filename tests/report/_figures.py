"""Reading plotted data back from a matplotlib Figure (shared by the report tests)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def line(ax, label):
    """The one line of ``ax`` with this legend label."""
    found = [ln for ln in ax.get_lines() if ln.get_label() == label]
    assert len(found) == 1, f"{label!r} among {[ln.get_label() for ln in ax.get_lines()]}"
    return found[0]


def assert_line(ax, label, x, y, rtol=1e-12, atol=0.0):
    """The line ``label`` of ``ax`` draws exactly ``(x, y)``."""
    ln = line(ax, label)
    np.testing.assert_allclose(np.asarray(ln.get_xdata(), float), np.asarray(x, float), rtol=rtol, atol=atol)
    np.testing.assert_allclose(np.asarray(ln.get_ydata(), float), np.asarray(y, float), rtol=rtol, atol=atol)


def bar_heights(ax):
    """Heights of the bars of ``ax``, in drawing order."""
    return np.array([p.get_height() for p in ax.patches])


def assert_png(path):
    """``path`` is a PNG file."""
    assert Path(path).read_bytes()[:8] == PNG_MAGIC
