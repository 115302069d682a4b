"""Table of broken problem files shared by the problem-loader and CLI tests.

Each case edits the shipped ``problems/l1_time_optimal.toml`` and gives the regular
expression the error message must match (it must name the field).
"""

from __future__ import annotations

from .conftest import PROBLEMS_DIR, replace_once as _replace

BASE = PROBLEMS_DIR / "l1_time_optimal.toml"


BAD_PROBLEMS = [
    ("missing_field", _replace("force = [450.0, 450.0, 450.0]", ""), r"missing field 'limits\.force'"),
    ("missing_table", _replace("[motion]", "[motion_]"), r"unknown field 'motion_'"),
    ("missing_optimization", _replace("[optimization]", "[optimisation]"), r"unknown field 'optimisation'"),
    ("unknown_field", _replace("free = true", "free = true\nfree_time = 2.0"), r"unknown field 'optimization\.final_time\.free_time'"),
    ("unknown_top_field", _replace('kind = "point_to_point"', 'kind = "point_to_point"\nsolver_name = "x"'), r"unknown field 'solver_name'"),
    ("wrong_type", _replace("w = 0.0 ", 'w = "zero" '), r"field 'parameters\.w': expected a finite number"),
    ("wrong_shape", _replace("force = [450.0, 450.0, 450.0]", "force = [450.0, 450.0]"), r"field 'limits\.force': expected a list of 3"),
    ("negative_limit", _replace("force = [450.0, 450.0, 450.0]", "force = [450.0, -450.0, 450.0]"), r"field 'limits\.force': expected 3 positive"),
    ("negative_weight", _replace("w = 0.0 ", "w = -1.0 "), r"field 'parameters\.w': expected a non-negative"),
    ("unreachable_start", _replace("start = [-0.20, 2.75, -0.40]", "start = [-0.20, 7.75, -0.40]"), r"field 'motion\.start': pose .* unreachable: arm"),
    ("start_outside_limits", _replace("start = [-0.20, 2.75, -0.40]", "start = [-1.9, 2.75, -0.40]"), r"field 'motion\.start': .*outside the workspace"),
    ("start_equals_end", _replace("end   = [ 0.20, 3.00, -0.60]", "end = [-0.20, 2.75, -0.40]"), r"field 'motion\.end': expected a pose different from motion\.start"),
    ("bad_kind", _replace('kind = "point_to_point"', 'kind = "teleport"'), r"field 'kind': expected one of point_to_point"),
    ("bad_robot", _replace('parameters = "L1"', 'parameters = "Z9"'), r"field 'robot\.parameters'"),
    ("bad_scheme", _replace('scheme = "radau"', 'scheme = "euler"'), r"field 'collocation\.scheme': expected one of radau, legendre"),
    ("bad_bounds", _replace("bounds = [0.05, 10.0]", "bounds = [10.0, 0.05]"), r"field 'optimization\.final_time\.bounds'"),
    ("free_time_without_bounds", _replace("bounds = [0.05, 10.0]", ""), r"field 'optimization\.final_time\.bounds': expected bounds \[lo, hi\] for a free final time"),
    ("fixed_time_without_value", _replace("free = true", "free = false"), r"field 'optimization\.final_time\.value': expected the final time"),
    ("undefined_name", _replace("integral((r * tau1)^2", "integral((r * tua1)^2"), r"field 'optimization\.objective': undefined name at column \d+: 'tua1'; did you mean 'tau1'"),
    ("expression_syntax", _replace('objective = "final_time + w', 'objective = "final_time + + * w'), r"field 'optimization\.objective': .*syntax"),
    ("eval_attempt", _replace('objective = "final_time + w', 'objective = "__import__(\'os\').system(\'ls\') + final_time + w'), r"field 'optimization\.objective'"),
    ("bad_constraint", _replace("[optimization.final_time]", 'constraints = ["abs(qd1) < 1.0"]\n\n[optimization.final_time]'), r"field 'optimization\.constraints\[0\]': strict comparison"),
    ("sweep_unknown_parameter", _replace("w = 0.0 ", "w_ = 0.0 "), r"undefined name at column \d+: 'w'"),
    ("force_cannot_hold", _replace("force = [450.0, 450.0, 450.0]", "force = [100.0, 100.0, 100.0]"), r"field 'limits\.force': .*cannot hold the robot at rest at the start pose"),
    ("toml_syntax", _replace("[limits]", "[limits"), r"invalid TOML"),
]
