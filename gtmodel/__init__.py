"""gtmodel: modelling, calibration and optimal control of Gantry-Tau parallel robots on CasADi."""

from __future__ import annotations

import sys as _sys

_argv0 = (getattr(_sys, "argv", None) or [""])[0]
if _argv0 == "-m" or _argv0.replace("\\", "/").rsplit("/", 1)[-1] == "gtmodel":
    # the ``gtmodel`` command (``python -m gtmodel``, the console script): SIGINT and
    # SIGTERM are counted from here on, before anything else is imported (gtmodel/__main__.py)
    from gtmodel import _signals

    _signals.install()

import logging

from gtmodel.errors import GtModelError

__version__ = "0.1.0"
__all__ = ["GtModelError", "__version__"]

logging.getLogger("gtmodel").addHandler(logging.NullHandler())
