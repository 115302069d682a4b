"""Independent references of the drive problems ``problems/drive_*.toml``: direct multiple shooting in plain CasADi.

The models of ``models/drives.py`` written out by hand as ODEs (no gtmodel code: neither its
components, its reduction nor its transcriptions), with states ``x = (i, phi_m, w_m, phi_l, w_l)``
(the rigid drive: ``(i, phi_m, w_m)``)::

    L i'      = v - R i - k w_m                         armature
    J_m w_m'  = k i - tau_s / n                          rotor, gear n
    tau_s     = c (phi_m / n - phi_l) + d (w_m / n - w_l)   compliant shaft / joint spring
    J_l w_l'  = tau_s - tau_load(phi_l, w_l)             load or link

with ``tau_load = Fc tanh(w_l / w_eps) + dv w_l`` (two-mass drive) or ``m g l sin(phi_l)``
(flexible joint); the rigid drive: ``(J_m + J_l / n^2) w_m' = k i - d_f w_m / n^2``. The belt drive
(states ``(i, phi_m, w_m, s_p, v_p)``: a pulley of radius r, no gear, carries the cart rigidly, ``s_c = r phi_m``)::

    (J_m + m_c r^2) w_m' = k i - r (d_r v_c + F_b)      rotor and cart on its viscous rail
    F_b     = c (s_c - s_p) + d (v_c - v_p)              belt
    m_p v_p' = F_b                                       payload

The ball-screw drive (states ``(i, w_m, phi_c, phi_s, w_s)``: a coupling of twist ``phi_c`` between rotor
and screw, a screw of lead l carrying the table, ``s = l phi_s / (2 pi)``, ``rho = l / (2 pi)``)::

    J_m w_m'              = k i - tau_c,   tau_c = c phi_c + d (w_m - w_s),   phi_c' = w_m - w_s
    (J_s + m rho^2) w_s'  = tau_c - rho (Fc tanh(rho w_s / v_eps) + dv rho w_s)

Minimum final time T (the belt: ``T + w int v^2 dt``, its problem's energy term) from rest to rest with
``|v| <= v_max`` and ``|i| <= i_max``; the
voltage piecewise constant on N intervals, each integrated by ``S`` classical Runge-Kutta
(RK4) steps, the current bound enforced at every step's end (not the nodes alone), IPOPT.
The references are the solves on the finest mesh (800 intervals; the two-mass drive, whose
friction makes the solve slow: 400), beside the coarser ones (the difference is the
discretisation's, O(1/N): a switch inside an interval; 100 -> 400 -> 800 intervals of the
rigid drive: 0.26871, 0.26604, 0.26572 s). The flexible joint starts from T = 0.35 s: from
0.3 or 0.5 s IPOPT ends in a local optimum at 0.648 s (the link swinging back once).

Run ``python benchmarks/drive_references.py [--only=drive_belt,...]`` (several CPU-minutes); it writes
``tests/problems/data/drive_references.json``, which ``tests/problems/test_drive_models.py`` reads.
"""

from __future__ import annotations

import json
import math
import pathlib
import sys
import time

import casadi as ca

#: The problems' data (SI units), as ``models/drives.py`` and ``problems/drive_*.toml`` declare them.
DRIVES = {
    "drive_motor_gear_load": {"R": 0.5, "L": 0.85e-3, "k": 0.05, "Jm": 1e-4, "n": 50.0, "Jl": 0.01, "df": 0.02,
                              "rigid": True, "vmax": 24.0, "imax": 10.0, "phi_l": math.pi / 2, "intervals": (100, 400, 800)},
    "drive_two_mass": {"R": 1.0, "L": 2e-3, "k": 0.1, "Jm": 5e-5, "n": 20.0, "c": 50.0, "d": 0.2, "Jl": 0.05,
                       "load": "friction", "Fc": 0.3, "w_eps": 0.05, "dv": 0.05, "vmax": 24.0, "imax": 8.0, "phi_l": 1.0,
                       "intervals": (100, 400)},
    "drive_flexible_joint": {"R": 1.0, "L": 1e-3, "k": 0.05, "Jm": 1e-5, "n": 50.0, "c": 200.0, "d": 0.5, "Jl": 0.5,
                             "load": "gravity", "mgl": 1.0 * 9.81 * 0.2, "vmax": 24.0, "imax": 8.0, "phi_l": 1.0,
                             "intervals": (100, 400, 800), "t_guess": 0.35},
    "drive_belt": {"R": 1.2, "L": 2e-3, "k": 0.08, "Jm": 4e-5, "r": 0.02, "mc": 1.5, "dr": 3.0, "c": 4000.0, "d": 20.0,
                   "mp": 0.8, "load": "belt", "s_p": 0.3, "energy": 1e-4, "vmax": 24.0, "imax": 8.0,
                   "intervals": (100, 400, 800)},
    "drive_ball_screw": {"R": 0.8, "L": 1.5e-3, "k": 0.12, "Jm": 2e-4, "c": 100.0, "d": 0.05, "Js": 1e-4, "lead": 0.01,
                         "m": 20.0, "Fc": 20.0, "v_eps": 0.002, "dv": 50.0, "load": "screw", "s": 0.2, "vmax": 48.0,
                         "imax": 10.0, "intervals": (100, 400, 800, 1600), "t_guess": 0.5},
}


