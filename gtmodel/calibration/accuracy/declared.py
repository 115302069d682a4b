"""A pose accuracy analysis as declared by a problem file: tolerance cases, a section, checks.

Dressler (2012), ch. 4.3 (Table 4.2, Figs. 4.8-4.10) and Appendix A: for every tolerance
case the geometric worst case (A.2) and the parallelepiped (A.4) are mapped over a
workspace section; at the check poses (the map's smallest, largest and central points and
any declared) the exact worst case (the NLP of :mod:`~gtmodel.calibration.accuracy.exact`)
and a Monte-Carlo distribution are computed and compared with them; optionally the inverse
question (:func:`~gtmodel.calibration.accuracy.inverse.largest_tolerances`) is answered
over the section. The result's status is ``check_failed`` when a Monte-Carlo maximum
exceeds the exact worst case or the exact NLP ends below a corner it started from (its
own consistency checks), the worst IPOPT status otherwise.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from gtmodel.calibration.accuracy.exact import MonteCarlo, WorstCase, monte_carlo, worst_case
from gtmodel.calibration.accuracy.geometric import ellipsoid_corners, parallelepiped
from gtmodel.calibration.accuracy.inverse import InverseResult, largest_tolerances
from gtmodel.calibration.accuracy.section import Section, SectionMap, actuator_crossings, section_map
from gtmodel.calibration.accuracy.tolerances import NominalPoses, Tolerances, nominal_pose
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.status import Status

__all__ = ["AccuracyCase", "PoseAccuracyDeclaration", "CheckPose", "CaseResult", "PoseAccuracyResult"]

_log = logging.getLogger("gtmodel")

#: Relative slack of the consistency checks (round-off of the FK at metre scale).
CHECK_SLACK = 1e-9


@dataclass(frozen=True)
class AccuracyCase:
    """One tolerance case (a column of Table 4.2).

    Parameters
    ----------
    name : str
        Case name.
    tolerances : Tolerances
        The error bounds.
    reference_range : tuple of float or None
        The thesis' ``(min, max)`` of the map [m], compared in the result (None: none).
    """

    name: str
    tolerances: Tolerances
    reference_range: tuple[float, float] | None = None


@dataclass(frozen=True)
class CheckPose:
    """The three methods compared at one pose.

    Parameters
    ----------
    label : str
        ``"min"``, ``"max"``, ``"centre"`` or ``"pose k"``.
    T : numpy.ndarray, shape (3,)
        The pose [m].
    geometric : float
        A.2 worst case [m].
    parallelepiped : float
        A.4 worst case [m].
    exact : WorstCase
        The NLP.
    monte_carlo : MonteCarlo
        The samples.
    face_areas : numpy.ndarray, shape (3,)
        Parallelepiped face areas [m^2].
    """

    label: str
    T: np.ndarray
    geometric: float
    parallelepiped: float
    exact: WorstCase
    monte_carlo: MonteCarlo
    face_areas: np.ndarray


@dataclass(frozen=True)
class CaseResult:
    """The map and the check poses of one case.

    Parameters
    ----------
    case : AccuracyCase
    map : SectionMap
    checks : list of CheckPose
    """

    case: AccuracyCase
    map: SectionMap
    checks: list[CheckPose]

    @property
    def range(self) -> tuple[float, float]:
        """``(min, max)`` of the geometric map [m]."""
        v = self.map.geometric[self.map.inside]
        return float(v.min()), float(v.max())

    @property
    def max_parallelepiped_gap(self) -> float:
        """Largest ``|parallelepiped - exact|`` over the check poses [m]."""
        return max(abs(c.parallelepiped - c.exact.error) for c in self.checks)

    @property
    def max_geometric_gap(self) -> float:
        """Largest ``|geometric (A.2) - exact|`` over the check poses [m]."""
        return max(abs(c.geometric - c.exact.error) for c in self.checks)

    @property
    def monte_carlo_within_exact(self) -> bool:
        """Whether no Monte-Carlo sample exceeds the exact worst case (at every check pose)."""
        return all(c.monte_carlo.max <= c.exact.error * (1 + CHECK_SLACK) for c in self.checks)


@dataclass
class PoseAccuracyResult:
    """The result of a pose accuracy analysis.

    Parameters
    ----------
    status : str
        One :class:`~gtmodel.status.Status` value.
    message : str
        What went wrong, or a one-line summary.
    cases : list of CaseResult
    inverse : InverseResult or None
    actuators : numpy.ndarray, shape (3, 2)
        The guideways' crossings of the section ``(y, z)`` [m].
    """

    status: str
    message: str
    cases: list[CaseResult] = field(default_factory=list)
    inverse: InverseResult | None = None
    actuators: np.ndarray | None = None


@dataclass(frozen=True)
class PoseAccuracyDeclaration:
    """A pose accuracy analysis: a robot, a section, tolerance cases and the checks.

    Parameters
    ----------
    kinematics : GantryTau3Kinematics
        The 3-link model (a full parameter set).
    section : Section
        The workspace section mapped.
    cases : tuple of AccuracyCase
        The tolerance cases.
    poses : numpy.ndarray, shape (K, 3)
        Further check poses [m] (may be empty).
    corner_starts : int
        IPOPT starts from the best corners.
    random_starts : int
        Further random IPOPT starts.
    samples : int
        Monte-Carlo samples per check pose.
    seed : int
        Random seed.
    inverse_tcp_error : float or None
        TCP error bound of the inverse question [m] (None: not asked).
    inverse_case : int
        The case whose tolerance shape the inverse question scales.
    """

    kinematics: GantryTau3Kinematics
    section: Section
    cases: tuple[AccuracyCase, ...]
    poses: np.ndarray
    corner_starts: int = 2
    random_starts: int = 2
    samples: int = 20000
    seed: int = 0
    inverse_tcp_error: float | None = None
    inverse_case: int = 0

    def _check(self, label: str, nominal: NominalPoses, k: int, tol: Tolerances, geo: float, pp: float, areas: np.ndarray) -> CheckPose:
        wc = worst_case(nominal, k, tol, self.corner_starts, self.random_starts, self.seed)
        mc = monte_carlo(nominal, k, tol, self.samples, self.seed)
        return CheckPose(label, nominal.T[k].copy(), geo, pp, wc, mc, areas)

    def solve(self, verbose: bool = False, previous: object = None, warm_start: bool = False) -> PoseAccuracyResult:
        """Map every case, compare the three methods at the check poses, answer the inverse question.

        Parameters
        ----------
        verbose : bool, optional
            Log progress at INFO.
        previous : object, optional
            Unused (the analysis has no warm start).
        warm_start : bool, optional
            Unused.

        Returns
        -------
        PoseAccuracyResult
            Status ``check_failed`` when a Monte-Carlo maximum exceeds the exact worst case
            or the exact NLP ends below its best corner start.
        """
        level = logging.INFO if verbose else logging.DEBUG
        results = []
        statuses = []
        problems = []
        for case in self.cases:
            m = section_map(self.kinematics, self.section, case.tolerances)
            checks = []
            for label in ("min", "max", "centre"):
                k = m.index(label)
                checks.append(self._check(label, m.nominal, k, case.tolerances, float(m.geometric[m.inside][k]),
                                          float(m.parallelepiped[m.inside][k]), m.face_areas[m.inside][k]))
            if self.poses.shape[0]:
                extra = nominal_pose(self.kinematics, self.poses)
                corners, _ = ellipsoid_corners(extra, case.tolerances)
                geo = np.linalg.norm(corners - extra.T[:, None], axis=2).max(axis=1)
                pp = parallelepiped(extra, case.tolerances)
                for k in range(extra.T.shape[0]):
                    checks.append(self._check(f"pose {k}", extra, k, case.tolerances, float(geo[k]), float(pp.worst[k]), pp.face_areas[k]))
            result = CaseResult(case, m, checks)
            results.append(result)
            statuses += [Status(c.exact.status) for c in checks]
            lo, hi = result.range
            _log.log(level, "pose accuracy %s: map %.1f-%.1f um, exact - parallelepiped gap %.3g um, A.2 gap %.3g um",
                     case.name, lo * 1e6, hi * 1e6, result.max_parallelepiped_gap * 1e6, result.max_geometric_gap * 1e6)
            if not result.monte_carlo_within_exact:
                problems.append(f"{case.name}: a Monte-Carlo sample exceeds the exact worst case")
            for c in checks:
                if c.exact.error < c.exact.best_corner * (1 - CHECK_SLACK):
                    problems.append(f"{case.name} {c.label}: the exact NLP ended below its best corner start")
        inverse = None
        if self.inverse_tcp_error is not None:
            base = results[self.inverse_case]
            inverse = largest_tolerances(base.map.nominal, base.case.tolerances, self.inverse_tcp_error)
            statuses.append(Status(inverse.status))
        status = Status.worst(statuses) if statuses else Status.OPTIMAL
        if problems and status.success:
            status = Status.CHECK_FAILED
        message = "; ".join(problems) if problems else "; ".join(
            f"{r.case.name}: {r.range[0] * 1e6:.0f}-{r.range[1] * 1e6:.0f} um" for r in results)
        return PoseAccuracyResult(status.value, message, results, inverse, actuator_crossings(self.kinematics, self.section.x))
