"""Shared fixtures of the codegen tests: generated and compiled libraries, once per session."""

from __future__ import annotations

import pytest

from gtmodel.codegen import compile_shared, generate, load_library


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """``built(robot) -> (GeneratedCode, CompiledLibrary)``, both sources compiled with -Werror."""
    cache = {}

    def get(robot: str):
        if robot not in cache:
            out = tmp_path_factory.mktemp(f"codegen_{robot}")
            gen = generate(robot, out / "src")
            lib = load_library(gen, compile_shared(gen, out / "build", werror=True))
            cache[robot] = (gen, lib)
        return cache[robot]

    return get
