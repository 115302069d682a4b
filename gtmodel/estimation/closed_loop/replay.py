"""A replay of actuator references on the closed-loop plant, held at the end to settle.

:func:`replay` extends the references by a hold of ``settle_time`` and simulates the
:class:`~gtmodel.estimation.TrackingPlant`; :class:`TrackingSolution` is the outcome the
``tracking`` problem kind writes (status ``completed``: a simulation, nothing optimised).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gtmodel.estimation.closed_loop.plant import TrackingPlant, TrackingResponse
from gtmodel.status import StatusResult

__all__ = ["TrackingSolution", "replay"]


@dataclass
class TrackingSolution(StatusResult):
    """The outcome of a ``tracking`` problem.

    Parameters
    ----------
    status : Status
        ``"completed"`` when the replay ran; the referenced problem's status when it did not
        solve (keyword only).
    message : str
        What happened (keyword only).
    response : TrackingResponse or None
        The simulated run.
    motion_samples : int
        Samples of the motion (before the settling hold).
    source_status : str
        Status of the referenced problem (``"file"`` for a trajectory file).
    """

    response: TrackingResponse | None = None
    motion_samples: int = 0
    source_status: str = "file"


def replay(plant: TrackingPlant, q: np.ndarray, settle_time: float, label: str, source_status: str = "file") -> TrackingSolution:
    """Simulate actuator references followed by a hold at the last one.

    Parameters
    ----------
    plant : TrackingPlant
        The closed-loop plant.
    q : numpy.ndarray, shape (N, 3)
        Actuator references at the plant's sample time ``plant.dt`` [m].
    settle_time : float
        Hold after the motion [s] (rounded up to whole samples).
    label : str
        Where the references come from (for the message).
    source_status : str, optional
        Status of the problem that produced ``q`` (``"file"`` for a trajectory file).

    Returns
    -------
    TrackingSolution
        The plant's response; status ``completed``.
    """
    settle = int(math.ceil(settle_time / plant.dt - 1e-9))
    q_ref = np.vstack([q, np.repeat(q[-1:], settle, axis=0)])
    response = plant.simulate(q_ref)
    return TrackingSolution(
        status=response.status, message=f"replayed {q.shape[0]} samples of {label} and {settle} settling samples",
        response=response, motion_samples=q.shape[0], source_status=source_status,
    )
