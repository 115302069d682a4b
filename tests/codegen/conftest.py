"""Shared fixtures of the codegen tests: generated and compiled libraries, once per session."""

from __future__ import annotations

import pytest

from gtmodel.codegen import Controller, compile_shared, generate, load_library

from .controller_functions import ilc_correction_function, kalman_step_function, learned_table


@pytest.fixture(scope="session")
def generated(tmp_path_factory):
    """``generated(robot) -> GeneratedCode``: the C sources alone, not compiled (F1 compiles in ~14 CPU-s)."""
    cache = {}

    def get(robot: str):
        if robot not in cache:
            cache[robot] = generate(robot, tmp_path_factory.mktemp(f"codegen_{robot}") / "src")
        return cache[robot]

    return get


@pytest.fixture(scope="session")
def built(generated):
    """``built(robot) -> (GeneratedCode, CompiledLibrary)``, both sources compiled with -Werror."""
    cache = {}

    def get(robot: str):
        if robot not in cache:
            gen = generated(robot)
            lib = load_library(gen, compile_shared(gen, gen.source.parent.parent / "build", werror=True))
            cache[robot] = (gen, lib)
        return cache[robot]

    return get


@pytest.fixture(scope="session")
def controller_built(tmp_path_factory):
    """An L1 library (ik, jacobian, inverse_dynamics) with the stand-in controller: ``(GeneratedCode, CompiledLibrary)``.

    The controller: the Kalman step of gtmodel.estimation for 3 directions and a learned table of 400
    cycles (:mod:`tests.codegen.controller_functions`), compiled with -Werror.
    """
    table = learned_table()
    controller = Controller(kalman_step=kalman_step_function(), ilc_correction=ilc_correction_function(table), ilc_table=table)
    out = tmp_path_factory.mktemp("codegen_controller")
    gen = generate("L1", out / "src", functions=("ik", "jacobian", "inverse_dynamics"), controller=controller)
    return gen, load_library(gen, compile_shared(gen, out / "build", werror=True))
