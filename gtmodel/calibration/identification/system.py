"""System identification of actuator and structural models from input/output data.

Dressler (2012), ch. 6.3: the closed-loop actuator models (6.11) and the 4th-order
structural model in physical form (6.14)-(6.15) were identified from experiments on the
L1. This module identifies both kinds of model from sampled data:

1. **Actuator models** (:func:`identify_actuator`): first order plus a known dead time,
   ``y_k = a y_(k-1) + b u_(k-nk)`` (an ARX model with ``na = nb = 1`` and delay ``nk``),
   by linear least squares (:func:`numpy.linalg.lstsq`), with standard deviations
   ``sqrt(diag(sigma^2 (Phi^T Phi)^-1))``, ``sigma^2 = RSS / (N - 2)``. With
   ``delay=None`` the delay is chosen over a range as the one with the smallest residual
   (every candidate is fitted on the same rows, so the residuals compare).
2. **Excitation** (:func:`prbs`): a maximum-length binary sequence from
   :func:`scipy.signal.max_len_seq`, held for ``hold`` samples, one circularly shifted
   copy per input channel.
3. **Black-box MIMO identification** (:func:`identify_state_space`) in three steps:
   a least-squares MIMO ARX model of order ``arx_order``
   ``y_k = sum_i A_i y_(k-i) + sum_i B_i u_(k-i)``; its Markov parameters
   ``[0, C B, C A B, ...]`` (impulse response of the ARX model in observer form); and the
   eigensystem realization algorithm :func:`control.eigensys_realization` (ERA), which
   reduces them to a balanced state-space model of the requested order. Why not
   :func:`control.markov` (least-squares FIR) for the Markov parameters: it assumes
   ``C A^k B = 0`` beyond the ``m`` estimated parameters. The L1's 100 Hz mode has a
   damping ratio of 0.007, so at 1 kHz the impulse response needs ~1500 samples to
   decay; measured on noise-free PRBS data of the reference model, ``m = 400`` (0.9 s)
   put the 14 Hz mode 0.6 Hz off and ``m = 1500`` took 15 s. The ARX model is exact
   for noise-free data from a 4-state, 2-output system already at order 2 (observability
   index 2) and, at order 8, keeps the modes within 0.05 Hz at 3 % output noise
   (where order 2 is 3 Hz off): its impulse response is not truncated.
4. **Physical form** (:func:`physical_from_state_space`): a state-space model with ``2n``
   states and ``n`` outputs (discrete ones are first converted to continuous time by the
   matrix logarithm, :func:`discrete_to_continuous`) is transformed to the coordinates
   ``z = T x``, ``T = [C; C A]``, where ``A' = T A T^-1 = [[0, I], [A21, A22]]`` and
   ``B' = T B = [C B; C A B] = [0; M^-1 B]``. Input/output data determine ``M^-1 B``
   only, so ``B`` is fixed (identity by default) to remove the scale ambiguity; then
   ``M = B (C A B)^-1`` and, in the thesis convention of
   :class:`~gtmodel.robots.structural.PhysicalModel` (``M x'' = D x' + K x + B u``),
   ``K = M A21``, ``D = M A22`` (standard convention: their negatives).

Every function validates its data: inconsistent lengths, non-finite values,
non-increasing or irregular time, too few samples and singular regressors raise
:class:`~gtmodel.errors.InputError` naming the argument.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg
import scipy.signal

from gtmodel._lazy import lazy_module
from gtmodel._arrays import as_signal, as_times
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.actuator_dynamics import actuator_tf
from gtmodel.robots.structural import CONVENTIONS, PhysicalModel
from gtmodel.status import Status, StatusResult

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = [
    "ActuatorIdentification",
    "StateSpaceIdentification",
    "identify_actuator",
    "identify_state_space",
    "discrete_to_continuous",
    "physical_from_state_space",
    "prbs",
    "MIN_ROWS",
    "SINGULAR_TOLERANCE",
    "TIME_STEP_RTOL",
]

_log = logging.getLogger("gtmodel")

#: Fewest regression rows (per estimated parameter of one output) a fit accepts.
MIN_ROWS = 10

#: A regressor whose smallest/largest singular value ratio (columns scaled to unit norm)
#: is below this is singular: the data do not determine the parameters.
SINGULAR_TOLERANCE = 1e-10

#: Relative tolerance on the time step: samples must be equally spaced.
TIME_STEP_RTOL = 1e-6


# ----------------------------------------------------------------------------- data checks
def _time(t: Any, n_min: int) -> tuple[np.ndarray, float]:
    t = as_times(t, "t", n_min)
    steps = np.diff(t)
    dt = float(np.mean(steps))
    worst = int(np.argmax(np.abs(steps - dt)))
    if abs(steps[worst] - dt) > TIME_STEP_RTOL * dt:
        raise InputError(
            f"t: samples must be equally spaced (mean step {dt:.6g} s), but step {worst} is {steps[worst]:.6g} s"
        )
    return t, dt


def _check_regressor(phi: np.ndarray, what: str) -> None:
    norms = np.linalg.norm(phi, axis=0)
    zero = np.nonzero(norms == 0)[0]
    if zero.size:
        raise InputError(f"{what}: singular regressor: column {int(zero[0])} is zero (no excitation or zero output)")
    s = np.linalg.svd(phi / norms, compute_uv=False)
    if s[-1] < SINGULAR_TOLERANCE * s[0]:
        raise InputError(
            f"{what}: singular regressor (singular value ratio {s[-1] / s[0]:.2e} < {SINGULAR_TOLERANCE:g}): "
            "the input does not excite the model (constant or too short input, or y proportional to the delayed input)"
        )


def _int(name: str, value: Any, lo: int, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo or (hi is not None and value > hi):
        rng = f">= {lo}" if hi is None else f"in {lo}..{hi}"
        raise InputError(f"{name}: expected an integer {rng}, got {value!r}")
    return int(value)


# ----------------------------------------------------------------------------- PRBS
def prbs(n_samples: int, bits: int = 10, hold: int = 1, amplitude: float = 1.0, channels: int = 1) -> np.ndarray:
    """Pseudo-random binary sequence (maximum-length sequence) for identification.

    The MLS of :func:`scipy.signal.max_len_seq` (period ``2^bits - 1``), mapped to
    ``+-amplitude``, each value held for ``hold`` samples, repeated to ``n_samples``.
    Channel ``c`` is the sequence circularly shifted by ``c * period / channels``
    (shifted MLS are nearly uncorrelated). Used for the experiments of Dressler (2012),
    ch. 6.3 (eqs. 6.11, 6.14).

    Parameters
    ----------
    n_samples : int
        Number of samples ``N`` (>= 2).
    bits : int, optional
        Register length, 2..24 (default 10: period 1023).
    hold : int, optional
        Samples per sequence value (>= 1, default 1); larger moves energy to lower
        frequencies.
    amplitude : float, optional
        Level (positive, default 1).
    channels : int, optional
        Number of input channels (>= 1, default 1).

    Returns
    -------
    numpy.ndarray
        Shape ``(N,)`` for one channel, else ``(N, channels)``; values ``+-amplitude``.

    Raises
    ------
    InputError
        Out-of-range arguments.
    """
    n_samples = _int("n_samples", n_samples, 2)
    bits = _int("bits", bits, 2, 24)
    hold = _int("hold", hold, 1)
    channels = _int("channels", channels, 1)
    if isinstance(amplitude, bool) or not isinstance(amplitude, (int, float)) or not math.isfinite(amplitude) or amplitude <= 0:
        raise InputError(f"amplitude: expected a positive number, got {amplitude!r}")
    seq, _ = scipy.signal.max_len_seq(bits)
    period = seq.size
    base = amplitude * (2.0 * seq.astype(float) - 1.0)
    out = np.empty((n_samples, channels))
    for c in range(channels):
        shifted = np.roll(base, (c * period) // channels)
        held = np.repeat(shifted, hold)
        reps = -(-n_samples // held.size)
        out[:, c] = np.tile(held, reps)[:n_samples]
    return out[:, 0] if channels == 1 else out


# ----------------------------------------------------------------------------- actuator
@dataclass
class ActuatorIdentification(StatusResult):
    """Result of :func:`identify_actuator`, Dressler (2012), eq. 6.11.

    Parameters
    ----------
    a, b : float
        Estimated pole and gain coefficient of ``y_k = a y_(k-1) + b u_(k-nk)``.
    delay : int
        Dead time ``nk`` in samples (given or estimated).
    dt : float
        Sampling time [s].
    std_a, std_b : float
        Standard deviations of ``a`` and ``b`` from the residual variance.
    rms_residual : float
        Root-mean-square one-step prediction error (output unit).
    n_rows : int
        Number of regression rows used.
    status : Status
        ``optimal`` (unique least-squares solution, stable pole) or ``error``
        (``success`` is True for ``optimal``).
    message : str
        Human-readable outcome.
    residuals_by_delay : dict of int to float
        RMS residual of each candidate delay (one entry when the delay was given).
    """

    a: float
    b: float
    delay: int
    dt: float
    std_a: float
    std_b: float
    rms_residual: float
    n_rows: int
    residuals_by_delay: dict[int, float] = field(default_factory=dict)

    def transfer_function(self) -> control.TransferFunction:
        """The identified model as a discrete transfer function (6.11).

        Returns
        -------
        control.TransferFunction
            ``b z^-nk / (1 - a z^-1)`` with ``dt``.

        Raises
        ------
        InputError
            The identified pole is not stable (``|a| >= 1``).
        """
        return actuator_tf(self.a, self.b, self.dt, self.delay)


def _fit_first_order(y: np.ndarray, u: np.ndarray, delay: int, start: int) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    rows = np.arange(start, y.size)
    phi = np.column_stack([y[rows - 1], u[rows - delay]])
    target = y[rows]
    theta, *_ = np.linalg.lstsq(phi, target, rcond=None)
    res = target - phi @ theta
    return theta, phi, float(res @ res), res


def identify_actuator(
    t: Any, u: Any, y: Any, delay: int | None = 5, delay_range: tuple[int, int] = (1, 20)
) -> ActuatorIdentification:
    """Identify a first-order-plus-delay actuator model from step or PRBS data.

    Dressler (2012), eq. 6.11: ``y_k = a y_(k-1) + b u_(k-nk)``, linear least squares
    (ARX with ``na = nb = 1``). Data start at rest (``y`` and ``u`` before ``t[0]`` are
    taken as not needed: the first ``max(nk, 1)`` samples only enter as regressors).

    Parameters
    ----------
    t : array_like, shape (N,)
        Equally spaced, strictly increasing sample times [s].
    u : array_like, shape (N,)
        Input (e.g. position reference).
    y : array_like, shape (N,)
        Measured output.
    delay : int or None, optional
        Known dead time ``nk`` in samples (default 5); ``None`` estimates it over
        ``delay_range`` by the smallest residual.
    delay_range : tuple of int, optional
        Inclusive candidate range ``(lo, hi)`` for ``delay=None`` (default 1..20).

    Returns
    -------
    ActuatorIdentification
        Estimates, standard deviations, residuals and status.

    Raises
    ------
    InputError
        Inconsistent lengths, NaN/inf, non-increasing or irregular time, too few samples
        (fewer than ``2 * MIN_ROWS`` regression rows) or a singular regressor.
    """
    if delay is None:
        if (
            not isinstance(delay_range, (tuple, list))
            or len(delay_range) != 2
            or any(isinstance(d, bool) or not isinstance(d, (int, np.integer)) for d in delay_range)
            or not 0 <= delay_range[0] <= delay_range[1]
        ):
            raise InputError(f"delay_range: expected two integers 0 <= lo <= hi, got {delay_range!r}")
        candidates = list(range(int(delay_range[0]), int(delay_range[1]) + 1))
    else:
        candidates = [_int("delay", delay, 0)]
    start = max(max(candidates), 1)
    t, dt = _time(t, 2)
    n = t.size
    uu = as_signal(u, "u", n=n, like="t", vector=True)
    yy = as_signal(y, "y", n=n, like="t", vector=True)
    if uu.shape[1] != 1 or yy.shape[1] != 1:
        raise InputError(f"u, y: expected single-channel signals, got {uu.shape[1]} and {yy.shape[1]} channels")
    uu, yy = uu[:, 0], yy[:, 0]
    if n - start < 2 * MIN_ROWS:
        raise InputError(f"t: too few samples: {n} samples give {n - start} regression rows, need at least {2 * MIN_ROWS}")
    fits = {}
    for nk in candidates:
        theta, phi, rss, _ = _fit_first_order(yy, uu, nk, start)
        fits[nk] = (theta, phi, rss)
    rms = {nk: math.sqrt(f[2] / (n - start)) for nk, f in fits.items()}
    best = min(candidates, key=lambda nk: fits[nk][2])
    theta, phi, rss = fits[best]
    _check_regressor(phi, "identify_actuator")
    rows = phi.shape[0]
    sigma2 = rss / (rows - 2)
    cov = sigma2 * np.linalg.inv(phi.T @ phi)
    a, b = float(theta[0]), float(theta[1])
    if abs(a) < 1.0:
        status, message = Status.OPTIMAL, f"least squares, {rows} rows, delay {best} samples"
    else:
        status, message = Status.ERROR, f"identified pole a = {a:.6g} is not stable (|a| >= 1): no first-order lag fits these data"
    _log.debug("identify_actuator: a=%.6g b=%.6g delay=%d rms=%.3g", a, b, best, rms[best])
    return ActuatorIdentification(
        a=a,
        b=b,
        delay=best,
        dt=dt,
        std_a=float(math.sqrt(cov[0, 0])),
        std_b=float(math.sqrt(cov[1, 1])),
        rms_residual=rms[best],
        n_rows=rows,
        status=status,
        message=message,
        residuals_by_delay=rms,
    )


# ----------------------------------------------------------------------------- black box
@dataclass
class StateSpaceIdentification(StatusResult):
    """Result of :func:`identify_state_space`, Dressler (2012), ch. 6.3 (model of eq. 6.14).

    Parameters
    ----------
    sys : control.StateSpace
        Identified discrete model (``dt`` of the data), ``order`` states.
    hankel_singular_values : numpy.ndarray
        Singular values of the ERA Hankel matrix (a gap after ``order`` supports it).
    arx_rms_residual : numpy.ndarray, shape (p,)
        RMS one-step prediction error of the ARX model per output.
    arx_order : int
        ARX order used.
    status : Status
        ``optimal`` (stable model) or ``error`` (an identified pole outside the unit
        circle); ``success`` is True for ``optimal``.
    message : str
        Human-readable outcome.
    """

    sys: control.StateSpace
    hankel_singular_values: np.ndarray
    arx_rms_residual: np.ndarray
    arx_order: int

    def to_physical(self, B: Any = None, convention: str = "thesis") -> PhysicalModel:
        """The identified model in physical form (6.14); see :func:`physical_from_state_space`.

        Parameters
        ----------
        B : array_like, shape (n, m), optional
            Fixed input matrix (default identity).
        convention : str, optional
            ``"thesis"`` (default) or ``"standard"``.

        Returns
        -------
        PhysicalModel
            ``M``, ``D``, ``K`` with the given ``B``.
        """
        return physical_from_state_space(self.sys, B=B, convention=convention)


def _arx_to_state_space(theta: np.ndarray, p: int, m: int, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Block observer form of ``y_k = sum A_i y_(k-i) + sum B_i u_(k-i)``."""
    nx = p * order
    A = np.zeros((nx, nx))
    B = np.zeros((nx, m))
    for i in range(order):
        A[i * p : (i + 1) * p, :p] = theta[i * p : (i + 1) * p].T
        B[i * p : (i + 1) * p] = theta[order * p + i * m : order * p + (i + 1) * m].T
        if i < order - 1:
            A[i * p : (i + 1) * p, (i + 1) * p : (i + 2) * p] = np.eye(p)
    C = np.zeros((p, nx))
    C[:, :p] = np.eye(p)
    return A, B, C


