"""Exchange with the Modelica world: FMUs out and in, Modelica source in (docs/fmu.md).

* :func:`export_fmu`: a gtmodel model as an FMU (FMI 2.0 model exchange and co-simulation
  with an embedded fixed-step RK4; FMI 3.0 through CasADi's own export, co-simulation added), C
  sources and a binary for this platform (:mod:`gtmodel.exchange.fmu_export`);
  :func:`export_step_fmu`: a discrete-time controller step (the 4 ms Kalman step) as an
  FMI 2.0 co-simulation FMU (:mod:`gtmodel.exchange.fmu_step`).
* :func:`import_fmu`: an FMU (FMI 2.0 / 3.0 model exchange) loaded by CasADi's
  ``DaeBuilder`` as an explicit model (:class:`ExplicitModel`, the modelling layer's
  :class:`~gtmodel.modeling.ExplicitODE`; :mod:`gtmodel.exchange.fmu_import`; the
  archive unpacked as untrusted input under :class:`ArchiveLimits`,
  :mod:`gtmodel.exchange.fmu_archive`), which
  :func:`simulate_explicit`, :func:`linearize_explicit`, :func:`connect_explicit` (with
  gtmodel models and components) and :func:`solve_explicit_ocp` (direct collocation, the
  transcription of :func:`gtmodel.modeling.solve`) use.
* :func:`load_modelica`: a ``.mo`` file as a gtmodel :class:`~gtmodel.modeling.Model`
  through pymoca (the optional extra ``modelica``; :mod:`gtmodel.exchange.modelica`).

Layer: above the modelling layer, the robots and the C code generation (it uses
:mod:`gtmodel._compiler`), below the problems and the command (``gtmodel export-fmu``).
"""

from __future__ import annotations

from gtmodel.exchange.explicit import ExplicitModel, explicit_model
from gtmodel.exchange.explicit_ocp import ExplicitOcpResult, solve_explicit_ocp
from gtmodel.exchange.explicit_ops import connect_explicit, linearize_explicit, simulate_explicit
from gtmodel.exchange.fmu_archive import ArchiveLimits
from gtmodel.exchange.fmu_export import ExportedFmu, export_fmu
from gtmodel.exchange.fmu_import import ImportedFmu, import_fmu
from gtmodel.exchange.fmu_step import StepFmu, export_step_fmu
from gtmodel.exchange.modelica import load_modelica

__all__ = [
    "ExplicitModel",
    "explicit_model",
    "ExportedFmu",
    "export_fmu",
    "StepFmu",
    "export_step_fmu",
    "ImportedFmu",
    "import_fmu",
    "ArchiveLimits",
    "simulate_explicit",
    "linearize_explicit",
    "connect_explicit",
    "ExplicitOcpResult",
    "solve_explicit_ocp",
    "load_modelica",
]
