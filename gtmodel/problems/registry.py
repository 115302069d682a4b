"""The registry of problem kinds: ``kind = "..."`` in a file -> its :class:`ProblemKind`.

Adding a kind is one class in :mod:`gtmodel.problems.kinds` and one line in
:data:`_CLASSES` (and its schema, in :mod:`gtmodel.problems.kinds.schemas`, one line in
:data:`_SCHEMAS`). The registry names each kind's class by its dotted path and imports a
kind's module only when the kind is first used, so that listing the kinds (``gtmodel
schema --list``) or a problem file of one kind does not import every kind's solvers; and
it names each kind's schema by its own (light) path, so that a file with a bad field is
reported (:func:`get_schema`) before its kind's solvers are imported.

The loop-controller files (an MPC file, a tracking-controller file, an estimator + ILC
bundle) are declared kinds too, :data:`LOOP_KINDS`: each a :class:`LoopKind`, its light
schema, its reader and the ``gtmodel codegen`` route that generates and checks it. They are
not solved (``gtmodel solve`` names the route), but ``gtmodel schema --list``, ``gtmodel
schema KIND``, ``docs/schemas`` and the readers' validation come from the same declarations
(:func:`get_schema`, :func:`read_declared`).

A kind renamed keeps its old name for a while (:data:`RENAMED`): a file that gives it is read
as the new kind, with a deprecation warning logged (:func:`canonical_kind`).
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterator, Mapping

from gtmodel.errors import ProblemError

if TYPE_CHECKING:
    from gtmodel.problems.base import ProblemKind
    from gtmodel.problems.schema import ProblemSchema

__all__ = ["KINDS", "LOOP_KINDS", "LOOP_OUTPUT", "MODEL_OCP_KINDS", "RENAMED", "LoopKind", "canonical_kind", "get_kind", "get_loop_kind", "get_schema",
           "kind_titles", "all_kinds"]

log = logging.getLogger("gtmodel")

#: Kind name -> ``module:class`` of its :class:`ProblemKind`, in the order of the documentation.
_CLASSES: dict[str, str] = {
    "point_to_point": "gtmodel.problems.kinds.point_to_point:PointToPointKind",
    "path_constrained": "gtmodel.problems.kinds.path_constrained:PathConstrainedKind",
    "calibration": "gtmodel.problems.kinds.calibration:CalibrationKind",
    "elasto_geometric_calibration": "gtmodel.problems.kinds.elasto_geometric_calibration:ElastoGeometricKind",
    "dynamic_identification": "gtmodel.problems.kinds.dynamic_identification:DynamicIdentificationKind",
    "joint_stiffness_calibration": "gtmodel.problems.kinds.joint_stiffness_calibration:JointStiffnessKind",
    "vision_calibration": "gtmodel.problems.kinds.vision_calibration:VisionCalibrationKind",
    "replay": "gtmodel.problems.kinds.replay:ReplayKind",
    "ilc": "gtmodel.problems.kinds.ilc:ILCKind",
    "state_estimation": "gtmodel.problems.kinds.state_estimation:StateEstimationKind",
    "correction_stability": "gtmodel.problems.kinds.correction_stability:CorrectionStabilityKind",
    "optimal_control": "gtmodel.problems.kinds.optimal_control:OptimalControlKind",
    "optimica": "gtmodel.problems.kinds.optimica:OptimicaKind",
    "lead_through": "gtmodel.problems.kinds.lead_through:LeadThroughKind",
    "pose_accuracy": "gtmodel.problems.kinds.pose_accuracy:PoseAccuracyKind",
    "automated_calibration": "gtmodel.problems.kinds.automated_calibration:AutomatedCalibrationKind",
    "robot_loop": "gtmodel.problems.kinds.robot_loop:RobotLoopKind",
}

#: Kind name -> ``module:class`` of its schema in a light module (pydantic, no solver); the
#: kind's ``schema`` is the same class. A kind not listed is validated against the
#: ``schema`` of its (imported) kind.
_SCHEMAS: dict[str, str] = {
    "point_to_point": "gtmodel.problems.kinds.schemas.point_to_point:PointToPointFile",
    "path_constrained": "gtmodel.problems.kinds.schemas.path_constrained:PathConstrainedFile",
    "optimal_control": "gtmodel.problems.kinds.schemas.optimal_control:OptimalControlFile",
    "optimica": "gtmodel.problems.kinds.schemas.optimica:OptimicaFile",
    "replay": "gtmodel.problems.kinds.schemas.replay:ReplayFile",
    "ilc": "gtmodel.problems.kinds.schemas.ilc:ILCFile",
    "calibration": "gtmodel.problems.kinds.schemas.calibration:CalibrationFile",
    "elasto_geometric_calibration": "gtmodel.problems.kinds.schemas.elasto_geometric_calibration:ElastoGeometricFile",
    "joint_stiffness_calibration": "gtmodel.problems.kinds.schemas.joint_stiffness_calibration:JointStiffnessFile",
    "vision_calibration": "gtmodel.problems.kinds.schemas.vision_calibration:VisionCalibrationFile",
    "dynamic_identification": "gtmodel.problems.kinds.schemas.dynamic_identification:DynamicIdentificationFile",
    "lead_through": "gtmodel.problems.kinds.schemas.lead_through:LeadThroughFile",
    "pose_accuracy": "gtmodel.problems.kinds.schemas.pose_accuracy:PoseAccuracyFile",
    "automated_calibration": "gtmodel.problems.kinds.schemas.automated_calibration:AutomatedCalibrationFile",
    "robot_loop": "gtmodel.problems.kinds.schemas.robot_loop:RobotLoopFile",
}


#: The kinds whose results are an optimal trajectory of a user's model (``summary.json``'s ``model`` and
#: ``trajectories.csv`` as ``optimal_control`` writes them): an ``optimica`` file's class is that kind's
#: declaration, so its result folder serves a tracking controller or a loop file's reference as well.
MODEL_OCP_KINDS: tuple[str, ...] = ("optimal_control", "optimica")

#: Former kind name -> its name now: a file of the former name is read as the new kind, with a
#: deprecation warning (``tracking``: the L1 replay, renamed so that "tracking" names one thing,
#: the tracking controller).
RENAMED: dict[str, str] = {"tracking": "replay"}

#: What ``gtmodel codegen --out DIR`` writes for a loop controller (prefix ``gt_<name>``): the
#: result folder contract of the loop-controller kinds (the folder's rule:
#: :func:`gtmodel.codegen.out_dir.check_out_dir`).
LOOP_OUTPUT: dict[str, str] = {
    "{prefix}.c": "the loop step's C: the step, its memory and the reference tables' wrapper",
    "{prefix}.h": "its header: the step's prototype, sizes and the memory's layout",
    "{prefix}_casadi.c": "the CasADi-generated C of the step's Function (the controller's graph, a solver inside for the MPC)",
    "{prefix}_casadi.h": "its header",
    "build/": "with --check: the compiled library and the closed-loop check's build",
}


@dataclass(frozen=True)
class LoopKind:
    """A loop-controller file kind: declared as a problem kind is (a light schema), built and checked by ``gtmodel codegen``.

    Parameters
    ----------
    name : str
        The kind's name (``gtmodel schema NAME``).
    title : str
        One line for ``gtmodel schema --list`` and the reference page.
    schema : str
        ``module:Class`` of its light schema (pydantic; unknown fields refused).
    reader : str
        ``module:function`` reading, validating and building a file (``reader(path)``).
    what : str
        The file's name in messages (``"MPC file"``).
    command : str
        The ``gtmodel codegen`` route that generates and checks it.
    section : str, optional
        The controller's table (``"mpc"``, ``"controller"``); empty for a file without one.
    suffixes : tuple of str, optional
        The file's suffixes.
    output : mapping of str to str, optional
        What the route writes into ``--out`` (:data:`LOOP_OUTPUT`), file name -> description.
    """

    name: str
    title: str
    schema: str
    reader: str
    what: str
    command: str
    section: str = ""
    suffixes: tuple[str, ...] = (".toml",)
    output: Mapping[str, str] = field(default_factory=lambda: dict(LOOP_OUTPUT))

    def schema_class(self) -> type:
        """The schema class (its light module imported).

        Returns
        -------
        type
            A pydantic model.
        """
        module, cls = self.schema.split(":")
        return getattr(importlib.import_module(module), cls)

    def read(self, path: str | Path) -> Any:
        """Read, validate and build a file of this kind (the reader imported on first use).

        Parameters
        ----------
        path : str or pathlib.Path
            The file.

        Returns
        -------
        Any
            What the reader builds (a :class:`~gtmodel.problems.loop_file.LoopSetup`; the
            bundle: a :class:`~gtmodel.codegen.EstimatorILCBundle`).

        Raises
        ------
        GtModelError
            The reader's (naming the file and the field).
        """
        module, fn = self.reader.split(":")
        return getattr(importlib.import_module(module), fn)(path)


#: Kind name -> the loop-controller file kind, in the order of the documentation.
LOOP_KINDS: dict[str, LoopKind] = {
    "mpc": LoopKind(
        name="mpc", title="MPC file: a real-time nonlinear MPC along a reference, generated as C ([mpc], [reference], [check])",
        schema="gtmodel.problems.kinds.schemas.mpc:MPCFile", reader="gtmodel.problems.mpc_file:load_mpc_file",
        what="MPC file", command="gtmodel codegen --mpc FILE.toml --out DIR [--check]", section="mpc"),
    "tracking_controller": LoopKind(
        name="tracking_controller",
        title="tracking-controller file: feedforward + time-varying LQR along a reference, generated as C ([controller], [reference], [check])",
        schema="gtmodel.problems.kinds.schemas.tracking_controller:TrackingFile", reader="gtmodel.problems.tracking_file:load_tracking_file",
        what="tracking-controller file", command="gtmodel codegen --controller FILE.toml --out DIR [--check]", section="controller"),
    "estimator_ilc": LoopKind(
        name="estimator_ilc",
        title="estimator + ILC bundle (.json/.npz): the Kalman step, the learned ILC correction, the fusion filters, the lead-through step",
        schema="gtmodel.problems.kinds.schemas.estimator_ilc:EstimatorILCFile", reader="gtmodel.codegen.controller_file:load_controller",
        what="controller file", command="gtmodel codegen [--robot L1] --controller FILE.json --out DIR [--check]", suffixes=(".json", ".npz"),
        output={"gt*.c": "the generated C of the bundle's Functions (with the robot's when --robot is given)", "gt*.h": "their header",
                "build/": "with --check: the compiled library and its check"}),
}


def canonical_kind(name: Any, where: str = "") -> Any:
    """The kind's current name: a renamed kind's new one (:data:`RENAMED`), with a deprecation warning logged.

    Parameters
    ----------
    name : Any
        The ``kind`` a file gives (returned unchanged when not a renamed kind's).
    where : str, optional
        The file, named in the warning.

    Returns
    -------
    Any
        ``RENAMED[name]`` or ``name``.
    """
    if isinstance(name, str) and name in RENAMED:
        log.warning("%skind = %r is deprecated: it is now kind = %r (the file is read as such; rename it)",
                    f"{where}: " if where else "", name, RENAMED[name])
        return RENAMED[name]
    return name


def get_loop_kind(name: str) -> LoopKind:
    """The loop-controller file kind of a name.

    Parameters
    ----------
    name : str
        E.g. ``"mpc"``.

    Returns
    -------
    LoopKind

    Raises
    ------
    ProblemError
        Not a loop-controller file kind.
    """
    if name not in LOOP_KINDS:
        raise ProblemError(f"unknown loop-controller file kind {name!r}: expected one of {', '.join(LOOP_KINDS)}")
    return LOOP_KINDS[name]


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
    name = canonical_kind(name)
    if name not in _CLASSES:
        raise ProblemError(_unknown(name))
    return KINDS[name]


def _unknown(name: str) -> str:
    if name in LOOP_KINDS:
        return (f"{name!r} is a loop-controller file kind, generated and checked by code generation, not solved: "
                f"{LOOP_KINDS[name].command}")
    return f"unknown problem kind {name!r}: expected one of {', '.join(KINDS)}"


def all_kinds() -> list[str]:
    """Every declared kind: the problem kinds, then the loop-controller file kinds.

    Returns
    -------
    list of str
        The names ``gtmodel schema`` takes, in the order of the documentation.
    """
    return [*KINDS, *LOOP_KINDS]


def get_schema(name: str) -> "type[ProblemSchema]":
    """The schema of a kind, without importing the kind's module where it has a light one.

    Parameters
    ----------
    name : str
        E.g. ``"point_to_point"``, or a loop-controller file kind (``"mpc"``).

    Returns
    -------
    type of ProblemSchema
        The same class as ``get_kind(name).schema`` (a loop-controller file kind: its schema,
        :meth:`LoopKind.schema_class`).

    Raises
    ------
    ProblemError
        Not a registered kind.
    """
    name = canonical_kind(name)
    if name in LOOP_KINDS:
        return LOOP_KINDS[name].schema_class()
    if name not in _CLASSES:
        raise ProblemError(f"unknown kind {name!r}: expected one of {', '.join(all_kinds())}")
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
        In the order of :data:`KINDS`, then the loop-controller file kinds of :data:`LOOP_KINDS`
        (their :attr:`LoopKind.title`); ``""`` for a kind whose title is not a literal.
    """
    titles = {}
    for name, target in _CLASSES.items():
        module, cls = target.split(":")
        spec = importlib.util.find_spec(module)
        tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8")) if spec is not None and spec.origin else ast.Module(body=[])
        titles[name] = next((node.value.value for c in tree.body if isinstance(c, ast.ClassDef) and c.name == cls
                             for node in c.body if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant)
                             and any(getattr(t, "id", None) == "title" for t in node.targets)), "")
    titles.update({name: kind.title for name, kind in LOOP_KINDS.items()})
    return titles
