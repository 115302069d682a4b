"""Moved to :mod:`gtmodel.control.mpc_fatrop`; this path is kept for existing code."""

from gtmodel.control.mpc_fatrop import *  # noqa: F401,F403
from gtmodel.control.mpc_fatrop import __all__  # noqa: F401
