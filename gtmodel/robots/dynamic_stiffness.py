"""Dynamic stiffness of a serial arm: one dominant mode per Cartesian direction, pose-interpolated.

Cvitanic (2021), section 2. At a pose, each Cartesian direction ``x, y, z`` of the TCP is
modelled independently (cross-coupling neglected) by the most compliant mode of its
impact-hammer FRF::

    m x'' + c x' + k x = F(t)                     Cvitanic (2021), eq. (8)
    H(j w) = X / F = 1 / (k - m w^2 + j c w)

The transfer function, its frequency response and forced responses come from
python-control (:func:`single_mode_tf`). :func:`fit_single_mode` fits ``(m, c, k)`` to FRF
data: the linear least-squares solution of ``1/H = k - m w^2 + j c w`` starts a nonlinear
least-squares refinement (``scipy.optimize.least_squares`` on ``log(m, c, k)``) of the
relative FRF error ``(H_model - H) / |H|``.

Pose dependence, eqs. (9)-(11): one Gaussian-process regression per (direction,
parameter), 9 models, input = TCP position [m] and the redundant angle ``A`` about the
spindle axis [rad] (:class:`DynamicStiffnessGP`, scikit-learn
``GaussianProcessRegressor`` on ``log`` of the parameter, so predictions stay positive).
The thesis gives no numeric pose coordinates for its Table 16; pose inputs used with
those figures are illustrative.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize

from gtmodel._lazy import lazy_module
from gtmodel._docstrings import fill_doc
from gtmodel._arrays import as_rows, positive_float, positive_int
from gtmodel.errors import InputError
from gtmodel.status import Status, StatusResult

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")
#: SciPy's signal package, imported on first use (~1 s of CPU with the scipy.stats it imports).
signal = lazy_module("scipy.signal")

__all__ = [
    "DIRECTIONS",
    "single_mode_tf",
    "single_mode_frf",
    "ModeFitResult",
    "fit_single_mode",
    "simulate_single_mode",
    "DynamicStiffnessGP",
]

_log = logging.getLogger("gtmodel")

#: Cartesian directions of the per-direction models.
DIRECTIONS = ("x", "y", "z")


# numpydoc entries of the single-mode parameters, shared by eq. (8)'s functions (gtmodel._docstrings)
_mck_doc = fill_doc(
    mck="""
    Parameters
    ----------
    m : float
        Modal mass [kg], > 0.
    c : float
        Modal damping [N s/m], > 0.
    k : float
        Modal stiffness [N/m], > 0.
    """
)


@_mck_doc
def single_mode_tf(m: float, c: float, k: float) -> control.TransferFunction:
    """Compliance transfer function ``X/F = 1/(m s^2 + c s + k)``, Cvitanic (2021), eq. (8).

    {mck}

    Returns
    -------
    control.TransferFunction
        Continuous-time transfer function from force [N] to displacement [m].

    Raises
    ------
    InputError
        A non-positive or non-finite parameter.
    """
    m, c, k = positive_float(m, "m"), positive_float(c, "c"), positive_float(k, "k")
    return control.tf([1.0], [m, c, k])


def _check_freq(freq_hz: Any, name: str = "freq_hz") -> np.ndarray:
    try:
        f = np.asarray(freq_hz, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of frequencies [Hz], got {freq_hz!r}") from None
    if f.ndim != 1 or f.size < 3:
        raise InputError(f"{name}: expected shape (n,) with n >= 3, got {f.shape}")
    if not np.all(np.isfinite(f)):
        raise InputError(f"{name}: non-finite frequency at index {int(np.flatnonzero(~np.isfinite(f))[0])}")
    if np.any(f <= 0):
        raise InputError(f"{name}: expected positive frequencies, index {int(np.flatnonzero(f <= 0)[0])} is {f[f <= 0][0]!r}")
    if np.any(np.diff(f) <= 0):
        i = int(np.flatnonzero(np.diff(f) <= 0)[0])
        raise InputError(f"{name}: expected strictly increasing frequencies, index {i + 1} ({float(f[i + 1])!r}) <= index {i} ({float(f[i])!r})")
    return f


@_mck_doc
def single_mode_frf(m: float, c: float, k: float, freq_hz: Any) -> np.ndarray:
    """Frequency response ``H(j 2 pi f)`` of the single-mode model, Cvitanic (2021), eq. (8).

    {mck}
    freq_hz : array_like, shape (n,)
        Strictly increasing positive frequencies [Hz], n >= 3.

    Returns
    -------
    numpy.ndarray, shape (n,), complex
        Compliance FRF [m/N] (python-control ``frequency_response``).

    Raises
    ------
    InputError
        Bad parameters or frequencies.
    """
    f = _check_freq(freq_hz)
    sys = single_mode_tf(m, c, k)
    resp = control.frequency_response(sys, 2 * np.pi * f)
    return np.asarray(resp.complex).reshape(-1)


@dataclass
class ModeFitResult(StatusResult):
    """Result of a single-mode FRF fit (status, never None).

    Implements :class:`gtmodel.status.SolverResult`: :attr:`success` is True if the
    least-squares solver converged.

    Parameters
    ----------
    status : Status
        ``"optimal"`` or ``"error"``; keyword only.
    message : str
        Solver message; keyword only.
    m : float
        Modal mass [kg].
    c : float
        Modal damping [N s/m].
    k : float
        Modal stiffness [N/m].
    std : numpy.ndarray, shape (3,)
        First-order standard deviations of ``(m, c, k)`` [kg, N s/m, N/m].
    natural_frequency_hz : float
        ``sqrt(k/m) / (2 pi)`` [Hz].
    damping_ratio : float
        ``c / (2 sqrt(k m))`` [-].
    rms_relative_error : float
        RMS of ``|H_model - H| / |H|`` at the solution [-].
    initial : numpy.ndarray, shape (3,)
        Linear least-squares start ``(m, c, k)``.
    """

    m: float
    c: float
    k: float
    std: np.ndarray
    natural_frequency_hz: float
    damping_ratio: float
    rms_relative_error: float
    initial: np.ndarray


def fit_single_mode(freq_hz: Any, H: Any) -> ModeFitResult:
    """Fit ``(m, c, k)`` of eq. (8) to a measured compliance FRF, Cvitanic (2021), eq. (8).

    Start: linear least squares of ``Re(1/H) = k - m w^2`` and ``Im(1/H) = c w``.
    Refinement: nonlinear least squares (``scipy.optimize.least_squares``, parameters in
    ``log``) of the relative complex error ``(H_model - H)/|H|``. Pass the band around the
    dominant mode: other modes in the data bias the single-mode fit.

    Parameters
    ----------
    freq_hz : array_like, shape (n,)
        Strictly increasing positive frequencies [Hz], n >= 3.
    H : array_like, shape (n,), complex
        Measured compliance FRF [m/N], finite and non-zero.

    Returns
    -------
    ModeFitResult
        Fitted parameters, standard deviations and status.

    Raises
    ------
    InputError
        Bad frequencies, an FRF of another length, non-finite or zero values, or data
        whose linear start is non-physical (negative m, c or k: not a single
        compliance mode).
    """
    f = _check_freq(freq_hz)
    try:
        Hc = np.asarray(H, dtype=complex)
    except (TypeError, ValueError):
        raise InputError(f"H: expected complex FRF values, got {H!r}") from None
    if Hc.shape != f.shape:
        raise InputError(f"H: expected shape {f.shape} (one value per frequency), got {Hc.shape}")
    if not np.all(np.isfinite(Hc)):
        raise InputError(f"H: non-finite value at index {int(np.flatnonzero(~np.isfinite(Hc))[0])}")
    if np.any(Hc == 0):
        raise InputError(f"H: zero value at index {int(np.flatnonzero(Hc == 0)[0])}")
    w = 2 * np.pi * f
    G = 1.0 / Hc
    A = np.zeros((2 * f.size, 3))
    A[: f.size, 0] = -(w**2)
    A[: f.size, 2] = 1.0
    A[f.size :, 1] = w
    b = np.concatenate([G.real, G.imag])
    scale = np.array([1.0 / np.max(w) ** 2, 1.0 / np.max(w), 1.0])
    p0 = np.linalg.lstsq(A / scale, b, rcond=None)[0] / scale
    if np.any(p0 <= 0):
        names = [n for n, v in zip(("m", "c", "k"), p0) if v <= 0]
        raise InputError(f"H: the linear fit gives non-positive {', '.join(names)} ({p0.tolist()}): not a single compliance mode (check units/sign, band)")
    absH = np.abs(Hc)

    def residual(logp: np.ndarray) -> np.ndarray:
        m, c, k = np.exp(logp)
        e = (1.0 / (k - m * w**2 + 1j * c * w) - Hc) / absH
        return np.concatenate([e.real, e.imag])

    sol = scipy.optimize.least_squares(residual, np.log(p0), method="lm", xtol=1e-14, ftol=1e-14)
    m, c, k = np.exp(sol.x)
    r = sol.fun
    dof = max(r.size - 3, 1)
    try:
        cov_log = (r @ r / dof) * np.linalg.inv(sol.jac.T @ sol.jac)
        std = np.exp(sol.x) * np.sqrt(np.clip(np.diag(cov_log), 0, None))
    except np.linalg.LinAlgError:
        std = np.full(3, np.inf)
    ok = bool(sol.success)
    return ModeFitResult(
        status=Status.OPTIMAL if ok else Status.ERROR,
        message=str(sol.message),
        m=float(m),
        c=float(c),
        k=float(k),
        std=std,
        natural_frequency_hz=float(np.sqrt(k / m) / (2 * np.pi)),
        damping_ratio=float(c / (2 * np.sqrt(k * m))),
        rms_relative_error=float(np.sqrt(np.mean(np.abs(r[: f.size] + 1j * r[f.size :]) ** 2))),
        initial=p0,
    )


def simulate_single_mode(m: Any, c: Any, k: Any, t: Any, F: Any) -> np.ndarray:
    """Displacement of the per-direction single-mode models under a force history, eq. (8).

    Parameters
    ----------
    m : array_like, shape (3,)
        Modal masses per direction [kg], > 0.
    c : array_like, shape (3,)
        Modal dampings per direction [N s/m], > 0.
    k : array_like, shape (3,)
        Modal stiffnesses per direction [N/m], > 0.
    t : array_like, shape (n,)
        Equally spaced, strictly increasing times [s], n >= 3.
    F : array_like, shape (n, 3)
        Force per direction [N].

    Returns
    -------
    numpy.ndarray, shape (n, 3)
        Displacements [m] from rest: exact zero-order-hold discretisation
        (``scipy.signal.cont2discrete``) filtered with ``scipy.signal.lfilter`` (the force is held
        constant over each sample).

    Raises
    ------
    InputError
        Bad shapes, non-finite values, non-positive parameters or unequal time steps.
    """
    pars = []
    for name, v in (("m", m), ("c", c), ("k", k)):
        arr = np.asarray(v, dtype=float)
        if arr.shape != (3,):
            raise InputError(f"{name}: expected shape (3,) (x, y, z), got {arr.shape}")
        for i in range(3):
            positive_float(arr[i], f"{name}[{i}]")
        pars.append(arr)
    tt = np.asarray(t, dtype=float)
    if tt.ndim != 1 or tt.size < 3 or not np.all(np.isfinite(tt)) or np.any(np.diff(tt) <= 0):
        raise InputError("t: expected a finite strictly increasing array of shape (n,), n >= 3")
    dt = np.diff(tt)
    if np.max(np.abs(dt - dt[0])) > 1e-9 * max(1.0, abs(tt[-1])):
        raise InputError("t: expected equally spaced times")
    FF = np.asarray(F, dtype=float)
    if FF.shape != (tt.size, 3):
        raise InputError(f"F: expected shape ({tt.size}, 3), got {FF.shape}")
    if not np.all(np.isfinite(FF)):
        raise InputError("F: non-finite value")
    out = np.zeros((tt.size, 3))
    for i in range(3):
        num, den, _ = signal.cont2discrete(([1.0], [pars[0][i], pars[1][i], pars[2][i]]), float(dt[0]), method="zoh")
        out[:, i] = signal.lfilter(np.asarray(num, dtype=float).reshape(-1), den, FF[:, i])
    return out


class DynamicStiffnessGP:
    """Nine Gaussian-process models of ``(m, c, k)`` per direction over poses, eqs. (9)-(11).

    Input per pose: by default TCP position ``(x, y, z)`` [m] and the redundant angle ``A``
    [rad] (4 columns, eqs. (9)-(11)); any other pose description of ``n_inputs`` columns
    works the same way (e.g. joint angles 2 and 3 [rad] for the closed-loop study of
    Cvitanic (2021), section 5: ``n_inputs=2``). Each of the 9 outputs (direction x parameter) gets a scikit-learn
    ``GaussianProcessRegressor`` on ``log(value)`` with an anisotropic RBF kernel plus a
    white-noise term (hyperparameters by maximum likelihood, inputs standardised, length
    scales bounded to 0.1-100 standard deviations of the inputs: without the lower bound
    the likelihood may prefer a degenerate fit that only memorises the training points).

    Parameters
    ----------
    X : array_like, shape (N, n_inputs)
        Training inputs (default: TCP position [m] and angle A [rad]); N >= 3 distinct rows.
    m : array_like, shape (N, 3)
        Modal masses [kg] per direction (x, y, z), > 0.
    c : array_like, shape (N, 3)
        Modal dampings [N s/m], > 0.
    k : array_like, shape (N, 3)
        Modal stiffnesses [N/m], > 0.
    noise_level : float, optional
        Initial white-noise level on ``log(value)`` (default 1e-4).
    seed : int, optional
        Seed of the optimiser restarts.
    n_restarts : int, optional
        Restarts of the hyperparameter optimiser per model (default 0).
    n_inputs : int, optional
        Columns of ``X`` (default 4: TCP position and angle A).

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, non-positive parameters or fewer than 3 poses.
    """

    def __init__(self, X: Any, m: Any, c: Any, k: Any, noise_level: float = 1e-4, seed: int = 0, n_restarts: int = 0, n_inputs: int = 4) -> None:
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        self.n_inputs = positive_int(n_inputs, "n_inputs")
        what = " (TCP x, y, z [m], A [rad])" if self.n_inputs == 4 else ""
        Xa = np.asarray(X, dtype=float)
        if Xa.ndim != 2 or Xa.shape[1] != self.n_inputs or Xa.shape[0] < 3:
            raise InputError(f"X: expected shape (N, {self.n_inputs}){what} with N >= 3, got {Xa.shape}")
        if not np.all(np.isfinite(Xa)):
            raise InputError("X: non-finite value")
        data = {}
        for name, v in (("m", m), ("c", c), ("k", k)):
            arr = np.asarray(v, dtype=float)
            if arr.shape != (Xa.shape[0], 3):
                raise InputError(f"{name}: expected shape ({Xa.shape[0]}, 3), got {arr.shape}")
            if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
                raise InputError(f"{name}: expected finite positive values")
            data[name] = arr
        noise_level = positive_float(noise_level, "noise_level")
        self._mu = Xa.mean(axis=0)
        sd = Xa.std(axis=0)
        self._sd = np.where(sd > 0, sd, 1.0)
        Z = (Xa - self._mu) / self._sd
        self.models: dict[tuple[str, str], Any] = {}
        for name in ("m", "c", "k"):
            for i, d in enumerate(DIRECTIONS):
                kernel = ConstantKernel(1.0, (1e-3, 1e3)) * RBF(np.ones(self.n_inputs), (1e-1, 1e2)) + WhiteKernel(noise_level, (1e-10, 1e-1))
                gp = GaussianProcessRegressor(kernel=kernel, normalize_y=True, n_restarts_optimizer=int(n_restarts), random_state=seed)
                gp.fit(Z, np.log(data[name][:, i]))
                self.models[(d, name)] = gp
        self.X = Xa

    def predict(self, X: Any, return_std: bool = False) -> dict[str, np.ndarray] | tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """Predict ``m, c, k`` per direction at new poses, Cvitanic (2021), eqs. (9)-(11).

        Parameters
        ----------
        X : array_like, shape (N, n_inputs) or (n_inputs,)
            Poses, the columns of the training inputs (default: TCP position [m] and angle A [rad]).
        return_std : bool, optional
            Also return the standard deviations of ``log(value)`` [-].

        Returns
        -------
        dict of str to numpy.ndarray
            Keys ``"m"``, ``"c"``, ``"k"``, each shape (N, 3) (columns x, y, z) [kg, N s/m,
            N/m]; with ``return_std`` a second dict of the log-standard deviations.

        Raises
        ------
        InputError
            Wrong shape or non-finite values.
        """
        Xa, _ = as_rows(X, "X", self.n_inputs)
        Z = (Xa - self._mu) / self._sd
        out = {n: np.zeros((Xa.shape[0], 3)) for n in ("m", "c", "k")}
        std = {n: np.zeros((Xa.shape[0], 3)) for n in ("m", "c", "k")}
        for (d, name), gp in self.models.items():
            i = DIRECTIONS.index(d)
            mu, s = gp.predict(Z, return_std=True)
            out[name][:, i] = np.exp(mu)
            std[name][:, i] = s
        return (out, std) if return_std else out
