"""Filters, learning control and closed-loop simulation of the 4 ms loop (Dressler (2012), ch. 7).

Tool-position estimators (complementary filter, stationary Kalman filter), iterative
learning control with its lifted-system stability checks, and the closed-loop tracking
simulation of the L1 at 4 ms. Lower layers only: robots, modeling and the base modules.
"""

from gtmodel.estimation.complementary import THESIS_CUTOFFS_HZ, ComplementaryFilter
from gtmodel.estimation.kalman import StationaryKalman, tune_position_noise

__all__: list[str] = []
__all__ += ["ComplementaryFilter", "THESIS_CUTOFFS_HZ"]
__all__ += ["StationaryKalman", "tune_position_noise"]
