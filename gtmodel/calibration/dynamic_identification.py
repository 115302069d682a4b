"""Identification of the rigid-body and friction parameters of the Gantry-Tau.

Dressler (2012), ch. 6.2: the inverse dynamics (6.7) with the cart friction (6.8) is
linear in the parameters ``theta = (m_p, m_c, m_a, f_c, f_v)``::

    tau = Y(T, T_dot, T_ddot) theta + tau_0

The regressor ``Y`` is not written by hand: the inverse dynamics of
:class:`gtmodel.robots.GantryTau3Dynamics` is built with the free parameters as CasADi
symbols (:meth:`~gtmodel.robots.GantryTau3Dynamics.inverse_dynamics_expression`) and
``Y = ca.jacobian(tau, theta)``; ``tau_0`` (the forces of the parameters that are *not*
estimated, e.g. friction taken from Table 6.1) is the same expression at ``theta = 0``.
Friction uses the exact sign (rows with ``|q_dot_i| < min_speed`` are left out of the fit,
where a sign is ill-defined and the unmodelled Stribeck effect lives).

Model variants (:data:`VARIANTS`), Table 6.3 and two more for analysis:

============  ==========================================================================
``model_1``   Coulomb friction only: ``m_p, m_c, f_c`` (``f_v = 0``, ``m_a = 0``)
``model_2``   symmetric Coulomb + viscous, link masses neglected: ``m_p, m_c, f_c, f_v``
              (the thesis' best fit, the L1 parameter set)
``model_3``   masses only ``m_p, m_c``; the asymmetric friction of Table 6.1
              (``f_c+-``, ``f_v+-``) is computed from the model and subtracted
``model_4``   masses + one symmetric Coulomb per cart ``m_p, m_c, f_c``
              (``f_c+ = f_c- = f_c``); the asymmetric viscous friction of Table 6.1 is
              subtracted
``full``      all of eq. 6.7/6.8: ``m_p, m_c, m_a, f_c, f_v`` (base-parameter analysis)
``asymmetric`` masses + the asymmetric friction of Table 6.1 estimated:
              ``m_p, m_c, f_c+, f_c-, f_v+, f_v-``
============  ==========================================================================

Why the link masses are poorly identifiable (ch. 6.2): a link cluster's mass sits at the
link midpoint ``(T + A_i)/2``, so its kinetic energy is that of a quarter of its mass in
the plate, a quarter in the cart and a cross term, and its potential energy that of half
its mass in the plate (eq. 6.7: ``m_p + sum m_a/2`` and ``m_c,i + m_a,i/4``). The column of
``m_a,i`` in ``Y`` is therefore nearly ``1/2 (m_p column) + 1/4 (m_c,i column)``; the
column-pivoted QR of :func:`gtmodel.calibration.identifiability.analyze_jacobian` puts
the ``m_a`` last, with the tiny ``|R_ii|`` and the dependency coefficients reported in
:attr:`DynamicIdentificationResult.near_dependencies`.

Signals (:class:`MotionLog`, :func:`read_motion_log`): logged cart positions ``q`` (or TCP
positions ``T``) and actuator forces ``tau`` sampled at a constant rate (4 ms on the L1);
:func:`preprocess_log` differentiates positions with a zero-phase filter
(:func:`scipy.signal.filtfilt` with a Butterworth low-pass, or a Savitzky-Golay filter),
filters ``tau`` with the *same* filter (so regressor and forces see the same phase),
trims the filter transients at both ends and decimates (so the residuals are close to
white and the least-squares standard deviations hold).

Constant-velocity experiment (6.9): ``tau = J^T G + f_c sign(q_dot) + f_v q_dot``; see
:func:`two_direction_friction` (gravity and friction separated by runs in both
directions) and :func:`subtract_gravity` (one-direction data: the model's ``J^T G`` with
the accumulated mass 22.38 kg removed first; without it the gravity is absorbed into
``f_c``, the ambiguity of the thesis' Fig. 6.2).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
import scipy.linalg
import scipy.signal

from gtmodel._compiler import compiled_function
from gtmodel.calibration.identifiability import IdentifiabilityReport, analyze_jacobian, observability_indices
from gtmodel.errors import InputError, ModelError, SingularConfigurationError, UnreachablePoseError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE, configuration_signs, fk_expression, link_cosines_expression
from gtmodel.robots.parameters import DynamicParameters, FrictionParameters, RobotParameters, load_parameters

__all__ = [
    "VARIANTS",
    "TABLE_6_3_COLUMNS",
    "THESIS_TABLE_6_3",
    "column_dependency",
    "ModelVariant",
    "get_variant",
    "DynamicRegressor",
    "MotionLog",
    "read_motion_log",
    "DynamicSamples",
    "preprocess_log",
    "DynamicIdentificationResult",
    "identify_dynamics",
    "StribeckTerm",
    "simulate_log",
    "ConstantVelocityData",
    "FrictionFit",
    "simulate_constant_velocity",
    "accumulated_gravity_forces",
    "subtract_gravity",
    "fit_friction",
    "two_direction_friction",
    "MIN_SAMPLES",
    "SPEED_BINS",
    "SPEED_MATCH_TOLERANCE",
]

_log = logging.getLogger("gtmodel")

#: Fewest samples of a motion log (a Butterworth ``filtfilt`` needs some periods of data).
MIN_SAMPLES = 30
#: Largest relative deviation of a sampling interval from the median before a log is
#: rejected as non-uniformly sampled (the filters assume a constant rate).
SAMPLING_TOLERANCE = 0.01
#: Samples per mapped evaluation of the regressor, a power of two (building a CasADi map
#: costs about 2 us per sample, more than the compiled evaluation; the remainder of a log
#: is split into powers of two, so that a regressor builds a few small maps once).
_CHUNK = 4096
#: From this many samples :meth:`DynamicRegressor.evaluate` runs the regressor compiled to
#: C (below it the CasADi interpreter is faster than a first compilation).
_COMPILE_MIN_SAMPLES = 5000
#: Compiler flags of the regressor's shared library (no fast-math: IEEE results).
_COMPILE_FLAGS = ("-O3", "-fPIC", "-shared")
#: Largest relative speed difference of two runs paired by :func:`two_direction_friction`.
SPEED_MATCH_TOLERANCE = 0.05
#: Edges [m/s] of the speed bins of the residual report (Stribeck effect at low speed).
SPEED_BINS = (0.0, 0.02, 0.05, 0.1, 0.2, 0.5, math.inf)
#: Column order of Dressler (2012), Table 6.3.
TABLE_6_3_COLUMNS = ("m_p", "m_c1", "m_c2", "m_c3", "f_c1", "f_c2", "f_c3", "f_v1", "f_v2", "f_v3")

#: Dressler (2012), Table 6.3: identified parameters of the four models in the column
#: order of :data:`TABLE_6_3_COLUMNS` (nan = not estimated, taken from Table 6.1) and the
#: residuals per actuator [1e7 N^2 m^2 as printed] (the thesis' scaling; not comparable
#: with :attr:`DynamicIdentificationResult.residual_ss` of other data).
THESIS_TABLE_6_3: dict[str, dict[str, tuple[float, ...]]] = {
    "model_1": {"row": (8.76, 14.33, 14.05, 38.10, 152.13, 259.09, 291.24, 0.0, 0.0, 0.0), "residual": (1.11, 2.33, 1.98)},
    "model_2": {"row": (9.13, 13.58, 13.64, 38.23, 128.62, 145.13, 194.57, 102.43, 355.25, 388.77), "residual": (1.03, 1.29, 1.05)},
    "model_3": {"row": (8.79, 13.85, 14.85, 38.47) + (math.nan,) * 6, "residual": (2.38, 3.07, 1.77)},
    "model_4": {"row": (9.67, 12.51, 12.73, 37.70, 109.97, 207.13, 243.75, math.nan, math.nan, math.nan), "residual": (1.11, 1.60, 1.31)},
}

_MASSES = ("m_p", "m_c1", "m_c2", "m_c3")
_LINKS = ("m_a1", "m_a2", "m_a3")
_FC = ("f_c1", "f_c2", "f_c3")
_FV = ("f_v1", "f_v2", "f_v3")
_ASYM = tuple(f"{p}{i}" for p in ("f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus") for i in (1, 2, 3))


def _unit(name: str) -> str:
    return "kg" if name.startswith("m_") else ("N s/m" if name.startswith("f_v") else "N")


# ----------------------------------------------------------------------------- variants
@dataclass(frozen=True)
class ModelVariant:
    """Which parameters of eqs. 6.7/6.8 are estimated (Dressler (2012), Table 6.3).

    Parameters not estimated are: link masses ``m_a`` zero; symmetric friction (if the
    variant is symmetric) zero; asymmetric friction (if asymmetric) the parameter set's
    Table 6.1 values, whose forces are computed by the model and subtracted.

    Parameters
    ----------
    name : str
        Short name (a key of :data:`VARIANTS`).
    description : str
        One line.
    free : tuple of str
        Estimated parameters, in the order of ``theta``.
    asymmetric : bool
        Friction in the asymmetric form of Table 6.1 (else symmetric, eq. 6.8).
    tied_coulomb : bool
        Asymmetric form with one Coulomb value per cart, ``f_c+ = f_c- = f_c`` (free
        names ``f_c1..3``).
    """

    name: str
    description: str
    free: tuple[str, ...]
    asymmetric: bool = False
    tied_coulomb: bool = False


#: The selectable model variants (module docstring).
VARIANTS: dict[str, ModelVariant] = {
    "model_1": ModelVariant("model_1", "Table 6.3 model 1: Coulomb friction only, link masses neglected", _MASSES + _FC),
    "model_2": ModelVariant("model_2", "Table 6.3 model 2: symmetric Coulomb + viscous friction, link masses neglected", _MASSES + _FC + _FV),
    "model_3": ModelVariant("model_3", "Table 6.3 model 3: masses only, asymmetric friction of Table 6.1 subtracted", _MASSES, asymmetric=True),
    "model_4": ModelVariant(
        "model_4", "Table 6.3 model 4: masses + symmetric Coulomb, asymmetric viscous friction of Table 6.1 subtracted", _MASSES + _FC,
        asymmetric=True, tied_coulomb=True,
    ),
    "full": ModelVariant("full", "eqs. 6.7/6.8 complete: plate, carts, link clusters, symmetric Coulomb + viscous", _MASSES + _LINKS + _FC + _FV),
    "asymmetric": ModelVariant("asymmetric", "masses + asymmetric Coulomb and viscous friction (Table 6.1 form)", _MASSES + _ASYM, asymmetric=True),
}


def get_variant(variant: str | ModelVariant) -> ModelVariant:
    """The model variant of a name (Dressler (2012), Table 6.3).

    Parameters
    ----------
    variant : str or ModelVariant
        A key of :data:`VARIANTS` or a variant.

    Returns
    -------
    ModelVariant

    Raises
    ------
    InputError
        Unknown name.
    """
    if isinstance(variant, ModelVariant):
        return variant
    if variant not in VARIANTS:
        raise InputError(f"variant: expected one of {', '.join(VARIANTS)}, got {variant!r}")
    return VARIANTS[variant]


def _symbolic_dynamics(variant: ModelVariant, base: DynamicParameters) -> tuple[ca.SX, DynamicParameters]:
    """The free parameters as symbols and a DynamicParameters built from them."""
    theta = ca.SX.sym("theta", len(variant.free))
    sym = dict(zip(variant.free, ca.vertsplit(theta))) if variant.free else {}

    def vec(prefix: str, default: Sequence[float]) -> ca.SX:
        return ca.vertcat(*[sym.get(f"{prefix}{i + 1}", ca.SX(float(default[i]))) for i in range(3)])

    zeros = np.zeros(3)
    m_p = sym.get("m_p", ca.SX(float(base.m_p)))
    m_c = vec("m_c", base.m_c)
    m_a = vec("m_a", zeros)
    asym = base.asymmetric
    if variant.asymmetric:
        if asym is None:
            raise InputError(f"variant {variant.name!r} needs the asymmetric friction (Table 6.1) of the parameter set, which has none")
        if variant.tied_coulomb:
            fcp = fcm = vec("f_c", zeros)
        else:
            fcp, fcm = vec("f_c_plus", asym.f_c_plus), vec("f_c_minus", asym.f_c_minus)
        asym = FrictionParameters(
            f_c_plus=fcp, f_c_minus=fcm, f_v_plus=vec("f_v_plus", asym.f_v_plus), f_v_minus=vec("f_v_minus", asym.f_v_minus), source=asym.source,
        )
        f_c, f_v = ca.SX.zeros(3), ca.SX.zeros(3)
    else:
        f_c, f_v = vec("f_c", zeros), vec("f_v", zeros)
    d = dataclasses.replace(base, m_p=m_p, m_c=m_c, m_a=m_a, f_c=f_c, f_v=f_v, asymmetric=asym)
    return theta, d


# ----------------------------------------------------------------------------- regressor
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
    parameters : RobotParameters or str or pathlib.Path, optional
        Parameter set: kinematics, gravity and the Table 6.1 friction of the variants that
        subtract it (default ``"L1"``).
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
        parameters: RobotParameters | str | Path = "L1",
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
        arrs = [_signal(a, n, None) for a, n in zip((x, x_dot, x_ddot), ("x", "x_dot", "x_ddot"))]
        n = arrs[0].shape[0]
        for a, name in zip(arrs[1:], ("x_dot", "x_ddot")):
            if a.shape[0] != n:
                raise InputError(f"{name}: expected {n} samples (as x), got {a.shape[0]}")
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


def _value_of(d: DynamicParameters, name: str, variant: ModelVariant) -> float:
    if name == "m_p":
        return float(d.m_p)
    i = int(name[-1]) - 1
    base = name[:-1]
    if base in ("m_c", "m_a"):
        return float(getattr(d, base)[i])
    if base in ("f_c", "f_v") and not variant.asymmetric:
        return float(getattr(d, base)[i])
    a = d.asymmetric
    if a is None:
        raise InputError(f"parameter {name!r}: the parameter set has no asymmetric friction (Table 6.1)")
    if base == "f_c":  # tied Coulomb
        return float((a.f_c_plus[i] + a.f_c_minus[i]) / 2)
    return float(getattr(a, base)[i])


# ----------------------------------------------------------------------------- signals
def _signal(a: Any, name: str, n: int | None) -> np.ndarray:
    try:
        arr = np.asarray(a, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of numbers of shape (N, 3)") from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{name}: expected shape (N, 3), got {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise InputError(f"{name}: expected {n} samples (one per time t), got {arr.shape[0]}")
    bad = ~np.isfinite(arr)
    if np.any(bad):
        k, j = (int(v) for v in np.argwhere(bad)[0])
        raise InputError(f"{name}: sample {k}, column {j + 1} is not finite ({arr[k, j]!r})")
    return arr


def _time(t: Any, name: str = "t") -> np.ndarray:
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a 1-D array of times in s") from None
    if arr.ndim != 1:
        raise InputError(f"{name}: expected a 1-D array of times in s, got shape {arr.shape}")
    if arr.size < MIN_SAMPLES:
        raise InputError(f"{name}: expected at least {MIN_SAMPLES} samples, got {arr.size}")
    bad = ~np.isfinite(arr)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise InputError(f"{name}: sample {k} is not finite ({arr[k]!r})")
    dt = np.diff(arr)
    if np.any(dt <= 0):
        k = int(np.argmax(dt <= 0)) + 1
        raise InputError(f"{name}: time is not strictly increasing at sample {k} (t[{k}] = {arr[k]!r} s <= t[{k - 1}] = {arr[k - 1]!r} s)")
    return arr


@dataclass
class MotionLog:
    """A logged motion: time, cart (or TCP) positions and actuator forces (Dressler (2012), ch. 6.2).

    Validated on construction: equal lengths, finite values, strictly increasing time.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times [s], strictly increasing (constant rate for :func:`preprocess_log`).
    tau : numpy.ndarray, shape (N, 3)
        Actuator (cart) forces [N].
    q : numpy.ndarray, shape (N, 3) or None
        Cart positions [m] (encoder), or None if ``T`` is given.
    T : numpy.ndarray, shape (N, 3) or None
        TCP positions [m], or None if ``q`` is given.
    source : str
        Where the data come from.

    Raises
    ------
    InputError
        Not exactly one of ``q`` and ``T``, signal lengths differing from ``len(t)``,
        a non-finite value or non-increasing time (the message names the signal and the
        sample index).
    """

    t: np.ndarray
    tau: np.ndarray
    q: np.ndarray | None = None
    T: np.ndarray | None = None
    source: str = ""

    def __post_init__(self) -> None:
        if (self.q is None) == (self.T is None):
            raise InputError("MotionLog: give exactly one of q (cart positions) and T (TCP positions)")
        self.t = _time(self.t)
        n = self.t.size
        self.tau = _signal(self.tau, "tau", n)
        if self.q is not None:
            self.q = _signal(self.q, "q", n)
        else:
            self.T = _signal(self.T, "T", n)

    @property
    def coordinates(self) -> str:
        """``"cart"`` for cart positions, ``"tcp"`` for TCP positions."""
        return "cart" if self.q is not None else "tcp"

    @property
    def positions(self) -> np.ndarray:
        """The logged positions, ``q`` or ``T`` (N, 3) [m]."""
        return self.q if self.q is not None else self.T

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    def columns(self) -> tuple[str, ...]:
        """CSV column names with units.

        Returns
        -------
        tuple of str
            ``("t_s", "q1_m", "q2_m", "q3_m", "tau1_N", "tau2_N", "tau3_N")`` or with
            ``Tx_m, Ty_m, Tz_m``.
        """
        pos = ("q1_m", "q2_m", "q3_m") if self.q is not None else ("Tx_m", "Ty_m", "Tz_m")
        return ("t_s",) + pos + ("tau1_N", "tau2_N", "tau3_N")

    def to_csv(self, path: str | Path) -> Path:
        """Write the log in the format of :func:`read_motion_log`.

        Parameters
        ----------
        path : str or pathlib.Path
            Output file.

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        InputError
            The file cannot be written.
        """
        from gtmodel.calibration.measurements import _write_csv

        comments = [f" {self.source}"] if self.source else []
        return _write_csv(Path(path), comments, self.columns(), np.column_stack([self.t, self.positions, self.tau]))


def read_motion_log(path: str | Path) -> MotionLog:
    """Read a logged motion from CSV (the identification data of Dressler (2012), ch. 6.2).

    Format (as the calibration CSV of :mod:`gtmodel.calibration.measurements`): optional
    ``#`` comment lines at the top, a header naming the columns with their units, then one
    row per sample::

        # L1, 4 ms servo log, excitation run 3
        t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N
        0.000,-0.0933,0.0415,0.0153,-12.5,30.1,210.7
        ...

    Columns (any order, each once): ``t_s``; either ``q1_m, q2_m, q3_m`` (cart positions)
    or ``Tx_m, Ty_m, Tz_m`` (TCP positions); ``tau1_N, tau2_N, tau3_N`` (actuator forces).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    MotionLog

    Raises
    ------
    InputError
        Unreadable file, missing/unknown column, a malformed or non-finite number, or
        non-increasing time; the message names the file and the line.
    """
    from gtmodel.calibration.measurements import _parse_rows, _read_table

    table = _read_table(path, "motion log")
    cols = table.columns
    q_cols, T_cols, tau_cols = ["q1_m", "q2_m", "q3_m"], ["Tx_m", "Ty_m", "Tz_m"], ["tau1_N", "tau2_N", "tau3_N"]
    allowed = {"t_s", *q_cols, *T_cols, *tau_cols}
    for c in cols:
        if c not in allowed:
            raise InputError(f"{table.origin}: line {table.header_line} (header): unknown column '{c}' (allowed: {', '.join(sorted(allowed))})")
    has_q, has_T = all(c in cols for c in q_cols), all(c in cols for c in T_cols)
    if has_q == has_T:
        raise InputError(f"{table.origin}: line {table.header_line} (header): expected exactly one of the column sets q1_m,q2_m,q3_m and Tx_m,Ty_m,Tz_m")
    for c in ["t_s", *tau_cols]:
        if c not in cols:
            raise InputError(f"{table.origin}: line {table.header_line} (header): missing column '{c}'")
    data = _parse_rows(table)
    idx = {c: j for j, c in enumerate(cols)}
    t = data[:, idx["t_s"]]
    dt = np.diff(t)
    if np.any(dt <= 0):
        r = int(np.argmax(dt <= 0)) + 1
        raise InputError(f"{table.origin}: line {table.rows[r][0]}, column 't_s': time not strictly increasing ({t[r]!r} after {t[r - 1]!r})")
    if t.size < MIN_SAMPLES:
        raise InputError(f"{table.origin}: {t.size} samples, expected at least {MIN_SAMPLES}")
    pos = data[:, [idx[c] for c in (q_cols if has_q else T_cols)]]
    tau = data[:, [idx[c] for c in tau_cols]]
    source = " ".join(s.strip() for s in table.comments) or str(path)
    return MotionLog(t=t, tau=tau, q=pos if has_q else None, T=None if has_q else pos, source=source)


@dataclass
class DynamicSamples:
    """Positions, velocities, accelerations and forces ready for the regressor.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Times [s].
    x, x_dot, x_ddot : numpy.ndarray, shape (N, 3)
        Cart (``coordinates="cart"``) or TCP positions [m], velocities [m/s],
        accelerations [m/s^2].
    tau : numpy.ndarray, shape (N, 3)
        Actuator forces [N] (filtered like the positions).
    coordinates : {"cart", "tcp"}
        Meaning of ``x``.
    info : dict
        How they were obtained (filter, cut-off, decimation, trimmed samples).
    decimate : int
        Row decimation applied by :func:`identify_dynamics` after the parallel filtering
        (default 1).
    smoother : callable or None
        The zero-phase filter that was applied to ``tau`` (``y (N, ...) -> y (N, ...)``
        along axis 0); :func:`identify_dynamics` applies it to the regressor too
        ("parallel filtering", Gautier 1997), so the filtered friction steps agree.

    Raises
    ------
    InputError
        Lengths differing from ``len(t)``, non-finite values, non-increasing time or an
        unknown ``coordinates`` (the message names the signal and sample).
    """

    t: np.ndarray
    x: np.ndarray
    x_dot: np.ndarray
    x_ddot: np.ndarray
    tau: np.ndarray
    coordinates: str = "cart"
    info: dict = field(default_factory=dict)
    decimate: int = 1
    smoother: Any = None

    def __post_init__(self) -> None:
        if isinstance(self.decimate, bool) or not isinstance(self.decimate, (int, np.integer)) or self.decimate < 1:
            raise InputError(f"decimate: expected a positive integer, got {self.decimate!r}")
        if self.smoother is not None and not callable(self.smoother):
            raise InputError("smoother: expected a callable filter (array (N, ...) -> array (N, ...)) or None")
        if self.coordinates not in ("cart", "tcp"):
            raise InputError(f"coordinates: expected 'cart' or 'tcp', got {self.coordinates!r}")
        try:
            t = np.asarray(self.t, dtype=float)
        except (TypeError, ValueError):
            raise InputError("t: expected a 1-D array of times in s") from None
        if t.ndim != 1 or t.size < 1:
            raise InputError(f"t: expected a non-empty 1-D array, got shape {t.shape}")
        if np.any(~np.isfinite(t)):
            raise InputError(f"t: sample {int(np.argmax(~np.isfinite(t)))} is not finite")
        if t.size > 1 and np.any(np.diff(t) <= 0):
            k = int(np.argmax(np.diff(t) <= 0)) + 1
            raise InputError(f"t: time is not strictly increasing at sample {k}")
        self.t = t
        n = t.size
        self.x = _signal(self.x, "x", n)
        self.x_dot = _signal(self.x_dot, "x_dot", n)
        self.x_ddot = _signal(self.x_ddot, "x_ddot", n)
        self.tau = _signal(self.tau, "tau", n)

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)


def _savgol_window(fs: float, cutoff: float, order: int) -> int:
    # -3 dB frequency of a Savitzky-Golay smoother: f_c ~ (order + 1) fs / (3.2 n - 4.6)
    # (Schafer, "What is a Savitzky-Golay filter?", IEEE Signal Processing Magazine, 2011)
    n = int(round(((order + 1) * fs / cutoff + 4.6) / 3.2))
    n = max(n, order + 2)
    return n + 1 if n % 2 == 0 else n


def preprocess_log(
    log: MotionLog,
    cutoff: float = 10.0,
    method: str = "butter",
    order: int = 4,
    decimate: int | None = None,
    trim: int | None = None,
) -> DynamicSamples:
    """Zero-phase filtering and numerical differentiation of a logged motion.

    ``"butter"``: positions and forces are filtered forward and backward
    (:func:`scipy.signal.filtfilt`, Butterworth low-pass of ``order`` with the cut-off
    ``cutoff``), then differentiated by central differences (:func:`numpy.gradient`).
    ``"savgol"``: Savitzky-Golay filter (:func:`scipy.signal.savgol_filter`, polynomial
    order ``order``, window chosen for a -3 dB frequency near ``cutoff``) with its
    derivatives. Either way both positions and forces pass the same zero-phase filter, the
    transients at both ends are trimmed and the result is decimated (Dressler (2012),
    ch. 6.2 identifies on filtered servo data). The output keeps the full rate; the
    decimation is done by :func:`identify_dynamics` after it has passed the regressor
    through the same filter as the forces ("parallel filtering and decimation", M.
    Gautier, "Dynamic identification of robots with power model", IEEE ICRA 1997): the
    filter smears the Coulomb steps ``f_c sign(q_dot)`` of the forces, and the same filter
    on ``Y`` smears them equally, which removes a bias of the masses.

    Parameters
    ----------
    log : MotionLog
        The motion, sampled at a constant rate.
    cutoff : float, optional
        Low-pass cut-off frequency [Hz] (default 10 Hz), below the Nyquist frequency.
    method : {"butter", "savgol"}, optional
        The filter.
    order : int, optional
        Butterworth order, or Savitzky-Golay polynomial order (>= 2) (default 4).
    decimate : int, optional
        Keep every ``decimate``-th row in the identification (default
        ``max(1, round(fs / cutoff))``: rows one filter correlation time apart, so the
        filtered noise is close to white and the least-squares standard deviations hold;
        with ``fs / (2.5 cutoff)`` they come out about 1.3 times too small in simulations).
    trim : int, optional
        Samples dropped at each end (default ``ceil(2 fs / cutoff)``, two periods of the
        cut-off), here and again after the regressor is filtered.

    Returns
    -------
    DynamicSamples

    Raises
    ------
    InputError
        Non-uniform sampling (names the sample), a cut-off at or above the Nyquist
        frequency, an unknown method, invalid ``order``/``decimate``/``trim``, or too few
        samples left.
    """
    if not isinstance(log, MotionLog):
        raise InputError(f"log: expected a MotionLog, got {type(log).__name__}")
    if method not in ("butter", "savgol"):
        raise InputError(f"method: expected 'butter' or 'savgol', got {method!r}")
    t = log.t
    dt_all = np.diff(t)
    dt = float(np.median(dt_all))
    dev = np.abs(dt_all - dt) > SAMPLING_TOLERANCE * dt
    if np.any(dev):
        k = int(np.argmax(dev)) + 1
        raise InputError(f"t: sampling is not uniform at sample {k} (interval {dt_all[k - 1]!r} s, median {dt!r} s); resample the log first")
    fs = 1.0 / dt
    if not (isinstance(cutoff, (int, float)) and math.isfinite(cutoff) and 0 < cutoff < fs / 2):
        raise InputError(f"cutoff: expected a frequency in (0, {fs / 2:g}) Hz (below Nyquist), got {cutoff!r}")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 1 <= order <= 10 or (method == "savgol" and order < 2):
        raise InputError(f"order: expected an integer in 1..10 (>= 2 for savgol), got {order!r}")
    if decimate is None:
        decimate = max(1, int(round(fs / cutoff)))
    if isinstance(decimate, bool) or not isinstance(decimate, (int, np.integer)) or decimate < 1:
        raise InputError(f"decimate: expected a positive integer, got {decimate!r}")
    if trim is None:
        trim = int(math.ceil(2 * fs / cutoff))
    if isinstance(trim, bool) or not isinstance(trim, (int, np.integer)) or trim < 0:
        raise InputError(f"trim: expected a non-negative integer, got {trim!r}")
    x = log.positions
    n = x.shape[0]
    if method == "butter":
        b, a = scipy.signal.butter(order, cutoff, fs=fs)
        need = 3 * max(len(a), len(b))
        if n <= max(need, 2 * trim + 3):
            raise InputError(f"log: {n} samples are too few for the filter and trim={trim} (need more than {max(need, 2 * trim + 3)})")
        xf = scipy.signal.filtfilt(b, a, x, axis=0)
        xd = np.gradient(xf, dt, axis=0)
        xdd = np.gradient(xd, dt, axis=0)
        tauf = scipy.signal.filtfilt(b, a, log.tau, axis=0)
        info = {"filter": f"Butterworth order {order}, filtfilt (zero phase)", "window": None}
    else:
        w = _savgol_window(fs, cutoff, order)
        if n <= max(w, 2 * trim + 3):
            raise InputError(f"log: {n} samples are too few for the Savitzky-Golay window {w} and trim={trim}")
        xf = scipy.signal.savgol_filter(x, w, order, axis=0)
        xd = scipy.signal.savgol_filter(x, w, order, deriv=1, delta=dt, axis=0)
        xdd = scipy.signal.savgol_filter(x, w, order, deriv=2, delta=dt, axis=0)
        tauf = scipy.signal.savgol_filter(log.tau, w, order, axis=0)
        info = {"filter": f"Savitzky-Golay order {order}, window {w} samples (zero phase)", "window": w}
    keep = np.arange(trim, n - trim)
    n_left = (keep.size - 2 * trim + decimate - 1) // decimate
    if n_left < MIN_SAMPLES:
        raise InputError(f"log: only {max(n_left, 0)} samples remain after trim={trim} (twice) and decimate={decimate}, expected at least {MIN_SAMPLES}")
    info.update(cutoff_hz=float(cutoff), sample_time_s=dt, decimate=int(decimate), trim=int(trim), method=method)
    # the smoother filters each signal of y (N, ...) along time; on the (signals, N) view
    # the filter runs about a third faster than along axis 0 of (N, 3, p) (same results)
    if method == "butter":
        def smoother(y: np.ndarray) -> np.ndarray:
            y = np.asarray(y)
            return scipy.signal.filtfilt(b, a, y.reshape(y.shape[0], -1).T, axis=-1).T.reshape(y.shape)
    else:
        def smoother(y: np.ndarray) -> np.ndarray:
            y = np.asarray(y)
            return scipy.signal.savgol_filter(y.reshape(y.shape[0], -1).T, w, order, axis=-1).T.reshape(y.shape)
    return DynamicSamples(t[keep], xf[keep], xd[keep], xdd[keep], tauf[keep], log.coordinates, info, int(decimate), smoother)


# ----------------------------------------------------------------------------- identification
@dataclass
class DynamicIdentificationResult:
    """Identified rigid-body and friction parameters (Dressler (2012), ch. 6.2, Table 6.3).

    Parameters
    ----------
    variant : str
        The model variant (:data:`VARIANTS`).
    names : tuple of str
        Parameter names (order of ``theta``).
    theta : numpy.ndarray, shape (p,)
        Estimates [kg, N, N s/m]; parameters outside the identifiable (base) set are 0.
    std : numpy.ndarray, shape (p,)
        Standard deviations from ``sigma^2 (Y_w^T Y_w)^-1`` (``inf`` if not identifiable).
    covariance : numpy.ndarray, shape (p, p)
        Covariance of ``theta``.
    residual_rms : numpy.ndarray, shape (3,)
        RMS of ``tau - Y theta - tau0`` per actuator on the fitted rows [N].
    residual_ss : numpy.ndarray, shape (3,)
        Sum of squared residuals per actuator on the fitted rows [N^2] (the thesis' Table
        6.3 residuals are of this kind, on its own data and scaling).
    residual_by_speed : list of dict
        Per speed bin (:data:`SPEED_BINS`) and actuator: ``{"v_min", "v_max", "n",
        "rms"}`` of all samples (fitted or not) [N]: the unmodelled low-speed (Stribeck)
        friction shows here.
    condition_number : float
        Condition number of the weighted, column-scaled regressor.
    condition_number_raw : float
        Condition number of the weighted regressor in SI units.
    identifiability : IdentifiabilityReport
        Pivoted-QR analysis (base parameters) of the weighted regressor.
    near_dependencies : list of dict
        The least-determined parameters (pivot order, last first): ``parameter``,
        ``r_ratio`` (``|R_jj| / |R_00|`` of the scaled QR) and ``depends_on`` (the column
        as a combination of the better-determined ones, in parameter units).
    weights : numpy.ndarray, shape (3,)
        Row weight per actuator [1/N].
    n_samples : int
        Samples used.
    n_rows : int
        Equations fitted (samples x actuators above ``min_speed``).
    status : str
        ``"optimal"`` or ``"error"``.
    message : str
        What happened.
    solve_time : float
        Wall time [s].
    info : dict
        Options (min_speed, weighting, preprocessing) and the split of :attr:`solve_time`
        [s]: ``regressor_time_s`` (regressor evaluation), ``filter_time_s`` (parallel
        filtering of the regressor) and ``least_squares_time_s`` (least squares and all
        statistics).
    """

    variant: str
    names: tuple[str, ...]
    theta: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    residual_rms: np.ndarray
    residual_ss: np.ndarray
    residual_by_speed: list
    condition_number: float
    condition_number_raw: float
    identifiability: IdentifiabilityReport
    near_dependencies: list
    weights: np.ndarray
    n_samples: int
    n_rows: int
    status: str = "optimal"
    message: str = ""
    solve_time: float = 0.0
    info: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """True when the estimate is the least-squares optimum."""
        return self.status == "optimal"

    @property
    def parameters(self) -> dict[str, float]:
        """``{name: estimate}``."""
        return {n: float(v) for n, v in zip(self.names, self.theta)}

    def table_6_3_row(self) -> np.ndarray:
        """The estimates in the column order of Table 6.3 (:data:`TABLE_6_3_COLUMNS`).

        Returns
        -------
        numpy.ndarray, shape (10,)
            ``[m_p, m_c1..3, f_c1..3, f_v1..3]``; ``nan`` where the variant does not estimate
            the parameter (taken from Table 6.1), 0 where it fixes it at zero (model 1's
            ``f_v``), as in the thesis' table.
        """
        p = self.parameters
        v = get_variant(self.variant)
        row = []
        for c in TABLE_6_3_COLUMNS:
            if c in p:
                row.append(p[c])
            elif c.startswith("f_") and not v.asymmetric:
                row.append(0.0)
            else:
                row.append(math.nan)
        return np.array(row)

    def z_scores(self, truth: np.typing.ArrayLike) -> np.ndarray:
        """``|theta - truth| / std`` per parameter.

        Parameters
        ----------
        truth : array_like, shape (p,)
            Reference values in the order of :attr:`names`.

        Returns
        -------
        numpy.ndarray, shape (p,)
            Deviations in standard deviations (``nan`` where ``std`` is 0 or infinite).

        Raises
        ------
        InputError
            ``truth`` of the wrong length.
        """
        tr = np.asarray(truth, dtype=float).ravel()
        if tr.size != self.theta.size:
            raise InputError(f"truth: expected {self.theta.size} values, got {tr.size}")
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.abs(self.theta - tr) / self.std
        return np.where(np.isfinite(self.std) & (self.std > 0), z, np.nan)

    def describe(self) -> str:
        """Parameter table as text.

        Returns
        -------
        str
            One line per parameter: name, estimate, standard deviation, unit.
        """
        lines = [f"variant {self.variant}: {self.message}"]
        for n, v, s in zip(self.names, self.theta, self.std):
            lines.append(f"  {n:12s} {v:12.4f} +- {s:9.4f} {_unit(n)}")
        lines.append(f"  residual RMS [N]: {np.round(self.residual_rms, 2).tolist()}, cond (scaled) {self.condition_number:.3g}")
        return "\n".join(lines)


def _near_dependencies(A: np.ndarray, names: Sequence[str], count: int) -> list[dict[str, Any]]:
    """The last ``count`` pivots of the column-pivoted QR of the scaled regressor, each as a
    combination of the columns before it (the near-dependencies behind a large std)."""
    norms = np.linalg.norm(A, axis=0)
    As = A / np.where(norms > 0, norms, 1.0)
    R, piv = scipy.linalg.qr(As, mode="r", pivoting=True, check_finite=False)
    d = np.abs(np.diag(R))
    out = []
    n = len(piv)
    for j in range(n - 1, max(n - 1 - count, 0), -1):
        c = scipy.linalg.solve_triangular(R[:j, :j], R[:j, j], lower=False, check_finite=False) if j else np.zeros(0)
        col = piv[j]
        deps = {}
        for ii in np.argsort(-np.abs(c)):
            if abs(c[ii]) > 1e-3 and norms[col] > 0:
                deps[names[piv[ii]]] = float(c[ii] * norms[col] / norms[piv[ii]])
        out.append({"parameter": names[col], "r_ratio": float(d[j] / d[0]) if d[0] > 0 else 0.0, "depends_on": deps})
    return out


def column_dependency(Y: np.typing.ArrayLike, names: Sequence[str], parameter: str, on: Sequence[str] | None = None) -> dict[str, Any]:
    """How well one regressor column is a combination of others (why a parameter is poorly identifiable).

    Least squares ``Y_j ~= sum_i c_i Y_i`` over the columns ``on``: a change ``d`` of
    parameter ``j`` acts on the forces like the changes ``c_i d`` of the others, up to the
    relative residual. For a link-cluster mass ``m_a,i`` and ``on = (m_p, m_c,i)`` the
    coefficients are near ``(1/2 .. 1/4, 1/4 .. 1/2)`` (Dressler (2012), eq. 6.7:
    ``m_p + sum m_a/2`` and ``m_c,i + m_a,i/4``) and the residual is small.

    Parameters
    ----------
    Y : array_like, shape (m, p) or (N, 3, p)
        Regressor (rows stacked or per sample and actuator).
    names : sequence of str
        Column names.
    parameter : str
        The column to explain.
    on : sequence of str, optional
        The explaining columns (default: all others).

    Returns
    -------
    dict
        ``coefficients`` ({name: c_i}, in parameter units), ``relative_residual``
        (``|Y_j - sum c_i Y_i| / |Y_j|``, 0 = exactly dependent).

    Raises
    ------
    InputError
        Unknown names or shapes that do not match.
    """
    A = np.asarray(Y, dtype=float)
    A = A.reshape(-1, A.shape[-1])
    names = list(names)
    if A.shape[1] != len(names):
        raise InputError(f"names: expected {A.shape[1]} names (one per column of Y), got {len(names)}")
    if parameter not in names:
        raise InputError(f"parameter: {parameter!r} is not one of {', '.join(names)}")
    others = [n for n in names if n != parameter] if on is None else list(on)
    for n in others:
        if n not in names or n == parameter:
            raise InputError(f"on: {n!r} is not another column ({', '.join(names)})")
    yj = A[:, names.index(parameter)]
    X = A[:, [names.index(n) for n in others]]
    c, *_ = np.linalg.lstsq(X, yj, rcond=None)
    nrm = float(np.linalg.norm(yj))
    rel = float(np.linalg.norm(yj - X @ c) / nrm) if nrm > 0 else 0.0
    return {"coefficients": {n: float(v) for n, v in zip(others, c)}, "relative_residual": rel}


def _speed_bins(q_dot: np.ndarray, r: np.ndarray) -> list[dict[str, Any]]:
    # one pass: bin index of every (sample, actuator), then counts and sums of squares per bin
    edges = np.asarray(SPEED_BINS)
    nb = edges.size - 1
    v = np.abs(q_dot)
    idx = np.searchsorted(edges, v, side="right") - 1  # edges[j] <= v < edges[j + 1]
    ok = (idx >= 0) & (idx < nb)
    flat = (idx * 3 + np.arange(3))[ok]
    n = np.bincount(flat, minlength=3 * nb).reshape(nb, 3)
    ss = np.bincount(flat, weights=np.square(r)[ok], minlength=3 * nb).reshape(nb, 3)
    out = []
    for j, (lo, hi) in enumerate(zip(SPEED_BINS[:-1], SPEED_BINS[1:])):
        out.append({"v_min": lo, "v_max": hi, "n": [int(c) for c in n[j]],
                    "rms": [float(np.sqrt(ss[j, i] / n[j, i])) if n[j, i] else math.nan for i in range(3)]})
    return out


def _row_factors(Y: np.ndarray, b: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Per actuator ``i`` a (p+1)-square ``S_i`` with ``S_i^T S_i = M_i^T M_i`` of its rows
    ``M_i = [Y[k, i, :], b[k, i]]`` (``mask[k, i]``): the R of a Householder QR (LAPACK
    ``dgeqrf`` on a Fortran-ordered copy of the rows, the only copy made)."""
    p = Y.shape[2]
    S = np.zeros((3, p + 1, p + 1))
    for i in range(3):
        mi = mask[:, i]
        r = int(np.count_nonzero(mi))
        if r == 0:
            continue
        Mt = np.empty((p + 1, r))
        Mt[:p] = Y[:, i, :][mi].T
        Mt[p] = b[mi, i]
        M = Mt.T  # Fortran order, as LAPACK wants it
        if r <= p:  # fewer rows than columns: the rows themselves have the right Gram matrix
            S[i, :r] = M
            continue
        qr, _, _, info = scipy.linalg.lapack.dgeqrf(M, overwrite_a=True)
        if info != 0:
            raise ModelError(f"QR of the regressor rows of actuator {i + 1} failed (LAPACK dgeqrf info {info})")
        S[i] = np.triu(qr[:p + 1])
    return S


