"""The identification regressor ``tau = Y theta + tau_0`` from the symbolic inverse dynamics.

Dressler (2012), ch. 6.2: the inverse dynamics (6.7) with the cart friction (6.8) is
linear in the parameters ``theta = (m_p, m_c, m_a, f_c, f_v)``. The regressor ``Y`` is
not written by hand: the inverse dynamics of :class:`gtmodel.robots.GantryTau3Dynamics`
is built with the free parameters of a model variant
(:mod:`~gtmodel.calibration.identification.variants`) as CasADi symbols and
``Y = ca.jacobian(tau, theta)``; ``tau_0`` (the forces of the parameters that are *not*
estimated, e.g. friction taken from Table 6.1) is the same expression at ``theta = 0``.
On many samples the graph runs compiled to C (a cached shared library).
"""

from __future__ import annotations

import logging
from functools import cached_property
from pathlib import Path
from typing import Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_signal
from gtmodel._compiler import compiled_function
from gtmodel.calibration.identification.variants import ModelVariant, _symbolic_dynamics, _unit, _value_of, get_variant
from gtmodel.errors import InputError, SingularConfigurationError, UnreachablePoseError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH
from gtmodel.robots.kinematic_expressions import configuration_signs, fk_expression, link_cosines_expression
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE
from gtmodel.robots.parameters import DynamicParameters, RobotParameters, load_parameters

__all__ = ["DynamicRegressor"]

_log = logging.getLogger("gtmodel")

#: Samples per mapped evaluation of the regressor, a power of two (building a CasADi map
#: costs about 2 us per sample, more than the compiled evaluation; the remainder of a log
#: is split into powers of two, so that a regressor builds a few small maps once).
_CHUNK = 4096
#: From this many samples :meth:`DynamicRegressor.evaluate` runs the regressor compiled to
#: C (below it the CasADi interpreter is faster than a first compilation).
_COMPILE_MIN_SAMPLES = 5000
#: Compiler flags of the regressor's shared library (no fast-math: IEEE results).
_COMPILE_FLAGS = ("-O3", "-fPIC", "-shared")


def _chunks(n: int) -> list[tuple[int, int]]:
    """(start, size) of the mapped evaluations of n samples: chunks of :data:`_CHUNK`, then
    the remainder's binary digits (map sizes from a fixed small set)."""
    out = [(s, _CHUNK) for s in range(0, n - n % _CHUNK, _CHUNK)]
    start = n - n % _CHUNK
    size = _CHUNK // 2
    while size:
        if (n - start) >= size:
            out.append((start, size))
            start += size
        size //= 2
    return out


