"""``gtmodel codegen --model FILE:CLASS``: C for a user model, compiled with -Werror, equal to Python.

Checked against the same CasADi Functions evaluated from Python (the explicit ODE of
``gtmodel.modeling.explicit_ode``, parameters as an input) to 1e-12, against the closed form of
the cart-pendulum's accelerations (Lagrange's equations solved by hand for s'', theta''), and
each C step iterated over 250 periods against ``simulate()`` (IDAS).
"""

from __future__ import annotations

import re
import subprocess

import casadi as ca
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main
from gtmodel.codegen import compile_shared, generate, load_library, parameter_hash
from gtmodel.codegen.build import find_compiler
from gtmodel.codegen.model_code import MODEL_TOLERANCE, STRICT_EXTRA, check_model, generate_model, model_parameter_hash
from gtmodel.errors import ConvergenceError, InputError, ModelError
from gtmodel.modeling import Model
from gtmodel.problems.user_model import load_user_model
from gtmodel.robots import load_parameters

from ..conftest import REPO, replace_once
from ..modeling._builders import nonlinear_loop

MODEL_FILE = REPO / "models" / "cart_pendulum.py"


@pytest.fixture(scope="module")
def cart_pendulum(tmp_path_factory):
    model = load_user_model(MODEL_FILE, "CartPendulum")
    gen = generate_model(model, tmp_path_factory.mktemp("cp") / "src")
    return model, gen, check_model(gen, n=500)


def _dae_model() -> Model:
    """An index-1 DAE with an algebraic variable, a vector state and an output named like a C local."""
    m = Model("rc_dae")
    a = m.parameter("a", 2.0)
    q = m.state("q", 2, start=[1.0, -0.5])
    y = m.algebraic("y")
    u = m.input("u")
    m.equation(m.der(q), ca.vertcat(-a * q[0] + y, -q[1] + u))
    m.equation(y, q[0] * q[1] + 0.1 * m.time)
    m.output("w", q[0] ** 2 + y)  # "w" is the wrapper's work array: the C parameter is y_w
    m.output("pos", ca.vertcat(q[0], q[1], y))
    return m


def test_cart_pendulum_code_equals_python(cart_pendulum):
    _, gen, report = cart_pendulum
    assert gen.functions == ("ode", "outputs", "step_rk4", "step_implicit")
    assert report.passed, "\n".join(report.summary_lines())
    assert max(f.max_abs_diff for f in report.functions if "periods" not in f.name) <= MODEL_TOLERANCE


def test_header_has_the_models_own_hash_and_no_robot_macros(cart_pendulum):
    model, gen, _ = cart_pendulum
    text = gen.header.read_text()
    assert gen.parameter_hash == model_parameter_hash(model.flatten()) != parameter_hash(load_parameters("L1"))
    assert f'GT_CART_PENDULUM_PARAMETER_HASH "{gen.parameter_hash}"' in text
    assert not any(word in text for word in ("ROBOT", "SINGULARITY_TOLERANCE", "Gantry-Tau", "friction"))


def test_parameter_hash_changes_with_a_parameter_value(tmp_path):
    other = tmp_path / "heavier.py"
    other.write_text(replace_once('"m_pole", 0.3,', '"m_pole", 0.31,')(MODEL_FILE.read_text()))
    a, b = load_user_model(MODEL_FILE, "CartPendulum"), load_user_model(other, "CartPendulum")
    assert model_parameter_hash(a.flatten()) == model_parameter_hash(load_user_model(MODEL_FILE, "CartPendulum").flatten())
    assert model_parameter_hash(a.flatten()) != model_parameter_hash(b.flatten())


def test_ode_equals_the_closed_form_accelerations(cart_pendulum):
    # Lagrange's equations of the cart-pole solved by hand (Tedrake, Underactuated Robotics, ch. 3):
    # s'' = (F + m sin(th) (l om^2 + g cos(th))) / (M + m sin^2(th)),  th'' = -(s'' cos(th) + g sin(th)) / l
    _, gen, _ = cart_pendulum
    lib = load_library(gen, compile_shared(gen, gen.out_dir / "build2", werror=True))
    rng = np.random.default_rng(1)
    x = rng.uniform(-3, 3, (50, 4))
    F = rng.uniform(-20, 20, (50, 1))
    status, (xdot,) = lib["ode"].call_rows(x, F)
    M, m, l, g = 1.0, 0.3, 0.5, 9.81
    th, om = x[:, 2], x[:, 3]
    sdd = (F[:, 0] + m * np.sin(th) * (l * om**2 + g * np.cos(th))) / (M + m * np.sin(th) ** 2)
    thdd = -(sdd * np.cos(th) + g * np.sin(th)) / l
    assert np.all(status == 0)
    np.testing.assert_allclose(xdot, np.column_stack([x[:, 1], sdd, om, thdd]), rtol=1e-12, atol=1e-12)


