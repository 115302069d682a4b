"""Moved to :mod:`gtmodel.control.reference`; this path is kept for existing code."""

import gtmodel.control.reference as _moved
from gtmodel.control.reference import *  # noqa: F401,F403

__all__ = list(_moved.__all__)
