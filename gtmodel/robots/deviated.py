"""The "true" robot of a simulated calibration: a closure model with actuator errors.

:class:`DeviatedClosure` adds the actuator errors (Dressler (2012), Table 4.1: straightness,
scale, backlash, ...; :class:`gtmodel.calibration.synthetic.ActuatorErrors`) to the
actuator-side joint points of any closure model, in the guideway frames of
:func:`guideway_axes`.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel
from gtmodel.robots.wrapped import WrappedClosure, guideway_frame

__all__ = ["DeviatedClosure", "guideway_axes", "joint_point_functions"]


def joint_point_functions(model: ClosureModel) -> tuple[ca.Function, ca.Function]:
    """Actuator-side joint points and guideway directions of a model as CasADi Functions.

    Parameters
    ----------
    model : ClosureModel
        Any closure model; arm ``i`` is driven by the actuator ``q_i``.

    Returns
    -------
    A : casadi.Function
        ``A(p, q)``: joint points ``A_ij`` as columns, shape (3, n_links) [m].
    dA_dq : casadi.Function
        ``dA_dq(p, q)``: ``dA_ij/dq_i`` as columns, shape (3, n_links).
    """
    p, q = ca.SX.sym("p", model.n_parameters), ca.SX.sym("q", model.n_q)
    T, R = ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
    A, G = [], []
    for i, arm in enumerate(model.links):
        Ai = model.link_points(p, q, T, R, i)[0]
        for j in range(len(arm)):
            A.append(Ai[:, j])
            G.append(ca.jacobian(Ai[:, j], q)[:, i])
    return ca.Function("A", [p, q], [ca.horzcat(*A)]), ca.Function("dA_dq", [p, q], [ca.horzcat(*G)])


def guideway_axes(model: ClosureModel, q: np.typing.ArrayLike | None = None) -> np.ndarray:
    """Guideway frames of a model: ``e1`` along ``dA_i1/dq_i`` (by AD of its link points).

    ``e2 = e_z x e1`` normalised (horizontal for a horizontal guideway; ``e_x x e1`` if the
    guideway is within ~6 deg of vertical, as on the F1), ``e3 = e1 x e2``.

    Parameters
    ----------
    model : ClosureModel
        Any closure model; arm ``i`` is driven by the linear actuator ``q_i``.
    q : array_like, shape (n_q,), optional
        Where to take the derivative (default zeros).

    Returns
    -------
    numpy.ndarray, shape (3, 3, 3)
        ``axes[i]`` has columns ``e1, e2, e3`` of arm ``i``.

    Raises
    ------
    InputError
        If an arm's joint point does not move with its actuator.
    """
    q0 = np.zeros(model.n_q) if q is None else np.asarray(q, dtype=float).reshape(model.n_q)
    _, fG = joint_point_functions(model)
    G = np.array(fG(model.parameter_vector(), q0))
    out = np.empty((3, 3, 3))
    col = 0
    for i, arm in enumerate(model.links):
        g = G[:, col]
        col += len(arm)
        n = np.linalg.norm(g)
        if not n > 0:
            raise InputError(f"{model.name}: joint point of arm {i + 1} does not move with q{i + 1} (dA/dq = 0)")
        out[i] = guideway_frame(g / n)
    return out


class DeviatedClosure(WrappedClosure):
    """A closure model whose actuator-side joint points carry actuator errors (the "true" robot).

    ``A_ij(q) -> A_ij(q) + d_i(q_i, direction_i)`` for every link of arm ``i``, with ``d_i``
    from :meth:`gtmodel.calibration.synthetic.ActuatorErrors.deviation_expression` in the guideway frame of the arm (the
    cart translates; its small rotations are neglected). Parameters, links and orientation
    are those of the wrapped model.

    Parameters
    ----------
    model : ClosureModel
        The ideal (error-free) model.
    errors : ActuatorErrors
        The actuator errors (:class:`gtmodel.calibration.ActuatorErrors`, or any object
        with its ``deviation_expression(arm, q_i, direction, axes)``).
    direction : array_like, shape (3,), optional
        Direction of the last motion per arm (+1 or -1), for the backlash.
    axes : array_like, shape (3, 3, 3), optional
        Guideway frames (default :func:`guideway_axes` of ``model``).

    Raises
    ------
    InputError
        If ``direction`` is not +-1 per arm or ``axes`` has the wrong shape.
    """

    def __init__(
        self,
        model: ClosureModel,
        errors: Any,
        direction: np.typing.ArrayLike = (1.0, 1.0, 1.0),
        axes: np.typing.ArrayLike | None = None,
    ) -> None:
        d = np.asarray(direction, dtype=float).reshape(-1)
        if d.shape != (3,) or not np.all(np.abs(d) == 1.0):
            raise InputError(f"direction: expected +1 or -1 for each of the 3 arms, got {direction!r}")
        self.inner = model
        self.errors = errors
        self.direction = d
        self.axes = guideway_axes(model) if axes is None else np.asarray(axes, dtype=float)
        if self.axes.shape != (3, 3, 3):
            raise InputError(f"axes: expected shape (3, 3, 3), got {self.axes.shape}")
        self.name = f"{model.name}+actuator_errors"
        self.n_q = model.n_q
        self.orientation = model.orientation
        self.links = model.links

    @property
    def model(self) -> ClosureModel:
        """The ideal (error-free) model (the wrapped model)."""
        return self.inner

    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """The wrapped model's link points with the actuator error added to ``A``.

        Parameters
        ----------
        p : casadi.SX, shape (n_parameters,)
            Parameters.
        q : casadi.SX, shape (n_q,)
            Actuator values [m, rad].
        T : casadi.SX, shape (3,)
            TCP position [m].
        R : casadi.SX, shape (3, 3)
            Plate orientation.
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        A, B : casadi.SX, shape (3, n_links_of_arm)
            Joint points [m].
        L : casadi.SX, shape (n_links_of_arm,)
            Link lengths [m].
        """
        A, B, L = self.model.link_points(p, q, T, R, arm)
        d = self.errors.deviation_expression(arm, q[arm], float(self.direction[arm]), self.axes[arm])
        return A + ca.repmat(d, 1, A.size2()), B, L

    def rewrap(self, inner: ClosureModel, own: np.ndarray, R: np.ndarray | None) -> "DeviatedClosure":
        """The same actuator errors on another ideal model; a frame change rotates the guideway frames.

        Parameters
        ----------
        inner : ClosureModel
            The ideal model.
        own : numpy.ndarray, shape (0,)
            No own parameters.
        R : numpy.ndarray, shape (3, 3) or None
            Rotation of a frame change.

        Returns
        -------
        DeviatedClosure
        """
        return DeviatedClosure(inner, self.errors, self.direction, self.axes if R is None else R @ self.axes)
