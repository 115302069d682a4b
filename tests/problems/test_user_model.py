"""The user-model protocol of :mod:`gtmodel.problems.user_model`: what a model file may define.

Each case writes a small model file and loads it: a Model subclass, a class with
``build()`` or ``to_model()`` are accepted; every failure is one ModelError whose message
starts with the file path and names the class (checked against the protocol's text).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from gtmodel.errors import ModelError
from gtmodel.modeling import Model
from gtmodel.problems.user_model import ModelFileError, load_user_model, split_model_reference

HEAD = "from gtmodel.modeling import Model\n\n\ndef oscillator():\n    m = Model('osc')\n    x = m.state('x', start=1.0)\n    v = m.state('v')\n    m.equation(m.der(x), v)\n    m.equation(m.der(v), -x)\n    return m\n\n\n"
GOOD = {
    "subclass": "class Osc(Model):\n    def __init__(self):\n        super().__init__('osc')\n        x = self.state('x')\n        self.equation(self.der(x), -x)\n",
    "build": "class Osc:\n    def build(self):\n        return oscillator()\n",
    "to_model": "class Osc:\n    def to_model(self):\n        return oscillator()\n",
}
BAD = {
    "not_a_class": ("Osc = oscillator\n", ModelError, "has 'Osc', but it is a function, not a class"),
    "no_build": ("class Osc:\n    pass\n", ModelError, r"Osc\(\) is a Osc, not a gtmodel\.modeling\.Model, and has no build\(\) or to_model\(\)"),
    "build_returns_other": ("class Osc:\n    def build(self):\n        return 42\n", ModelError, r"Osc\(\)\.build\(\) returned a int"),
    "build_raises": ("class Osc:\n    def build(self):\n        raise KeyError('k')\n", ModelError, r"Osc\(\)\.build\(\) raised KeyError"),
    "init_needs_arguments": ("class Osc:\n    def __init__(self, k):\n        pass\n", ModelError, r"Osc\(\) raised TypeError"),
    "does_not_flatten": ("class Osc(Model):\n    def __init__(self):\n        super().__init__('osc')\n        self.state('x')\n",
                         ModelError, r"class Osc: model 'osc' is under-determined \(0 scalar equations, 1 unknowns\); variables \['x'\]"),
    "syntax_error": ("class Osc(:\n", ModelFileError, "syntax error at line 13"),
    "import_raises": ("import not_a_module_anywhere\n", ModelFileError, "importing it raised ModuleNotFoundError"),
    "exit_on_import": ("raise SystemExit(3)\n", ModelFileError, "importing it raised SystemExit"),
}


def _write(tmp_path: Path, body: str) -> Path:
    f = tmp_path / "model.py"
    f.write_text(HEAD + body)
    return f


@pytest.mark.parametrize("case", GOOD)
def test_accepted_forms_give_a_model(tmp_path, case):
    model = load_user_model(_write(tmp_path, GOOD[case]), "Osc")
    assert isinstance(model, Model) and model.name == "osc"


@pytest.mark.parametrize("case", BAD)
def test_refused_forms_name_the_file(tmp_path, case):
    body, error, match = BAD[case]
    f = _write(tmp_path, body)
    with pytest.raises(error, match=match) as info:
        load_user_model(f, "Osc")
    assert str(info.value).startswith(str(f))


def test_missing_file_and_bad_class_name(tmp_path):
    with pytest.raises(ModelFileError, match="no such model file"):
        load_user_model(tmp_path / "nope.py", "Osc")
    with pytest.raises(ModelError, match="class name must be a Python identifier"):
        load_user_model(_write(tmp_path, GOOD["build"]), "not valid")


@pytest.mark.parametrize(
    "ref, expected",
    [("models/cp.py:CartPendulum", (Path("models/cp.py"), "CartPendulum")), ("C:/m/cp.py:CP", (Path("C:/m/cp.py"), "CP"))],
    ids=["relative", "drive_letter"],
)
def test_split_model_reference(ref, expected):
    assert split_model_reference(ref) == expected


@pytest.mark.parametrize("ref", ["models/cp.py", "models/cp.py:", ":CP"], ids=["no_colon", "no_class", "no_file"])
def test_split_model_reference_refuses(ref):
    with pytest.raises(ModelError, match="expected FILE:CLASS"):
        split_model_reference(ref)
