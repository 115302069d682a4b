"""Pose accuracy analysis of the 3-link Gantry-Tau: worst-case TCP errors from actuator tolerances.

Dressler (2012), ch. 4.3 and Appendix A: the geometric method (ellipsoidal joint-point
errors, the iterative intersection of the bounding ellipsoids, link-length errors, the
parallelepiped approximation), the exact worst case as a CasADi NLP, a Monte-Carlo
estimate, the inverse question (largest tolerances for a TCP error bound, Kim and Choi
(2000)) and maps over a workspace section (Figs. 4.8-4.10).
"""

from gtmodel.calibration.accuracy.declared import (
    AccuracyCase,
    CaseResult,
    CheckPose,
    PoseAccuracyDeclaration,
    PoseAccuracyResult,
)
from gtmodel.calibration.accuracy.exact import MonteCarlo, WorstCase, monte_carlo, worst_case
from gtmodel.calibration.accuracy.geometric import Parallelepiped, ellipsoid_corners, parallelepiped, sphere_corners
from gtmodel.calibration.accuracy.inverse import InverseResult, largest_tolerances
from gtmodel.calibration.accuracy.section import Section, SectionMap, actuator_crossings, section_map
from gtmodel.calibration.accuracy.tolerances import NominalPoses, Tolerances, nominal_pose

__all__ = [
    "Tolerances",
    "NominalPoses",
    "nominal_pose",
    "ellipsoid_corners",
    "sphere_corners",
    "Parallelepiped",
    "parallelepiped",
    "WorstCase",
    "worst_case",
    "MonteCarlo",
    "monte_carlo",
    "InverseResult",
    "largest_tolerances",
    "Section",
    "SectionMap",
    "section_map",
    "actuator_crossings",
    "AccuracyCase",
    "CheckPose",
    "CaseResult",
    "PoseAccuracyDeclaration",
    "PoseAccuracyResult",
]
