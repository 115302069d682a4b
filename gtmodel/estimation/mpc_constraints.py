"""Moved to :mod:`gtmodel.control.mpc_constraints`; this path is kept for existing code."""

from gtmodel.control.mpc_constraints import *  # noqa: F401,F403
from gtmodel.control.mpc_constraints import __all__  # noqa: F401
