"""One Status: ranking, worst(), success, and the one status -> exit code table."""

from __future__ import annotations

import re

import pytest

from gtmodel.cli import build_parser
from gtmodel.status import EXIT_CODES, Status, StatusResult, SolverResult

from .conftest import REPO

# the table of the issue and of docs/getting_started.md, written out independently of the code
EXPECTED_EXIT = {
    "optimal": 0, "converged": 0, "completed": 0, "acceptable": 1, "check_failed": 1, "max_iterations": 1, "infeasible": 1,
    "error": 1, "invalid_input": 2, "internal_error": 3, "interrupted": 130,
}


@pytest.mark.parametrize("status, code", EXPECTED_EXIT.items())
def test_exit_code_per_status(status, code):
    assert Status(status).exit_code == code


def test_every_status_has_an_exit_code():
    assert set(EXIT_CODES) == set(Status)


@pytest.mark.parametrize(
    "statuses, worst",
    [
        ([], "optimal"),
        (["optimal", "acceptable"], "acceptable"),
        (["check_failed", "acceptable", "optimal"], "check_failed"),
        (["infeasible", "max_iterations"], "infeasible"),
        (["optimal", "infeasible", "error"], "error"),
        (["converged", "optimal"], "converged"),
        (["completed", "optimal"], "completed"),
        (["interrupted", "internal_error", "optimal"], "interrupted"),
    ],
)
def test_worst(statuses, worst):
    assert Status.worst(statuses) == worst


def test_infeasible_is_ranked_between_max_iterations_and_error():
    assert Status.MAX_ITERATIONS.rank < Status.INFEASIBLE.rank < Status.ERROR.rank


def test_unknown_status_is_refused():
    with pytest.raises(ValueError, match="'great' is not a valid Status"):
        Status.worst(["great"])


@pytest.mark.parametrize("status, success", [("optimal", True), ("converged", True), ("completed", True), ("acceptable", False), ("error", False)])
def test_status_result_success(status, success):
    result = StatusResult(status=status, message="m")
    assert result.success is success
    assert isinstance(result, SolverResult)
    assert result.status is Status(status)


def test_help_prints_the_table():
    epilog = build_parser().epilog
    rows = dict((s, int(c)) for c, s in re.findall(r"^\s*(\d+)\s+(\w+)$", epilog, flags=re.M))
    assert rows == EXPECTED_EXIT


def test_getting_started_prints_the_table():
    text = (REPO / "docs" / "getting_started.md").read_text(encoding="utf-8")
    rows = dict((s, int(c)) for s, c in re.findall(r"^\|\s*`(\w+)`\s*\|\s*(\d+)\s*\|", text, flags=re.M))
    assert rows == EXPECTED_EXIT
