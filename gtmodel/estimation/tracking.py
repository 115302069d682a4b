"""Moved to :mod:`gtmodel.control.tracking`; this path is kept for existing code."""

import gtmodel.control.tracking as _moved
from gtmodel.control.tracking import *  # noqa: F401,F403

__all__ = list(_moved.__all__)