def test_dae_model_residual_and_vector_outputs(tmp_path):
    gen = generate_model(_dae_model(), tmp_path / "src")
    report = check_model(gen, n=300)
    assert gen.functions == ("ode", "outputs")  # time-dependent: no fixed steps
    assert report.passed, "\n".join(report.summary_lines())
    assert "double y_w[1], double pos[3]" in gen.header.read_text()


def test_cli_codegen_model_check_passes(tmp_path, capsys):
    code = main(["codegen", "--model", f"{MODEL_FILE}:CartPendulum", "--out", str(tmp_path / "c"), "--check", "-n", "200"])
    out = capsys.readouterr().out
    assert code == EXIT_OK, out
    assert "PASSED" in out and "model cart_pendulum sha256:" in out


@pytest.mark.parametrize(
    "ref, match",
    [
        (f"{MODEL_FILE}:CartPole", r"cart_pendulum\.py: defines no class 'CartPole'"),
        (f"{REPO / 'models' / 'nope.py'}:CartPendulum", r"nope\.py: no such model file"),
        (str(MODEL_FILE), r"--model: expected FILE:CLASS"),
    ],
    ids=["class_not_defined", "file_missing", "no_class"],
)
def test_cli_codegen_model_bad_input(tmp_path, capsys, ref, match):
    code = main(["codegen", "--model", ref, "--out", str(tmp_path / "c")])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "Traceback" not in err and re.search(match, err), err


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        ({"functions": ["alg"]}, InputError, r"functions: \['alg'\] not among the model's functions \(ode, outputs, step_rk4, step_implicit\)"),
        ({"prefix": "1bad"}, InputError, "prefix: expected a C identifier"),
        ({"real": "long double"}, InputError, "real: expected 'double' or 'float'"),
    ],
    ids=["absent_function", "bad_prefix", "bad_real"],
)
def test_generate_model_bad_arguments(tmp_path, kwargs, error, match):
    with pytest.raises(error, match=match):
        generate_model(load_user_model(MODEL_FILE, "CartPendulum"), tmp_path, **kwargs)


def test_generate_model_refuses_a_model_that_does_not_flatten(tmp_path):
    m = Model("underdetermined")
    m.state("x")
    with pytest.raises(ModelError, match=r"'underdetermined' is under-determined \(0 scalar equations, 1 unknowns\)"):
        generate_model(m, tmp_path)


def test_robot_generate_is_unchanged_by_the_model_path(tmp_path):
    # the robot generator keeps its own hash: the L1 parameter hash, not a model hash
    gen = generate("L1", tmp_path, functions=["ik"])
    assert gen.parameter_hash == parameter_hash(load_parameters("L1"))


def test_composed_model_code_equals_python(tmp_path):
    # a component model: hierarchical output names become C identifiers (mass.acc -> mass_acc;
    # the MSL-like Mass has its acceleration as a variable, the output is declared here)
    pytest.importorskip("gtmodel.modeling.components.component")
    f = tmp_path / "osc.py"
    f.write_text(
        "from gtmodel.modeling.components.component import Component, connect\n"
        "from gtmodel.modeling.library.translational import Fixed, Force, Mass, Spring\n\n\n"
        "class MassAcc(Mass):\n    def equations(self):\n        super().equations()\n        self.output('acc', self.a)\n\n\n"
        "class Oscillator(Component):\n    fixed = Fixed()\n    spring = Spring(c=4.0)\n    mass = MassAcc(m=1.0)\n    force = Force()\n\n"
        "    def equations(self):\n        connect(self.fixed.flange, self.spring.flange_a)\n"
        "        connect(self.spring.flange_b, self.mass.flange_a)\n        connect(self.force.flange, self.mass.flange_b)\n"
    )
    gen = generate_model(load_user_model(f, "Oscillator"), tmp_path / "src")
    report = check_model(gen, n=200)
    assert report.passed, "\n".join(report.summary_lines())
    assert "double mass_acc[1]" in gen.header.read_text()


