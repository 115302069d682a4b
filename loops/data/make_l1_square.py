"""Write l1_square.csv: the actuator references of the L1 ILC experiment's square, for loops/l1_egm_ilc.toml.

The square of problems/l1_ilc.toml (Dressler (2012), section 7.3: 10 mm side at 100 mm/s,
100-sample lead-in and lead-out) as planned by that file's kind, mapped to the three carts'
positions by IK, one row per 4 ms period, in mm (EGM carries linear axes in mm).
Run from the repository: python loops/data/make_l1_square.py
"""

from pathlib import Path

import numpy as np

from gtmodel.problems.run import load_problem

HERE = Path(__file__).resolve().parent

if __name__ == "__main__":
    experiment = load_problem(HERE.parent.parent / "problems" / "l1_ilc.toml").declaration.experiment
    q_mm = 1000.0 * experiment.reference.q
    t = np.arange(len(q_mm)) * experiment.plant.dt
    np.savetxt(HERE / "l1_square.csv", np.column_stack([t, q_mm]), delimiter=",", fmt="%.9g",
               header="t,q1,q2,q3", comments="")
