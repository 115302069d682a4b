"""Moved to :mod:`gtmodel.control.bounds`; this path is kept for existing code."""

import gtmodel.control.bounds as _moved
from gtmodel.control.bounds import *  # noqa: F401,F403

__all__ = list(_moved.__all__)