def ode(p: dict) -> tuple[ca.Function, list[float], list[float]]:
    """The hand-written ODE ``f(x, v)`` of a drive, its start and its final state (at rest)."""
    x, v = ca.SX.sym("x", 3 if p.get("rigid") else 5), ca.SX.sym("v")
    i, phi_m, w_m = x[0], x[1], x[2]
    di = (v - p["R"] * i - p["k"] * w_m) / p["L"]
    if p.get("load") == "screw":
        w_c, phi_c, phi_s, w_s, rho = x[1], x[2], x[3], x[4], p["lead"] / (2 * math.pi)
        tau_c = p["c"] * phi_c + p["d"] * (w_c - w_s)
        f_table = p["Fc"] * ca.tanh(rho * w_s / p["v_eps"]) + p["dv"] * rho * w_s
        rhs = ca.vertcat((v - p["R"] * i - p["k"] * w_c) / p["L"], (p["k"] * i - tau_c) / p["Jm"], w_c - w_s, w_s,
                         (tau_c - rho * f_table) / (p["Js"] + p["m"] * rho**2))
        final = [0.0, 0.0, 0.0, p["s"] / rho, 0.0]
    elif p.get("load") == "belt":
        s_p, v_p, r = x[3], x[4], p["r"]
        s_c, v_c = r * phi_m, r * w_m
        f_b = p["c"] * (s_c - s_p) + p["d"] * (v_c - v_p)
        rhs = ca.vertcat(di, w_m, (p["k"] * i - r * (p["dr"] * v_c + f_b)) / (p["Jm"] + p["mc"] * r**2), v_p, f_b / p["mp"])
        final = [0.0, p["s_p"] / r, 0.0, p["s_p"], 0.0]
    elif p.get("rigid"):
        n = p["n"]
        dw = (p["k"] * i - p["df"] * w_m / n**2) / (p["Jm"] + p["Jl"] / n**2)
        rhs = ca.vertcat(di, w_m, dw)
        final = [0.0, n * p["phi_l"], 0.0]
    else:
        phi_l, w_l, n = x[3], x[4], p["n"]
        tau_s = p["c"] * (phi_m / n - phi_l) + p["d"] * (w_m / n - w_l)
        if p["load"] == "friction":
            tau_load = p["Fc"] * ca.tanh(w_l / p["w_eps"]) + p["dv"] * w_l
            hold = 0.0
        else:
            tau_load = p["mgl"] * ca.sin(phi_l)
            hold = p["mgl"] * math.sin(p["phi_l"])  # the spring holds gravity at the end
        rhs = ca.vertcat(di, w_m, (p["k"] * i - tau_s / n) / p["Jm"], w_l, (tau_s - tau_load) / p["Jl"])
        final = [hold / (n * p["k"]), n * (p["phi_l"] + hold / p["c"]), 0.0, p["phi_l"], 0.0]
    return ca.Function("f", [x, v], [rhs]), [0.0] * x.numel(), final


