"""Model variants of the identification: which parameters of eqs. 6.7/6.8 are estimated.

Dressler (2012), Table 6.3 and two more variants for analysis (:data:`VARIANTS`):

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

Also the thesis' Table 6.3 (:data:`THESIS_TABLE_6_3`) and the symbolic parameter set of a
variant (the free parameters as CasADi symbols) from which
:class:`~gtmodel.calibration.identification.DynamicRegressor` differentiates the
inverse dynamics.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Sequence

import casadi as ca
import numpy as np

from gtmodel.errors import InputError
from gtmodel.robots.parameters import DynamicParameters, FrictionParameters

__all__ = ["VARIANTS", "TABLE_6_3_COLUMNS", "THESIS_TABLE_6_3", "ModelVariant", "get_variant"]

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
