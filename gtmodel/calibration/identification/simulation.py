"""Synthetic identification data: servo logs of an excitation motion and constant-velocity runs.

Dressler (2012), ch. 6.2 (the thesis' logs are not available): forces from the inverse
dynamics of a true parameter set, an optional Stribeck term the rigid-body model lacks,
Gaussian force and position noise and encoder quantisation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_signal
from gtmodel.calibration.identification.friction import ConstantVelocityData
from gtmodel.calibration.identification.signals import MotionLog
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.parameters import RobotParameters, load_parameters

__all__ = ["StribeckTerm", "simulate_log", "simulate_constant_velocity"]


@dataclass(frozen=True)
class StribeckTerm:
    """Low-speed friction the rigid-body model lacks: ``(f_s - f_c) exp(-(v/v_s)^2) sign(v)``.

    Added to simulated forces to reproduce the low-speed residual of Dressler (2012),
    ch. 6.2 (the Coulomb + viscous model of eq. 6.8 has no Stribeck effect).

    Parameters
    ----------
    amplitude : numpy.ndarray, shape (3,)
        ``f_s - f_c`` per cart [N] (static minus Coulomb friction).
    velocity : float
        Stribeck velocity ``v_s`` [m/s].
    """

    amplitude: np.ndarray = field(default_factory=lambda: np.array([40.0, 40.0, 40.0]))
    velocity: float = 0.02

    @cached_property
    def function(self) -> ca.Function:
        """CasADi Function ``stribeck(q_dot) -> f`` (3 in, 3 out) [m/s -> N]."""
        v = ca.SX.sym("q_dot", 3)
        f = ca.DM(np.asarray(self.amplitude, dtype=float)) * ca.exp(-((v / self.velocity) ** 2)) * ca.sign(v)
        return ca.Function("stribeck", [v], [f], ["q_dot"], ["f"])

    def force(self, q_dot: np.typing.ArrayLike) -> np.ndarray:
        """The Stribeck force at cart velocities.

        Parameters
        ----------
        q_dot : array_like, shape (N, 3)
            Cart velocities [m/s].

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            Force [N] (adds to the actuator force like friction).
        """
        v = as_signal(q_dot, "q_dot", 3)
        return np.asarray(self.function.map(v.shape[0])(v.T)).T


def simulate_log(
    trajectory: Any,
    duration: float,
    parameters: RobotParameters | str | Path,
    sample_time: float = LOOP_PERIOD_S,
    force_noise: float = 5.0,
    position_noise: float = 1e-6,
    position_resolution: float = 1e-6,
    stribeck: StribeckTerm | None = None,
    seed: int = 0,
    configuration: int | Sequence[int] = 0,
) -> tuple[MotionLog, dict[str, Any]]:
    """Synthetic servo log of an excitation motion (Dressler (2012), ch. 6.2 data, simulated).

    Forces from :meth:`gtmodel.robots.GantryTau3Dynamics.inverse_dynamics` of the parameter
    set (the L1 set holds Table 6.3 model 2), plus an optional Stribeck term the model
    lacks, plus Gaussian force noise; cart positions with Gaussian noise, quantised to the
    encoder resolution.

    Parameters
    ----------
    trajectory : object
        Has ``evaluate(t) -> (q, q_dot, q_ddot)`` with arrays (N, 3) [m, m/s, m/s^2], e.g.
        :class:`gtmodel.calibration.identification.FourierTrajectory`.
    duration : float
        Length of the log [s].
    parameters : RobotParameters or str or pathlib.Path
        The true robot (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML file or the parameters).
    sample_time : float, optional
        Sampling interval [s] (default 4 ms, the L1 servo rate).
    force_noise : float, optional
        Standard deviation of the force noise [N] (default 5 N).
    position_noise : float, optional
        Standard deviation of the position noise [m] (default 1 um).
    position_resolution : float, optional
        Encoder quantisation step [m] (default 1 um; 0 for none).
    stribeck : StribeckTerm, optional
        Unmodelled low-speed friction to add (default None).
    seed : int, optional
        Random seed.
    configuration : int or sequence of int, optional
        IK configuration (default 0).

    Returns
    -------
    log : MotionLog
        The noisy log (cart positions and forces).
    truth : dict
        ``t``, ``q``, ``q_dot``, ``q_ddot``, ``tau`` (noise-free, with the Stribeck term),
        ``tau_model`` (rigid-body model only) [SI].

    Raises
    ------
    InputError
        Invalid duration, sample time or noise levels.
    UnreachablePoseError
        The trajectory leaves the workspace.
    """
    for name, val, pos in (("duration", duration, True), ("sample_time", sample_time, True), ("force_noise", force_noise, False),
                           ("position_noise", position_noise, False), ("position_resolution", position_resolution, False)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and (val > 0 if pos else val >= 0)):
            raise InputError(f"{name}: expected a {'positive' if pos else 'non-negative'} number, got {val!r}")
    robot = load_parameters(parameters)
    dyn = GantryTau3Dynamics(robot, friction="exact")
    n = int(round(duration / sample_time)) + 1
    t = np.arange(n) * sample_time
    q, qd, qdd = (np.asarray(a, dtype=float) for a in trajectory.evaluate(t))
    kin = dyn.kinematics
    T = kin.fk(q)
    T_dot = np.einsum("nij,nj->ni", kin.jacobian(T, configuration), qd)
    T_ddot = kin.acceleration(T, T_dot, qdd, configuration)
    tau_model = dyn.inverse_dynamics(T, T_dot, T_ddot, configuration)
    tau = tau_model + (stribeck.force(qd) if stribeck is not None else 0.0)
    rng = np.random.default_rng(seed)
    tau_meas = tau + force_noise * rng.standard_normal(tau.shape)
    q_meas = q + position_noise * rng.standard_normal(q.shape)
    if position_resolution > 0:
        q_meas = np.round(q_meas / position_resolution) * position_resolution
    src = (f"SYNTHETIC: {robot.name} {robot.dynamics.source}; force noise {force_noise} N, position noise {position_noise} m, "
           f"resolution {position_resolution} m, {'Stribeck term added' if stribeck is not None else 'no Stribeck term'}, seed {seed}")
    return MotionLog(t=t, tau=tau_meas, q=q_meas, source=src), {"t": t, "q": q, "q_dot": qd, "q_ddot": qdd, "tau": tau, "tau_model": tau_model, "T": T}




def simulate_constant_velocity(
    poses: np.typing.ArrayLike,
    speeds: np.typing.ArrayLike,
    parameters: RobotParameters | str | Path,
    force_noise: float = 2.0,
    directions: str = "both",
    asymmetric: bool = True,
    seed: int = 0,
    configuration: int | Sequence[int] = 0,
) -> ConstantVelocityData:
    """Synthetic constant-velocity runs along the guideways (Dressler (2012), eq. 6.9, Table 6.1).

    The TCP moves along x (all carts together) at each speed through each pose; the mean
    force is the inverse dynamics (eqs. 6.7/6.8, zero acceleration) with the Table 6.1
    asymmetric friction (or the symmetric one) plus Gaussian noise of the mean.

    Parameters
    ----------
    poses : array_like, shape (P, 3)
        TCP positions [m].
    speeds : array_like, shape (S,)
        Positive TCP speeds [m/s] (the thesis: 15 speeds up to 1 m/s).
    parameters : RobotParameters or str or pathlib.Path
        The true robot (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML file or the parameters).
    force_noise : float, optional
        Standard deviation of each mean force [N] (default 2 N).
    directions : {"both", "positive", "negative"}, optional
        Which directions are run.
    asymmetric : bool, optional
        Table 6.1 asymmetric friction (default True) or the symmetric one.
    seed : int, optional
        Random seed.
    configuration : int or sequence of int, optional
        IK configuration (default 0).

    Returns
    -------
    ConstantVelocityData

    Raises
    ------
    InputError
        Invalid poses, speeds or options.
    """
    P = as_signal(np.atleast_2d(np.asarray(poses, dtype=float)), "poses", 3)
    S = np.asarray(speeds, dtype=float).ravel()
    if S.size == 0 or not np.all(np.isfinite(S)) or np.any(S <= 0):
        raise InputError(f"speeds: expected positive finite speeds in m/s, got {S.tolist()}")
    if directions not in ("both", "positive", "negative"):
        raise InputError(f"directions: expected 'both', 'positive' or 'negative', got {directions!r}")
    signs = {"both": (1.0, -1.0), "positive": (1.0,), "negative": (-1.0,)}[directions]
    dyn = GantryTau3Dynamics(load_parameters(parameters), asymmetric=asymmetric)
    T, Td, pose = [], [], []
    for k, p in enumerate(P):
        for s in S:
            for sg in signs:
                T.append(p)
                Td.append([sg * s, 0.0, 0.0])
                pose.append(k)
    T, Td = np.array(T), np.array(Td)
    tau = dyn.inverse_dynamics(T, Td, np.zeros_like(T), configuration)
    qd = np.einsum("nij,nj->ni", dyn.kinematics.jacobian_inverse(T, configuration), Td)
    rng = np.random.default_rng(seed)
    return ConstantVelocityData(T, qd, tau + force_noise * rng.standard_normal(tau.shape), np.array(pose))
