"""Moved to :mod:`gtmodel.control.mpc_fatrop`; this path is kept for existing code."""

import gtmodel.control.mpc_fatrop as _moved
from gtmodel.control.mpc_fatrop import *  # noqa: F401,F403

__all__ = list(_moved.__all__)
