"""gtmodel: modelling, calibration and optimal control of Gantry-Tau parallel robots on CasADi."""

from __future__ import annotations

import logging

from gtmodel.errors import GtModelError

__version__ = "0.1.0"
__all__ = ["GtModelError", "__version__"]

logging.getLogger("gtmodel").addHandler(logging.NullHandler())
