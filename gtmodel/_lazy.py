"""Lazy package exports (PEP 562): a package's public names imported on first use.

The ``gtmodel`` command starts in a fraction of a second because ``gtmodel --help``,
``gtmodel schema --list`` and input errors never import CasADi, SciPy, pandas or
matplotlib. The packages on that path (:mod:`gtmodel.problems`,
:mod:`gtmodel.problems.study`) therefore import their submodules only when one of their
public names is first used; ``from gtmodel.problems import load_problem`` works as before.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from types import ModuleType
from typing import Any, Callable, Mapping

__all__ = ["lazy_exports", "lazy_module"]


def lazy_module(name: str) -> ModuleType:
    """A module that is imported when one of its attributes is first used.

    The standard library's :class:`importlib.util.LazyLoader` (the recipe of the
    :mod:`importlib` documentation): python-control, for one, imports matplotlib.pyplot and
    SciPy's signal and stats packages (~2 s of CPU), which a model that never builds a
    transfer function should not pay for. A module already imported is returned as it is.

    Parameters
    ----------
    name : str
        The module's absolute name, e.g. ``"control"``.

    Returns
    -------
    module
        The module (registered in :data:`sys.modules`), loaded on first attribute access.

    Raises
    ------
    ModuleNotFoundError
        No module of that name is installed.
    """
    module = sys.modules.get(name)
    if module is not None:
        return module
    spec = importlib.util.find_spec(name)
    if spec is None or spec.loader is None:
        raise ModuleNotFoundError(f"No module named {name!r}", name=name)
    loader = importlib.util.LazyLoader(spec.loader)
    spec.loader = loader
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    parent, _, child = name.rpartition(".")
    if parent:  # as the import system does: ``import a.b`` then ``a.b`` finds it
        setattr(sys.modules[parent], child, module)
    loader.exec_module(module)
    return module


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
