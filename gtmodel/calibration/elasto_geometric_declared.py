"""An elasto-geometric calibration as declared by a problem file: truth, start, loads, and results.

Dressler (2012), ch. 5.3 and 6.3: :class:`ElastoGeometricDeclaration` holds a compliant
true robot, the start geometry, the grid poses and payloads;
:meth:`ElastoGeometricDeclaration.solve` compares geometric-only with elasto-geometric
calibration (:func:`~gtmodel.calibration.elasto_geometric_study`, also on a single load when
asked) and maps the true robot's stiffness on a section, giving an
:class:`ElastoGeometricOutcome`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.calibration.elasto_geometric import elasto_geometric_study
from gtmodel.errors import GtModelError, ProblemError
from gtmodel.status import Status

__all__ = ["ElastoGeometricDeclaration", "ElastoGeometricOutcome"]

_log = logging.getLogger("gtmodel")


@dataclass
class ElastoGeometricDeclaration:
    """A validated elasto-geometric calibration problem.

    Parameters
    ----------
    truth : GantryTau3Stiffness
        The true robot (geometry, stated stiffness values; ``payload_kg`` = the largest payload).
    start : ThreeLinkClosure
        Start geometry.
    q : numpy.ndarray, shape (N, 3)
        Grid poses (cart positions) [m].
    payloads_kg : numpy.ndarray, shape (n_loads,)
        Payloads every pose is measured with [kg].
    noise : str
        Device name.
    seed : int
        Noise seed.
    start_compliance : str
        ``"zero"`` or ``"stated"``.
    free_compliance : tuple of str
        Compliance names/patterns estimated.
    solver : str
        Calibration solver.
    max_iter : int
        Iteration limit.
    align : bool
        Frame alignment.
    compare_single_load : bool
        Also calibrate on single-load data.
    map_step : float
        Grid step of the stiffness map [m].
    map_x : float or None
        Section coordinate of the stiffness map [m].
    source : str
        Description of the data.
    """

    truth: Any
    start: Any
    q: np.ndarray
    payloads_kg: np.ndarray
    noise: str
    seed: int
    start_compliance: str
    free_compliance: tuple
    solver: str
    max_iter: int
    align: bool
    compare_single_load: bool
    map_step: float
    map_x: float | None
    source: str

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> "ElastoGeometricOutcome":
        """Run the comparison (and the single-load one), and the stiffness map of the truth.

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        ElastoGeometricOutcome

        Raises
        ------
        ProblemError
            A calibration that cannot be posed (too few poses, a singular problem naming the
            non-identifiable parameters), or a stiffness-map section without workspace points.
        """
        decl = self
        t0 = time.perf_counter()
        opts = dict(
            noise=decl.noise, seed=decl.seed, start_compliance=decl.start_compliance, free_compliance=decl.free_compliance,
            solver=decl.solver, align=decl.align, max_iter=decl.max_iter,
        )
        try:
            study = elasto_geometric_study(decl.truth, decl.start, decl.q, payloads_kg=decl.payloads_kg, **opts)
            if verbose:
                _log.info("elasto-geometric study: %s / %s", study.geometric.summary(), study.elasto.summary())
            single = None
            if decl.compare_single_load:
                single = elasto_geometric_study(decl.truth, decl.start, decl.q, payloads_kg=None, **opts)
            T = decl.truth.section_grid(decl.map_x, decl.map_step)
            smap = decl.truth.stiffness_map(T)
        except GtModelError as exc:
            raise ProblemError(str(exc)) from None
        return ElastoGeometricOutcome(study, single, smap, time.perf_counter() - t0)


@dataclass
class ElastoGeometricOutcome:
    """Results of an elasto-geometric calibration problem.

    Parameters
    ----------
    study : ElastoGeometricStudy
        The comparison on the declared loads.
    single_load : ElastoGeometricStudy or None
        The same on single-load data (``compare_single_load``).
    stiffness_map : StiffnessMap
        Stiffness of the true robot on a yz section.
    solve_time : float
        Wall time [s].
    """

    study: Any
    single_load: Any
    stiffness_map: Any
    solve_time: float

    @property
    def status(self) -> Status:
        """Worst status of the calibrations."""
        return Status.worst([self.study.status] + ([self.single_load.status] if self.single_load is not None else []))
