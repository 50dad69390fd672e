"""The robustness benchmark's pieces: how a trial is judged, the round-off trials, and one trial end to end."""

from __future__ import annotations

from pathlib import Path

import pytest

from convexguid.robustness.instances import GENERATORS, roundoff_trials
from convexguid.robustness.report import render
from convexguid.robustness.trial import Trial, judged, run_trial

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def _outcome(status="converged", verified=True, gap=0.0, infeasible=False, objective=1.0):
    reference = {"objective": None if gap is None else objective / (1 + gap), "method": "m", "solved": 1,
                 "starts": 1, "infeasible": infeasible, "gap": gap}
    return {"status": status, "verified": verified, "reference": reference, "objective": objective}


@pytest.mark.parametrize(("outcome", "verdict"), [
    (_outcome(), "success"),
    (_outcome(gap=-0.01), "success"),  # better than the reference
    (_outcome(gap=2e-3), "gap"),
    (_outcome(verified=False), "not verified"),
    (_outcome(status="max_iterations"), "max_iterations"),
    (_outcome(status="infeasible", gap=None, infeasible=True), "success"),
    (_outcome(status="infeasible", gap=None), "infeasible without certificate"),
    (_outcome(gap=None), "no reference"),
])
def test_a_trial_succeeds_only_converged_verified_and_near_the_reference(outcome, verdict):
    assert judged(outcome) == verdict


def test_roundoff_trials_are_the_file_and_its_perturbations():
    trials = list(roundoff_trials([PROBLEMS / "cai2018_flat_attitude.yaml"], 2, {}))
    assert [t.label for t in trials] == ["nominal", "perturbed 1", "perturbed 2"]
    inertias = [t.problem["spacecraft"]["inertia_kgm2"] for t in trials]
    assert inertias[0] != inertias[1] != inertias[2]


def test_random_instances_are_seeded():
    first = [t.problem for t in GENERATORS["slew"](PROBLEMS, 2, 7)]
    assert first == [t.problem for t in GENERATORS["slew"](PROBLEMS, 2, 7)]
    assert first != [t.problem for t in GENERATORS["slew"](PROBLEMS, 2, 8)]


def test_one_random_rendezvous_is_solved_and_judged_against_lcvx():
    trial = next(GENERATORS["rendezvous"](PROBLEMS, 1, 3))
    outcome = run_trial(trial)
    assert judged(outcome) == "success", outcome["message"]
    assert abs(outcome["reference"]["gap"]) <= 1e-3 and outcome["reference"]["method"].startswith("LCvx")
    text = render([(trial, outcome)], "python -m convexguid.robustness", 1.0, "in process", [])
    assert "**1 of 1 successes**" in text


def test_a_trial_that_raises_is_an_error_outcome():
    outcome = run_trial(Trial(0, "s", "g", "bad", {"family": "nope"}, "x.yaml"))
    assert outcome["status"] == "error" and judged(outcome) == "error" and "nope" in outcome["message"]