def _stacked_factor(S: np.ndarray, w: np.ndarray, cols: Sequence[int]) -> np.ndarray:
    """R (k+1 square) of the weighted rows restricted to the columns ``cols`` plus the
    right-hand side: QR of the stack ``[w_i S_i[:, cols + rhs]]``; ``R[:k, :k] x = R[:k, k]``
    is the least-squares solution and ``R[k, k]^2`` the weighted residual sum of squares.
    Rows are signed so that the diagonal is non-negative: R is then the unique Cholesky
    factor of the weighted Gram matrix, whatever order the QR steps took (the pivoted QR of
    the identifiability report sees the same matrix for the same data)."""
    c = [*cols, S.shape[2] - 1]
    Z = np.concatenate([w[i] * S[i][:, c] for i in range(3)])
    R = scipy.linalg.qr(Z, mode="r", check_finite=False)[0][:len(c)]
    return R * np.where(np.diag(R) < 0, -1.0, 1.0)[:, None]


def identify_dynamics(
    samples: DynamicSamples,
    parameters: RobotParameters | str | Path = "L1",
    variant: str | ModelVariant = "model_2",
    weighting: str | Sequence[float] = "actuator",
    min_speed: float = 0.05,
    rank_deficient: str = "raise",
    configuration: int | Sequence[int] = 0,
    solution: int = 1,
    regressor: DynamicRegressor | None = None,
    parallel_filter: bool = True,
) -> DynamicIdentificationResult:
    """Least-squares identification of masses and friction, Dressler (2012), ch. 6.2, Table 6.3.

    Solves ``min || W (Y theta + tau0 - tau) ||^2`` over the rows (sample k, actuator i)
    with ``|q_dot_i| >= min_speed``; ``Y`` from :class:`DynamicRegressor` (one symbolic
    model). Standard deviations from ``sigma^2 (Y_w^T Y_w)^-1`` with ``sigma^2 = RSS_w /
    (m - p)`` and the base (identifiable) parameters from the column-pivoted QR of
    :func:`gtmodel.calibration.identifiability.analyze_jacobian`. The rows are read once:
    each actuator's rows ``[Y_i, tau_i - tau0_i]`` are reduced to a (p+1)-square triangular
    factor by a Householder QR; the weighting, the solution, the standard deviations and
    the base-parameter analysis then work on the stack of these factors (the same least
    squares, as accurate as :func:`numpy.linalg.lstsq` on the rows).

    Parameters
    ----------
    samples : DynamicSamples
        Filtered motion and forces (see :func:`preprocess_log`).
    parameters : RobotParameters or str or pathlib.Path, optional
        Parameter set (kinematics, gravity, Table 6.1 friction) (default ``"L1"``).
    variant : str or ModelVariant, optional
        Which parameters are estimated (default ``"model_2"``, :data:`VARIANTS`).
    weighting : {"actuator", "none"} or sequence of 3 float, optional
        ``"actuator"`` (default): two steps, the second weighting each actuator's rows by
        ``1 / (residual RMS of the first)``; ``"none"``: ordinary least squares; or three
        positive weights [1/N].
    min_speed : float, optional
        Rows with ``|q_dot_i|`` below this [m/s] are not fitted (default 0.05 m/s): the
        sign is ill-defined near zero and the unmodelled Stribeck friction lives there.
    rank_deficient : {"raise", "base"}, optional
        For a rank-deficient regressor: raise :class:`~gtmodel.errors.ModelError`
        naming the dependent parameters (default), or estimate the base parameters (the
        identifiable subset; the others are set to 0 with infinite std).
    configuration : int or sequence of int, optional
        IK configuration of the data (default 0).
    solution : {1, -1}, optional
        FK assembly for cart-coordinate data (default 1).
    regressor : DynamicRegressor, optional
        A prepared regressor (reused across calls; overrides ``parameters``/``variant``).
    parallel_filter : bool, optional
        Pass ``Y`` and ``tau0`` through the filter the forces went through
        (``samples.smoother``, see :func:`preprocess_log`) before decimating (default
        True).

    Returns
    -------
    DynamicIdentificationResult

    Raises
    ------
    InputError
        Invalid options or data, or fewer fitted rows than parameters.
    ModelError
        Rank-deficient regressor with ``rank_deficient="raise"`` (names the parameters
        and their dependencies).
    UnreachablePoseError, SingularConfigurationError
        A sample outside the workspace or singular (names the sample).
    """
    t0 = time.perf_counter()
    if not isinstance(samples, DynamicSamples):
        raise InputError(f"samples: expected DynamicSamples (see preprocess_log), got {type(samples).__name__}")
    if not (isinstance(min_speed, (int, float)) and math.isfinite(min_speed) and min_speed >= 0):
        raise InputError(f"min_speed: expected a non-negative speed in m/s, got {min_speed!r}")
    if rank_deficient not in ("raise", "base"):
        raise InputError(f"rank_deficient: expected 'raise' or 'base', got {rank_deficient!r}")
    if isinstance(weighting, str):
        if weighting not in ("actuator", "none"):
            raise InputError(f"weighting: expected 'actuator', 'none' or three positive weights, got {weighting!r}")
        fixed_w = None
    else:
        fixed_w = np.asarray(weighting, dtype=float).ravel()
        if fixed_w.size != 3 or not np.all(np.isfinite(fixed_w)) or np.any(fixed_w <= 0):
            raise InputError(f"weighting: expected three positive finite weights, got {list(np.ravel(weighting))!r}")
    reg = regressor if regressor is not None else DynamicRegressor(parameters, variant, configuration, solution)
    names = reg.names
    p = len(names)
    t_reg = time.perf_counter()
    Y, tau0, q_dot = reg.evaluate(samples.x, samples.x_dot, samples.x_ddot, samples.coordinates)
    t_reg = time.perf_counter() - t_reg
    t_filt = time.perf_counter()
    tau = samples.tau
    edge = 0
    if parallel_filter and samples.smoother is not None:
        Y, tau0 = samples.smoother(Y), samples.smoother(tau0)
        edge = int(samples.info.get("trim", 0))
    t_filt = time.perf_counter() - t_filt
    t_ls = time.perf_counter()
    sel = slice(edge, samples.n_samples - edge, samples.decimate)  # views, no copies
    n_used = len(range(samples.n_samples)[sel])
    if n_used < 2:
        raise InputError(f"samples: {samples.n_samples} samples leave {n_used} after trim={edge} and decimate={samples.decimate}")
    Y, tau0, q_dot, tau = Y[sel], tau0[sel], q_dot[sel], tau[sel]
    b_all = tau - tau0
    mask = np.abs(q_dot) >= min_speed  # (N, 3)
    counts = mask.sum(axis=0)
    m = int(counts.sum())
    if m <= p:
        raise InputError(f"samples: {m} rows with |q_dot| >= min_speed = {min_speed} m/s, expected more than the {p} parameters")

    # One pass over the data: per actuator the triangular factor S_i of its rows [Y_i b_i]
    # (Householder QR). The rows of any weighting and any column subset have the factor of
    # the small stack [w_i S_i] (orthogonal invariance), so the solution, the residual sums,
    # the standard deviations and the base-parameter analysis all come from (p+1)-square
    # blocks; no second pass and no normal equations.
    S = _row_factors(Y, b_all, mask)
    R0 = _stacked_factor(S, np.ones(3), list(range(p)))[:p, :p]
    report0 = analyze_jacobian(R0, names)
    ident = sorted(names.index(n) for n in report0.identifiable)
    if not report0.full_rank:
        msg = f"the regressor of variant {reg.variant.name!r} is rank-deficient (rank {report0.rank} of {p}): {report0.describe()}"
        if rank_deficient == "raise":
            raise ModelError(msg + "; choose a variant without these parameters or rank_deficient='base'")
        _log.warning(msg)
    k = len(ident)

    def solve(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # least squares on the identifiable columns with actuator weights w: R x = c
        F = _stacked_factor(S, w, ident)
        th = np.zeros(p)
        th[ident] = scipy.linalg.solve_triangular(F[:k, :k], F[:k, k], check_finite=False)
        return th, F[:k, :k]

    w = fixed_w if fixed_w is not None else np.ones(3)
    th, R = solve(w)
    if fixed_w is None and weighting == "actuator":
        # residual sum of squares per actuator ||S_i [theta; -1]||^2 (no pass over the rows)
        ext = np.append(th, -1.0)
        rss = np.array([float(np.sum((S[i] @ ext) ** 2)) for i in range(3)])
        rms = np.where(counts > 0, np.sqrt(rss / np.maximum(counts, 1)), 1.0)
        w = 1.0 / np.where(rms > 0, rms, 1.0)
        th, R = solve(w)
    r_all = b_all - (Y.reshape(-1, p) @ th).reshape(-1, 3) if p else b_all.copy()
    res_ss = np.array([float(np.sum(np.square(r_all[:, i][mask[:, i]]))) for i in range(3)])
    res_rms = np.array([math.sqrt(res_ss[i] / counts[i]) if counts[i] else math.nan for i in range(3)])
    # covariance sigma^2 (Y_I^T W^2 Y_I)^-1 = sigma^2 R^-1 R^-T, sigma^2 = RSS_w / (m - rank)
    sigma2 = float(np.sum(w**2 * res_ss)) / (m - k)
    Rinv = scipy.linalg.solve_triangular(R, np.eye(k), check_finite=False)
    cov = np.full((p, p), math.inf)
    cov[np.ix_(ident, ident)] = sigma2 * (Rinv @ Rinv.T)
    std = np.array([math.sqrt(cov[j, j]) if j in ident else math.inf for j in range(p)])
    # the base-parameter report on all columns (R of the weighted rows, all parameters)
    R_all = R if k == p else _stacked_factor(S, w, list(range(p)))[:p, :p]
    report = analyze_jacobian(R_all, names)
    report = dataclasses.replace(
        report, n_residuals=int(m), std={n: float(std[j]) for j, n in enumerate(names)}, covariance=cov,
        observability=observability_indices(report.singular_values, m) if report.full_rank else report.observability,
    )
    sv = np.linalg.svd(R, compute_uv=False)
    cond_raw = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    sv_s = np.linalg.svd(R / np.linalg.norm(R, axis=0), compute_uv=False)
    cond = float(sv_s[0] / sv_s[-1]) if sv_s[-1] > 0 else math.inf
    near = _near_dependencies(R, [names[j] for j in ident], count=min(3, k - 1))
    by_speed = _speed_bins(q_dot, r_all)
    t_ls = time.perf_counter() - t_ls
    status = "optimal"
    message = f"{m} rows ({n_used} samples), rank {report.rank}/{p}"
    if not report.full_rank:
        message += f"; base parameters only: {report.describe()}"
    return DynamicIdentificationResult(
        variant=reg.variant.name, names=names, theta=th, std=std, covariance=cov, residual_rms=res_rms, residual_ss=res_ss,
        residual_by_speed=by_speed, condition_number=float(cond), condition_number_raw=cond_raw,
        identifiability=report, near_dependencies=near, weights=w, n_samples=n_used, n_rows=int(m),
        status=status, message=message, solve_time=time.perf_counter() - t0,
        info={"min_speed": float(min_speed), "weighting": weighting if isinstance(weighting, str) else "fixed",
              "regressor_time_s": t_reg, "filter_time_s": t_filt, "least_squares_time_s": t_ls, **samples.info},
    )


# ----------------------------------------------------------------------------- simulation
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
        v = _signal(q_dot, "q_dot", None)
        return np.asarray(self.function.map(v.shape[0])(v.T)).T


def simulate_log(
    trajectory: Any,
    duration: float,
    parameters: RobotParameters | str | Path = "L1",
    sample_time: float = 0.004,
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
        :class:`gtmodel.calibration.excitation.FourierTrajectory`.
    duration : float
        Length of the log [s].
    parameters : RobotParameters or str or pathlib.Path, optional
        The true robot (default ``"L1"``).
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


# ----------------------------------------------------------------------------- eq. 6.9
@dataclass
class ConstantVelocityData:
    """Mean actuator forces of constant-velocity runs (Dressler (2012), eq. 6.9, Table 6.1).

    Parameters
    ----------
    T : numpy.ndarray, shape (N, 3)
        TCP position of each run (the pose at which the force is averaged) [m].
    q_dot : numpy.ndarray, shape (N, 3)
        Cart velocities [m/s] (constant during the run).
    tau : numpy.ndarray, shape (N, 3)
        Mean actuator forces [N].
    pose : numpy.ndarray, shape (N,)
        Integer pose index of each run (runs at the same pose share it).

    Raises
    ------
    InputError
        Shapes differ or values are not finite.
    """

    T: np.ndarray
    q_dot: np.ndarray
    tau: np.ndarray
    pose: np.ndarray

    def __post_init__(self) -> None:
        self.T = _signal(self.T, "T", None)
        n = self.T.shape[0]
        self.q_dot = _signal(self.q_dot, "q_dot", n)
        self.tau = _signal(self.tau, "tau", n)
        pose = np.asarray(self.pose).ravel()
        if pose.size != n:
            raise InputError(f"pose: expected {n} indices (one per run), got {pose.size}")
        self.pose = pose.astype(int)


@dataclass
class FrictionFit:
    """Coulomb and viscous friction from constant-velocity runs (Dressler (2012), Table 6.1).

    Parameters
    ----------
    f_c_plus, f_c_minus : numpy.ndarray, shape (3,)
        Coulomb friction [N] for positive / negative velocity (equal if symmetric).
    f_v_plus, f_v_minus : numpy.ndarray, shape (3,)
        Viscous friction [N s/m].
    std : dict of str to numpy.ndarray
        Standard deviations of the four, shape (3,) each.
    gravity : numpy.ndarray, shape (P, 3) or None
        Gravity force ``J^T G`` per pose [N] where estimated (two-direction runs).
    accumulated_mass : float or None
        ``m_p + sum m_a / 2`` [kg] estimated from the pose dependence of the gravity.
    accumulated_mass_std : float or None
        Its standard deviation [kg].
    method : str
        How the fit was made.
    """

    f_c_plus: np.ndarray
    f_c_minus: np.ndarray
    f_v_plus: np.ndarray
    f_v_minus: np.ndarray
    std: dict = field(default_factory=dict)
    gravity: np.ndarray | None = None
    accumulated_mass: float | None = None
    accumulated_mass_std: float | None = None
    method: str = ""

    @property
    def f_c(self) -> np.ndarray:
        """Symmetric Coulomb friction, the mean of both directions [N]."""
        return (self.f_c_plus + self.f_c_minus) / 2

    @property
    def f_v(self) -> np.ndarray:
        """Symmetric viscous friction, the mean of both directions [N s/m]."""
        return (self.f_v_plus + self.f_v_minus) / 2


def _gravity_model(parameters: RobotParameters, accumulated_mass: float) -> GantryTau3Dynamics:
    d = parameters.dynamics
    robot = dataclasses.replace(parameters, dynamics=dataclasses.replace(d, m_p=float(accumulated_mass), m_a=np.zeros(3)))
    return GantryTau3Dynamics(robot)


def accumulated_gravity_forces(T: np.typing.ArrayLike, parameters: RobotParameters | str | Path = "L1", accumulated_mass: float | None = None, configuration: int | Sequence[int] = 0) -> np.ndarray:
    """Gravity forces ``J^T G`` on the carts for the accumulated mass (Dressler (2012), eq. 6.9, Table 6.2).

    ``G = g (0, 0, m_acc)`` with ``m_acc = m_p + sum m_a/2`` carried by the plate (eq. 6.7),
    plus the carts' weight along their (nearly horizontal) guideways, evaluated by
    :meth:`gtmodel.robots.GantryTau3Dynamics.gravity_forces`.

    Parameters
    ----------
    T : array_like, shape (3,) or (N, 3)
        TCP positions [m].
    parameters : RobotParameters or str or pathlib.Path, optional
        Parameter set (default ``"L1"``).
    accumulated_mass : float, optional
        ``m_acc`` [kg] (default: the parameter set's ``m_p + sum m_a/2``; the thesis'
        friction experiment used 22.38 kg).
    configuration : int or sequence of int, optional
        IK configuration (default 0).

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        ``J^T G`` [N].

    Raises
    ------
    InputError
        Non-positive mass or invalid ``T``.
    """
    robot = load_parameters(parameters)
    if accumulated_mass is None:
        accumulated_mass = float(robot.dynamics.m_p + np.sum(robot.dynamics.m_a) / 2)
    if not (isinstance(accumulated_mass, (int, float)) and math.isfinite(accumulated_mass) and accumulated_mass > 0):
        raise InputError(f"accumulated_mass: expected a positive mass in kg, got {accumulated_mass!r}")
    return _gravity_model(robot, accumulated_mass).gravity_forces(T, configuration)


def subtract_gravity(data: ConstantVelocityData, parameters: RobotParameters | str | Path = "L1", accumulated_mass: float = 22.38, configuration: int | Sequence[int] = 0) -> ConstantVelocityData:
    """Remove the model's gravity ``J^T G`` from constant-velocity forces (eq. 6.9).

    With runs in one direction only, ``tau = J^T G + f_c + f_v v`` at one pose cannot tell
    the gravity from the Coulomb friction: a straight-line fit of ``tau`` over ``v`` puts
    ``J^T G`` into ``f_c`` (Dressler (2012), Fig. 6.2). Subtracting the model's gravity
    with the accumulated mass (22.38 kg in the thesis) first leaves friction only.

    Parameters
    ----------
    data : ConstantVelocityData
        The runs.
    parameters : RobotParameters or str or pathlib.Path, optional
        Parameter set (kinematics, gravity) (default ``"L1"``).
    accumulated_mass : float, optional
        ``m_p + sum m_a/2`` [kg] (default 22.38 kg, ch. 6.2).
    configuration : int or sequence of int, optional
        IK configuration (default 0).

    Returns
    -------
    ConstantVelocityData
        The same runs with ``tau - J^T G``.

    Raises
    ------
    InputError
        Invalid data or mass.
    """
    if not isinstance(data, ConstantVelocityData):
        raise InputError(f"data: expected ConstantVelocityData, got {type(data).__name__}")
    G = accumulated_gravity_forces(data.T, parameters, accumulated_mass, configuration)
    return ConstantVelocityData(data.T, data.q_dot, data.tau - G, data.pose)


def _line_fit(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    m, n = X.shape
    if m > n:
        r = y - X @ coef
        s2 = float(r @ r) / (m - n)
        cov = s2 * np.linalg.inv(X.T @ X)
        std = np.sqrt(np.diag(cov))
    else:
        std = np.full(n, math.nan)
    return coef, std


def fit_friction(data: ConstantVelocityData, asymmetric: bool = True, min_speed: float = 1e-3) -> FrictionFit:
    """Coulomb + viscous friction from gravity-free constant-velocity forces (eq. 6.8, Table 6.1).

    Per actuator a straight line ``tau = f_c + f_v v`` through the runs of each direction
    (asymmetric, Table 6.1) or ``tau = f_c sign(v) + f_v v`` through all (symmetric). The
    forces must not contain gravity: use :func:`subtract_gravity` or
    :func:`two_direction_friction`; otherwise ``J^T G`` ends up in ``f_c`` (Fig. 6.2).

    Parameters
    ----------
    data : ConstantVelocityData
        Runs (gravity removed).
    asymmetric : bool, optional
        Separate lines per direction (default True).
    min_speed : float, optional
        Runs with ``|q_dot_i|`` below this [m/s] are ignored (default 1 mm/s).

    Returns
    -------
    FrictionFit
        ``f_c_minus``/``f_v_minus`` are reported as positive numbers (force opposing the
        motion: ``tau = -f_c- + f_v- v`` for ``v < 0``). A direction without runs gives
        ``nan``.

    Raises
    ------
    InputError
        Invalid data, or fewer than two runs for a line.
    """
    if not isinstance(data, ConstantVelocityData):
        raise InputError(f"data: expected ConstantVelocityData, got {type(data).__name__}")
    out = {k: np.full(3, math.nan) for k in ("f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus")}
    std = {k: np.full(3, math.nan) for k in out}
    for i in range(3):
        v, y = data.q_dot[:, i], data.tau[:, i]
        if asymmetric:
            for sgn, suffix in ((1, "plus"), (-1, "minus")):
                m = sgn * v >= min_speed
                if m.sum() < 2:
                    continue
                X = np.column_stack([np.full(m.sum(), float(sgn)), v[m]])
                c, s = _line_fit(X, y[m])
                out[f"f_c_{suffix}"][i], out[f"f_v_{suffix}"][i] = c
                std[f"f_c_{suffix}"][i], std[f"f_v_{suffix}"][i] = s
        else:
            m = np.abs(v) >= min_speed
            if m.sum() < 2:
                raise InputError(f"data: actuator {i + 1} has fewer than two runs with |q_dot| >= {min_speed} m/s")
            c, s = _line_fit(np.column_stack([np.sign(v[m]), v[m]]), y[m])
            for suffix in ("plus", "minus"):
                out[f"f_c_{suffix}"][i], out[f"f_v_{suffix}"][i] = c
                std[f"f_c_{suffix}"][i], std[f"f_v_{suffix}"][i] = s
    return FrictionFit(**out, std=std, method="asymmetric lines per direction" if asymmetric else "symmetric f_c sign(v) + f_v v")


def two_direction_friction(data: ConstantVelocityData, parameters: RobotParameters | str | Path | None = "L1", configuration: int | Sequence[int] = 0, min_speed: float = 1e-3) -> FrictionFit:
    """Gravity and friction separated by runs in both directions (Dressler (2012), eq. 6.9, Fig. 6.2).

    At one pose and speed ``|v|`` the runs in both directions give
    ``tau(+v) = J^T G + f_c+ + f_v+ |v|`` and ``tau(-v) = J^T G - f_c- - f_v- |v|``: the half
    difference ``f_c + f_v |v|`` (mean friction) no longer holds gravity, and the mean
    ``J^T G + (f_c+ - f_c-)/2 + (f_v+ - f_v-)/2 |v|`` holds gravity plus the friction
    asymmetry. At a single pose the two cannot be told apart (a constant either way);
    with several poses the gravity changes with the pose as ``m_acc J^T g e_z`` (the
    model's :func:`accumulated_gravity_forces` per kg) while the asymmetry does not, so
    ``m_acc`` and the asymmetry are estimated by least squares over all poses (if
    ``parameters`` is given and there are at least two poses). Otherwise the asymmetry is
    taken as zero and the mean is the gravity.

    Parameters
    ----------
    data : ConstantVelocityData
        Runs in both directions at the same poses, paired by ``pose`` and the closest
        ``|v|`` (within :data:`SPEED_MATCH_TOLERANCE`).
    parameters : RobotParameters or str or pathlib.Path or None, optional
        Parameter set for the gravity direction ``J^T e_z`` (default ``"L1"``); None:
        symmetric friction assumed, no mass estimate.
    configuration : int or sequence of int, optional
        IK configuration (default 0).
    min_speed : float, optional
        Runs with ``|q_dot_i|`` below this [m/s] are ignored (default 1 mm/s).

    Returns
    -------
    FrictionFit
        Asymmetric friction, the per-pose gravity ``J^T G`` and, with several poses, the
        accumulated mass.

    Raises
    ------
    InputError
        A run without its opposite-direction partner, or too few runs.
    """
    if not isinstance(data, ConstantVelocityData):
        raise InputError(f"data: expected ConstantVelocityData, got {type(data).__name__}")
    poses = np.unique(data.pose)
    P = poses.size
    # mean of +- per (pose, |v|) and actuator; half difference
    rows = []  # (pose position, |v| (3,), mean (3,), half (3,))
    speed = np.abs(data.q_dot).mean(axis=1)
    direction = np.sign(data.q_dot.mean(axis=1))
    for pi, p in enumerate(poses):
        pos = np.flatnonzero((data.pose == p) & (direction > 0))
        neg = list(np.flatnonzero((data.pose == p) & (direction < 0)))
        for kp in pos:
            # the partner: the negative run at this pose with the closest speed
            if neg:
                kn = min(neg, key=lambda k: abs(speed[k] - speed[kp]))
            if not neg or abs(speed[kn] - speed[kp]) > SPEED_MATCH_TOLERANCE * speed[kp]:
                raise InputError(f"data: run {int(kp)} (pose {p}, speed {speed[kp]:.4g} m/s) needs a partner run in the opposite direction "
                                 f"at the same pose and speed (within {100 * SPEED_MATCH_TOLERANCE:g} %)")
            neg.remove(kn)
            vabs = (np.abs(data.q_dot[kp]) + np.abs(data.q_dot[kn])) / 2
            if np.any(vabs < min_speed):
                continue
            rows.append((pi, vabs, (data.tau[kp] + data.tau[kn]) / 2, (data.tau[kp] - data.tau[kn]) / 2))
        if neg:
            k = int(neg[0])
            raise InputError(f"data: run {k} (pose {p}, speed {speed[k]:.4g} m/s) needs a partner run in the opposite direction "
                             f"at the same pose and speed (within {100 * SPEED_MATCH_TOLERANCE:g} %)")
    if len(rows) < 2:
        raise InputError(f"data: {len(rows)} matched run pairs, expected at least 2")
    pidx = np.array([r[0] for r in rows])
    V = np.array([r[1] for r in rows])
    Mean = np.array([r[2] for r in rows])
    Half = np.array([r[3] for r in rows])
    out = {k: np.zeros(3) for k in ("f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus")}
    std = {k: np.zeros(3) for k in out}
    fc, fv, fc_s, fv_s = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    for i in range(3):
        c, s = _line_fit(np.column_stack([np.ones(len(rows)), V[:, i]]), Half[:, i])
        fc[i], fv[i] = c
        fc_s[i], fv_s[i] = s
    gravity = np.zeros((P, 3))
    dfc, dfv, dfc_s, dfv_s = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    m_acc = m_std = None
    if parameters is not None and P >= 2:
        T_pose = np.array([data.T[data.pose == p][0] for p in poses])
        G1 = accumulated_gravity_forces(T_pose, parameters, 1.0, configuration)
        G2 = accumulated_gravity_forces(T_pose, parameters, 2.0, configuration)
        g1 = G2 - G1  # J^T G per kg of accumulated mass
        g0 = 2 * G1 - G2  # the carts' weight along their guideways
        # unknowns: m_acc, dfc_1..3, dfv_1..3; rows: (pair, actuator)
        n = len(rows)
        X = np.zeros((3 * n, 7))
        y = np.zeros(3 * n)
        for i in range(3):
            X[i * n:(i + 1) * n, 0] = g1[pidx, i]
            X[i * n:(i + 1) * n, 1 + i] = 1.0
            X[i * n:(i + 1) * n, 4 + i] = V[:, i]
            y[i * n:(i + 1) * n] = Mean[:, i] - g0[pidx, i]
        c, s = _line_fit(X, y)
        m_acc, m_std = float(c[0]), float(s[0])
        dfc, dfv = c[1:4], c[4:7]
        dfc_s, dfv_s = s[1:4], s[4:7]
        gravity = m_acc * g1 + g0
        method = "two directions, several poses: gravity m_acc J^T g e_z and friction asymmetry separated"
    else:
        for pi in range(P):
            sel = pidx == pi
            for i in range(3):
                gravity[pi, i] = float(np.mean(Mean[sel, i]))
        method = "two directions: gravity = mean of +- (friction asymmetry assumed zero)"
    out["f_c_plus"], out["f_c_minus"] = fc + dfc, fc - dfc
    out["f_v_plus"], out["f_v_minus"] = fv + dfv, fv - dfv
    # the mean and half-difference fits use independent combinations of the runs
    sc, sv = np.sqrt(fc_s**2 + dfc_s**2), np.sqrt(fv_s**2 + dfv_s**2)
    std = {"f_c_plus": sc, "f_c_minus": sc, "f_v_plus": sv, "f_v_minus": sv}
    return FrictionFit(**out, std=std, gravity=gravity, accumulated_mass=m_acc, accumulated_mass_std=m_std, method=method)


def simulate_constant_velocity(
    poses: np.typing.ArrayLike,
    speeds: np.typing.ArrayLike,
    parameters: RobotParameters | str | Path = "L1",
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
    parameters : RobotParameters or str or pathlib.Path, optional
        The true robot (default ``"L1"``).
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
    P = _signal(np.atleast_2d(np.asarray(poses, dtype=float)), "poses", None)
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
