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

from gtmodel._blas import limit_casadi_blas as _limit_casadi_blas
from gtmodel.errors import GtModelError

__version__ = "0.1.0"
__all__ = ["GtModelError", "__version__"]

logging.getLogger("gtmodel").addHandler(logging.NullHandler())
# CasADi's own OpenBLAS (under IPOPT's MUMPS) to one thread unless OPENBLAS_NUM_THREADS & co.
# say otherwise: its threads only spin on gtmodel's sparse NLPs (gtmodel/_blas.py)
_limit_casadi_blas()