COMPOSED_FILE = '''
from gtmodel.modeling import Component, connect
from gtmodel.modeling.structure.index_reduction import structural_simplify
from gtmodel.modeling.library import translational as tr
from gtmodel.modeling.library.drive import CompliantDriveAxis


class Axis:
    """The library's compliant drive axis, of higher index: reduced before flattening."""

    def build(self):
        return structural_simplify(CompliantDriveAxis().to_model("axis"))


class PushedTwoMass(Component):
    """Force -> mass -- spring -- mass: index 1, 18 algebraic variables (the connectors)."""

    push = tr.Force()
    m1 = tr.Mass(m=1.0)
    spring = tr.Spring(c=100.0)
    m2 = tr.Mass(m=2.0)

    def equations(self):
        connect(self.push.flange, self.m1.flange_a)
        connect(self.m1.flange_b, self.spring.flange_a)
        connect(self.spring.flange_b, self.m2.flange_a)
'''
#: The robot wrapper's strict set (tests/codegen/test_build.py); the CasADi part without
#: -Wshadow -Wconversion, as the robot's.
STRICT = ("-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic")


@pytest.mark.parametrize(
    "cls, functions",
    [("Axis", ("ode", "outputs", "step_rk4", "step_implicit")),
     pytest.param("PushedTwoMass", ("ode", "step_rk4", "step_implicit"), marks=pytest.mark.slow)],
)
def test_composed_library_models_compile_strictly_and_equal_python(tmp_path, cls, functions):
    # reference: the model's own CasADi Functions from Python (check_model, 1e-12); the sources
    # compiled one by one with the robot code's strict flags
    f = tmp_path / "composed.py"
    f.write_text(COMPOSED_FILE)
    gen = generate_model(load_user_model(f, cls), tmp_path / "src")
    assert gen.functions == functions
    cc = find_compiler()
    procs = {
        src.name: subprocess.run([*cc, *STRICT, *extra, "-I", str(gen.out_dir), "-c", str(src), "-o", str(tmp_path / "x.o")],
                                 capture_output=True, text=True)
        for src, extra in ((gen.source, ("-Wshadow", "-Wconversion")), (gen.casadi_source, ()))
    }
    failed = {name: p.stderr for name, p in procs.items() if p.returncode != 0}
    assert not failed, failed
    report = check_model(gen, n=200)  # compiles with -Werror -pedantic too (STRICT_EXTRA)
    assert report.passed, "\n".join(report.summary_lines())
    assert max(r.max_rel_diff for r in report.functions if "periods" not in r.name) <= MODEL_TOLERANCE


@pytest.mark.slow  # tens of seconds of the default run's budget (measured 2026-11-28)
def test_cli_codegen_composed_axis_check_passes(tmp_path, capsys):
    # reference: check_model's comparison with Python (1e-12), through the command line
    f = tmp_path / "composed.py"
    f.write_text(COMPOSED_FILE)
    code = main(["codegen", "--model", f"{f}:Axis", "--out", str(tmp_path / "c"), "--check", "-n", "100"])
    out = capsys.readouterr().out
    assert code == EXIT_OK, out
    assert "PASSED" in out and "model axis sha256:" in out


def test_check_model_compiles_pedantically():
    # reference: the robot code's strict set (filter_check.STRICT_FLAGS = compile_shared's + -pedantic)
    assert STRICT_EXTRA == ("-pedantic",)


@pytest.mark.slow  # 15 s: compiles and runs the Newton model C
def test_newton_model_c_gives_not_converged_never_nan(tmp_path):
    # reference: the same explicit ODE from Python (1e-12) and simulate() over the horizon;
    # a state whose Newton solve overflows gives GT_NOT_CONVERGED with the outputs untouched
    gen = generate_model(nonlinear_loop("newton_loop", output=False), tmp_path / "src", functions=["ode", "step_implicit"], substeps=1)
    report = check_model(gen, n=200)
    assert report.passed, "\n".join(report.summary_lines())
    lib = load_library(gen, compile_shared(gen, tmp_path / "build2", werror=True))
    status, (xdot,) = lib["ode"].call_rows(np.array([[1.0], [1e308]]), np.zeros((2, 1)), fill=-7.0)
    assert status.tolist() == [0, 6] and xdot[1, 0] == -7.0 and np.isfinite(xdot[0, 0])
    status, (x_next,) = lib["step_implicit"].call_rows(np.array([[1e308]]), np.zeros((1, 1)), fill=-7.0)
    assert status.tolist() == [6] and x_next[0, 0] == -7.0


