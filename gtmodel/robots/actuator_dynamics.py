"""Closed-loop actuator models of the Gantry-Tau as discrete transfer functions.

Dressler (2012), eq. 6.11: each axis of the L1, position servo closed, from the
motor-angle reference to the measured position, is a first-order lag with a dead time of
five samples of the 4 ms controller::

    G_a,i(q) = q^-5 b_i / (1 - a_i q^-1),    y_k = a_i y_(k-1) + b_i u_(k-5)

As a python-control :class:`control.TransferFunction` in ``z`` (``dt`` the loop period, 4 ms) this is
``b_i z^-5 z / (z - a_i) = b_i / (z^5 - a_i z^4)``: numerator ``[b_i]``, denominator
``[1, -a_i, 0, 0, 0, 0]``. The thesis' numbers are in the data file
``gtmodel/robots/data/L1_dynamics_models.toml`` (table ``[actuators]``), loaded and
validated by :func:`load_dynamics_models`.

Bandwidth
---------
:func:`bandwidth` returns the first frequency where the gain is ``dbdrop`` (default
-3 dB) below the DC gain. For a continuous system it is :func:`control.bandwidth`. For a
discrete system python-control 0.10.2 evaluates the transfer function at ``z = j w``
instead of ``z = exp(j w dt)`` (fixed upstream in python-control PR #1212, after 0.10.2),
so here the same definition is evaluated with :meth:`control.LTI.frequency_response`,
which does use ``z = exp(j w dt)``: the first grid frequency below the threshold brackets
the crossing, which is then found by bisection (:func:`scipy.optimize.brentq`). The delay
does not change the gain, so a first-order lag has the closed form
``cos(w dt) = (1 + a^2 - 10^(-dbdrop/10) (1 - a)^2) / (2 a)``.
The three L1 axes give 1.43, 1.39 and 1.10 Hz: the thesis' "about 1.1 Hz" is axis 3,
axes 1 and 2 are about 1.4 Hz.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import scipy.optimize

from gtmodel._lazy import lazy_module
from gtmodel._arrays import as_times
from gtmodel.defaults import LOOP_PERIOD_S, defaults
from gtmodel.errors import InputError
from gtmodel.robots.parameters import _read_data_file, _Reader

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = [
    "ActuatorParameters",
    "ComplianceParameters",
    "DynamicsModels",
    "load_dynamics_models",
    "dynamics_models_from_mapping",
    "loop_period",
    "actuator_tf",
    "actuator_models",
    "bandwidth",
    "step",
    "simulate",
]

_log = logging.getLogger("gtmodel")
#: The shipped dynamics-models file (named in the message for an unknown name).
_SHIPPED_FILE = "L1_dynamics_models"
_CONVENTIONS = ("thesis", "standard")


@dataclass(frozen=True)
class ActuatorParameters:
    """First-order-plus-delay closed-loop actuator models, Dressler (2012), eq. 6.11.

    Parameters
    ----------
    a : numpy.ndarray, shape (n,)
        Pole of each axis (dimensionless, ``0 < a < 1`` for a stable lag).
    b : numpy.ndarray, shape (n,)
        Gain coefficient of each axis (output unit per input unit).
    sample_time : float
        Sampling time ``Ts`` [s].
    delay_samples : int
        Dead time in samples (the ``q^-5``).
    bandwidth_hz_reported : float or None
        Bandwidth stated by the source [Hz].
    source : str
        Where the numbers come from.
    """

    a: np.ndarray
    b: np.ndarray
    sample_time: float
    delay_samples: int
    bandwidth_hz_reported: float | None = None
    source: str = ""


@dataclass(frozen=True)
class ComplianceParameters:
    """Identified structural model in physical form, Dressler (2012), eqs. 6.14-6.15.

    Parameters
    ----------
    M, D, K : numpy.ndarray, shape (n, n)
        Mass-, damping- and stiffness-like matrices (identified, not symmetric).
    B : numpy.ndarray, shape (n, m)
        Input matrix.
    convention : str
        Sign convention of ``D`` and ``K`` (see :class:`gtmodel.robots.structural.PhysicalModel`).
    modes_hz_reported : numpy.ndarray, shape (n,)
        Modes stated by the source [Hz].
    lowest_resonance_with_wrist_hz, lowest_resonance_without_wrist_hz : numpy.ndarray, shape (2,)
        Ranges of the lowest resonance of the robot stated by the source [Hz].
    source : str
        Where the numbers come from.
    """

    M: np.ndarray
    D: np.ndarray
    K: np.ndarray
    B: np.ndarray
    convention: str
    modes_hz_reported: np.ndarray
    lowest_resonance_with_wrist_hz: np.ndarray
    lowest_resonance_without_wrist_hz: np.ndarray
    source: str = ""


@dataclass(frozen=True)
class DynamicsModels:
    """The contents of a dynamics-models data file.

    Parameters
    ----------
    name : str
        Name of the set.
    description : str
        One line.
    actuators : ActuatorParameters
        Closed-loop actuator models (6.11).
    compliance : ComplianceParameters
        Structural model (6.14).
    path : pathlib.Path or None
        The file read.
    """

    name: str
    description: str
    actuators: ActuatorParameters
    compliance: ComplianceParameters
    path: Path | None = None


def _actuators(r: _Reader) -> ActuatorParameters:
    r.check_keys({"source", "sample_time_s", "delay_samples", "a", "b", "bandwidth_hz_reported"})
    a_raw = r.data.get("a")
    n = len(a_raw) if isinstance(a_raw, list) and a_raw else 0
    if n == 0:
        raise r.error("a", "a non-empty list of numbers", a_raw)
    a = r.array("a", (n,))
    if np.any(np.abs(a) >= 1.0):
        raise r.error("a", "poles inside the unit circle (|a_i| < 1)", a.tolist())
    b = r.array("b", (n,))
    if np.any(b == 0):
        raise r.error("b", "non-zero gains", b.tolist())
    delay = r.data.get("delay_samples")
    if isinstance(delay, bool) or not isinstance(delay, int) or delay < 0:
        raise r.error("delay_samples", "a non-negative integer", delay)
    bw = r.data.get("bandwidth_hz_reported")
    return ActuatorParameters(
        a=a,
        b=b,
        sample_time=r.number("sample_time_s", positive=True),
        delay_samples=int(delay),
        bandwidth_hz_reported=None if bw is None else r.number("bandwidth_hz_reported", positive=True),
        source=r.string("source", default=""),
    )


def _compliance(r: _Reader) -> ComplianceParameters:
    r.check_keys(
        {
            "source",
            "convention",
            "M",
            "D",
            "K",
            "B",
            "modes_hz_reported",
            "lowest_resonance_with_wrist_hz",
            "lowest_resonance_without_wrist_hz",
        }
    )
    m_raw = r.data.get("M")
    n = len(m_raw) if isinstance(m_raw, list) and m_raw else 0
    if n == 0:
        raise r.error("M", "a square matrix (list of rows)", m_raw)
    M = r.array("M", (n, n))
    if abs(np.linalg.det(M)) <= 1e-12 * max(1.0, float(np.max(np.abs(M)))) ** n:
        raise r.error("M", "a non-singular matrix", M.tolist())
    convention = r.string("convention", default="thesis")
    if convention not in _CONVENTIONS:
        raise r.error("convention", f"one of {', '.join(_CONVENTIONS)}", convention)
    b_raw = r.data.get("B")
    m = len(b_raw[0]) if isinstance(b_raw, list) and b_raw and isinstance(b_raw[0], list) and b_raw[0] else 0
    B = r.array("B", (n, m)) if "B" in r.data else np.eye(n)
    return ComplianceParameters(
        M=M,
        D=r.array("D", (n, n)),
        K=r.array("K", (n, n)),
        B=B,
        convention=convention,
        modes_hz_reported=r.array("modes_hz_reported", (n,), positive=True),
        lowest_resonance_with_wrist_hz=r.array("lowest_resonance_with_wrist_hz", (2,), positive=True),
        lowest_resonance_without_wrist_hz=r.array("lowest_resonance_without_wrist_hz", (2,), positive=True),
        source=r.string("source", default=""),
    )


def dynamics_models_from_mapping(data: Mapping[str, Any], origin: str = "<mapping>", path: Path | None = None) -> DynamicsModels:
    """Validate a parsed dynamics-models file.

    Dressler (2012), eqs. 6.11 (``[actuators]``) and 6.14-6.15 (``[compliance]``).

    Parameters
    ----------
    data : Mapping[str, Any]
        The parsed TOML document.
    origin : str, optional
        Name used in error messages (usually the file path).
    path : pathlib.Path or None, optional
        Recorded as :attr:`DynamicsModels.path`.

    Returns
    -------
    DynamicsModels
        The validated models.

    Raises
    ------
    ParameterError
        A table or field is missing, unknown, of the wrong shape or out of range; the
        message names ``origin`` and the field.
    """
    r = _Reader(data, origin)
    r.check_keys({"name", "description", "actuators", "compliance"})
    return DynamicsModels(
        name=r.string("name"),
        description=r.string("description", default=""),
        actuators=_actuators(r.sub("actuators")),
        compliance=_compliance(r.sub("compliance")),
        path=path,
    )


def load_dynamics_models(name_or_path: str | Path) -> DynamicsModels:
    """Load and validate a dynamics-models file by shipped name or path.

    Dressler (2012), eqs. 6.11 and 6.14-6.15 (the shipped ``L1_dynamics_models``).

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A shipped name (``"L1_dynamics_models"``) or the path of a TOML file in the same
        format.

    Returns
    -------
    DynamicsModels
        The validated models.

    Raises
    ------
    ParameterError
        Unknown name, unreadable file, TOML syntax error or an invalid field (the message
        names the file and the field).
    """
    data, origin, path = _read_data_file(
        name_or_path, "dynamics-models file", f"not a shipped name ({_SHIPPED_FILE}) and no such file", any_suffix_must_exist=True
    )
    return dynamics_models_from_mapping(data, origin=origin, path=path)


def loop_period(source: str | Path | DynamicsModels | None = None) -> float:
    """Period of a robot's controller loop [s], read from its data file.

    The loop period is the sample time of the closed-loop actuator models (Dressler (2012),
    eq. 6.11), ``[actuators] sample_time_s`` of the dynamics-models file. Without a file,
    the fallback :data:`gtmodel.defaults.LOOP_PERIOD_S` (via ``defaults["loop.period"]``).

    Parameters
    ----------
    source : str, pathlib.Path, DynamicsModels or None, optional
        Shipped name (e.g. ``"L1_dynamics_models"``), file path or loaded models; None
        (default): no robot is known.

    Returns
    -------
    float
        The period [s], positive.

    Raises
    ------
    ParameterError
        The file is invalid (see :func:`load_dynamics_models`).
    """
    if source is None:
        return float(defaults["loop.period"])
    models = source if isinstance(source, DynamicsModels) else load_dynamics_models(source)
    return float(models.actuators.sample_time)


def _check_dt(dt: Any) -> float:
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating, np.integer)) or not math.isfinite(dt) or dt <= 0:
        raise InputError(f"dt: expected a positive sampling time in s, got {dt!r}")
    return float(dt)


def actuator_tf(a: float, b: float, dt: float = LOOP_PERIOD_S, delay: int = 5) -> control.TransferFunction:
    """One closed-loop actuator model as a discrete transfer function.

    Dressler (2012), eq. 6.11: ``G(q) = q^-delay b / (1 - a q^-1)``, i.e.
    ``y_k = a y_(k-1) + b u_(k-delay)``; as a function of ``z`` it is
    ``b z^-delay z / (z - a) = b / (z^(delay-1) (z - a))``: numerator ``[b]``, denominator
    ``[1, -a]`` followed by ``delay - 1`` zeros.

    Parameters
    ----------
    a : float
        Pole (dimensionless, ``|a| < 1``).
    b : float
        Gain coefficient (non-zero).
    dt : float, optional
        Sampling time [s] (default the loop period, :data:`gtmodel.defaults.LOOP_PERIOD_S`).
    delay : int, optional
        Dead time in samples (default 5; ``delay = 0`` gives ``b z / (z - a)``, with a
        direct feedthrough).

    Returns
    -------
    control.TransferFunction
        SISO, discrete with ``dt``.

    Raises
    ------
    InputError
        Non-finite or out-of-range ``a``, zero ``b``, bad ``dt`` or ``delay``.
    """
    dt = _check_dt(dt)
    for name, value in (("a", a), ("b", b)):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value):
            raise InputError(f"{name}: expected a finite number, got {value!r}")
    if abs(a) >= 1.0:
        raise InputError(f"a: expected a stable pole |a| < 1, got {a!r}")
    if b == 0:
        raise InputError("b: expected a non-zero gain, got 0")
    if isinstance(delay, bool) or not isinstance(delay, (int, np.integer)) or delay < 0:
        raise InputError(f"delay: expected a non-negative integer number of samples, got {delay!r}")
    if delay == 0:
        return control.tf([float(b), 0.0], [1.0, -float(a)], dt)
    den = [1.0, -float(a)] + [0.0] * (int(delay) - 1)
    return control.tf([float(b)], den, dt)


def actuator_models(source: str | Path | DynamicsModels) -> list[control.TransferFunction]:
    """The closed-loop actuator models of every axis as discrete transfer functions.

    Dressler (2012), eq. 6.11, with ``Ts`` and the delay from the data file.

    Parameters
    ----------
    source : str, pathlib.Path or DynamicsModels
        Shipped name (e.g. ``"L1_dynamics_models"``), file path or loaded models.

    Returns
    -------
    list of control.TransferFunction
        One per axis, ``dt = sample_time_s``.

    Raises
    ------
    ParameterError
        The file is invalid (see :func:`load_dynamics_models`).
    """
    models = source if isinstance(source, DynamicsModels) else load_dynamics_models(source)
    act = models.actuators
    return [actuator_tf(float(a), float(b), act.sample_time, act.delay_samples) for a, b in zip(act.a, act.b)]


def bandwidth(sys: control.LTI, dbdrop: float = -3.0) -> float:
    """Bandwidth of a SISO system in Hz: first frequency ``dbdrop`` below the DC gain.

    Continuous systems: :func:`control.bandwidth`. Discrete systems: the same definition
    on ``z = exp(j w dt)`` (see the module docstring for why); the search is limited to
    the Nyquist frequency. Dressler (2012), eq. 6.11 and the ~1.1 Hz of ch. 6.3.

    Parameters
    ----------
    sys : control.LTI
        SISO transfer function or state-space system with finite non-zero DC gain.
    dbdrop : float, optional
        Gain drop in dB defining the bandwidth (negative, default -3).

    Returns
    -------
    float
        Bandwidth [Hz]; ``inf`` if the gain never drops that far (below Nyquist for a
        discrete system).

    Raises
    ------
    InputError
        Not a SISO LTI system, ``dbdrop`` not negative, or an infinite or zero DC gain.
    """
    if not isinstance(sys, control.LTI) or not sys.issiso():
        raise InputError(f"sys: expected a SISO control.LTI system, got {type(sys).__name__}")
    if isinstance(dbdrop, bool) or not isinstance(dbdrop, (int, float)) or not math.isfinite(dbdrop) or dbdrop >= 0:
        raise InputError(f"dbdrop: expected a negative number of dB, got {dbdrop!r}")
    dc = complex(np.squeeze(sys.dcgain()))
    if not np.isfinite(abs(dc)) or abs(dc) == 0.0:
        raise InputError(f"sys: the DC gain is {dc}: the bandwidth needs a finite non-zero DC gain")
    if sys.isctime():
        return float(control.bandwidth(sys, dbdrop)) / (2.0 * math.pi)
    dt = float(sys.dt) if sys.dt is not True else 1.0
    level = abs(dc) * 10.0 ** (dbdrop / 20.0)
    nyquist = math.pi / dt * (1.0 - 1e-9)  # python-control warns at and above Nyquist
    omega = np.logspace(math.log10(nyquist) - 6.0, math.log10(nyquist), 2000)

    def gain(w: np.ndarray | float) -> np.ndarray:
        return np.abs(np.squeeze(sys.frequency_response(np.atleast_1d(w)).magnitude))

    below = np.nonzero(gain(omega) < level)[0]
    if below.size == 0:
        return math.inf
    i = int(below[0])
    if i == 0:
        return float(omega[0]) / (2.0 * math.pi)
    w = scipy.optimize.brentq(lambda x: float(gain(x)) - level, omega[i - 1], omega[i], xtol=1e-12)
    return float(w) / (2.0 * math.pi)


def step(sys: control.LTI, duration: float = 2.0, amplitude: float = 1.0) -> control.TimeResponseData:
    """Step response of an actuator model (or any SISO system) over ``duration`` seconds.

    Dressler (2012), eq. 6.11; computed with :func:`control.step_response`.

    Parameters
    ----------
    sys : control.LTI
        SISO system.
    duration : float, optional
        Length [s] (default 2).
    amplitude : float, optional
        Step height (input unit, default 1).

    Returns
    -------
    control.TimeResponseData
        ``.time`` [s], ``.outputs`` (scaled by ``amplitude``), ``.inputs``.

    Raises
    ------
    InputError
        Non-positive ``duration``, non-finite ``amplitude`` or a non-SISO system.
    """
    if not isinstance(sys, control.LTI) or not sys.issiso():
        raise InputError(f"sys: expected a SISO control.LTI system, got {type(sys).__name__}")
    if not isinstance(duration, (int, float)) or not math.isfinite(duration) or duration <= 0:
        raise InputError(f"duration: expected a positive time in s, got {duration!r}")
    if not isinstance(amplitude, (int, float)) or not math.isfinite(amplitude):
        raise InputError(f"amplitude: expected a finite number, got {amplitude!r}")
    if sys.isdtime(strict=True):
        t = np.arange(0.0, duration + 0.5 * sys.dt, sys.dt)
    else:
        t = np.linspace(0.0, duration, 1001)
    resp = control.step_response(sys, t)
    return control.TimeResponseData(
        resp.time, np.squeeze(resp.outputs) * amplitude, inputs=np.full(resp.time.shape, float(amplitude)), issiso=True
    )


def simulate(sys: control.LTI, t: np.ndarray, u: np.ndarray) -> control.TimeResponseData:
    """Response of an actuator model (or any SISO system) to an input signal.

    Dressler (2012), eq. 6.11; computed with :func:`control.forced_response` from zero
    initial state. For a discrete system the times must be the system's samples.

    Parameters
    ----------
    sys : control.LTI
        SISO system.
    t : numpy.ndarray, shape (N,)
        Strictly increasing times [s]; for a discrete system equally spaced by ``sys.dt``.
    u : numpy.ndarray, shape (N,)
        Input signal (finite).

    Returns
    -------
    control.TimeResponseData
        ``.time``, ``.outputs`` shape (N,), ``.inputs``.

    Raises
    ------
    InputError
        Non-SISO system, non-finite or mismatched ``t``/``u``, non-increasing times or a
        time step other than ``sys.dt``.
    """
    if not isinstance(sys, control.LTI) or not sys.issiso():
        raise InputError(f"sys: expected a SISO control.LTI system, got {type(sys).__name__}")
    t = as_times(t)
    u = np.asarray(u, dtype=float)
    if u.shape != t.shape:
        raise InputError(f"u: expected shape {t.shape} like t, got {u.shape}")
    if not np.all(np.isfinite(u)):
        raise InputError(f"u: non-finite value at index {int(np.nonzero(~np.isfinite(u))[0][0])}")
    if sys.isdtime(strict=True):
        steps = np.diff(t)
        if not np.allclose(steps, sys.dt, rtol=1e-6, atol=0.0):
            raise InputError(f"t: expected equally spaced samples dt = {sys.dt} s of the discrete system, got steps {steps.min():g}..{steps.max():g} s")
    return control.forced_response(sys, t, u)
