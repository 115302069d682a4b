"""Moved to :mod:`gtmodel.control.mpc`; this path is kept for existing code."""

from gtmodel.control.mpc import *  # noqa: F401,F403
from gtmodel.control.mpc import __all__  # noqa: F401
