"""Constraint coefficients from the symbolic model: one CasADi Function per robot and limit kinds, cached.

``rows(T, dT, ddT, sg) -> (m, c, d, g, q, dq, ddq, disc, cos)`` maps path samples to the
coefficients of every row ``m a + c b + d sqrt(b) + g`` (``a = s_ddot``, ``b = s_dot^2``),
extracted from the inverse dynamics with ``casadi.jacobian`` (see the package docstring).
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.path_projection import path_rows_function

__all__: list[str] = []


def _exact_dynamics(robot: Any) -> GantryTau3Dynamics:
    """Dynamics with the exact Coulomb sign (the path projection fixes its argument)."""
    if isinstance(robot, GantryTau3Dynamics):
        if robot.friction == "exact":
            return robot
        return GantryTau3Dynamics(robot.parameters, friction="exact", asymmetric=robot.asymmetric, gravity=robot.gravity)
    return GantryTau3Dynamics(robot, friction="exact")


_FUNCTION_CACHE: OrderedDict = OrderedDict()
_FUNCTION_CACHE_SIZE = 16


def _cache_key(robot: Any) -> Any:
    if robot is None:
        return None
    if isinstance(robot, str):
        return ("name", robot)
    return ("object", id(robot))


def _rows_function(dyn: GantryTau3Dynamics | None, kinds: tuple[str, ...], viscous: bool) -> ca.Function:
    """CasADi Function ``rows(T, dT, ddT, sg) -> (m, c, d, g, q, dq, ddq, disc, cos)``.

    Rows in the order of :meth:`PathConstraints.bounds`; ``dq = q'(s)``, ``ddq = q''(s)``.
    The graph is :func:`gtmodel.robots.path_projection.path_rows_function`, the one the
    generated C re-timing function is generated from.
    """
    return path_rows_function(dyn, kinds, viscous)


def _cached_rows_function(robot: Any, dyn: GantryTau3Dynamics | None, kinds: tuple[str, ...], viscous: bool) -> ca.Function:
    key = ("rows", _cache_key(robot), kinds, viscous)
    hit = _FUNCTION_CACHE.get(key)
    if hit is not None and (robot is None or isinstance(robot, str) or hit[0] is robot):  # id() may be reused
        _FUNCTION_CACHE.move_to_end(key)
        return hit[1]
    f = _rows_function(dyn, kinds, viscous)
    _FUNCTION_CACHE[key] = (robot, f, dyn)
    if len(_FUNCTION_CACHE) > _FUNCTION_CACHE_SIZE:
        _FUNCTION_CACHE.popitem(last=False)
    return f


def _cached_dynamics(robot: Any) -> GantryTau3Dynamics:
    if isinstance(robot, GantryTau3Dynamics) and robot.friction == "exact":
        return robot
    key = ("dynamics", _cache_key(robot))
    hit = _FUNCTION_CACHE.get(key)
    if hit is not None and (isinstance(robot, str) or hit[0] is robot):
        _FUNCTION_CACHE.move_to_end(key)
        return hit[2]
    dyn = _exact_dynamics(robot)
    _FUNCTION_CACHE[key] = (robot, None, dyn)
    if len(_FUNCTION_CACHE) > _FUNCTION_CACHE_SIZE:
        _FUNCTION_CACHE.popitem(last=False)
    return dyn


class _MapCache:
    """Evaluate a Function on N samples (columns), one ``map`` per N."""

    def __init__(self, f: ca.Function) -> None:
        self.f = f
        self.maps: dict[int, ca.Function] = {}
        self.buffers: dict[int, tuple] = {}

    def __call__(self, n: int, *args: np.ndarray) -> list[np.ndarray]:
        if n not in self.maps:
            self.maps[n] = self.f.map(n)
        out = self.maps[n](*args)
        if not isinstance(out, (list, tuple)):
            out = [out]
        return [np.asarray(o) for o in out]

    def rows(self, n: int, *args: np.ndarray) -> list[np.ndarray]:
        """The same evaluation on sample-major arrays ``(n, k)``, returning ``(n, rows)`` arrays.

        Through the map's zero-copy buffer (:meth:`casadi.Function.buffer`): a C-ordered
        ``(n, k)`` array is the column-major ``(k, n)`` matrix CasADi expects, so neither the
        inputs nor the outputs pass through per-element Python objects (``DM.full`` does).
        """
        if n not in self.buffers:
            fm = self.maps.get(n) or self.f.map(n)
            self.maps[n] = fm
            buf, run = fm.buffer()
            self.buffers[n] = (buf, run, [fm.size1_out(i) for i in range(fm.n_out())])
        buf, run, sizes = self.buffers[n]
        ins = [np.ascontiguousarray(a, dtype=float) for a in args]
        outs = [np.empty((n, k)) for k in sizes]
        for i, a in enumerate(ins):
            buf.set_arg(i, memoryview(a))
        for i, o in enumerate(outs):
            buf.set_res(i, memoryview(o))
        run()
        return outs
