"""A closure model whose arms come from different closure models: "the best model per arm".

Dressler (2012), section 5.3, model 5 of Table 5.3: the arms of a Gantry-Tau are calibrated
separately (each arm's closure equations share no parameter with the others), so the most
accurate model of each arm can be joined into one robot: the six-link model with linear
actuators for arms 1 and 3 (model 3) and with the piecewise-linear actuator for arm 2
(model 4). :class:`ArmwiseClosure` takes arm ``i``'s joint points and link lengths from
``sources[i]``; its parameters are the parameters those arms depend on, under their
sources' names. The plate pose solves all joined closure equations (the generic Newton FK,
started from the best-determined source's own FK; where the joined equations leave a direction
undetermined, the assembly nearest to that start, :mod:`gtmodel.robots.pose_rank`).
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import GtModelError, InputError
from gtmodel.robots.closure import ClosureModel
from gtmodel.robots.pose_rank import closure_inverse_condition

__all__ = ["ArmwiseClosure"]


class ArmwiseClosure(ClosureModel):
    """Arm ``i`` of ``sources[i]`` (Dressler (2012), Table 5.3, model 5).

    Parameters
    ----------
    sources : sequence of 3 ClosureModel
        The model of each arm, in one frame (e.g. calibrated on the same measurements); all
        with the same number of actuators and the same orientation flag.
    name : str, optional
        Model name (default ``"armwise"``).

    Raises
    ------
    InputError
        Not three closure models, differing ``n_q`` or orientation flags, or two arms
        whose parameters have the same name.
    """

    def __init__(self, sources: Sequence[ClosureModel], name: str = "armwise") -> None:
        src = tuple(sources)
        if len(src) != 3 or not all(isinstance(s, ClosureModel) for s in src):
            raise InputError(f"sources: expected 3 closure models (one per arm), got {len(src)}")
        if len({s.n_q for s in src}) != 1 or len({bool(s.orientation) for s in src}) != 1:
            raise InputError("sources: the arms' models must have the same number of actuators and the same orientation flag, got "
                             + ", ".join(f"{s.name} (n_q {s.n_q}, orientation {s.orientation})" for s in src))
        self.sources = src
        self.name = name
        self.n_q = src[0].n_q
        self.orientation = bool(src[0].orientation)
        self.links = tuple(s.links[i] for i, s in enumerate(src))
        #: Per arm, the indices into its source's parameter vector that the arm depends on.
        self.arm_indices = tuple(np.asarray(s.arm_parameter_indices(i), dtype=int) for i, s in enumerate(src))
        names = [src[i].parameter_names()[j] for i in range(3) for j in self.arm_indices[i]]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise InputError(f"sources: arms of different models share parameter names {dup}")
        self._names = tuple(names)

    def parameter_names(self) -> tuple[str, ...]:
        """The parameters of each arm under its source's names, arm 1 first.

        Returns
        -------
        tuple of str
        """
        return self._names

    def parameter_vector(self) -> np.ndarray:
        """Current values, in the order of :meth:`parameter_names`.

        Returns
        -------
        numpy.ndarray, shape (n_parameters,)
        """
        return np.concatenate([s.parameter_vector()[self.arm_indices[i]] for i, s in enumerate(self.sources)])

    def _offsets(self) -> list[int]:
        return [0, *np.cumsum([ix.size for ix in self.arm_indices]).tolist()]

    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """Arm ``arm``'s joint points and lengths from its source (see :meth:`ClosureModel.link_points`).

        Parameters
        ----------
        p : casadi.SX, shape (n_parameters,)
            Parameter vector.
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
        src = self.sources[arm]
        off = self._offsets()
        full = ca.SX(ca.DM(src.parameter_vector()))
        for k, j in enumerate(self.arm_indices[arm]):
            full[int(j)] = p[off[arm] + k]
        return src.link_points(full, q, T, R, arm)

    def with_parameters(self, p: np.typing.ArrayLike) -> "ArmwiseClosure":
        """The same arms with other parameter values.

        Parameters
        ----------
        p : array_like, shape (n_parameters,)
            New values.

        Returns
        -------
        ArmwiseClosure

        Raises
        ------
        InputError
            Wrong size or non-finite values.
        """
        pa = np.asarray(p, dtype=float).ravel()
        if pa.size != self.n_parameters or not np.all(np.isfinite(pa)):
            raise InputError(f"p: expected {self.n_parameters} finite values, got {pa.size}")
        off = self._offsets()
        new = []
        for i, s in enumerate(self.sources):
            v = s.parameter_vector().copy()
            v[self.arm_indices[i]] = pa[off[i]:off[i + 1]]
            new.append(s.with_parameters(v))
        return ArmwiseClosure(new, self.name)

    def transformed(self, R: np.typing.ArrayLike, t: np.typing.ArrayLike) -> "ArmwiseClosure":
        """Every source moved into another frame, ``x' = R x + t``.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Rotation.
        t : array_like, shape (3,)
            Translation [m].

        Returns
        -------
        ArmwiseClosure
        """
        return ArmwiseClosure([s.transformed(R, t) for s in self.sources], self.name)

    def fk(self, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: Newton on the joined closure equations from a source's FK.

        The start is the FK of the source whose closure equations determine its pose best
        (largest worst-pose :func:`~gtmodel.robots.pose_rank.closure_inverse_condition`;
        the first in arm order among equals) of those whose own FK succeeds at every pose.
        Where the joined equations leave a direction undetermined (a source whose arm's links
        coincide), :meth:`~gtmodel.robots.closure.ClosureModel.fk_newton` takes the solution
        nearest to that start: the well-determined source fixes what the others leave free.

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
        ConvergenceError
            Newton's method does not converge at a pose (names the row).
        GtModelError
            No source's FK gives a start.
        """
        last: GtModelError | None = None
        starts = []
        for s in self.sources:
            try:
                T0, R0 = s.fk(q)
            except GtModelError as exc:
                last = exc
                continue
            starts.append((float(np.min(closure_inverse_condition(s, q, T0, R0))), T0, R0))
        if not starts:
            assert last is not None
            raise last
        _, T0, R0 = max(starts, key=lambda c: c[0])  # the best-determined source; the first of equals
        return self.fk_newton(q, T0, R0)

    def __repr__(self) -> str:
        return f"ArmwiseClosure({', '.join(s.name for s in self.sources)})"

    def describe(self) -> dict[str, Any]:
        """The source model of each arm.

        Returns
        -------
        dict
            ``{"arm 1": name, ...}``.
        """
        return {f"arm {i + 1}": s.name for i, s in enumerate(self.sources)}