def identify_state_space(
    t: Any, u: Any, y: Any, order: int | None = None, arx_order: int = 8, markov_length: int = 600, hankel_size: int = 100
) -> StateSpaceIdentification:
    """Black-box MIMO identification: least-squares ARX, Markov parameters, ERA.

    Used for the 4th-order structural model of Dressler (2012), ch. 6.3 (eq. 6.14). See
    the module docstring for the method and why it is preferred over
    :func:`control.markov`. The ARX regressor's input columns must have full rank
    (persistent excitation); its output columns may be rank-deficient for noise-free
    data of a system of lower order than ``p * arx_order`` (the minimum-norm solution has
    the same impulse response).

    Parameters
    ----------
    t : array_like, shape (N,)
        Equally spaced, strictly increasing sample times [s].
    u : array_like, shape (N,) or (N, m)
        Inputs.
    y : array_like, shape (N,) or (N, p)
        Measured outputs.
    order : int, optional
        State dimension of the model (default ``2 p``: a second-order system in ``p``
        coordinates).
    arx_order : int, optional
        ARX order (default 8).
    markov_length : int, optional
        Number of Markov parameters passed to ERA (default 600).
    hankel_size : int, optional
        Block rows and columns of the ERA Hankel matrix (default 100; needs
        ``markov_length > 2 hankel_size``).

    Returns
    -------
    StateSpaceIdentification
        Discrete state-space model, Hankel singular values, ARX residuals and status.

    Raises
    ------
    InputError
        Inconsistent lengths, NaN/inf, non-increasing or irregular time, too few samples,
        an input that does not excite the ARX model (singular input regressor) or
        inconsistent sizes.
    """
    arx_order = _int("arx_order", arx_order, 1)
    markov_length = _int("markov_length", markov_length, 3)
    hankel_size = _int("hankel_size", hankel_size, 1)
    if markov_length - 1 < 2 * hankel_size:
        raise InputError(f"markov_length: expected more than 2 * hankel_size = {2 * hankel_size}, got {markov_length}")
    t, dt = _time(t, 2)
    n = t.size
    U = as_signal(u, "u", n=n, like="t", vector=True)
    Y = as_signal(y, "y", n=n, like="t", vector=True)
    p, m = Y.shape[1], U.shape[1]
    order = 2 * p if order is None else _int("order", order, 1)
    if order > p * hankel_size or order > m * hankel_size:
        raise InputError(f"order: {order} exceeds the Hankel matrix size (hankel_size {hankel_size})")
    n_par = arx_order * (p + m)
    rows = n - arx_order
    if rows < MIN_ROWS * n_par:
        raise InputError(
            f"t: too few samples: {n} samples give {rows} rows for {n_par} ARX parameters per output, "
            f"need at least {MIN_ROWS * n_par + arx_order} samples"
        )
    phi_y = np.hstack([Y[arx_order - i : n - i] for i in range(1, arx_order + 1)])
    phi_u = np.hstack([U[arx_order - i : n - i] for i in range(1, arx_order + 1)])
    _check_regressor(phi_u, "identify_state_space (input part of the ARX regressor)")
    if np.all(np.linalg.norm(phi_y, axis=0) == 0):
        raise InputError("y: the outputs are identically zero: nothing to identify")
    phi = np.hstack([phi_y, phi_u])
    target = Y[arx_order:]
    theta, *_ = np.linalg.lstsq(phi, target, rcond=None)
    res = target - phi @ theta
    arx_rms = np.sqrt(np.mean(res**2, axis=0))
    A, B, C = _arx_to_state_space(theta, p, m, arx_order)
    markov = np.zeros((p, m, markov_length))
    X = B.copy()
    for k in range(1, markov_length):
        markov[:, :, k] = C @ X
        X = A @ X
    era, S = control.eigensys_realization(markov, r=order, m=hankel_size, n=hankel_size)
    sys = control.ss(era.A, era.B, era.C, era.D, dt)
    radius = float(np.max(np.abs(sys.poles())))
    if radius < 1.0:
        status, message = Status.OPTIMAL, f"ARX({arx_order}) + ERA, order {order}, largest pole radius {radius:.6f}"
    else:
        status, message = Status.ERROR, f"identified model unstable: pole radius {radius:.6f} >= 1 (try another arx_order or more data)"
    return StateSpaceIdentification(
        sys=sys,
        hankel_singular_values=np.asarray(S),
        arx_rms_residual=arx_rms,
        arx_order=arx_order,
        status=status,
        message=message,
    )


