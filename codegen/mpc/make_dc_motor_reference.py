"""Write dc_motor_reference.csv: the reference motion of the DC motor MPC (dc_motor_mpc.toml).

The composed DC motor of models/dc_motor.py driven by a smooth voltage, one period of
v(t) = 6 sin(2 pi t / 1 s) V over 1 s, then 0 V: the states (armature current, rotor angle,
rotor speed) simulated with the model's own fixed RK4 step (1 ms substeps), sampled every 4 ms.
Run from the repository root: PYTHONPATH=. python codegen/mpc/make_dc_motor_reference.py
"""

from pathlib import Path

import numpy as np

from gtmodel._tables import write_table
from gtmodel.modeling import explicit_ode
from gtmodel.problems.user_model import load_user_model

HERE = Path(__file__).resolve().parent
DT = 0.004

ode = explicit_ode(load_user_model(HERE.parents[1] / "models" / "dc_motor.py", "DCMotorModel"))
t = DT * np.arange(int(round(1.2 / DT)) + 1)
v = np.where(t < 1.0, 6.0 * np.sin(2 * np.pi * t), 0.0)[:, None]
x, _ = ode.simulate_steps(ode.step(DT, "rk4", substeps=4), v[:-1])
write_table(HERE / "dc_motor_reference.csv", ["t", *ode.x_names, *ode.u_names], np.column_stack([t, x, v]),
            comments=["reference of dc_motor_mpc.toml: models/dc_motor.py under v = 6 sin(2 pi t) V for 1 s, then 0 V",
                      "written by codegen/mpc/make_dc_motor_reference.py (RK4, 1 ms substeps, 4 ms samples)"])
print(HERE / "dc_motor_reference.csv", x.shape)
