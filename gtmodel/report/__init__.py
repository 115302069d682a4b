"""Reporting layer: plots and tables over models and results (matplotlib lives here).

One module per topic (``trajectory``, ``calibration``, ``structural``, ``stiffness``,
...). The domain packages (``robots``, ``calibration``, ``modeling``, ...) never draw,
nor import this layer; the problem layer and notebooks call these functions. Every plot
function draws a new figure through the one helper :mod:`gtmodel.report._figure` (size,
resolution and layout from :mod:`gtmodel.defaults`), writes it to the PNG file it is given
and returns the :class:`matplotlib.figure.Figure`, so a test or a notebook can read the
plotted data back. No global pyplot state is touched: safe under the ``Agg`` backend and
headless.

The notebook entry points, importable from here (each module loads on first use):

- :func:`plot_result` (:func:`gtmodel.report.model_trajectory.plot_result`): variables of an
  :class:`~gtmodel.modeling.OptimizationResult` against time, with their bounds;
- :func:`bode_plot` and :func:`step_plot` (:func:`gtmodel.report.linear.plot_bode`,
  :func:`~gtmodel.report.linear.plot_step`): a :class:`~gtmodel.modeling.simulation.linear.Linearization`
  (or a python-control system) through python-control.

:mod:`~gtmodel.report.result_page` is the one HTML page: ``report.html`` of a result
folder, its figures drawn in the browser by Plotly's basic bundle (vendored, inlined) from
the folder's tables.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["plot_result", "bode_plot", "step_plot"]

#: Public name -> (module, function) of the notebook entry points, loaded on first use (matplotlib, python-control).
_ENTRY_POINTS = {"plot_result": ("gtmodel.report.model_trajectory", "plot_result"),
                 "bode_plot": ("gtmodel.report.linear", "plot_bode"),
                 "step_plot": ("gtmodel.report.linear", "plot_step")}


def __getattr__(name: str) -> Any:
    if name in _ENTRY_POINTS:
        module, attr = _ENTRY_POINTS[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'gtmodel.report' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_ENTRY_POINTS])