def discrete_to_continuous(sys: control.StateSpace) -> control.StateSpace:
    """Continuous model whose zero-order-hold sampling is ``sys`` (inverse of ZOH).

    ``A_c = logm(A_d) / dt`` (:func:`scipy.linalg.logm`), ``B_c = (A_d - I)^-1 A_c B_d``;
    ``C`` and ``D`` unchanged. Used to bring an identified model to the continuous
    physical form of Dressler (2012), eq. 6.14.

    Parameters
    ----------
    sys : control.StateSpace
        Discrete system with a numeric ``dt``.

    Returns
    -------
    control.StateSpace
        Continuous system.

    Raises
    ------
    InputError
        Not a discrete state-space system with numeric ``dt``.
    ModelError
        A pole on the non-positive real axis or at 1 (no real logarithm / integrator).
    """
    if not isinstance(sys, control.StateSpace) or not sys.isdtime(strict=True) or sys.dt is True:
        raise InputError("sys: expected a discrete control.StateSpace with a numeric dt")
    dt = float(sys.dt)
    Ad = np.asarray(sys.A)
    poles = np.linalg.eigvals(Ad)
    bad = [z for z in poles if (abs(z.imag) <= 1e-12 * max(abs(z), 1e-300) and z.real <= 0) or abs(z - 1.0) < 1e-12]
    if bad:
        raise ModelError(f"discrete_to_continuous: pole {complex(bad[0]):.6g} has no continuous equivalent under ZOH")
    Ac = scipy.linalg.logm(Ad) / dt
    Ac = np.real_if_close(Ac, tol=1e6).real
    Bc = np.linalg.solve(Ad - np.eye(Ad.shape[0]), Ac @ np.asarray(sys.B))
    return control.ss(Ac, Bc, np.asarray(sys.C), np.asarray(sys.D))


