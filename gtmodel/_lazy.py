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


class _LazyModule(ModuleType):
    """Stands for a module not yet imported; imports it (the ordinary way) on first attribute use.

    Not registered in :data:`sys.modules`, so the import system never sees a half-loaded
    package: the standard library's :class:`importlib.util.LazyLoader` registers its module
    and, for a package whose ``__init__`` imports its own submodules (``gtmodel.robots``,
    ``scipy.sparse``), a later ``import package.submodule`` then executes that submodule
    twice (two copies of its classes: ``isinstance`` fails).
    """

    def __init__(self, name: str) -> None:
        super().__init__(name)
        object.__setattr__(self, "_lazy_target", None)

    def _lazy_load(self) -> ModuleType:
        target = object.__getattribute__(self, "_lazy_target")
        if target is None:
            target = importlib.import_module(object.__getattribute__(self, "__name__"))
            object.__setattr__(self, "_lazy_target", target)
        return target

    def __getattr__(self, attr: str) -> Any:  # only for names not on the stand-in itself
        return getattr(self._lazy_load(), attr)

    def __setattr__(self, attr: str, value: Any) -> None:  # e.g. a test's monkeypatch
        setattr(self._lazy_load(), attr, value)

    def __delattr__(self, attr: str) -> None:
        delattr(self._lazy_load(), attr)

    def __dir__(self) -> list[str]:
        return dir(self._lazy_load())


def lazy_module(name: str) -> ModuleType:
    """A module that is imported when one of its attributes is first used.

    python-control, for one, imports matplotlib.pyplot and SciPy's signal and stats
    packages (~2 s of CPU), which a model that never builds a transfer function should not
    pay for; SciPy's sparse matrices (~1 s with their array-API layer) likewise for a
    problem that never checks a model's structure. A module already imported is returned
    as it is; otherwise a stand-in that imports the module the ordinary way
    (:func:`importlib.import_module`) on its first attribute use and forwards every
    attribute to it (reads, and writes such as a test's monkeypatch).

    Parameters
    ----------
    name : str
        The module's absolute name, e.g. ``"control"``.

    Returns
    -------
    module
        The module, or its stand-in until first use.

    Raises
    ------
    ModuleNotFoundError
        No module of that name is installed (for a submodule of a package not yet imported:
        no such package; the submodule itself is then looked for on first use).
    """
    module = sys.modules.get(name)
    if module is not None:
        return module
    top = name.partition(".")[0]
    # finding a submodule imports its package (SciPy's: ~0.01 CPU-s), so a submodule of a package not yet
    # imported is looked for on first use, its package now (without importing it)
    spec = importlib.util.find_spec(top if top != name and top not in sys.modules else name)
    if spec is None or spec.loader is None:
        raise ModuleNotFoundError(f"No module named {name!r}", name=name)
    return _LazyModule(name)


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