def test_dc_motor_steps_over_the_horizon_equal_simulate(tmp_path):
    # the composed DC motor (29 algebraic variables eliminated): C steps iterated over 250
    # periods of 4 ms against IDAS (simulate) within HORIZON_TOLERANCE
    gen = generate_model(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"), tmp_path / "src")
    report = check_model(gen, n=200)
    horizon = [r for r in report.functions if "periods" in r.name]
    assert report.passed, "\n".join(report.summary_lines())
    assert [r.name for r in horizon] == ["step_rk4 over 250 periods vs simulate()", "step_implicit over 250 periods vs simulate()"]
    assert "#define GT_DC_MOTOR_DT 0.004" in gen.header.read_text() and "const double x[3], const double u[1], double xdot[3]" in gen.header.read_text()
    # the library's units, as the components declare them (MSL: A, rad, rad/s, V, N.m)
    text = gen.header.read_text()
    assert " * States x: ind.i [A], emf.phi [rad], rotor.w [rad/s]\n" in text and " * Inputs u: src.v [V]\n" in text
    assert "emf.flange.tau [N.m]" in text and " * Outputs y: rotor.phi [rad], " in text


#: The derivatives the DC motor's index reduction keeps, by hand (di/dt, angular velocity and
#: acceleration): the header names them with these units (docs/modeling.md, section 6).
DC_MOTOR_DERIVATIVES = ["der_ind_i [A/s]", "der_emf_phi [rad/s]", "der_rotor_w [rad/s2]", "der2_emf_phi [rad/s2]", "der2_load_phi [rad/s2]"]


@pytest.fixture(scope="module")
def dc_motor_algebraics(tmp_path_factory):
    """The header's list of the DC motor's algebraic variables, ``name [unit]`` each."""
    gen = generate_model(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"), tmp_path_factory.mktemp("dc_motor"))
    line = next(line for line in gen.header.read_text().splitlines() if line.startswith(" * Algebraic variables z"))
    return line.split(": ", 1)[1].split(", ")


@pytest.mark.parametrize("entry", DC_MOTOR_DERIVATIVES)
def test_the_header_names_the_kept_derivatives_with_their_units(dc_motor_algebraics, entry):
    assert entry in dc_motor_algebraics


def test_horizon_check_fails_when_simulate_fails(tmp_path):
    # no reference, no success: a simulate() that fails makes the horizon check (and the report) fail
    gen = generate_model(nonlinear_loop("newton_loop", output=False), tmp_path / "src", functions=["step_rk4"], substeps=1)

    def failing(*args, **kwargs):
        raise ConvergenceError("IDAS gave up")

    gen.parameters.model.simulate = failing
    report = check_model(gen, n=20)
    assert not report.passed
    assert [r.name for r in report.functions if not r.ok] == ["step_rk4 over 250 periods vs simulate() (simulate failed)"]


# --------------------------------------------------------------------------- names are text, never code
#: The model name of issue 44: written unescaped it closed the version literal and added a constructor.
HOSTILE_NAME = ('p"; } int system(const char *); __attribute__((constructor)) static void pwn(void) '
                '{ system("touch PWNED"); } const char *gt_q(void) { return "')
HOSTILE_FILE = f'''
from gtmodel.modeling import Model

class Hostile(Model):
    def __init__(self):
        super().__init__({HOSTILE_NAME!r})
        q = self.state("q", start=1.0)
        u = self.input("u")
        self.equation(self.der(q), -2.0 * q + u)
'''


def _named_model(name: str) -> Model:
    m = Model(name)
    q = m.state("q", start=1.0)
    u = m.input("u")
    m.equation(m.der(q), -2.0 * q + u)
    m.output("y", q * q)
    return m


def _exported(library) -> list[str]:
    """Defined dynamic symbols of a shared library (binutils' nm, independent of gtmodel's loader)."""
    out = subprocess.run(["nm", "-D", "--defined-only", str(library)], check=True, capture_output=True, text=True).stdout
    return sorted(line.split()[-1] for line in out.splitlines() if line.strip())


def test_codegen_model_with_a_hostile_name_writes_it_as_text(tmp_path, monkeypatch, capsys):
    """``codegen --model`` with the issue's name: an identifier prefix, the name a C literal, no file created.

    Independent checks: gcc -Werror builds both libraries; nm lists the same exported symbols as
    for a plain name; the compiled version string (read through ctypes) holds the name byte for
    byte; loading the library (where a constructor would run) creates no file."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "hostile.py").write_text(HOSTILE_FILE)
    assert main(["codegen", "--model", f"{tmp_path / 'hostile.py'}:Hostile", "--out", str(tmp_path / "cli")]) == EXIT_OK
    (header,) = (tmp_path / "cli").glob("gt_*[!i].h")
    assert re.fullmatch(r"gt_[A-Za-z0-9_]+\.h", header.name)
    symbols, versions = [], []
    for name in (HOSTILE_NAME, "plain"):
        gen = generate_model(_named_model(name), tmp_path / ("hostile" if name != "plain" else "plain"), prefix="gt_m")
        lib_path = compile_shared(gen, gen.out_dir / "build", werror=True)
        lib = load_library(gen, lib_path)
        symbols.append(_exported(lib_path))
        versions.append(lib.version())
    assert symbols[0] == symbols[1] and "gt_m_ode" in symbols[0]
    assert f"model {HOSTILE_NAME} sha256:" in versions[0]
    assert not list(tmp_path.rglob("PWNED"))
    assert '#define GT_M_MODEL "p\\"; } int system(const char *);' in (tmp_path / "hostile" / "gt_m.h").read_text()


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.text(st.characters(blacklist_categories=("Cc", "Cs")), min_size=1, max_size=60).filter(
    lambda s: re.search(r"[A-Za-z0-9]", s)).map(lambda s: s + "*/ ??= %:include \\"))
def test_any_model_name_leaves_the_c_unchanged_but_for_its_literals(tmp_path_factory, name):
    """Arbitrary printable Unicode names: the wrapper compiles with -Werror -pedantic (trigraphs on,
    syntax only) and the header defines the same macros, with the same values but the name's
    literals and hash, as for a plain name (gcc -dM -E: the preprocessor's own view); the
    literal, read back by a decoder of its own, is the name's UTF-8."""
    macros, literal = _macros(tmp_path_factory.mktemp("names"), name)
    assert macros == _macros(tmp_path_factory.mktemp("plain"), "plain")[0]
    assert _c_literal_bytes(literal) == name.encode("utf-8")


def _macros(folder, name: str) -> tuple[dict[str, str], str]:
    """The GT_ macros of a model's header but its name, version and hash; the GT_M_MODEL literal."""
    cc = find_compiler()
    gen = generate_model(_named_model(name), folder / "src", functions=["ode"], prefix="gt_m")
    flags = ["-std=c99", "-trigraphs", "-Wall", "-Wextra", "-pedantic", "-Werror", f"-I{gen.out_dir}"]
    subprocess.run([*cc, *flags, "-fsyntax-only", str(gen.source)], check=True, capture_output=True)
    out = subprocess.run([*cc, *flags, "-dM", "-E", str(gen.header)], check=True, capture_output=True, text=True).stdout
    defined = dict(line[len("#define "):].partition(" ")[::2] for line in out.splitlines())
    literal = defined.pop("GT_M_MODEL")
    return {k: v for k, v in defined.items() if k.startswith("GT_") and k not in ("GT_M_VERSION", "GT_M_PARAMETER_HASH")}, literal


def _c_literal_bytes(literal: str) -> bytes:
    """The bytes of a C string literal of printable ASCII with octal and one-character escapes (a reader of its own)."""
    assert literal[0] == literal[-1] == '"'
    return re.sub(rb"\\([0-7]{3}|.)", lambda m: bytes([int(m.group(1), 8)]) if len(m.group(1)) == 3 else m.group(1),
                  literal[1:-1].encode("ascii"))
