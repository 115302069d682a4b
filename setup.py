"""Build hook of the wheel: the shipped examples go into the package as ``gtmodel/_examples/``.

Everything else about the package is declared in ``pyproject.toml``. The example trees
(:data:`EXAMPLES`: the problem files, the models they name, the studies and the robot-loop
files, each runnable as it is) live at the top of the repository, outside the package; this
hook copies them into the built package so that a user with only ``pip install`` gets them
(``gtmodel examples DIR`` copies them out: ``gtmodel/cli_examples.py``). An editable install
reads them from the checkout instead. ``MANIFEST.in`` puts them into the sdist.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
#: The folders copied, as the repository has them (cli_examples.EXAMPLES names the same).
EXAMPLES = ("problems", "models", "studies", "loops")
SKIPPED = shutil.ignore_patterns("__pycache__", "*.pyc", ".ipynb_checkpoints", "results")


class BuildWithExamples(build_py):
    """``build_py``, then the example trees copied into ``<build_lib>/gtmodel/_examples/``."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        target = Path(self.build_lib) / "gtmodel" / "_examples"
        shutil.rmtree(target, ignore_errors=True)  # a build folder of an earlier build holds no stale example
        for tree in EXAMPLES:
            if (HERE / tree).is_dir():
                shutil.copytree(HERE / tree, target / tree, ignore=SKIPPED)


setup(cmdclass={"build_py": BuildWithExamples})
