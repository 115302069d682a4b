"""The study analyses under their former path: :mod:`gtmodel.problems.study.analyses`.

Kept because the documentation names ``gtmodel.problems.analyses.ANALYSES``.
"""

from gtmodel.problems.study.analyses import ANALYSES

__all__ = ["ANALYSES"]
