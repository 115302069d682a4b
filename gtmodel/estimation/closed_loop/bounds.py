"""Moved to :mod:`gtmodel.control.bounds`; this path is kept for existing code."""

from gtmodel.control.bounds import *  # noqa: F401,F403
from gtmodel.control.bounds import __all__  # noqa: F401
