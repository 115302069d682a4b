"""The registry of problem kinds: ``kind = "..."`` in a file -> its :class:`ProblemKind`.

Adding a kind is one class in :mod:`gtmodel.problems.kinds` and one line in
:data:`_CLASSES` (and its schema, in :mod:`gtmodel.problems.kinds.schemas`, one line in
:data:`_SCHEMAS`). The registry names each kind's class by its dotted path and imports a
kind's module only when the kind is first used, so that listing the kinds (``gtmodel
schema --list``) or a problem file of one kind does not import every kind's solvers; and
it names each kind's schema by its own (light) path, so that a file with a bad field is
reported (:func:`get_schema`) before its kind's solvers are imported.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
from pathlib import Path
from typing import TYPE_CHECKING, Iterator, Mapping

from gtmodel.errors import ProblemError

if TYPE_CHECKING:
    from gtmodel.problems.base import ProblemKind
    from gtmodel.problems.schema import ProblemSchema

__all__ = ["KINDS", "get_kind", "get_schema", "kind_titles"]

#: Kind name -> ``module:class`` of its :class:`ProblemKind`, in the order of the documentation.
_CLASSES: dict[str, str] = {
    "point_to_point": "gtmodel.problems.kinds.point_to_point:PointToPointKind",
    "path_constrained": "gtmodel.problems.kinds.path_constrained:PathConstrainedKind",
    "calibration": "gtmodel.problems.kinds.calibration:CalibrationKind",
    "elasto_geometric_calibration": "gtmodel.problems.kinds.elasto_geometric_calibration:ElastoGeometricKind",
    "dynamic_identification": "gtmodel.problems.kinds.dynamic_identification:DynamicIdentificationKind",
    "joint_stiffness_calibration": "gtmodel.problems.kinds.joint_stiffness_calibration:JointStiffnessKind",
    "vision_calibration": "gtmodel.problems.kinds.vision_calibration:VisionCalibrationKind",
    "tracking": "gtmodel.problems.kinds.tracking:TrackingKind",
    "ilc": "gtmodel.problems.kinds.ilc:ILCKind",
    "state_estimation": "gtmodel.problems.kinds.state_estimation:StateEstimationKind",
    "correction_stability": "gtmodel.problems.kinds.correction_stability:CorrectionStabilityKind",
    "optimal_control": "gtmodel.problems.kinds.optimal_control:OptimalControlKind",
    "lead_through": "gtmodel.problems.kinds.lead_through:LeadThroughKind",
    "pose_accuracy": "gtmodel.problems.kinds.pose_accuracy:PoseAccuracyKind",
    "automated_calibration": "gtmodel.problems.kinds.automated_calibration:AutomatedCalibrationKind",
}

#: Kind name -> ``module:class`` of its schema in a light module (pydantic, no solver); the
#: kind's ``schema`` is the same class. A kind not listed is validated against the
#: ``schema`` of its (imported) kind.
_SCHEMAS: dict[str, str] = {
    "point_to_point": "gtmodel.problems.kinds.schemas.point_to_point:PointToPointFile",
    "path_constrained": "gtmodel.problems.kinds.schemas.path_constrained:PathConstrainedFile",
    "optimal_control": "gtmodel.problems.kinds.schemas.optimal_control:OptimalControlFile",
    "tracking": "gtmodel.problems.kinds.schemas.tracking:TrackingFile",
    "ilc": "gtmodel.problems.kinds.schemas.ilc:ILCFile",
    "calibration": "gtmodel.problems.kinds.schemas.calibration:CalibrationFile",
    "elasto_geometric_calibration": "gtmodel.problems.kinds.schemas.elasto_geometric_calibration:ElastoGeometricFile",
    "joint_stiffness_calibration": "gtmodel.problems.kinds.schemas.joint_stiffness_calibration:JointStiffnessFile",
    "vision_calibration": "gtmodel.problems.kinds.schemas.vision_calibration:VisionCalibrationFile",
    "dynamic_identification": "gtmodel.problems.kinds.schemas.dynamic_identification:DynamicIdentificationFile",
    "lead_through": "gtmodel.problems.kinds.schemas.lead_through:LeadThroughFile",
    "pose_accuracy": "gtmodel.problems.kinds.schemas.pose_accuracy:PoseAccuracyFile",
    "automated_calibration": "gtmodel.problems.kinds.schemas.automated_calibration:AutomatedCalibrationFile",
}


class _Kinds(Mapping[str, "ProblemKind"]):
    """Kind name -> the kind (one instance each), its module imported on first use."""

    def __init__(self, classes: Mapping[str, str]) -> None:
        self._classes = dict(classes)
        self._kinds: dict[str, ProblemKind] = {}

    def __getitem__(self, name: str) -> "ProblemKind":
        kind = self._kinds.get(name)
        if kind is None:
            module, cls = self._classes[name].split(":")
            kind = self._kinds[name] = getattr(importlib.import_module(module), cls)()
        return kind

    def __iter__(self) -> Iterator[str]:
        return iter(self._classes)

    def __len__(self) -> int:
        return len(self._classes)

    def __contains__(self, name: object) -> bool:
        return name in self._classes

    def __repr__(self) -> str:
        return f"KINDS({', '.join(self._classes)})"


#: Kind name -> the kind (one instance each), in the order of the documentation.
KINDS: Mapping[str, "ProblemKind"] = _Kinds(_CLASSES)


def get_kind(name: str) -> "ProblemKind":
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
    if name not in _CLASSES:
        raise ProblemError(f"unknown problem kind {name!r}: expected one of {', '.join(KINDS)}")
    return KINDS[name]


def get_schema(name: str) -> "type[ProblemSchema]":
    """The schema of a kind, without importing the kind's module where it has a light one.

    Parameters
    ----------
    name : str
        E.g. ``"point_to_point"``.

    Returns
    -------
    type of ProblemSchema
        The same class as ``get_kind(name).schema``.

    Raises
    ------
    ProblemError
        Not a registered kind.
    """
    if name not in _CLASSES:
        raise ProblemError(f"unknown problem kind {name!r}: expected one of {', '.join(KINDS)}")
    target = _SCHEMAS.get(name)
    if target is None:
        return KINDS[name].schema
    module, cls = target.split(":")
    return getattr(importlib.import_module(module), cls)


def kind_titles() -> dict[str, str]:
    """Kind name -> its one-line title, read from the kinds' sources without importing them.

    The title is the ``title = "..."`` class attribute of the kind's class (what
    ``KINDS[name].title`` gives); reading it from the source keeps ``gtmodel schema
    --list`` from importing every kind's solvers.

    Returns
    -------
    dict of str to str
        In the order of :data:`KINDS`; ``""`` for a kind whose title is not a literal.
    """
    titles = {}
    for name, target in _CLASSES.items():
        module, cls = target.split(":")
        spec = importlib.util.find_spec(module)
        tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8")) if spec is not None and spec.origin else ast.Module(body=[])
        titles[name] = next((node.value.value for c in tree.body if isinstance(c, ast.ClassDef) and c.name == cls
                             for node in c.body if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant)
                             and any(getattr(t, "id", None) == "title" for t in node.targets)), "")
    return titles
