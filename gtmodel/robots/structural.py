"""Structural dynamics in physical form: modes, state space, Bode and impulse responses.

Dressler (2012), eq. 6.14 writes an identified 4th-order model of the L1 (vision data,
only cart 3 moving) in physical form with 2x2 matrices ``M``, ``D``, ``K``, and eq. 6.15
gives its resonance modes as ``sqrt(lambda)`` of the generalised eigenproblem
``det(M lambda + K) = 0``. The identified matrices are not symmetric, so the general
(non-symmetric) eigenproblem is solved (:func:`scipy.linalg.eig`).

Sign convention (a decision, with its reason)
---------------------------------------------
The spec prints (6.14) as ``X(s) = (M s^2 + D s + K) B U(s)``. Read literally this is
not a dynamic system (an improper, differentiating transfer function): the intended
relation is the inverse, ``X(s) = (...)^-1 B U(s)``. The signs cannot be the textbook
ones either: with the thesis' matrices, ``M x'' + D x' + K x = B u`` has the real poles
``-660, 672, 99, -72`` rad/s (unstable, no oscillation at all), and the textbook mode
condition ``det(K - M w^2) = 0`` has negative ``w^2``. What the thesis' numbers do
satisfy is (6.15) as printed, ``det(M w^2 + K) = 0`` with ``w^2 = 7546`` and
``421574`` rad^2/s^2 (13.83 and 103.34 Hz, reported 14 and 103 Hz), and with the same
signs the damped system is stable (poles ``-14.9 +- 88.0j``, ``-4.3 +- 631.8j`` rad/s).
That is the state-space parametrisation ``x'' = M^-1 (D x' + K x + B u)``, i.e.::

    thesis   (default):  M x'' = D x' + K x + B u,   X(s) = (M s^2 - D s - K)^-1 B U(s),
                         modes: det(M lambda + K) = 0, f = sqrt(lambda) / (2 pi)   (6.15)

The textbook form is available as ``convention="standard"``::

    standard:            M x'' + D x' + K x = B u,   X(s) = (M s^2 + D s + K)^-1 B U(s),
                         modes: det(K - M lambda) = 0

and the two differ only in the sign of ``D`` and ``K``
(:meth:`PhysicalModel.standard_form`, :meth:`PhysicalModel.with_convention`).

Two sets of frequencies are reported (:class:`Modes`): the undamped modes of (6.15)
(``frequencies_hz``: 13.83 and 103.34 Hz for the L1) and the natural frequencies and
damping ratios of the damped poles (``natural_frequencies_hz``: 14.21 and 100.56 Hz,
damping ratios 0.167 and 0.0068).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from gtmodel._lazy import lazy_module
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.actuator_dynamics import DynamicsModels, load_dynamics_models

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = ["Modes", "PhysicalModel", "CONVENTIONS"]

_log = logging.getLogger("gtmodel")

#: Sign conventions of ``D`` and ``K`` (see the module docstring).
CONVENTIONS = ("thesis", "standard")

#: Largest relative imaginary part of a (6.15) eigenvalue still treated as real.
_REAL_TOLERANCE = 1e-8


@dataclass(frozen=True)
class Modes:
    """Resonance modes of a :class:`PhysicalModel`, Dressler (2012), eq. 6.15.

    Parameters
    ----------
    frequencies_hz : numpy.ndarray, shape (n,)
        Undamped modes ``sqrt(lambda) / (2 pi)`` of (6.15), ascending [Hz].
    eigenvalues : numpy.ndarray, shape (n,)
        ``lambda = w^2`` of the generalised eigenproblem, same order [rad^2/s^2].
    shapes : numpy.ndarray, shape (n, n)
        Column ``k`` is the mode shape of ``frequencies_hz[k]``, scaled so that its
        largest-magnitude entry is 1.
    poles : numpy.ndarray, shape (2 n,)
        Poles of the damped system (state-space eigenvalues) [rad/s], by magnitude.
    natural_frequencies_hz : numpy.ndarray, shape (p,)
        ``|p| / (2 pi)`` of the poles with positive imaginary part, ascending [Hz]
        (``p = n`` when every mode is underdamped).
    damping_ratios : numpy.ndarray, shape (p,)
        ``-Re(p) / |p|`` of the same poles.
    """

    frequencies_hz: np.ndarray
    eigenvalues: np.ndarray
    shapes: np.ndarray
    poles: np.ndarray
    natural_frequencies_hz: np.ndarray
    damping_ratios: np.ndarray


def _matrix(name: str, value: Any, shape: tuple[int | None, int | None]) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a matrix of numbers, got {value!r}") from None
    if arr.ndim != 2 or any(s is not None and s != arr.shape[i] for i, s in enumerate(shape)):
        want = "x".join("n" if s is None else str(s) for s in shape)
        raise InputError(f"{name}: expected a matrix of shape {want}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite numbers, got {arr.tolist()}")
    arr.setflags(write=False)
    return arr


class PhysicalModel:
    """Structural model in physical (second-order) form, Dressler (2012), eq. 6.14.

    ``thesis`` convention: ``M x'' = D x' + K x + B u``; ``standard``:
    ``M x'' + D x' + K x = B u`` (see the module docstring for the choice).

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass-like matrix (non-singular, need not be symmetric).
    D : array_like, shape (n, n)
        Damping-like matrix.
    K : array_like, shape (n, n)
        Stiffness-like matrix.
    B : array_like, shape (n, m), optional
        Input matrix (default the identity, ``m = n``).
    convention : str, optional
        ``"thesis"`` (default) or ``"standard"``.
    name : str, optional
        Label for plots.

    Raises
    ------
    InputError
        Wrong shapes, non-finite entries, singular ``M`` or an unknown convention.
    """

    def __init__(self, M: Any, D: Any, K: Any, B: Any = None, convention: str = "thesis", name: str = "") -> None:
        self.M = _matrix("M", M, (None, None))
        n = self.M.shape[0]
        if self.M.shape != (n, n):
            raise InputError(f"M: expected a square matrix, got shape {self.M.shape}")
        self.D = _matrix("D", D, (n, n))
        self.K = _matrix("K", K, (n, n))
        self.B = _matrix("B", np.eye(n) if B is None else B, (n, None))
        if convention not in CONVENTIONS:
            raise InputError(f"convention: expected one of {', '.join(CONVENTIONS)}, got {convention!r}")
        cond = np.linalg.cond(self.M)
        if not np.isfinite(cond) or cond > 1e12:
            raise InputError(f"M: expected a non-singular matrix, got condition number {cond:.3g}")
        self.convention = convention
        self.name = name

    @classmethod
    def from_file(cls, source: Any) -> "PhysicalModel":
        """The structural model of a dynamics-models file (table ``[compliance]``).

        Dressler (2012), eq. 6.14 (``"L1_dynamics_models"``: the thesis' identified L1
        matrices).

        Parameters
        ----------
        source : str, pathlib.Path or DynamicsModels
            Shipped name (e.g. ``"L1_dynamics_models"``), path or loaded models.

        Returns
        -------
        PhysicalModel
            With the file's ``M``, ``D``, ``K``, ``B`` and convention.

        Raises
        ------
        ParameterError
            The file is invalid.
        """
        models = source if isinstance(source, DynamicsModels) else load_dynamics_models(source)
        c = models.compliance
        return cls(c.M, c.D, c.K, c.B, convention=c.convention, name=models.name)

    @property
    def n(self) -> int:
        """Number of coordinates ``n`` (size of ``M``)."""
        return int(self.M.shape[0])

    def standard_form(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(M, D, K)`` of the textbook form ``M x'' + D x' + K x = B u``.

        Dressler (2012), eq. 6.14 (thesis signs: ``D`` and ``K`` negated).

        Returns
        -------
        M, D, K : numpy.ndarray, shape (n, n)
            The standard-form matrices.
        """
        if self.convention == "standard":
            return np.array(self.M), np.array(self.D), np.array(self.K)
        return np.array(self.M), -np.array(self.D), -np.array(self.K)

    def with_convention(self, convention: str) -> "PhysicalModel":
        """The same system with ``D`` and ``K`` in another sign convention.

        Dressler (2012), eq. 6.14.

        Parameters
        ----------
        convention : str
            ``"thesis"`` or ``"standard"``.

        Returns
        -------
        PhysicalModel
            Same dynamics, matrices re-signed.

        Raises
        ------
        InputError
            Unknown convention.
        """
        if convention not in CONVENTIONS:
            raise InputError(f"convention: expected one of {', '.join(CONVENTIONS)}, got {convention!r}")
        M, D, K = self.standard_form()
        if convention == "thesis":
            D, K = -D, -K
        return PhysicalModel(M, D, K, self.B, convention=convention, name=self.name)

    def modes(self) -> Modes:
        """Resonance modes: generalised eigenproblem (6.15) and the damped poles.

        Dressler (2012), eq. 6.15: ``det(M lambda + K) = 0`` (thesis convention; in the
        standard one ``det(K - M lambda) = 0``), ``f = sqrt(lambda) / (2 pi)``, solved
        with :func:`scipy.linalg.eig` (general, non-symmetric matrices).

        Returns
        -------
        Modes
            Undamped modes, shapes, damped poles, natural frequencies, damping ratios.

        Raises
        ------
        ModelError
            An eigenvalue ``lambda`` is not real and positive (no oscillatory mode; for
            identified matrices usually the wrong sign convention).
        """
        M, D, K = self.standard_form()
        lam, vecs = scipy.linalg.eig(K, M)
        bad = [
            complex(v) for v in lam if not np.isfinite(v) or abs(v.imag) > _REAL_TOLERANCE * max(abs(v), 1.0) or v.real <= 0
        ]
        if bad:
            raise ModelError(
                f"modes: eigenvalue lambda = {bad[0]:.6g} of the {self.convention}-convention eigenproblem "
                f"({'det(M lambda + K) = 0' if self.convention == 'thesis' else 'det(K - M lambda) = 0'}) "
                "is not real and positive, so it is no oscillatory mode; check the sign convention of D and K"
            )
        lam = lam.real
        order = np.argsort(lam)
        lam = lam[order]
        shapes = np.real_if_close(vecs[:, order], tol=1e6).real
        shapes = shapes / shapes[np.argmax(np.abs(shapes), axis=0), np.arange(shapes.shape[1])]
        poles = self.to_state_space().poles()
        poles = poles[np.argsort(np.abs(poles))]
        upper = poles[poles.imag > 0]
        upper = upper[np.argsort(np.abs(upper))]
        return Modes(
            frequencies_hz=np.sqrt(lam) / (2.0 * math.pi),
            eigenvalues=lam,
            shapes=shapes,
            poles=poles,
            natural_frequencies_hz=np.abs(upper) / (2.0 * math.pi),
            damping_ratios=-upper.real / np.abs(upper),
        )

    def to_state_space(self) -> control.StateSpace:
        """Continuous state-space model with states ``[x; x']`` and outputs ``x``.

        Dressler (2012), eq. 6.14: ``A = [[0, I], [-M^-1 K, -M^-1 D]]``,
        ``B = [0; M^-1 B]``, ``C = [I, 0]``, ``D = 0`` (standard-form ``D``, ``K``).

        Returns
        -------
        control.StateSpace
            ``2n`` states, ``m`` inputs, ``n`` outputs.
        """
        M, D, K = self.standard_form()
        n, m = self.n, self.B.shape[1]
        Mi_K = np.linalg.solve(M, K)
        Mi_D = np.linalg.solve(M, D)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi_K, -Mi_D]])
        Bs = np.vstack([np.zeros((n, m)), np.linalg.solve(M, self.B)])
        C = np.hstack([np.eye(n), np.zeros((n, n))])
        return control.ss(A, Bs, C, np.zeros((n, m)), name=self.name or None)

    def frequency_response(self, freqs_hz: Any) -> control.FrequencyResponseData:
        """Frequency response ``X(j w) / U(j w)`` at the given frequencies.

        Dressler (2012), eq. 6.14; computed with :func:`control.frequency_response`.

        Parameters
        ----------
        freqs_hz : array_like, shape (F,)
            Positive frequencies [Hz].

        Returns
        -------
        control.FrequencyResponseData
            ``.magnitude`` and ``.phase`` of shape (n, m, F), ``.omega`` [rad/s].

        Raises
        ------
        InputError
            Empty, non-finite or non-positive frequencies.
        """
        f = np.atleast_1d(np.asarray(freqs_hz, dtype=float))
        if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
            raise InputError(f"freqs_hz: expected a non-empty 1-D array of positive finite frequencies in Hz, got {freqs_hz!r}")
        return control.frequency_response(self.to_state_space(), 2.0 * math.pi * f, squeeze=False)

    def impulse_response(self, duration: float = 0.5, n_points: int = 2001) -> control.TimeResponseData:
        """Impulse responses from every input to every coordinate.

        Dressler (2012), eq. 6.14; computed with :func:`control.impulse_response`.

        Parameters
        ----------
        duration : float, optional
            Length [s] (default 0.5).
        n_points : int, optional
            Number of time points (default 2001).

        Returns
        -------
        control.TimeResponseData
            ``.outputs`` of shape (n, m, n_points).

        Raises
        ------
        InputError
            Non-positive duration or fewer than 10 points.
        """
        if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not math.isfinite(duration) or duration <= 0:
            raise InputError(f"duration: expected a positive time in s, got {duration!r}")
        if isinstance(n_points, bool) or not isinstance(n_points, int) or n_points < 10:
            raise InputError(f"n_points: expected an integer >= 10, got {n_points!r}")
        t = np.linspace(0.0, float(duration), n_points)
        return control.impulse_response(self.to_state_space(), t, squeeze=False)

    def __repr__(self) -> str:
        return f"PhysicalModel(n={self.n}, m={self.B.shape[1]}, convention={self.convention!r}, name={self.name!r})"
