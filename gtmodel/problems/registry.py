"""The registry of problem kinds: ``kind = "..."`` in a file -> its :class:`ProblemKind`.

Adding a kind is one class in :mod:`gtmodel.problems.kinds` and one line in
:data:`_CLASSES`.
"""

from __future__ import annotations

from gtmodel.errors import ProblemError
from gtmodel.problems.base import ProblemKind
from gtmodel.problems.kinds.path_constrained import PathConstrainedKind
from gtmodel.problems.kinds.calibration import CalibrationKind
from gtmodel.problems.kinds.elasto_geometric_calibration import ElastoGeometricKind
from gtmodel.problems.kinds.dynamic_identification import DynamicIdentificationKind
from gtmodel.problems.kinds.joint_stiffness_calibration import JointStiffnessKind
from gtmodel.problems.kinds.point_to_point import PointToPointKind
from gtmodel.problems.kinds.tracking import TrackingKind
from gtmodel.problems.kinds.ilc import ILCKind
from gtmodel.problems.kinds.state_estimation import StateEstimationKind
from gtmodel.problems.kinds.correction_stability import CorrectionStabilityKind
from gtmodel.problems.kinds.optimal_control import OptimalControlKind

__all__ = ["KINDS", "get_kind"]

_CLASSES: tuple[type[ProblemKind], ...] = (
    PointToPointKind,
    PathConstrainedKind,
    CalibrationKind,
    ElastoGeometricKind,
    DynamicIdentificationKind,
    JointStiffnessKind,
    TrackingKind,
    ILCKind,
    StateEstimationKind,
    CorrectionStabilityKind,
    OptimalControlKind,
)

#: Kind name -> the kind (one instance each), in the order of the documentation.
KINDS: dict[str, ProblemKind] = {cls.name: cls() for cls in _CLASSES}


def get_kind(name: str) -> ProblemKind:
    """The kind of a name.

    Parameters
    ----------
    name : str
        E.g. ``"point_to_point"``.

    Returns
    -------
    ProblemKind

    Raises
    ------
    ProblemError
        Not a registered kind.
    """
    try:
        return KINDS[name]
    except KeyError:
        raise ProblemError(f"unknown problem kind {name!r}: expected one of {', '.join(KINDS)}") from None
