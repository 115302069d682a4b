"""The method objects of a transcription (:mod:`gtmodel.modeling.ocp.methods`).

Independent check: the precedence rule written out by hand (the transcription's setting,
else the declaration's, else None for the default) on a stand-in declaration, and the
former import paths compared by identity.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

import gtmodel.trajectory as trajectory
import gtmodel.trajectory.model_ocp as model_ocp
import gtmodel.trajectory.settings as settings
from gtmodel.errors import InputError
from gtmodel.modeling.ocp.methods import Collocation, MultipleShooting, Refinement, SolverSettings, VerificationSettings
from gtmodel.modeling.ocp.verification import verify_settings

DECLARED = SimpleNamespace(verification_tolerance=0.2, verification_rtol=None, verification_integrator="idas")


@pytest.mark.parametrize("settings, expected", [
    (VerificationSettings(), VerificationSettings(0.2, None, "idas")),
    (VerificationSettings(tolerance=0.01), VerificationSettings(0.01, None, "idas")),
    (VerificationSettings(rtol=1e-9, integrator="cvodes"), VerificationSettings(0.2, 1e-9, "cvodes")),
])
def test_settings_over_the_declaration(settings, expected):
    assert settings.over(DECLARED) == expected


def test_refinement_gives_its_verification_settings():
    assert Refinement(tolerance=0.03, rtol=1e-7, integrator="cvodes").verification == VerificationSettings(0.03, 1e-7, "cvodes")


@pytest.mark.parametrize("verify, expected", [(True, None), (False, None), (VerificationSettings(0.1), VerificationSettings(0.1))])
def test_verify_argument(verify, expected):
    assert verify_settings(verify) == expected


def test_verify_argument_refused():
    with pytest.raises(InputError, match="verify: expected True, False or a VerificationSettings, got float"):
        verify_settings(0.1)


@pytest.mark.parametrize("name", ["Collocation", "MultipleShooting", "SolverSettings", "Refinement"])
def test_former_paths_re_export_the_same_class(name):
    here = {"Collocation": Collocation, "MultipleShooting": MultipleShooting, "SolverSettings": SolverSettings,
            "Refinement": Refinement}[name]
    assert getattr(settings, name) is here and getattr(trajectory, name) is here
    assert name != "MultipleShooting" or model_ocp.MultipleShooting is here
