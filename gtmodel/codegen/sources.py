"""The one front door of code generation: a :class:`CodeSource` per kind of code, :func:`generate_code`, :func:`check_code`.

Every kind of generated code is a source (:class:`~gtmodel.codegen.code_source.CodeSource`,
the base class) that supplies its function declarations
(:meth:`CodeSource.specs`, each a :class:`~gtmodel.codegen.declarations.FunctionSpec` with
its C signature and status checks), the Python reference the check compares the C with
(:meth:`CodeSource.reference`), a one-line :meth:`CodeSource.summary` of what it generates
(the header's first line, ``gtmodel codegen``'s) and its writer (:meth:`CodeSource.generate`,
through the one library writer :func:`gtmodel.codegen.writer.write_library`):

=====================  ================================================================
source                 what it generates
=====================  ================================================================
:class:`RobotSource`   a robot's kinematics and inverse dynamics (``gtmodel codegen robot``)
:class:`UserModelSource`  a user's model: explicit ODE, outputs, fixed steps (``... model``)
:class:`~gtmodel.codegen.loop_step.LoopStep`  a loop controller's step: the tracking controller
                       (TV-LQR) or an MPC (``... tracking``, ``... mpc``)
:class:`ControllerSource`  a controller bundle of a ``.json``/``.npz`` file: Kalman step, ILC
                       table, the fusion KF/EKF filters, the lead-through step (``... controller``)
=====================  ================================================================

:func:`generate_code` dispatches on the source's type;
:func:`gtmodel.codegen.verdict.check_code` on the generated code's source (:func:`source_of`)
and returns one :class:`~gtmodel.codegen.verdict.CodeCheck` whose status is the shared
:class:`~gtmodel.status.Status` (every part's report has one: ``CheckReport.status``,
``LoopCheck.status``). The former front doors (:func:`gtmodel.codegen.generate.generate`,
:func:`~gtmodel.codegen.model_code.generate_model`,
:func:`~gtmodel.codegen.loop_step.generate_loop_step`, ``generate(controller=)``) stay as the
sources' writers; :func:`generate` here and :func:`gtmodel.codegen.verdict.check` are the
package's ``gtmodel.codegen.generate`` / ``gtmodel.codegen.check``, which keep their former calls.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

from gtmodel.codegen.code_source import CodeSource
from gtmodel.codegen.controller import Controller
from gtmodel.codegen.declarations import CONTROLLER_KIND, FunctionSpec
from gtmodel.codegen.generate import generate as generate_robot
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.codegen.loop_step import LoopStep, mpc_step, tracking_step
from gtmodel.codegen.model_code import MODEL_KIND, ModelSource, generate_model, model_specs
from gtmodel.codegen.robot import RobotModel, load_robot
from gtmodel.codegen.specs import SPECS_BY_KIND, default_functions
from gtmodel.control.mpc import MPCController
from gtmodel.control.tracking import TrackingController
from gtmodel.defaults import LOOP_PERIOD_S, REAL_TYPES
from gtmodel.modeling import Component, Model, explicit_ode
from gtmodel.errors import InputError

__all__ = ["CodeSource", "RobotSource", "UserModelSource", "ControllerSource", "as_source", "source_of", "generate_code", "generate"]

log = logging.getLogger("gtmodel")


@dataclass(frozen=True)
class RobotSource(CodeSource):
    """A robot's model functions (kinematics, inverse dynamics), optionally with a controller bundle and the re-timing.

    Parameters
    ----------
    robot : str or pathlib.Path or RobotParameters or SixLinkClosure or F1Closure
        The robot (:func:`gtmodel.codegen.robot.load_robot`): ``"L1"``, ``"D1"``, ``"L1_ideal"``,
        ``"D1_six_link"``, ``"F1"`` or a parameter TOML path.
    friction : str
        Friction form of ``inverse_dynamics`` (``"exact"``, ``"tanh"``, ``"piecewise"``).
    functions : sequence of str, optional
        A subset of the robot kind's functions (default all).
    newton_tolerance : float, optional
        Tolerance of the Newton loops (default per function).
    max_iter : int, optional
        Iteration limit of the Newton loops.
    controller : Controller, optional
        A controller bundle generated into the same library.
    retime_n_max : int, optional
        Also the online re-timing with at most this many grid points.
    """

    robot: Any = "L1"
    friction: str = "exact"
    functions: Sequence[str] | None = None
    newton_tolerance: float | None = None
    max_iter: int | None = None
    controller: Controller | None = None
    retime_n_max: int | None = None
    kind: str = field(default="robot", init=False)

    def model(self) -> RobotModel:
        """The symbolic robot model (:class:`~gtmodel.codegen.robot.RobotModel`).

        Returns
        -------
        RobotModel
        """
        return RobotModel(load_robot(self.robot), self.friction)

    def _summary(self) -> str:
        return f"kinematics and inverse dynamics of the robot {self.robot}" + (" with a controller bundle" if self.controller else "")

    def _specs(self) -> tuple[FunctionSpec, ...]:
        # the robot kind's table (gtmodel.codegen.specs.SPECS_BY_KIND), then the controller's
        kind = self.model().kind
        table = SPECS_BY_KIND[kind]
        names = default_functions(kind) if self.functions is None else self.functions
        return tuple(table[n] for n in names) + (self.controller.specs() if self.controller else ())

    def _target(self, spec: FunctionSpec) -> Any:
        return self.controller if spec.kind == CONTROLLER_KIND else self.model()

    def _write(self, out_dir: str | Path, real: str, prefix: str | None) -> GeneratedCode:
        return generate_robot(self.robot, out_dir, functions=self.functions, prefix=prefix, friction=self.friction, real=real,
                              newton_tolerance=self.newton_tolerance, max_iter=self.max_iter, controller=self.controller,
                              retime_n_max=self.retime_n_max)


@dataclass(frozen=True)
class UserModelSource(CodeSource):
    """A user's model: its explicit ODE, outputs and fixed steps (:mod:`gtmodel.codegen.model_code`).

    Parameters
    ----------
    model : Model or Component
        The model (e.g. from :func:`gtmodel.problems.user_model.load_user_model`).
    dt : float
        Period of the fixed-step functions [s] (default the 4 ms loop).
    functions : sequence of str, optional
        A subset of :data:`gtmodel.codegen.model_code.MODEL_FUNCTIONS`.
    """

    model: Any
    dt: float = LOOP_PERIOD_S
    functions: Sequence[str] | None = None
    kind: str = field(default=MODEL_KIND, init=False)

    def _source(self) -> ModelSource:
        model = self.model.to_model() if isinstance(self.model, Component) else self.model
        return ModelSource(model, explicit_ode(model), self.dt)

    def _summary(self) -> str:
        return f"the explicit ODE, outputs and fixed {self.dt:g} s steps of the model {getattr(self.model, 'name', self.model)}"

    def _specs(self) -> tuple[FunctionSpec, ...]:
        specs = model_specs(self._source().ode, self.dt)
        return specs if self.functions is None else tuple(s for s in specs if s.name in self.functions)

    def _target(self, spec: FunctionSpec) -> Any:
        return self._source()

    def _write(self, out_dir: str | Path, real: str, prefix: str | None) -> GeneratedCode:
        return generate_model(self.model, out_dir, functions=self.functions, prefix=prefix, real=real, dt=self.dt)


@dataclass(frozen=True)
class ControllerSource(CodeSource):
    """A controller bundle alone (:class:`~gtmodel.codegen.controller.EstimatorILCBundle`: Kalman step, ILC table, fusion filters, lead-through).

    Parameters
    ----------
    controller : EstimatorILCBundle
        The bundle (e.g. :func:`gtmodel.codegen.controller_file.load_controller`).
    """

    controller: Controller
    kind: str = field(default=CONTROLLER_KIND, init=False)

    def _summary(self) -> str:
        return f"the controller bundle's steps ({', '.join(self.controller.functions)})"

    def _specs(self) -> tuple[FunctionSpec, ...]:
        return tuple(self.controller.specs())

    def _target(self, spec: FunctionSpec) -> Any:
        return self.controller

    def default_prefix(self) -> str:
        """``gt`` for the lead-through step alone, else ``gt_fusion`` (as ``gtmodel codegen controller`` names them).

        Returns
        -------
        str
        """
        return "gt" if self.controller.functions == ("lead_through_step",) else "gt_fusion"

    def _write(self, out_dir: str | Path, real: str, prefix: str | None) -> GeneratedCode:
        return generate_robot(out_dir=out_dir, functions=[], prefix=prefix or self.default_prefix(), real=real, controller=self.controller)


def as_source(obj: Any, real: str = "double") -> CodeSource:
    """The code source of an object: a source itself, a loop controller, a controller bundle or a user model.

    Parameters
    ----------
    obj : CodeSource or TrackingController or MPCController or Controller or Model or Component
        A :class:`CodeSource` is returned as is; a tracking controller or an MPC becomes its
        :class:`~gtmodel.codegen.loop_step.LoopStep`; a controller bundle a :class:`ControllerSource`;
        a model a :class:`UserModelSource`.
    real : {"double", "float"}, optional
        The real type an MPC's step is built for (:func:`~gtmodel.codegen.loop_step.mpc_step`).

    Returns
    -------
    CodeSource

    Raises
    ------
    InputError
        Nothing code is generated from.
    """
    if isinstance(obj, CodeSource):
        return obj
    if isinstance(obj, TrackingController):
        return tracking_step(obj)
    if isinstance(obj, MPCController):
        return mpc_step(obj, real=real)
    if isinstance(obj, Controller):
        return ControllerSource(obj)
    if isinstance(obj, (Model, Component)):
        return UserModelSource(obj)
    raise InputError(f"source: expected a CodeSource (RobotSource, UserModelSource, LoopStep, ControllerSource), a tracking "
                     f"controller, an MPC, a controller bundle or a model, got {type(obj).__name__}")


def source_of(generated: GeneratedCode) -> CodeSource:
    """The source a library was generated from (what :func:`check_code` dispatches on).

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`generate_code` or a former front door.

    Returns
    -------
    CodeSource
        The :class:`~gtmodel.codegen.loop_step.LoopStep`, a :class:`UserModelSource`, a
        :class:`ControllerSource` (no robot function) or a :class:`RobotSource`.
    """
    p = generated.parameters
    if isinstance(p, LoopStep):
        return p
    if isinstance(p, ModelSource):
        return UserModelSource(p.model, p.dt, generated.functions)
    robot_functions = tuple(s.name for s in generated.specs if s.kind != CONTROLLER_KIND)
    if generated.controller is not None and not robot_functions:
        return ControllerSource(generated.controller)
    return RobotSource(p, generated.friction, robot_functions, controller=generated.controller,
                       retime_n_max=generated.retime_n_max or None)


def generate_code(source: Any, out_dir: str | Path, *, real: str = "double", prefix: str | None = None) -> GeneratedCode:
    """Generate the C of any source: the one front door.

    Parameters
    ----------
    source : CodeSource or object
        A source, or what :func:`as_source` turns into one.
    out_dir : str or pathlib.Path
        Folder to write into (created if missing).
    real : {"double", "float"}, optional
        Floating-point type.
    prefix : str, optional
        C symbol prefix (default the source's).

    Returns
    -------
    GeneratedCode
        The files and declarations; :func:`source_of` gives the source back.

    Raises
    ------
    InputError
        Not a source, or a bad option.
    CodegenError
        CasADi's code generation or writing the files failed.
    """
    src = as_source(source, real=real if real in REAL_TYPES else "double")  # a bad real type: refused below
    return src.generate(out_dir, real=real, prefix=prefix)


def generate(source: Any = None, out_dir: str | Path | None = None, **options: Any) -> GeneratedCode:
    """``gtmodel.codegen.generate``: a source's code (:func:`generate_code`), or a robot's as before.

    Parameters
    ----------
    source : CodeSource or object or str or pathlib.Path or RobotParameters, optional
        A source or what :func:`as_source` takes (then ``options`` are ``real`` and ``prefix``);
        otherwise the robot of :func:`gtmodel.codegen.generate.generate` (also as ``robot=``;
        default ``"L1"``), with its options (``functions``, ``friction``, ``controller``, ...).
    out_dir : str or pathlib.Path, optional
        Folder to write into (the robot's default ``codegen_out``).
    **options
        Passed on.

    Returns
    -------
    GeneratedCode

    Raises
    ------
    InputError
        A bad source or option.
    CodegenError
        Generation failed.
    """
    if source is not None and not isinstance(source, (str, Path)) and _is_source(source):
        if out_dir is None:
            raise InputError("out_dir: expected the folder to write into")
        return generate_code(source, out_dir, **options)
    if source is not None:
        options["robot"] = source
    if out_dir is not None:
        options["out_dir"] = out_dir
    return generate_robot(**options)


def _is_source(obj: Any) -> bool:
    try:
        as_source(obj)
    except InputError:
        return False
    return True
