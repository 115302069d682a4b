"""A user's own model class, imported from a Python file named in a problem file or on the command line.

The protocol (``[model] file = "models/cart_pendulum.py"``, ``class = "CartPendulum"``,
or ``gtmodel codegen --model models/cart_pendulum.py:CartPendulum``):

* the file is the user's own Python code: it is imported as a module from its path
  (:mod:`importlib`), so it may import gtmodel and anything installed; it runs with the
  rights of the user, like any script they run. (The objective and constraints of a
  problem file are different: they are parsed, never evaluated.)
* ``CLASS`` must be a class defined (or imported) at the top level of the file;
  ``CLASS()`` is called without arguments;
* the instance must be a :class:`gtmodel.modeling.Model` (e.g. a subclass that declares
  its variables and equations in ``__init__``), or have a method ``build()`` or
  ``to_model()`` (a component of :mod:`gtmodel.modeling`) returning one;
* the model is reduced as :meth:`~gtmodel.modeling.Model.simulate` reduces it: a model
  that :meth:`~gtmodel.modeling.Model.flatten` refuses (alias equations between states,
  higher index: a motor, a gear and a load composed from library components) goes through
  :func:`~gtmodel.modeling.structural_simplify`; the states it chose are logged (and the
  problem's summary names them); every variable of the user's model keeps its name (a
  state, an algebraic variable, or an output for an eliminated alias);
* its parameters have default values, which a problem file may override by name.

A Modelica or Optimica source file (:data:`MODELICA_SUFFIXES`: ``models/drive.mo:Drive``,
``problems/optimica/double_integrator_min_time.mop:DoubleIntegrator.MinTime``) is read, not
run: a ``.mo`` class through :func:`gtmodel.exchange.modelica.load_modelica`, a ``.mop`` file's
``optimization`` class through :func:`gtmodel.exchange.optimica.load_optimica` (its model, the
Optimica parts left out); so ``gtmodel codegen model FILE.mo:CLASS`` and the tracking
controller of an ``optimica`` result folder reach a model that came from Modelica source.

Every failure (missing file, syntax error, an exception while importing or
instantiating, class not defined, not a Model, a model that does not flatten) is one
:class:`~gtmodel.errors.ModelError` whose message starts with the file path.
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import logging
import sys
from pathlib import Path
from typing import Any

from gtmodel.errors import GtModelError, ModelError
from gtmodel.modeling import Model, structural_simplify

__all__ = ["load_user_model", "reduced_model", "split_model_reference", "ModelFileError", "BUILD_METHODS", "MODELICA_SUFFIXES"]

_log = logging.getLogger("gtmodel")

#: Methods tried, in this order, on an instance that is not itself a Model.
BUILD_METHODS = ("build", "to_model")
#: Endings of the model files read as Modelica (``.mo``) or Optimica (``.mop``) source, not imported as Python.
MODELICA_SUFFIXES = (".mo", ".mop")


class ModelFileError(ModelError):
    """The model file itself failed: missing, not importable, a syntax error, an exception on import."""


def _import(path: Path) -> Any:
    """Import ``path`` as a fresh module; errors name the file (and the line of a syntax error)."""
    name = "gtmodel_user_" + hashlib.sha256(str(path).encode()).hexdigest()[:12]
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ModelFileError(f"{path}: cannot be imported as a Python module (expected a .py file)")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and typing look the module up while it runs
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        sys.modules.pop(name, None)
        raise ModelFileError(f"{path}: syntax error at line {exc.lineno}: {exc.msg}") from None
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - the user's code: any failure is bad input
        sys.modules.pop(name, None)
        raise ModelFileError(f"{path}: importing it raised {type(exc).__name__}: {exc}") from None
    return module


def load_user_model(path: str | Path, class_name: str, reduce: bool = True) -> Model:
    """Import a model file and build the model of one of its classes.

    Parameters
    ----------
    path : str or pathlib.Path
        The Python file (absolute or relative to the working directory), or a Modelica
        ``.mo`` / Optimica ``.mop`` file (:data:`MODELICA_SUFFIXES`).
    class_name : str
        Name of a class at the top level of the file (see the module docstring for the
        protocol); of a Modelica file, the dotted class name (of a ``.mop`` file, an
        ``optimization`` class).
    reduce : bool, optional
        Reduce a model that does not flatten (:func:`reduced_model`; default). False: the
        model as written, unchecked (for :class:`~gtmodel.modeling.Optimization`, which
        reduces it itself and keeps the model as written).

    Returns
    -------
    Model
        The model, reduced to index 1 by :func:`~gtmodel.modeling.structural_simplify` if
        :meth:`~gtmodel.modeling.Model.flatten` refuses it as written (checked to flatten).

    Raises
    ------
    ModelFileError
        The file is missing or cannot be imported (syntax error, exception).
    ModelError
        It defines no class ``class_name``, the instance is not (and builds no) Model, or the model
        does not flatten; the message starts with the file path and names the class.
    """
    p = Path(path)
    try:
        found = p.is_file()
    except (OSError, ValueError):
        found = False
    if not found:
        raise ModelFileError(f"{p}: no such model file")
    if p.suffix.lower() in MODELICA_SUFFIXES:
        model = _modelica_model(p, class_name)
        try:
            return reduced_model(model) if reduce else model
        except GtModelError as exc:
            raise ModelError(f"{p}: class {class_name}: {exc}") from None
    if not isinstance(class_name, str) or not class_name.isidentifier():
        raise ModelError(f"{p}: class name must be a Python identifier, got {class_name!r}")
    module = _import(p)
    cls = getattr(module, class_name, None)
    if not inspect.isclass(cls):
        classes = sorted(n for n, v in vars(module).items() if inspect.isclass(v) and not n.startswith("_"))
        what = "defines no class" if cls is None else f"has {class_name!r}, but it is a {type(cls).__name__}, not a class;"
        raise ModelError(f"{p}: {what} {class_name!r} (classes in the file: {', '.join(classes) or 'none'})")
    try:
        obj = cls()
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - the user's code
        raise ModelError(f"{p}: {class_name}() raised {type(exc).__name__}: {exc}") from None
    model = obj
    if not isinstance(model, Model):
        method = next((m for m in BUILD_METHODS if callable(getattr(obj, m, None))), None)
        if method is None:
            raise ModelError(
                f"{p}: {class_name}() is a {type(obj).__name__}, not a gtmodel.modeling.Model, and has no "
                f"{' or '.join(m + '()' for m in BUILD_METHODS)} method returning one"
            )
        try:
            model = getattr(obj, method)()
        except GtModelError as exc:
            raise ModelError(f"{p}: {class_name}().{method}(): {exc}") from None
        except Exception as exc:  # noqa: BLE001 - the user's code
            raise ModelError(f"{p}: {class_name}().{method}() raised {type(exc).__name__}: {exc}") from None
        if not isinstance(model, Model):
            raise ModelError(f"{p}: {class_name}().{method}() returned a {type(model).__name__}, not a gtmodel.modeling.Model")
    try:
        model = reduced_model(model) if reduce else model
    except GtModelError as exc:
        raise ModelError(f"{p}: class {class_name}: {exc}") from None
    _log.debug("loaded model %r from %s:%s", model.name, p, class_name)
    return model


def _modelica_model(path: Path, class_name: str) -> Model:
    """The model of a Modelica class (``.mo``) or of an Optimica ``optimization`` class (``.mop``), as written."""
    # the exchange layer (pymoca, and its package's FMU export, the acausal components) imported for Modelica source
    # only: solving a Python model's problem does not load it (tests/test_cli.py checks the solve path's sys.modules)
    try:
        if path.suffix.lower() == ".mop":
            return importlib.import_module("gtmodel.exchange.optimica").load_optimica(path, class_name).user_model
        return importlib.import_module("gtmodel.exchange.modelica").load_modelica(path, class_name)
    except GtModelError as exc:  # each names the file (and the line and construct where it has one)
        raise ModelError(str(exc) if str(exc).startswith(str(path)) else f"{path}: {exc}") from None


def reduced_model(model: Model) -> Model:
    """The model as ``simulate()`` integrates it: itself if it flattens, else reduced to index 1.

    Parameters
    ----------
    model : Model
        A model, e.g. ``Component().to_model()`` of composed library components.

    Returns
    -------
    Model
        ``model`` if :meth:`~gtmodel.modeling.Model.flatten` accepts it, else
        :func:`~gtmodel.modeling.structural_simplify` of it (the states it chose are logged at
        INFO level; every variable keeps its name as a state, an algebraic variable or an
        output).

    Raises
    ------
    ModelError
        The model is structurally singular (naming the equations and variables) or cannot
        be reduced.
    """
    if model._flattens():
        return model
    reduced = structural_simplify(model)
    flat = reduced.flatten()
    _log.info("model %r reduced to index 1 (structural_simplify): states %s", model.name, ", ".join(flat.x_names))
    return reduced


def split_model_reference(ref: str) -> tuple[Path, str]:
    """Split ``FILE:CLASS`` (the ``--model`` argument of ``gtmodel codegen``).

    Parameters
    ----------
    ref : str
        E.g. ``"models/cart_pendulum.py:CartPendulum"`` (the last ``:`` separates the
        class, so Windows drive letters are kept).

    Returns
    -------
    tuple of (pathlib.Path, str)
        The file and the class name.

    Raises
    ------
    ModelError
        No ``:`` or an empty part.
    """
    file, sep, cls = str(ref).rpartition(":")
    if not sep or not file or not cls:
        raise ModelError(f"--model: expected FILE:CLASS, e.g. models/cart_pendulum.py:CartPendulum, got {ref!r}")
    return Path(file), cls
