"""Lazy package exports (PEP 562): a package's public names imported on first use.

The ``gtmodel`` command starts in a fraction of a second because ``gtmodel --help``,
``gtmodel schema --list`` and input errors never import CasADi, SciPy, pandas or
matplotlib. The packages on that path (:mod:`gtmodel.problems`,
:mod:`gtmodel.problems.study`) therefore import their submodules only when one of their
public names is first used; ``from gtmodel.problems import load_problem`` works as before.
"""

from __future__ import annotations

import importlib
from typing import Any, Callable, Mapping

__all__ = ["lazy_exports"]


def lazy_exports(package: str, exports: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of a package with lazy exports.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : Mapping[str, str]
        Public name -> the submodule defining it, relative to ``package`` (e.g.
        ``{"run_problem": "run"}``).

    Returns
    -------
    getattr : callable
        ``__getattr__(name)``: imports the submodule, caches the value in the package.
    dir : callable
        ``__dir__()``: the package's names and the lazy ones.

    Examples
    --------
    >>> __getattr__, __dir__ = lazy_exports(__name__, {"run_problem": "run"})  # doctest: +SKIP
    """
    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(importlib.import_module(package), name, value)
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(importlib.import_module(package)), *exports})

    return __getattr__, __dir__
