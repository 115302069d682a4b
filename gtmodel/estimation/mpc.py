"""Moved to :mod:`gtmodel.control.mpc`; this path is kept for existing code."""

import gtmodel.control.mpc as _moved
from gtmodel.control.mpc import *  # noqa: F401,F403

__all__ = list(_moved.__all__)
