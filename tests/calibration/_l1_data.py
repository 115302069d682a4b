"""Synthetic L1 laser-tracker data shared by the calibration tests (truth: Table 5.1
modified model; start: the ideal model)."""

from __future__ import annotations

import numpy as np

from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import load_parameters

NOISE = 10e-6  # laser tracker [m]


def l1_poses(seed: int, n_poses: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """``n_poses`` poses spread over the 0.115 m workspace grid: (q, T with ``NOISE``) of the true L1."""
    true = ThreeLinkClosure(load_parameters("L1"))
    T = GantryTau3Kinematics(load_parameters("L1")).workspace_grid(0.115)
    T = T[np.unique(np.linspace(0, len(T) - 1, n_poses).round().astype(int))]
    q = true.ik(T)
    return q, T + NOISE * np.random.default_rng(seed).standard_normal(T.shape)


def nominal() -> ThreeLinkClosure:
    """The ideal L1 model in the 21-parameter modified structure (the calibration start)."""
    return ThreeLinkClosure(load_parameters("L1_ideal"), model="modified")
