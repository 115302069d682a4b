"""The schema of an estimator + ILC bundle file (light), the ``.json`` / ``.npz`` that ``gtmodel codegen --controller`` reads.

The file carries what :class:`gtmodel.codegen.EstimatorILCBundle` holds (the Kalman step,
the learned ILC correction and its table, the fusion filters, the lead-through step),
written by :func:`gtmodel.codegen.save_controller` (the ``ilc`` kind writes one into its
result folder, ``controller.json``) and read by :func:`gtmodel.codegen.load_controller`,
whose checks are the ones below plus what a schema cannot say (at least one Function, the
Functions' signatures, ``ilc_table`` with ``ilc_correction``). The kind is
``estimator_ilc`` in :data:`gtmodel.problems.registry.LOOP_KINDS` (``gtmodel schema
estimator_ilc``); the keys equal :data:`gtmodel.codegen.controller_file.CONTROLLER_KEYS`
(a test keeps them so).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gtmodel.problems.schema import Section, number

__all__ = ["BUNDLE_FORMAT", "EstimatorILCFile"]

#: The ``format`` of the file (:data:`gtmodel.codegen.controller_file.CONTROLLER_FORMAT`; a test keeps them equal).
BUNDLE_FORMAT = "gtmodel.controller/1"
_SERIALISED = "serialised by casadi.Function.serialize()"


class EstimatorILCFile(Section):
    """An estimator + ILC bundle file (``.json``; an ``.npz`` holds the same keys).

    Parameters
    ----------
    format : str
        ``"gtmodel.controller/1"``.
    dt : float
        Sample time of the loop [s].
    kalman_step, ilc_correction, kf_step, ekf_step, lead_through_step : str, optional
        Serialised CasADi Functions.
    ilc_table : list of list of float, optional
        ``(N, d)`` the learned correction [m].
    description : str, optional
        Free text.
    """

    format: Literal["gtmodel.controller/1"] = Field(description="the file's format and version")
    dt: number(gt=0, unit="s", description="sample time of the loop (4 ms on the L1; the sensors' for the filters, 0.001 at 1 kHz)")
    kalman_step: str | None = Field(default=None, description=f"the Function kalman_step(x, y) -> (x_next, z_hat), {_SERIALISED}")
    ilc_correction: str | None = Field(default=None, description=f"the Function ilc_correction(k) -> u, {_SERIALISED} (with ilc_table)")
    ilc_table: list[list[float]] | None = Field(default=None, description="the learned correction (N, d) [m] the Function looks up (with ilc_correction)")
    kf_step: str | None = Field(default=None, description=f"the tracker + IMU fusion's KF step kf_step(x, P, z) -> (x_next, P_next, pivots), {_SERIALISED}")
    ekf_step: str | None = Field(default=None, description=f"the 19-D model's EKF step, the signature of kf_step, {_SERIALISED}")
    lead_through_step: str | None = Field(default=None, description="the lead-through step lead_through_step(x, F_h, F_t, n_n) -> "
                                                                    f"(x_next, V_tool, n, valid), {_SERIALISED}")
    description: str = Field(default="", description="free text (what run, which case)")
