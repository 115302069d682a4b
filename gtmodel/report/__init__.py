"""Reporting layer: plots and tables over models and results (matplotlib lives here).

One module per topic (``trajectory``, ``calibration``, ``structural``, ``stiffness``,
...). The domain packages (``robots``, ``calibration``, ``trajectory``, ...) never draw;
the problem layer and notebooks call these functions. Every function writes into the
axes or file it is given and touches no global pyplot state, so it is safe under the
``Agg`` backend and headless.
"""
