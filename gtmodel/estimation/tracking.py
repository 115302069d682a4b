"""Moved to :mod:`gtmodel.control.tracking`; this path is kept for existing code."""

from gtmodel.control.tracking import *  # noqa: F401,F403
from gtmodel.control.tracking import __all__  # noqa: F401
