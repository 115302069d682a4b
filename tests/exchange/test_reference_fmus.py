"""Held-out FMUs: the Modelica Association's Reference FMUs (github.com/modelica/Reference-FMUs),
built from their sources, imported by gtmodel and simulated against SciPy and closed forms.

Not in the repository: set ``GTMODEL_REFERENCE_FMUS`` to a checkout of Reference-FMUs to run
these (``git clone https://github.com/modelica/Reference-FMUs``); skipped otherwise.
"""

from __future__ import annotations

import os
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel._compiler import find_compiler, run_compiler
from gtmodel.errors import InputError
from gtmodel.exchange import import_fmu, linearize_explicit, simulate_explicit
from gtmodel.exchange.fmu_export import fmi_platform

SOURCE = os.environ.get("GTMODEL_REFERENCE_FMUS")
pytestmark = [pytest.mark.slow, pytest.mark.skipif(not SOURCE, reason="GTMODEL_REFERENCE_FMUS not set")]


def build(model: str, version: str, out: Path) -> Path:
    """A binary FMU of one Reference FMU, built as their CMake build does (one model, one FMI version)."""
    src = Path(SOURCE)
    v = version[0]
    plat, ext = fmi_platform(version)
    stage = out / f"{model}_{v}"
    (stage / "binaries" / plat).mkdir(parents=True)
    sources = [src / "src" / f"fmi{v}Functions.c", src / "src" / "cosimulation.c", src / "src" / f"FMI{v}.c",
               src / "src" / "FMI.c", src / model / "model.c"]
    run_compiler([*find_compiler(), "-shared", "-fPIC", "-O1", f"-DFMI_VERSION={v}", "-DDISABLE_PREFIX",
                  f"-I{src / 'include'}", f"-I{src / model}", *map(str, sources), "-o",
                  str(stage / "binaries" / plat / f"{model}{ext}"), "-lm"], f"building {model}")
    shutil.copy(src / model / f"FMI{v}.xml", stage / "modelDescription.xml")
    fmu = out / f"{model}_fmi{v}.fmu"
    with zipfile.ZipFile(fmu, "w") as zf:
        for f in stage.rglob("*"):
            zf.write(f, f.relative_to(stage).as_posix())
    return fmu


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_van_der_pol_reference_fmu(tmp_path, version):
    imp = import_fmu(build("VanDerPol", version, tmp_path))
    assert imp.model.x_names == ["x0", "x1"] and imp.derivatives == "directional derivatives of the FMU"
    t = np.linspace(0.0, 5.0, 51)
    sim = simulate_explicit(imp.model, t, rtol=1e-10, atol=1e-12)
    ref = solve_ivp(lambda _, y: [y[1], (1 - y[0] ** 2) * y[1] - y[0]], (0, 5), [2.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-12)
    assert np.max(np.abs(sim.x["x0"] - ref.y[0])) < 1e-7
    np.testing.assert_allclose(linearize_explicit(imp.model).A, [[0.0, 1.0], [-1.0, -3.0]], atol=1e-9)  # mu = 1 at (2, 0)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_dahlquist_reference_fmu_without_directional_derivatives(tmp_path, version):
    imp = import_fmu(build("Dahlquist", version, tmp_path))
    assert imp.derivatives == "finite differences (CasADi)"
    sim = simulate_explicit(imp.model, np.linspace(0.0, 2.0, 11), rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(sim.x["x"], np.exp(-np.linspace(0.0, 2.0, 11)), rtol=1e-8)  # x' = -k x, k = 1


def test_bouncing_ball_reference_fmu_is_refused_for_its_events(tmp_path):
    with pytest.raises(InputError, match="BouncingBall_fmi2.fmu: the FMU has 1 event indicator.s. .state events"):
        import_fmu(build("BouncingBall", "2.0", tmp_path))


def source_fmu(model: str, version: str, out: Path) -> Path:
    """A source-only FMU (no binaries) laid out as the Reference FMUs' CMake build packs it:
    ``sources/`` with the model, the FMI functions and, for FMI 2.0, ``all.c`` listed under both
    interfaces; for FMI 3.0 ``buildDescription.xml`` with its ``FMI_VERSION`` definition."""
    src = Path(SOURCE)
    v = version[0]
    fmu = out / f"{model}_fmi{v}_sources.fmu"
    with zipfile.ZipFile(fmu, "w") as zf:
        zf.write(src / model / f"FMI{v}.xml", "modelDescription.xml")
        for f in (src / model / "model.c", src / model / "config.h", src / "include" / "model.h", src / "include" / "cosimulation.h",
                  src / "src" / f"fmi{v}Functions.c", src / "src" / "cosimulation.c"):
            zf.write(f, f"sources/{f.name}")
        if v == "2":
            zf.writestr("sources/all.c", '#define FMI_VERSION 2\n#include "fmi2Functions.c"\n#include "model.c"\n#include "cosimulation.c"\n')
        else:
            zf.write(src / model / "buildDescription.xml", "sources/buildDescription.xml")
    return fmu


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("model", ["VanDerPol", "Dahlquist"])
def test_source_only_reference_fmus_build_and_match_their_binary(tmp_path, model, version):
    """Built here from the sources (FMI 2.0: all.c listed twice; FMI 3.0: FMI_VERSION from the
    build description): the same trajectory as the binary built like their CMake (1e-10)."""
    built = import_fmu(source_fmu(model, version, tmp_path))
    binary = import_fmu(build(model, version, tmp_path))
    assert built.built_from_sources and not binary.built_from_sources
    t = np.linspace(0.0, 3.0, 31)
    a, b = (simulate_explicit(i.model, t, rtol=1e-10, atol=1e-12) for i in (built, binary))
    assert max(np.max(np.abs(a.x[n] - b.x[n])) for n in built.model.x_names) < 1e-10


@pytest.mark.parametrize(("model", "version", "match"), [
    ("Stair", "2.0", r"discrete-time variables changed at events \(counter\): time events \(next event time\)"),
    ("Stair", "3.0", r"discrete-time variables changed at events \(counter\): time events \(next event time\)"),
    ("Feedthrough", "2.0", r"discrete-time variables changed at events"),
    ("Resource", "3.0", r"no continuous states"),
])
def test_reference_fmus_that_cannot_be_simulated_are_refused_by_feature(tmp_path, model, version, match):
    with pytest.raises(InputError, match=match):
        import_fmu(source_fmu(model, version, tmp_path))
