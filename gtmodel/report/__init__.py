"""Reporting layer: plots and tables over models and results (matplotlib lives here).

One module per topic (``trajectory``, ``calibration``, ``structural``, ``stiffness``,
...). The domain packages (``robots``, ``calibration``, ``trajectory``, ...) never draw;
the problem layer and notebooks call these functions. Every plot function draws a new
figure through the one helper :mod:`gtmodel.report._figure` (size, resolution and layout
from :mod:`gtmodel.defaults`), writes it to the PNG file it is given and returns the
:class:`matplotlib.figure.Figure`, so a test or a notebook can read the plotted data back.
No global pyplot state is touched: safe under the ``Agg`` backend and headless.

:mod:`~gtmodel.report.result_page` is the one HTML page: ``report.html`` of a result
folder, its figures drawn by Plotly (inlined) in the browser from the folder's tables.
"""