class DynamicRegressor:
    """The regressor ``tau = Y theta + tau_0`` of the inverse dynamics, Dressler (2012), eqs. 6.7-6.8.

    ``Y = d tau / d theta`` by CasADi from the symbolic inverse dynamics of
    :class:`gtmodel.robots.GantryTau3Dynamics` (exact, the model is linear in ``theta``).

    Parameters
    ----------
    parameters : RobotParameters or str or pathlib.Path
        Parameter set (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML file or the parameters): kinematics, gravity and the Table 6.1 friction of the
        variants that subtract it.
    variant : str or ModelVariant, optional
        Which parameters are estimated (default ``"model_2"``; see :data:`VARIANTS`).
    configuration : int or sequence of int, optional
        IK configuration (default 0, see :meth:`gtmodel.robots.GantryTau3Kinematics.ik`).
    solution : {1, -1}, optional
        FK assembly used for cart-coordinate data (default 1).
    friction : {"exact", "tanh", "piecewise"}, optional
        Form of the sign (default ``"exact"``; ``"tanh"`` for the excitation design).
    friction_width : float, optional
        Velocity width [m/s] of the smooth forms.

    Raises
    ------
    InputError
        Unknown variant, invalid configuration or friction form, or an asymmetric variant
        for a parameter set without Table 6.1 friction.
    """

    def __init__(
        self,
        parameters: RobotParameters | str | Path,
        variant: str | ModelVariant = "model_2",
        configuration: int | Sequence[int] = 0,
        solution: int = 1,
        friction: str = "exact",
        friction_width: float = DEFAULT_FRICTION_WIDTH,
    ) -> None:
        self.robot = load_parameters(parameters)
        self.variant = get_variant(variant)
        if self.variant.asymmetric and self.robot.dynamics.asymmetric is None:
            raise InputError(f"variant {self.variant.name!r} needs the asymmetric friction (Table 6.1) of parameter set {self.robot.name!r}, which has none")
        self.model = GantryTau3Dynamics(self.robot, friction=friction, friction_width=friction_width, asymmetric=self.variant.asymmetric)
        self.signs = configuration_signs(configuration)
        if solution not in (1, -1) or isinstance(solution, bool):
            raise InputError(f"solution: expected +1 or -1, got {solution!r}")
        self.solution = float(solution)
        self._maps: dict[tuple[str, bool, int], ca.Function] = {}
        self._evaluation: dict[tuple[str, bool], ca.Function] = {}

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the estimated parameters, the order of ``theta``."""
        return self.variant.free

    @property
    def n_parameters(self) -> int:
        """Number of estimated parameters."""
        return len(self.variant.free)

    def units(self) -> tuple[str, ...]:
        """Unit of every parameter (kg, N or N s/m).

        Returns
        -------
        tuple of str
            One unit per name of :attr:`names`.
        """
        return tuple(_unit(n) for n in self.names)

    def _expressions(self, T, T_dot, T_ddot):
        theta, d = _symbolic_dynamics(self.variant, self.robot.dynamics)
        tau, t = self.model.inverse_dynamics_expression(T, T_dot, T_ddot, ca.DM(self.signs), d)
        Y = ca.densify(ca.jacobian(tau, theta))
        tau0 = ca.densify(ca.substitute(tau, theta, ca.DM.zeros(theta.numel())))
        cos_min = ca.mmin(ca.fabs(link_cosines_expression(T, t["q"], self.model.As, self.model.v)))
        return Y, tau0, t, cos_min

    @cached_property
    def tcp_function(self) -> ca.Function:
        """CasADi Function ``regressor_tcp(T, T_dot, T_ddot) -> (Y, tau0, q_dot, disc, cos_min)``.

        ``Y`` (3, p) and ``tau0`` (3) [N] of eqs. 6.7/6.8 for a TCP motion; ``disc`` (3) is
        the IK discriminant (negative: unreachable), ``cos_min`` the smallest link-guideway
        cosine (zero: singular).
        """
        T, T_dot, T_ddot = (ca.SX.sym(n, 3) for n in ("T", "T_dot", "T_ddot"))
        Y, tau0, t, cos_min = self._expressions(T, T_dot, T_ddot)
        return ca.Function("regressor_tcp", [T, T_dot, T_ddot], [Y, tau0, t["q_dot"], t["disc"], cos_min],
                           ["T", "T_dot", "T_ddot"], ["Y", "tau0", "q_dot", "disc", "cos_min"])

    @cached_property
    def cart_function(self) -> ca.Function:
        """CasADi Function ``regressor_cart(q, q_dot, q_ddot) -> (Y, tau0, cart_velocity, h2, cos_min)``.

        The TCP motion comes from the forward kinematics (eq. 4.9) differentiated by CasADi:
        ``T_dot = dT/dq q_dot``, ``T_ddot = dT/dq q_ddot + d(dT/dq q_dot)/dq q_dot``; ``h2``
        negative means the joint values admit no pose.
        """
        q, q_dot, q_ddot = (ca.SX.sym(n, 3) for n in ("q", "q_dot", "q_ddot"))
        T, h2, _ = fk_expression(q, self.solution, self.model.L, self.model.As, self.model.v)
        T_dot = ca.jtimes(T, q, q_dot)
        T_ddot = ca.jtimes(T_dot, q, q_dot) + ca.jtimes(T, q, q_ddot)
        Y, tau0, _, cos_min = self._expressions(T, T_dot, T_ddot)
        return ca.Function("regressor_cart", [q, q_dot, q_ddot], [Y, tau0, q_dot, h2, cos_min],
                           ["q", "q_dot", "q_ddot"], ["Y", "tau0", "cart_velocity", "h2", "cos_min"])

    def _evaluation_function(self, coordinates: str, compiled: bool) -> ca.Function:
        """:attr:`cart_function` or :attr:`tcp_function` with ``Y`` transposed (so that a map
        writes (N, 3, p) in C order) and common subexpressions merged (:func:`casadi.cse`),
        compiled to C if ``compiled`` (see :func:`gtmodel._compiler.compiled_function`)."""
        key = (coordinates, compiled)
        if key not in self._evaluation:
            f = self.cart_function if coordinates == "cart" else self.tcp_function
            xs = f.sx_in()
            outs = f.call(xs)
            outs = ca.cse([outs[0].T, *outs[1:]])
            g = ca.Function(f"{f.name()}_eval", xs, outs, f.name_in(), f.name_out())
            if compiled:
                g, how = compiled_function(g, _COMPILE_FLAGS, "regressor")
                _log.info("DynamicRegressor (%s, variant %s, %s coordinates): %s", self.robot.name, self.variant.name, coordinates, how)
            self._evaluation[key] = g
        return self._evaluation[key]

    def evaluate(self, x: np.typing.ArrayLike, x_dot: np.typing.ArrayLike, x_ddot: np.typing.ArrayLike, coordinates: str = "cart") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Regressor on N samples, Dressler (2012), eqs. 6.7-6.8.

        Parameters
        ----------
        x, x_dot, x_ddot : array_like, shape (N, 3)
            Cart positions [m], velocities [m/s], accelerations [m/s^2]
            (``coordinates="cart"``) or the TCP's (``"tcp"``).
        coordinates : {"cart", "tcp"}, optional
            Meaning of ``x``.

        Returns
        -------
        Y : numpy.ndarray, shape (N, 3, p)
            Regressor [N per parameter unit].
        tau0 : numpy.ndarray, shape (N, 3)
            Forces of the parameters not estimated [N].
        q_dot : numpy.ndarray, shape (N, 3)
            Cart velocities [m/s].

        Raises
        ------
        InputError
            Wrong shapes, non-finite values or an unknown ``coordinates``.
        UnreachablePoseError
            A sample admits no pose (names the sample).
        SingularConfigurationError
            A link is perpendicular to its guideway at some sample (names it).

        Notes
        -----
        From a few thousand samples the CasADi graph (common subexpressions merged by
        :func:`casadi.cse`) runs as C generated from it and compiled once into a shared
        library cached under ``$GTMODEL_CACHE_DIR`` (default ``~/.cache/gtmodel``),
        mapped over the samples; without a C compiler (or with ``GTMODEL_COMPILE=0``)
        the CasADi interpreter runs the same graph. The path taken is logged (INFO).
        """
        if coordinates not in ("cart", "tcp"):
            raise InputError(f"coordinates: expected 'cart' or 'tcp', got {coordinates!r}")
        x = as_signal(x, "x", 3)
        n = x.shape[0]
        arrs = [x, as_signal(x_dot, "x_dot", 3, n, like="x"), as_signal(x_ddot, "x_ddot", 3, n, like="x")]
        compiled = n >= _COMPILE_MIN_SAMPLES
        f = self._evaluation_function(coordinates, compiled)
        p = self.n_parameters
        n_reach = f.nnz_out(3)
        Y = np.empty((n, 3, max(p, 1)))
        tau0, q_dot, cos_min = np.empty((n, 3)), np.empty((n, 3)), np.empty(n)
        reach = np.empty((n, n_reach))
        # evaluation through Function.buffer: the mapped CasADi graph writes into the NumPy
        # arrays (column-major (p, 3) blocks Y^T per sample = C-order (3, p)); chunks cap the map size
        for start, m in _chunks(n):
            key = (coordinates, compiled, m)
            if key not in self._maps:
                self._maps[key] = f.map(m) if m > 1 else f
            fb, ev = self._maps[key].buffer()
            args = [np.ascontiguousarray(a[start:start + m]) for a in arrs]
            outs = [Y[start:start + m], tau0[start:start + m], q_dot[start:start + m], reach[start:start + m], cos_min[start:start + m]]
            for i, a in enumerate(args):
                fb.set_arg(i, memoryview(a))
            for i, o in enumerate(outs):
                if i == 0 and p == 0:
                    continue
                fb.set_res(i, memoryview(o))
            ev()
        bad = np.flatnonzero(np.any(reach < 0, axis=1))
        if bad.size:
            k = int(bad[0])
            raise UnreachablePoseError(f"{'q' if coordinates == 'cart' else 'T'}: sample {k} ({arrs[0][k].tolist()}) admits no pose")
        if np.any(cos_min < SINGULARITY_TOLERANCE):
            k = int(np.argmin(cos_min))
            raise SingularConfigurationError(f"sample {k}: a link is perpendicular to its guideway (singular Jacobian, eq. 6.5)")
        return (Y if p else np.zeros((n, 3, 0))), tau0, q_dot

    def forces(self, theta: np.typing.ArrayLike, x: np.typing.ArrayLike, x_dot: np.typing.ArrayLike, x_ddot: np.typing.ArrayLike, coordinates: str = "cart") -> np.ndarray:
        """Actuator forces ``Y theta + tau0`` of a parameter vector (eqs. 6.7-6.8).

        Parameters
        ----------
        theta : array_like, shape (p,)
            Parameters in the order of :attr:`names` [kg, N, N s/m].
        x, x_dot, x_ddot : array_like, shape (N, 3)
            Motion, see :meth:`evaluate`.
        coordinates : {"cart", "tcp"}, optional
            Meaning of ``x``.

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            Actuator forces [N].

        Raises
        ------
        InputError
            ``theta`` of the wrong length or non-finite, or invalid motion data.
        """
        th = np.asarray(theta, dtype=float).ravel()
        if th.size != self.n_parameters or not np.all(np.isfinite(th)):
            raise InputError(f"theta: expected {self.n_parameters} finite values ({', '.join(self.names)}), got {np.asarray(theta).tolist()}")
        Y, tau0, _ = self.evaluate(x, x_dot, x_ddot, coordinates)
        return Y @ th + tau0

    def theta_of(self, dynamics: DynamicParameters | None = None) -> np.ndarray:
        """The values of the estimated parameters in a parameter set (e.g. the truth).

        Parameters
        ----------
        dynamics : DynamicParameters, optional
            Source of the values (default: the regressor's parameter set). Asymmetric
            names are read from its Table 6.1 friction; ``f_c`` of a tied variant is the
            mean of ``f_c+`` and ``f_c-``.

        Returns
        -------
        numpy.ndarray, shape (p,)
            Values in the order of :attr:`names`.

        Raises
        ------
        InputError
            An asymmetric name without Table 6.1 friction in ``dynamics``.
        """
        d = self.robot.dynamics if dynamics is None else dynamics
        return np.array([_value_of(d, n, self.variant) for n in self.names])