def physical_from_state_space(sys: control.StateSpace, B: Any = None, convention: str = "thesis") -> PhysicalModel:
    """Physical form ``M``, ``D``, ``K`` of a state-space model with ``2n`` states, ``n`` outputs.

    Dressler (2012), eq. 6.14: coordinates ``z = [C x; C A x]`` give
    ``A' = [[0, I], [A21, A22]]``, ``B' = [C B; C A B]``; with the fixed input matrix
    ``B`` (``M^-1 B = C A B``): ``M = B (C A B)^+`` and ``K = M A21``, ``D = M A22``
    (thesis convention) or ``K = -M A21``, ``D = -M A22`` (standard convention). A
    discrete model is converted first (:func:`discrete_to_continuous`).

    Parameters
    ----------
    sys : control.StateSpace
        ``2n`` states, ``n`` outputs (positions), ``m`` inputs, no feedthrough.
    B : array_like, shape (n, m), optional
        Fixed input matrix (default the identity; requires ``m = n``).
    convention : str, optional
        ``"thesis"`` (default) or ``"standard"``, see
        :class:`~gtmodel.robots.structural.PhysicalModel`.

    Returns
    -------
    PhysicalModel
        The model with ``B``; ``C B`` (ideally 0) is logged when it is not small.

    Raises
    ------
    InputError
        Wrong sizes, unknown convention, a non-zero feedthrough.
    ModelError
        ``[C; C A]`` singular (the outputs do not observe the states as positions and
        velocities) or ``C A B`` rank-deficient.
    """
    if not isinstance(sys, control.StateSpace):
        raise InputError(f"sys: expected a control.StateSpace, got {type(sys).__name__}")
    if convention not in CONVENTIONS:
        raise InputError(f"convention: expected one of {', '.join(CONVENTIONS)}, got {convention!r}")
    if sys.isdtime(strict=True):
        sys = discrete_to_continuous(sys)
    A, Bs, C, Dd = (np.asarray(x, dtype=float) for x in (sys.A, sys.B, sys.C, sys.D))
    nx, p, m = A.shape[0], C.shape[0], Bs.shape[1]
    if nx != 2 * p:
        raise InputError(f"sys: expected 2n states for n = {p} outputs, got {nx} states")
    n = p
    Bfix = np.eye(n) if B is None else np.asarray(B, dtype=float)
    if Bfix.shape != (n, m) or not np.all(np.isfinite(Bfix)):
        raise InputError(f"B: expected a finite matrix of shape ({n}, {m}), got {Bfix.shape}")
    scale = max(float(np.max(np.abs(C @ A @ Bs))), 1e-300)
    if np.max(np.abs(Dd)) > 1e-9 * scale:
        raise InputError(f"sys: expected no feedthrough (D = 0), got max |D| = {np.max(np.abs(Dd)):.3g}")
    T = np.vstack([C, C @ A])
    cond = np.linalg.cond(T)
    if not np.isfinite(cond) or cond > 1e12:
        raise ModelError(f"physical_from_state_space: [C; C A] is singular (condition {cond:.3g}): the outputs are not positions of a 2nd-order model")
    Ti = np.linalg.inv(T)
    A2 = T @ A @ Ti
    B2 = T @ Bs
    cb = float(np.max(np.abs(B2[:n])))
    if cb > 1e-6 * float(np.max(np.abs(B2[n:]))):
        _log.info("physical_from_state_space: C B = %.3g (relative %.3g) is not zero; it is ignored", cb, cb / np.max(np.abs(B2[n:])))
    Minv_B = B2[n:]
    if np.linalg.matrix_rank(Minv_B) < n:
        raise ModelError("physical_from_state_space: C A B has rank below n: M cannot be recovered")
    M = Bfix @ np.linalg.pinv(Minv_B)
    sign = 1.0 if convention == "thesis" else -1.0
    K = sign * M @ A2[n:, :n]
    D = sign * M @ A2[n:, n:]
    return PhysicalModel(M, D, K, Bfix, convention=convention)