def solve(p: dict, intervals: int, steps: int = 2, guess: dict | None = None, t_guess: float = 0.3) -> dict:
    """Minimum time by multiple shooting (RK4, ``steps`` per interval); returns T, the objective, the solver's status and the trajectory."""
    f, x0, xf = ode(p)
    nx = len(x0)
    opti = ca.Opti()
    T = opti.variable()
    X = opti.variable(nx, intervals + 1)
    V = opti.variable(1, intervals)
    h = T / (intervals * steps)
    opti.subject_to(X[:, 0] == x0)
    opti.subject_to(X[:, -1] == xf)
    for j in range(intervals):
        xk = X[:, j]
        for _ in range(steps):
            k1 = f(xk, V[j])
            k2 = f(xk + h / 2 * k1, V[j])
            k3 = f(xk + h / 2 * k2, V[j])
            k4 = f(xk + h * k3, V[j])
            xk = xk + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            opti.subject_to(opti.bounded(-p["imax"], xk[0], p["imax"]))
        opti.subject_to(X[:, j + 1] == xk)
    opti.subject_to(opti.bounded(-p["vmax"], V, p["vmax"]))
    opti.subject_to(opti.bounded(0.02, T, 2.0))
    # the belt's problem adds an energy term: the voltage is constant on each interval of length T / intervals
    opti.minimize(T + p.get("energy", 0.0) * ca.sumsqr(V) * T / intervals)
    if guess is None:  # a straight line of the angles, the other states at rest
        opti.set_initial(T, t_guess)
        for r in range(nx):
            opti.set_initial(X[r, :], [x0[r] + (xf[r] - x0[r]) * s / intervals for s in range(intervals + 1)])
    else:  # the coarser solve's, interpolated (the same normalised time)
        import numpy as np

        s_old = np.linspace(0.0, 1.0, guess["X"].shape[1])
        s_new = np.linspace(0.0, 1.0, intervals + 1)
        opti.set_initial(T, guess["T"])
        opti.set_initial(X, np.vstack([np.interp(s_new, s_old, row) for row in guess["X"]]))
        opti.set_initial(V, np.interp(s_new[:-1], s_old[:-1], guess["V"]))
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "max_iter": 3000, "tol": 1e-10})
    start = time.process_time()
    try:
        sol = opti.solve()
        status = "Solve_Succeeded"
    except RuntimeError:
        sol = opti.debug
        status = opti.stats()["return_status"]
    import numpy as np

    return {"T": float(sol.value(T)), "objective": float(sol.value(opti.f)), "status": status, "cpu_s": time.process_time() - start,
            "X": np.atleast_2d(sol.value(X)), "V": np.atleast_1d(sol.value(V))}


def main(out: pathlib.Path, only: list[str] | None = None) -> dict:
    """Solve the drives (``only`` these; default all) on their meshes, each from the previous, and write the references.

    A reference is the finest mesh's solve; the others of ``out`` are kept when ``only`` names some.
    """
    unknown = sorted(set(only or []) - set(DRIVES))
    if unknown:
        raise SystemExit(f"drive_references.py: unknown drive(s) {unknown}; expected some of {sorted(DRIVES)}")
    refs = json.loads(out.read_text()) if only and out.exists() else {}
    for name, p in DRIVES.items():
        if only and name not in only:
            continue
        runs = {}
        prev = None
        for n in p["intervals"]:
            prev = solve(p, n, guess=prev, t_guess=p.get("t_guess", 0.3))
            runs[n] = prev
            print(f"{name}: N = {n}: T = {prev['T']:.7f} s ({prev['status']}, {prev['cpu_s']:.1f} CPU-s)", flush=True)
        finest = p["intervals"][-1]
        refs[name] = {"final_time": runs[finest]["T"], "objective": runs[finest]["objective"], "status": runs[finest]["status"],
                      "by_intervals": {str(n): r["T"] for n, r in runs.items()},
                      "objective_by_intervals": {str(n): r["objective"] for n, r in runs.items()},
                      "method": f"direct multiple shooting, plain CasADi, piecewise-constant voltage on {finest} intervals, "
                                "2 RK4 steps each, the current bound at every step, IPOPT tol 1e-10"}
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(refs, indent=2) + "\n")
    return refs


if __name__ == "__main__":
    root = pathlib.Path(__file__).resolve().parents[1]
    args = [a for a in sys.argv[1:] if not a.startswith("--only=")]
    names = [n for a in sys.argv[1:] if a.startswith("--only=") for n in a.removeprefix("--only=").split(",")]
    main(pathlib.Path(args[0]) if args else root / "tests" / "problems" / "data" / "drive_references.json", names or None)
