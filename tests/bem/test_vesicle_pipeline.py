"""The pipeline's diagnosis of a point where no start and no relaxation converged."""

from __future__ import annotations

import math

from bem.vesicle.pipeline import RELAX_TIME, _diagnosis
from lubrication.checks import Deadline
from lubrication.results import Status


def _relaxed(label, un, v, approaching, failure=""):
    return {"label": label, "curve": None if failure else object(), "t": RELAX_TIME,
            "max_un": un, "V": v, "approaching": approaching, "failure": failure,
            "evaluations": 100}


def test_two_relaxations_that_keep_changing_are_no_steady_state_with_their_evidence():
    status, text = _diagnosis([_relaxed("A", (0.1, 0.12), (1.80, 1.74), False),
                               _relaxed("B", (0.2, 0.19), (1.70, 1.77), False)], Deadline(None))
    assert status is Status.NO_STEADY_STATE
    assert "no steady state reached" in text and f"{RELAX_TIME:g} R/U" in text
    for needle in ("from A", "1.0e-01 -> 1.2e-01", "1.8 -> 1.74", "from B", "1.7 -> 1.77"):
        assert needle in text, needle


def test_a_relaxation_still_approaching_is_not_called_no_steady_state():
    status, text = _diagnosis([_relaxed("A", (0.17, 0.092), (1.84, 1.66), True),
                               _relaxed("B", (0.2, 0.19), (1.7, 1.77), False)], Deadline(None))
    assert status is Status.NOT_CONVERGED and "still approaching" in text


def test_a_membrane_that_becomes_invalid_in_both_relaxations_is_named():
    status, text = _diagnosis(
        [_relaxed("A", (0.1, math.nan), (1.8, math.nan), False, "touches the wall at t = 3"),
         _relaxed("B", (0.1, math.nan), (1.8, math.nan), False, "touches the wall at t = 5")],
        Deadline(None))
    assert status is Status.NO_STEADY_STATE and text.count("touches the wall") == 2


def test_a_spent_budget_is_a_time_limit():
    deadline = Deadline(1e-9)
    while not deadline.expired():
        pass
    status, _ = _diagnosis([_relaxed("A", (0.1, 0.05), (1.8, 1.7), True)], deadline)
    assert status is Status.TIME_LIMIT
