"""Moved to :mod:`gtmodel.control.reference`; this path is kept for existing code."""

from gtmodel.control.reference import *  # noqa: F401,F403
from gtmodel.control.reference import __all__  # noqa: F401
