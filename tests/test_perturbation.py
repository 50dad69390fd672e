"""Round-off does not choose the answer: problem files solved with every physical input moved by 1e-12 relative
(:func:`convexguid.spec.perturb.perturb_inputs`, the size of the differences between machines) end with the same
status, the same objective and a similar number of iterations. The full sweep over every problem file is in the
robustness benchmark (``python -m convexguid.robustness``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from convexguid.api import solve
from convexguid.problem_files import parse_problem
from convexguid.spec.loader import apply_overrides, read_yaml_mapping
from convexguid.spec.perturb import perturb_inputs

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
RELATIVE = 1e-12

BILIMORIA_WIE = ["spacecraft.torque_max_Nm=1.0", "keep_out=[]", "spacecraft.rate_max_degps=1000.0",
                 "boundary.final.axis=[1.0,0.0,0.0]", "boundary.final.angle_deg=180.0",
                 "spacecraft.inertia_kgm2=[1.0,1.0,1.0]"]
"""Bilimoria & Wie (1993): a unit-inertia body, |u_i| <= 1 N m, 180 deg rest to rest; a symmetric problem whose
symmetric stationary point is not a minimum."""

CASES = [
    pytest.param("cai2018_flat_attitude.yaml", [], 1e-6, True, id="flat-energy"),
    pytest.param("feng2018_nominal.yaml", [], 1e-6, True, id="quaternion-energy"),
    pytest.param("wang2003_rendezvous.yaml", [], 1e-6, True, id="rendezvous-burn-time"),
    pytest.param("betts_asymmetric_slew.yaml", [], 1e-4, True, id="betts-time"),
    pytest.param("guo2011_scp_energy.yaml", ["boundary.tf_from=null", "boundary.tf_s=196.8"], 1e-6, True,
                 id="guo2011-energy"),
]


def _solve(name: str, overrides: list[str], seed: int | None):
    source = str(PROBLEMS / name)
    data = apply_overrides(read_yaml_mapping(source, "a problem file"), overrides, source)
    if seed is not None:
        data, changed = perturb_inputs(data, RELATIVE, seed)
        assert changed > 0
    return solve(parse_problem(data, source))


@pytest.mark.parametrize(("name", "overrides", "objective_rel", "same_path"), CASES)
def test_tiny_input_changes_give_the_same_answer(name, overrides, objective_rel, same_path):
    nominal = _solve(name, overrides, None)
    assert nominal.status == "converged", nominal.message
    for seed in (1, 2):
        moved = _solve(name, overrides, seed)
        assert moved.status == nominal.status, moved.message
        assert moved.objective == pytest.approx(nominal.objective, rel=objective_rel)
        if same_path:
            assert abs(moved.iterations - nominal.iterations) <= max(3, 0.3 * nominal.iterations)
            assert moved.iterations <= 30  # every case here (issue 19 asks it of Betts and guo2011 energy)


def test_the_exactly_symmetric_slew_ends_at_a_verified_local_minimum_under_tiny_input_changes():
    """Bilimoria & Wie's slew is exactly symmetric, and its first subproblem (a linear program: no multipliers yet)
    has a face of equally good steps, not one; which of them the interior-point solver returns moves with a 1e-12
    change of the inertia, and the roads part. Most reach 3.2446 s; some reach another local minimum about 1.3%
    slower. Measured over perturbation seeds 1-12: 3 of 12 (seeds 6, 8, 12) at 3.2851 s with Clarabel and the paired
    equality rows of the previous assembly, 1 of 12 (seed 2) at 3.2864 s with PIQP. A step made unique (a least-norm
    tie-break) is the open fix (docs/ocp.md, Known limits); until then each road must at least end converged, verified,
    at a local minimum no more than 1.5% above the best of them."""
    runs = [_solve("wang_multicone_time.yaml", BILIMORIA_WIE, seed) for seed in (None, 1, 2)]
    assert all(run.status == "converged" for run in runs), [run.message for run in runs]
    best = min(run.objective for run in runs)
    assert best == pytest.approx(3.2446, rel=1e-3)  # the published 3.2431 s on this 50-interval grid
    assert all(run.objective <= 1.015 * best for run in runs), [run.objective for run in runs]


def test_perturbation_moves_physical_numbers_only():
    data = {"name": "x", "solver": {"tolerance": 1e-7}, "spacecraft": {"inertia_kgm2": [1.0, 2, 0.0], "runs": 3},
            "boundary": {"tf_s": 10.0, "flag": True}}
    moved, changed = perturb_inputs(data, 1e-12, 0)
    assert changed == 3
    assert moved["solver"] == data["solver"] and moved["spacecraft"]["runs"] == 3 and moved["boundary"]["flag"] is True
    assert moved["spacecraft"]["inertia_kgm2"][2] == 0.0
    for before, after in ((2.0, moved["spacecraft"]["inertia_kgm2"][1]), (10.0, moved["boundary"]["tf_s"])):
        assert after != before and abs(after / before - 1) == pytest.approx(1e-12, rel=1e-3)
    assert perturb_inputs(data, 1e-12, 0)[0] == moved and data["boundary"]["tf_s"] == 10.0
