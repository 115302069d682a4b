"""Exchange with the Modelica world: FMUs out and in, Modelica source in (docs/fmu.md).

* :func:`~gtmodel.exchange.fmu_export.export_fmu`: a gtmodel model as an FMU (FMI 2.0
  model exchange + co-simulation, FMI 3.0 model exchange through CasADi's export), C
  sources and a binary for this platform.
* :func:`~gtmodel.exchange.fmu_import.import_fmu`: an FMU (2.0 / 3.0 model exchange) as a
  gtmodel component (CasADi's ``DaeBuilder`` loading the FMU).
* :func:`~gtmodel.exchange.modelica.load_modelica`: a ``.mo`` file as a gtmodel model
  through pymoca (optional extra ``modelica``).
"""

from __future__ import annotations

from gtmodel.exchange.explicit import ExplicitModel, explicit_model
from gtmodel.exchange.fmu_export import ExportedFmu, export_fmu

__all__ = ["ExplicitModel", "explicit_model", "ExportedFmu", "export_fmu"]
