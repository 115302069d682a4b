"""The Gantry-Tau as a model of the modelling layer (:class:`gtmodel.modeling.Model`).

Two choices of states, the same equations (:mod:`gtmodel.robots.dynamics`):

``"tcp"``
    states ``T`` (3) [m] and ``T_dot`` (3) [m/s]; the carts follow from the IK
    (eq. 4.9) and eq. 6.5. Equations: ``der(T) = T_dot`` and
    ``M(T) der(T_dot) + h + G = J^-T (tau - f_fric(q_dot))`` (eqs. 6.7, 6.8).
``"cart"``
    states ``q`` (3) [m] and ``q_dot`` (3) [m/s]; the TCP follows from the FK.
    Equations: ``der(q) = q_dot`` and ``M(q) der(q_dot) + h + G = tau - f_fric(q_dot)``.

Input ``tau`` (3) [N], the actuator forces. Outputs: the other coordinate set and its
velocity, the friction force ``f_fric`` [N], kinetic ``KE`` and potential ``V`` energy
[J], and ``power`` = ``tau . q_dot`` [W].
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca

from gtmodel.errors import InputError
from gtmodel.modeling import Model
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH
from gtmodel.robots.kinematic_expressions import configuration_signs
from gtmodel.robots.parameters import RobotParameters

__all__ = ["STATE_CHOICES", "gantry_tau_model"]

#: Allowed state choices of :func:`gantry_tau_model`.
STATE_CHOICES = ("tcp", "cart")


def gantry_tau_model(
    parameters: RobotParameters | str,
    states: str = "tcp",
    friction: str = "tanh",
    friction_width: float = DEFAULT_FRICTION_WIDTH,
    asymmetric: bool = False,
    configuration: int | Sequence[int] = 0,
    solution: int = 1,
    name: str | None = None,
) -> Model:
    """Build the rigid-body Gantry-Tau model with friction (Dressler (2012), eqs. 6.7, 6.8).

    Parameters
    ----------
    parameters : RobotParameters or str or pathlib.Path
        Parameter set or its name/path.
    states : {"tcp", "cart"}, optional
        State choice (see the module docstring); default ``"tcp"``.
    friction : {"exact", "tanh", "piecewise"}, optional
        Form of the friction sign; default ``"tanh"`` (smooth, for optimisation).
    friction_width : float, optional
        Velocity width [m/s] of the smooth friction forms; default 0.01.
    asymmetric : bool, optional
        Use the asymmetric friction of Table 6.1.
    configuration : int or sequence of int, optional
        IK configuration used with TCP states (see
        :func:`gtmodel.robots.kinematic_expressions.configuration_signs`).
    solution : {1, -1}, optional
        FK assembly used with cart states.
    name : str, optional
        Model name; default ``"GantryTau_<set>_<states>"``.

    Returns
    -------
    gtmodel.modeling.Model
        States ``T``, ``T_dot`` (or ``q``, ``q_dot``), input ``tau``, outputs ``q``,
        ``q_dot`` (or ``T``, ``T_dot``), ``f_fric``, ``KE``, ``V``, ``power``.

    Raises
    ------
    InputError
        Unknown state choice, friction form, configuration or solution.
    ParameterError
        Invalid parameter set.
    """
    if states not in STATE_CHOICES:
        raise InputError(f"states: expected one of {', '.join(STATE_CHOICES)}, got {states!r}")
    if solution not in (1, -1):
        raise InputError(f"solution: expected +1 or -1, got {solution!r}")
    dyn = GantryTau3Dynamics(parameters, friction=friction, friction_width=friction_width, asymmetric=asymmetric)
    s = configuration_signs(configuration)
    m = Model(name or f"GantryTau_{dyn.parameters.name}_{states}")
    tau = m.input("tau", 3)
    if states == "tcp":
        T = m.state("T", 3)
        T_dot = m.state("T_dot", 3)
        t = dyn.tcp_terms(T, T_dot, s)
        q_dot = t["q_dot"]
        f_fric = dyn.friction_force(q_dot)
        m.equation(m.der(T), T_dot)
        m.equation(t["M"] @ m.der(T_dot) + t["h"] + t["G"], t["Jinv"].T @ (tau - f_fric))
        m.output("q", t["q"])
        m.output("q_dot", q_dot)
    else:
        q = m.state("q", 3)
        q_dot = m.state("q_dot", 3)
        t = dyn.cart_terms(q, q_dot, float(solution))
        f_fric = dyn.friction_force(q_dot)
        m.equation(m.der(q), q_dot)
        m.equation(t["M"] @ m.der(q_dot) + t["h"] + t["G"], tau - f_fric)
        m.output("T", t["T"])
        m.output("T_dot", t["T_dot"])
    m.output("f_fric", f_fric)
    m.output("KE", t["KE"])
    m.output("V", t["V"])
    m.output("power", ca.dot(tau, q_dot))
    m.dynamics = dyn  # the object the equations came from (kinematics, parameters)
    return m
