"""Closure models built on another closure model: the delegation written once.

A :class:`WrappedClosure` adds something to an *inner* closure model (actuator errors on
its joint points, compliant links under a load, piecewise-linear guideways) and keeps
the inner model's way of being moved and re-parametrised:

- parameters: the inner model's, then the wrapper's own (:meth:`own_parameter_names`);
- :meth:`with_parameters` checks the vector once (size, finite) and rebuilds the wrapper
  around ``inner.with_parameters``; :meth:`transformed` around ``inner.transformed``
  (the wrapper rotates its own frame-dependent data in :meth:`rewrap`);
- :meth:`fk`: Newton on the wrapper's closure equations
  (:meth:`~gtmodel.robots.closure.ClosureModel.fk_newton`) from the FK of a simpler model
  (:meth:`fk_start`, by default the inner model's).

A wrapper whose parameters are not the inner model's plus its own (the piecewise-linear
actuator model) overrides :meth:`_with_parameters` and :meth:`_transformed` and keeps the
shared check and the Newton FK. :func:`guideway_frame` is the frame convention of a
guideway shared by the actuator models.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel

__all__ = ["WrappedClosure", "guideway_frame"]


def guideway_frame(e1: np.typing.ArrayLike) -> np.ndarray:
    """Frame of a guideway from its unit direction: columns ``e1, e2, e3``.

    ``e2 = e_z x e1`` normalised (horizontal for a horizontal guideway; ``e_x x e1`` if the
    guideway is within ~6 deg of vertical, as on the F1), ``e3 = e1 x e2``.

    Parameters
    ----------
    e1 : array_like, shape (3,)
        Unit vector along the guideway.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        A rotation matrix with columns ``e1, e2, e3``.
    """
    e1 = np.asarray(e1, dtype=float)
    e2 = np.cross([0.0, 0.0, 1.0], e1)
    if np.linalg.norm(e2) < 0.1:
        e2 = np.cross([1.0, 0.0, 0.0], e1)
    e2 /= np.linalg.norm(e2)
    return np.column_stack([e1, e2, np.cross(e1, e2)])


class WrappedClosure(ClosureModel):
    """A closure model built on an inner closure model (see the module docstring).

    Subclasses set :attr:`inner` and implement :meth:`link_points` and :meth:`rewrap`
    (and :meth:`own_parameter_names` / :meth:`own_parameter_vector` when they add
    parameters).
    """

    #: The wrapped closure model.
    inner: ClosureModel

    # ------------------------------------------------------------------ parameters
    def own_parameter_names(self) -> tuple[str, ...]:
        """Names of the wrapper's own parameters, after the inner model's (default none).

        Returns
        -------
        tuple of str
        """
        return ()

    def own_parameter_vector(self) -> np.ndarray:
        """Values of the wrapper's own parameters (default none).

        Returns
        -------
        numpy.ndarray, shape (n_own,)
        """
        return np.zeros(0)

    def parameter_names(self) -> tuple[str, ...]:
        """The inner model's parameter names, then :meth:`own_parameter_names`.

        Returns
        -------
        tuple of str
        """
        return tuple(self.inner.parameter_names()) + tuple(self.own_parameter_names())

    def parameter_vector(self) -> np.ndarray:
        """Values in the order of :meth:`parameter_names`.

        Returns
        -------
        numpy.ndarray, shape (n_parameters,)
        """
        return np.concatenate([self.inner.parameter_vector(), self.own_parameter_vector()])

    def quaternion_indices(self) -> list[tuple[int, int, int, int]]:
        """The inner model's quaternion parameter indices (own parameters come after).

        Returns
        -------
        list of tuple of int
        """
        return self.inner.quaternion_indices()

    def rewrap(self, inner: ClosureModel, own: np.ndarray, R: np.ndarray | None) -> "WrappedClosure":
        """The same wrapper around another inner model (a subclass's constructor call).

        Parameters
        ----------
        inner : ClosureModel
            The new inner model.
        own : numpy.ndarray, shape (n_own,)
            Values of the own parameters.
        R : numpy.ndarray, shape (3, 3) or None
            Rotation of a frame change (:meth:`transformed`) to apply to the wrapper's
            frame-dependent data, None for a change of parameters.

        Returns
        -------
        WrappedClosure

        Raises
        ------
        NotImplementedError
            In a subclass that overrides :meth:`_with_parameters` and :meth:`_transformed`
            instead.
        """
        raise NotImplementedError(f"{type(self).__name__}.rewrap")

    def _with_parameters(self, p: np.ndarray) -> "WrappedClosure":
        n = self.inner.n_parameters
        return self.rewrap(self.inner.with_parameters(p[:n]), p[n:], None)

    def _transformed(self, R: np.ndarray, t: Any) -> "WrappedClosure":
        Rm = R.reshape(3, 3)
        return self.rewrap(self.inner.transformed(Rm, t), self.own_parameter_vector(), Rm)

    def with_parameters(self, p: np.typing.ArrayLike) -> "WrappedClosure":
        """The model with other parameter values (same structure).

        Parameters
        ----------
        p : array_like, shape (n_parameters,)
            Values in the order of :meth:`parameter_names`.

        Returns
        -------
        WrappedClosure
            Of the same class.

        Raises
        ------
        InputError
            Wrong size or non-finite values (or values the model rejects).
        """
        pa = np.asarray(p, dtype=float).ravel()
        if pa.size != self.n_parameters or not np.all(np.isfinite(pa)):
            raise InputError(f"{self.name}: expected {self.n_parameters} finite parameters, got {pa.size}")
        return self._with_parameters(pa)

    def transformed(self, R: np.typing.ArrayLike, t: np.typing.ArrayLike) -> "WrappedClosure":
        """The model in another frame, ``x' = R x + t`` (Dressler (2012), eqs. 5.3-5.4).

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Rotation.
        t : array_like, shape (3,)
            Translation [m].

        Returns
        -------
        WrappedClosure
            Of the same class.
        """
        return self._transformed(np.asarray(R, dtype=float), t)

    # ------------------------------------------------------------------ forward kinematics
    def fk_inputs(self, q: np.typing.ArrayLike) -> Any:
        """The actuator values as :meth:`fk` uses them, checked (default: unchanged).

        Parameters
        ----------
        q : array_like, shape (n_q,) or (N, n_q)
            Actuator values.

        Returns
        -------
        array_like
        """
        return q

    def fk_start(self, q: Any) -> tuple[Any, Any]:
        """Start pose of Newton's method: the inner model's FK.

        Parameters
        ----------
        q : array_like, shape (n_q,) or (N, n_q)
            Actuator values (:meth:`fk_inputs`).

        Returns
        -------
        T0 : numpy.ndarray, shape (3,) or (N, 3)
            Start TCP positions [m].
        R0 : numpy.ndarray or None
            Start orientations (None: identity).
        """
        return self.inner.fk(q)

    def fk(self, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """FK by Newton on this model's closure equations from :meth:`fk_start`.

        Parameters
        ----------
        q : array_like, shape (n_q,) or (N, n_q)
            Actuator values [m, rad].

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations.

        Raises
        ------
        InputError
            Wrong shape of ``q`` (or outside the model's range).
        UnreachablePoseError
            If the start model finds no pose.
        ConvergenceError
            If Newton's method does not converge (names the pose).
        """
        qa = self.fk_inputs(q)
        T0, R0 = self.fk_start(qa)
        return self.fk_newton(qa, T0, R0)
