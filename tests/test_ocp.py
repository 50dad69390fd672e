"""A guidance problem stated in Python (issue 22, first part): convexguid.ocp on published and closed-form answers.

* The brachistochrone (examples/brachistochrone.py) against Bernoulli's cycloid, and the same time when gravity
  moves by 1e-12.
* A rest-to-rest double integrator at minimum energy: the closed form u = 6 - 12 t, J = 12.
* A keep-out circle (a nonconvex path constraint) at minimum energy: verified between the nodes, and the same
  optimum as IPOPT on the same Hermite-Simpson NLP from the same start.
* Betts' asymmetric minimum-time slew (examples/betts_slew.py) against the published 28.6304 s.
* A Clohessy-Wiltshire docking in an approach cone at minimum fuel with a free final time (examples/cw_docking.py):
  inside the cone, the thrust box and the speed limit on the dense re-propagation, and IPOPT's fuel on the same NLP.
* An attitude slew with a keep-out instrument and a keep-in instrument (examples/two_instrument_slew.py) against
  IPOPT on the same NLP.
* A problem stated wrongly: one line naming what is wrong, before any solve.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from example_modules import load_example
from scipy.optimize import brentq

from convexguid.errors import SpecError
from convexguid.ocp import Problem
from convexguid.ocp.hermite_simpson import HermiteSimpsonProgram
from convexguid.ocp.reference import solve_with_ipopt
from convexguid.ocp.scaling import scale_advice
from convexguid.ocp.solve import transcribe

ROOT = Path(__file__).resolve().parents[1]


def _example(name: str):
    return load_example(name)


def cycloid_time(x: float, y: float, g: float) -> float:
    """Time along the cycloid from rest at the origin to (x, -y): x = r(phi - sin phi), y = r(1 - cos phi)."""
    phi = brentq(lambda p: (p - math.sin(p)) / (1 - math.cos(p)) - x / y, 1e-6, 2 * math.pi - 1e-3)
    r = y / (1 - math.cos(phi))
    return phi * math.sqrt(r / g)


def test_the_brachistochrone_is_the_cycloid():
    brachistochrone = _example("brachistochrone")
    solution = brachistochrone.build().solve()
    assert solution.status == "converged", solution.message
    assert solution.verification.passed
    exact = cycloid_time(2.0, 2.0, brachistochrone.G)
    assert solution.figures.final_time_s == pytest.approx(exact, rel=1e-5)
    assert solution.summary()["final_time_s"] == solution.figures.final_time_s
    assert solution.summary()["units"] == {"x": "m", "y": "m", "v": "m/s", "theta": "rad"}


@pytest.mark.parametrize("intervals", [10, 20, 60])
def test_the_brachistochrone_converges_on_other_grids(intervals):
    brachistochrone = _example("brachistochrone")
    solution = brachistochrone.build(intervals).solve()
    assert solution.ok and solution.kkt["met"], solution.message
    assert solution.figures.final_time_s == pytest.approx(cycloid_time(2.0, 2.0, brachistochrone.G), rel=1e-4)


def test_the_brachistochrone_does_not_hang_on_round_off(monkeypatch):
    brachistochrone = _example("brachistochrone")
    times = []
    for g in (brachistochrone.G, brachistochrone.G * (1 + 1e-12), brachistochrone.G * (1 - 1e-12)):
        monkeypatch.setattr(brachistochrone, "G", g)
        solution = brachistochrone.build().solve()
        assert solution.ok, solution.message
        times.append(solution.figures.final_time_s)
    assert max(times) - min(times) <= 1e-9 * times[0]


def double_integrator(method: str = "hermite-simpson", intervals: int = 10, duration: float = 1.0) -> Problem:
    """Rest to rest over 1 m at minimum energy in ``duration`` seconds (also used by tests/test_ocp_holds.py)."""
    p = Problem("double-integrator")
    x = p.state("x", initial=0.0, final=1.0)
    v = p.state("v", initial=0.0, final=0.0)
    u = p.control("u")
    p.dynamics({x: v, v: u})
    p.final_time(fixed=duration)
    p.minimize_energy()
    p.transcription(intervals, method)
    return p


def test_minimum_energy_rest_to_rest_is_the_closed_form():
    solution = double_integrator().solve()
    assert solution.ok, solution.message
    assert solution.objective == pytest.approx(12.0, rel=1e-8)  # J = integral of (6 - 12 t)^2 over [0, 1]
    t = solution.nodes.t
    assert np.allclose(solution.nodes.columns["u"], 6 - 12 * t, atol=1e-6)


@pytest.mark.parametrize("backend", ["clarabel", "piqp", "daqp"])
def test_a_problem_names_the_backend_of_its_subproblems(backend):
    """``solve(backend=...)`` runs the subproblems there (the summary says which) and reaches the same optimum.
    (OSQP does not: docs/ocp.md, the ``p.solve`` row.)"""
    solution = _keep_out().solve(backend=backend)
    assert solution.ok, solution.message
    assert solution.summary()["solver"] == backend
    assert solution.objective == pytest.approx(_keep_out().solve().objective, rel=1e-6)


def test_an_unknown_backend_is_one_line_naming_the_call_and_what_is_installed():
    with pytest.raises(SpecError, match=r"^double-integrator: solve: backend: unknown backend 'gurobi'; installed: "
                                        r"auto, clarabel") as error:
        double_integrator().solve(backend="gurobi")
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("weight, expected", [(0.0, math.tanh(1.0)), (1.0, 1.0), (3.0, (3 + math.tanh(1.0))
                                                                                   / (1 + 3 * math.tanh(1.0)))])
def test_an_integral_cost_with_a_terminal_one_is_the_riccati_value(weight, expected):
    """x' = u from x(0) = 1, x(1) free, minimise S x(1)^2 + integral of x^2 + u^2: the Riccati equation
    p' = p^2 - 1, p(1) = S, gives J = p(0) x(0)^2 = (S + tanh 1) / (1 + S tanh 1) (tanh 1 without the terminal
    cost, exactly 1 at S = 1). The integral is a state, shown in the tables."""
    p = Problem("lq")
    x = p.state("x", initial=1.0)
    u = p.control("u")
    p.dynamics({x: u})
    p.final_time(fixed=1.0)
    cost = p.minimize_integral(x**2 + u**2, terminal=weight * x**2)
    p.transcription(20)
    solution = p.solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    assert solution.objective == pytest.approx(expected, rel=1e-6)
    assert str(cost) == "cost" and abs(solution.nodes.columns["cost"][0]) < 1e-12
    assert solution.nodes.columns["cost"][-1] + weight * solution.nodes.columns["x"][-1] ** 2 == \
        pytest.approx(expected, rel=1e-6)


def test_a_thrust_cone_holds_between_the_nodes_of_a_quadratic_control():
    """A minimum-time turn with the thrust's magnitude a cone: Hermite-Simpson's quadratic through node, midpoint
    and node values inside the cone may leave it between them, so a cone on the controls alone is held at the
    midpoints and at the six samples where the bounds are (it was at the nodes only: a CW minimum-time transfer's
    flown thrust then left the cone by 43% and the repair tightened it past its own bound). The flown thrust stays
    within the cone; the time is IPOPT's on the same transcription."""
    p = Problem("turn")
    x, y = p.state("x", initial=0.0, final=1.0), p.state("y", initial=0.0, final=0.0)
    vx, vy = p.state("vx", initial=0.0, final=0.0), p.state("vy", initial=1.0, final=0.0)
    ux, uy = p.control("ux", bounds=(-1.0, 1.0)), p.control("uy", bounds=(-1.0, 1.0))
    p.dynamics({x: vx, y: vy, vx: ux, vy: uy})
    p.cone_constraint("thrust", [ux, uy], 1.0)
    p.final_time(bounds=(0.5, 10.0), guess=3.0)
    p.minimize_time()
    p.transcription(12)
    program = transcribe(p)
    assert {point for point, _, _ in program.cone_rows} == {"node", "mid", "sample"}
    solution = p.solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    flown = np.hypot(solution.dense.columns["ux"], solution.dense.columns["uy"])
    assert flown.max() <= 1.0 + 1e-6
    answer = solve_with_ipopt(program)
    assert answer.success and solution.figures.final_time_s == pytest.approx(answer.objective, rel=1e-4)  # a repair
    # tightened the cone by its excess between the samples (2e-5 longer)


def test_a_throttle_annulus_holds_between_the_nodes_of_a_quadratic_control():
    """A planar transfer at least energy with the thrust's magnitude between 0.5 and 1 (the lower limit nonconvex, as
    a throttled engine's, and active all the way: the thrust turns at 0.5). An inequality on the controls alone is
    known exactly wherever the controls are interpolated, so it is held at the six samples too (it was at the nodes
    and midpoints only: the first plan's flown thrust dipped to 0.23 between them, and six repair rounds, margins and
    then controls held linear, left the plan 2.3% above the optimum; a Mars powered descent's repair ran out of
    rounds). The plan is IPOPT's on the same transcription."""
    p = Problem("annulus")
    x, y = p.state("x", initial=0.0, final=1.0), p.state("y", initial=0.0, final=0.0)
    vx, vy = p.state("vx", initial=0.0, final=0.0), p.state("vy", initial=0.0, final=0.0)
    ux, uy = p.control("ux", bounds=(-1.0, 1.0)), p.control("uy", bounds=(-1.0, 1.0))
    p.dynamics({x: vx, y: vy, vx: ux, vy: uy})
    p.path_constraint("throttle_min", 0.25 - (ux**2 + uy**2))
    p.path_constraint("throttle_max", ux**2 + uy**2 - 1.0)
    p.final_time(fixed=3.0)
    p.minimize_energy()
    p.transcription(12)
    program = transcribe(p)
    between = [label for label in program.path_labels if "between the nodes" in label]
    assert len(between) == 2 * 12 * 6 and "throttle_min between the nodes of interval 0" in between
    solution = p.solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    assert len(solution.repair_rounds) <= 3
    flown = np.hypot(solution.dense.columns["ux"], solution.dense.columns["uy"])
    assert flown.min() >= 0.5 - 1e-6 and flown.max() <= 1.0
    answer = solve_with_ipopt(program)
    assert answer.success and solution.objective == pytest.approx(answer.objective, rel=1e-4)


@pytest.mark.parametrize("rate", [2.0, -0.2])
def test_a_plan_on_unstable_dynamics_is_judged_interval_by_interval_and_says_so(rate):
    """x' = a x + u from 1 to 0 in 20 s at least energy. With a = 2 the flight from the initial state amplifies the
    plan's local errors by e^40 and no grid can pass it; the check then flies each interval from its node and the
    message says so. With a = -0.2 the plan is judged on the flight from the initial state, as every plan is."""
    p = Problem("scalar")
    x = p.state("x", initial=1.0, final=0.0)
    u = p.control("u")
    p.dynamics({x: rate * x + u})
    p.final_time(fixed=20.0)
    p.minimize_energy()
    p.transcription(20)
    solution = p.solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    amplified = "flown interval by interval from the plan's nodes" in solution.message
    assert amplified == (rate > 0)


def _keep_out() -> Problem:
    p = Problem("keep-out")
    px = p.state("px", initial=0.0, final=10.0)
    py = p.state("py", initial=0.0, final=0.0, scale=10.0)
    vx = p.state("vx", initial=0.0, final=0.0)
    vy = p.state("vy", initial=0.0, final=0.0)
    ax = p.control("ax", bounds=(-5.0, 5.0))
    ay = p.control("ay", bounds=(-5.0, 5.0))
    p.dynamics({px: vx, py: vy, vx: ax, vy: ay})
    p.path_constraint("keep_out", 2.0**2 - (px - 5.0) ** 2 - (py - 0.3) ** 2, "m^2")
    p.final_time(fixed=5.0)
    p.minimize_energy()
    p.transcription(30)
    return p


def _ipopt_optimum(problem: Problem, solution=None) -> float:
    """IPOPT (exact Hessian) on the same Hermite-Simpson NLP, from the straight-line start or, given the SCP's
    ``solution``, from its nodes (midpoint controls averaged from them): a nonconvex problem has more than one local
    optimum, and the check is that the SCP's is one of IPOPT's."""
    program = HermiteSimpsonProgram(problem)
    z0 = None
    if solution is not None:
        nodes = solution.nodes.columns
        states = np.column_stack([nodes[v.name] for v in problem.states])
        controls = np.column_stack([nodes[v.name] for v in problem.controls])
        z0 = np.concatenate([states.ravel(), controls.ravel(), (0.5 * (controls[:-1] + controls[1:])).ravel()])
    answer = solve_with_ipopt(program, z0)
    assert answer.success, answer.status
    return answer.objective


def test_a_keep_out_circle_is_respected_between_the_nodes_and_the_optimum_is_ipopts():
    problem = _keep_out()
    solution = problem.solve()
    assert solution.ok, solution.message
    keep_out = next(c for c in solution.verification.checks if c.name == "keep_out")
    assert keep_out.worst <= 1e-6  # on the dense SciPy re-propagation, not only at the nodes
    radius = np.hypot(solution.dense.columns["px"] - 5.0, solution.dense.columns["py"] - 0.3)
    assert radius.min() >= 2.0 - 1e-6
    assert solution.objective == pytest.approx(_ipopt_optimum(_keep_out(), solution), rel=1e-6)
    assert solution.objective <= _ipopt_optimum(_keep_out()) * (1 + 1e-6)  # IPOPT from the straight line: no better


@pytest.mark.parametrize(("statement", "message"), [
    (lambda p: (p.state("x"), p.state("x")), r"^demo: state 'x': the name is already taken"),
    (lambda p: p.state("x", bounds=(0.0, 1.0), initial=2.0), r"^demo: state 'x': initial value 2 is outside"),
    (lambda p: p.dynamics({ca.SX.sym("w"): 1.0}), r"^demo: dynamics: w is not a state of this problem"),
    (lambda p: p.final_time(bounds=(2.0, 1.0)), r"^demo: final_time: bounds: expected 0 < lower < upper"),
    (lambda p: p.path_constraint("c", ca.SX.sym("a", 2)), r"^demo: path_constraint 'c': expected a scalar"),
    (lambda p: p.transcription(1), r"^demo: transcription: intervals: expected an integer >= 2"),
    (lambda p: p.path_constraint("c", p.state("x"), scale=0.0), r"^demo: path_constraint 'c': scale: must be positive"),
    (lambda p: p.point_equality("e", p.state("x"), at=1.0, scale="big"),
     r"^demo: point_equality 'e': scale: expected a finite number"),
    (lambda p: p.boundary_constraint("b", {"x": 1.0}),
     r"^demo: boundary_constraint 'b': expected an expression or a list of them \(got dict"),
])
def test_a_wrong_statement_is_one_line_naming_it(statement, message):
    with pytest.raises(SpecError, match=message) as error:
        statement(Problem("demo"))
    assert "\n" not in str(error.value)


def test_a_column_may_be_stated_as_a_list_of_expressions():
    """``[x - 1, y]`` is a column as ``ca.vertcat(x - 1, y)`` is (it was CasADi's raw NotImplementedError)."""
    p = Problem("listed")
    x, y = p.state("x", initial=0.0), p.state("y", initial=0.0)
    p.dynamics({x: p.control("u"), y: x})
    p.boundary_constraint("end", [x - 1.0, y], at="final")
    assert p.boundary_constraints[-1][1].shape == (2, 1)


def test_a_derivative_that_is_not_a_number_at_the_iterate_is_named():
    """Drag |v| v from rest: CasADi's derivative of the norm at v = 0 is 0/0. The run stops before any subproblem
    (each would fail), and the status says which map's linearization is not a number there."""
    p = Problem("drag-from-rest")
    x, y = p.state("x", initial=0.0, final=1.0), p.state("y", initial=0.0, final=0.5)
    vx, vy = p.state("vx", initial=0.0, final=0.0), p.state("vy", initial=0.0, final=0.0)
    ux, uy = p.control("ux", bounds=(-2.0, 2.0)), p.control("uy", bounds=(-2.0, 2.0))
    speed = ca.norm_2(ca.vertcat(vx, vy))  # at rest along the whole straight-line guess
    p.dynamics({x: vx, y: vy, vx: ux - speed * vx, vy: uy - speed * vy})
    p.final_time(fixed=2.0)
    p.minimize_energy()
    p.transcription(10)
    solution = p.solve()
    assert solution.status == "solver_error" and solution.iterations == 0
    assert "not a number at the start point, in dynamics_defects" in solution.message


def test_a_later_final_time_replaces_an_earlier_one():
    """Free, then fixed: the problem is of fixed time (the bounds were kept, and the final time was free and fixed at
    once); fixed, then free: free, from the new guess."""
    p = Problem("twice")
    p.final_time(bounds=(1.0, 10.0), guess=3.0)
    p.final_time(fixed=2.0)
    assert not p.free_time and p.tf == 2.0
    p.final_time(bounds=(1.0, 10.0), guess=4.0)
    assert p.free_time and p.tf is None and p.tf_guess == 4.0


def test_an_incomplete_problem_is_refused_before_the_solve():
    p = Problem("demo")
    x = p.state("x", initial=0.0, final=1.0)
    p.state("v", initial=0.0)
    p.dynamics({x: 1.0})
    with pytest.raises(SpecError, match=r"^demo: dynamics: no rate given for state\(s\) v$"):
        p.solve()
    q = double_integrator()
    q.path_constraint("uses_unknown", ca.SX.sym("w") - 1.0)
    with pytest.raises(SpecError, match=r"^double-integrator: path_constraint 'uses_unknown': uses w"):
        q.solve()


def test_betts_asymmetric_slew_is_the_published_time():
    """Betts 2010, p. 299: 28.6304 s (a fine mesh); 100 Hermite-Simpson intervals, the torque held within its box
    between nodes as well (the quadratic control through node, midpoint and node is bounded at six points of every
    interval: on 50 intervals that costs 2.8% of the time, 29.4364 s, because a switch can no longer fall inside
    an interval)."""
    solution = _example("betts_slew").build().solve()
    assert solution.ok, solution.message
    assert solution.figures.final_time_s == pytest.approx(28.6304, rel=5e-4)
    torques = np.column_stack([solution.dense.columns[f"u{i}"] for i in (1, 2, 3)])
    assert np.abs(torques).max() <= 50.0 + 1e-9


def test_cw_docking_inside_its_approach_cone_at_minimum_fuel_matches_ipopt():
    cw = _example("cw_docking")
    solution = cw.build().solve()
    assert solution.ok, solution.message
    checks = {c.name: c for c in solution.verification.checks}
    assert checks["approach_cone"].violation <= 1e-6 and checks["speed"].violation <= 1e-6
    dense = solution.dense.columns
    lateral = np.hypot(dense["x"], dense["z"])
    # one-sided (in front of the port), to within the millimetre the re-propagated arrival may overshoot it by
    # (the final-state tolerance is 1e-4 of the 100 m scale)
    assert np.all(lateral <= math.tan(cw.CONE_HALF_ANGLE) * -dense["y"] + 1e-3)
    assert np.abs(np.column_stack([dense["ax"], dense["ay"], dense["az"]])).max() <= cw.THRUST_MAX + 1e-9
    answer = solve_with_ipopt(HermiteSimpsonProgram(cw.build()))
    assert answer.success, answer.status
    # the SCP's repairs tightened the cone where it broke between nodes: its fuel is at least IPOPT's on the
    # untightened NLP, and close to it
    assert answer.objective * (1 - 1e-6) <= solution.objective <= answer.objective * (1 + 1e-2)


def test_a_slew_with_a_keep_out_and_a_keep_in_instrument_is_ipopts_optimum():
    """examples/two_instrument_slew.py: the star tracker's Sun exclusion and the antenna's Earth inclusion both
    reached on the dense re-propagation, and the energy IPOPT finds on the same NLP, from the SCP's plan (the same
    local optimum) and from the straight line (no better); dearer than with the Sun exclusion alone."""
    slew = _example("two_instrument_slew")
    solution = slew.build().solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    checks = {c.name: c for c in solution.verification.checks}
    for name in ("tracker_sun_exclusion", "antenna_earth_inclusion"):
        assert -1e-5 <= checks[name].worst <= 1e-6, (name, checks[name].worst)  # met, and met with equality
    # the repair tightened the cones where they broke between nodes: at least IPOPT's energy, and close to it
    assert _ipopt_optimum(slew.build(), solution) <= solution.objective <= _ipopt_optimum(slew.build()) * (1 + 1e-5)
    free = slew.build()
    free.constraints = [c for c in free.constraints if c.name != "antenna_earth_inclusion"]
    assert solution.objective > free.solve().objective


def test_a_constraint_over_part_of_the_maneuver_and_at_one_instant():
    """Rest to rest over 1 m in 1 s at minimum energy, kept below 0.3 m over the first half and at or beyond
    0.45 m at half time: the window and the instant are imposed there only (the free optimum passes 0.5 m at half
    time and crosses 0.3 m in the first half)."""
    p = double_integrator()
    x = p.states[0].symbol
    p.path_constraint("low_first_half", x - 0.3, "m", during=(0.0, 0.4))
    p.point_constraint("far_at_half_time", 0.45 - x, at=0.5, unit="m")
    p.transcription(20)
    solution = p.solve()
    assert solution.ok, solution.message
    t, position = solution.dense.t, solution.dense.columns["x"]
    assert position[t <= 0.4].max() <= 0.3 + 1e-6
    assert np.interp(0.5, t, position) >= 0.45 - 1e-6
    assert position.max() > 0.3  # the limit holds where it is stated, not after
    assert solution.objective > 12.0  # dearer than the free optimum
    assert solution.objective == pytest.approx(solve_with_ipopt(HermiteSimpsonProgram(p)).objective, rel=1e-6)


@pytest.mark.parametrize("method", ["hermite-simpson", "foh", "chebyshev"])
def test_an_equality_at_an_instant_holds_there_on_a_state_and_on_a_control(method):
    """Rest to rest over 1 m in 1 s at minimum energy, through x = 0.6 m at half time and with the control back
    at zero as it ends (Dymos states a cart-pole's final force so): both equalities hold on the flown plan, and the
    cost is IPOPT's on the same transcription, above the free optimum's 12."""
    p = double_integrator(method, intervals=20)
    x, u = p.states[0].symbol, p.controls[0].symbol
    p.point_equality("through_at_half_time", x - 0.6, at=0.5, unit="m")
    p.point_equality("no_force_at_the_end", u, at=1.0, unit="m/s^2")
    solution = p.solve()
    assert solution.ok, solution.message
    half = np.flatnonzero(np.isclose(solution.nodes.t, 0.5))
    assert half.size == 1 and solution.nodes.columns["x"][half[0]] == pytest.approx(0.6, abs=1e-7)
    assert solution.nodes.columns["u"][-1] == pytest.approx(0.0, abs=1e-7)
    assert np.interp(0.5, solution.dense.t, solution.dense.columns["x"]) == pytest.approx(0.6, abs=1e-4)  # as flown
    assert solution.objective > 12.0 + 1.0
    assert solution.objective == pytest.approx(solve_with_ipopt(transcribe(p)).objective, rel=1e-6)


def test_a_boundary_constraint_on_a_control_points_to_the_point_equality():
    p = double_integrator()
    with pytest.raises(SpecError, match=r"uses a control.*point_equality\(name, expression, at=1.0\)"):
        p.boundary_constraint("no_force", p.controls[0].symbol)


def test_a_point_constraint_off_the_grid_is_refused():
    p = double_integrator()
    p.point_constraint("halfway", p.states[0].symbol - 0.4, at=0.33)
    with pytest.raises(SpecError, match=r"point_constraint 'halfway': at = 0.33 of the final time is not a node"):
        p.solve()


# --- the command line -------------------------------------------------------------------------------------------


def test_convexguid_solve_runs_a_problem_module(tmp_path, capsys):
    from convexguid.cli import main

    out = tmp_path / "out"
    assert main(["solve", str(ROOT / "examples" / "brachistochrone.py"), "--quiet", "--out", str(out),
                 "--set", "intervals=20"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["controls.png", "nodes.csv", "states.png", "summary.json",
                                                     "trajectory.csv"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["family"] == "ocp" and summary["status"] == "converged" and summary["verification"]["passed"]
    assert summary["final_time_s"] == pytest.approx(cycloid_time(2.0, 2.0, 9.81), rel=1e-4)  # 20 intervals


@pytest.mark.parametrize(("module", "overrides", "message"), [
    ("brachistochrone.py", ["g=3"], r"--set 'g=3': not a parameter of build\(\); its parameters: intervals"),
    ("missing.py", [], r"missing.py: file not found"),
    # a statement refused while build() states it names the file too
    ("brachistochrone.py", ["intervals=1"],
     r"brachistochrone.py: brachistochrone: transcription: intervals: expected an integer >= 2 \(got 1\)"),
    ("phases/two_burn_orbit_raise.py", ["intervals=8000"],
     r"two_burn_orbit_raise.py: two-burn-orbit-raise: burn1.transcription.intervals: problem too large"),
    # a size that would eat the machine's memory is refused before anything is transcribed
    ("brachistochrone.py", ["intervals=100000000"],
     r"brachistochrone.py: brachistochrone: transcription.intervals: problem too large: .* TiB .* \(got 100000000\)"),
])
def test_a_bad_problem_module_is_exit_2_with_one_line(module, overrides, message, capsys):
    from convexguid.cli import main

    args = ["solve", str(ROOT / "examples" / module), "--quiet"] + [a for o in overrides for a in ("--set", o)]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert re.search(message, err) and err.count("\n") == 1


def test_the_size_estimate_bounds_what_a_transcription_takes_and_admits_the_examples():
    """The estimate is an upper bound of the memory measured for ocp/size.py's docstring, and no example's
    default grid is near the limit."""
    from convexguid.ocp.size import estimate_size
    from convexguid.sizes import DEFAULT_MEMORY_LIMIT_BYTES, MIB, PROCESS_BYTES

    shuttle = _example("classics/shuttle_reentry").build()
    for intervals, method, measured_mib in ((200, "hermite-simpson", 48), (800, "hermite-simpson", 191),
                                            (200, "zoh", 319)):
        shuttle.transcription(intervals, method)
        assert estimate_size(shuttle).memory_bytes - PROCESS_BYTES > measured_mib * MIB
    for name in ("brachistochrone", "betts_slew", "cw_docking", "powered_descent", "classics/goddard_rocket"):
        assert estimate_size(_example(name).build()).memory_bytes < 0.5 * DEFAULT_MEMORY_LIMIT_BYTES


def test_a_module_whose_build_returns_something_else_is_refused(tmp_path, capsys):
    from convexguid.cli import main

    module = tmp_path / "wrong.py"
    module.write_text("def build():\n    return 42\n")
    assert main(["solve", str(module), "--quiet"]) == 2
    assert "build() returned int; it must return a convexguid.ocp.Problem" in capsys.readouterr().err


def test_a_wrong_statement_in_a_module_is_exit_2_naming_it(tmp_path, capsys):
    from convexguid.cli import main

    module = tmp_path / "twice.py"
    module.write_text("from convexguid.ocp import Problem\n\n\ndef build():\n    p = Problem('twice')\n"
                      "    p.state('x')\n    p.state('x')\n    return p\n")
    assert main(["solve", str(module), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "twice: state 'x': the name is already taken" in err and err.count("\n") == 1


def test_a_statement_of_the_same_graph_reuses_its_derivatives_and_another_does_not():
    """The derivative cache (convexguid.ocp.parts.DERIVATIVES) hands a statement built again the same CasADi
    functions, and a statement whose maps differ by one constant its own; it keeps only its last few graphs."""
    from convexguid.ocp.parts import DerivativeCache

    def brachistochrone(g: float):
        example = _example("brachistochrone")
        original = example.G
        example.G = g
        try:
            return transcribe(example.build(12))
        finally:
            example.G = original

    first, again, other = brachistochrone(9.81), brachistochrone(9.81), brachistochrone(9.80)
    assert first._defects is again._defects and first._hessian is again._hessian
    assert other._defects is not first._defects and other._hessian is not first._hessian
    z = first.initial_guess()
    assert np.array_equal(np.asarray(first._defects(z)[0]), np.asarray(again._defects(z)[0]))
    assert not np.allclose(np.asarray(first._defects(z)[0]), np.asarray(other._defects(z)[0]))

    cache, built = DerivativeCache(size=2), []
    x = ca.SX.sym("x")
    for c in (1.0, 2.0, 3.0, 1.0):
        cache.get("square", [x], [c * x**2], lambda c=c: built.append(c) or c)
    assert built == [1.0, 2.0, 3.0, 1.0]  # the graph of 1.0 left when 3.0 came: built again
    assert cache.get("square", [x], [3.0 * x**2], lambda: "new") == 3.0


def test_a_state_stated_with_bounds_alone_is_guessed_within_them():
    """A state with no boundary values and no guess starts at 0 where its bounds allow it, else at the nearest
    bound: an airspeed bounded to [10, 350] guessed at 0 would start the dynamics at a division by zero (IPOPT then
    stops at its first evaluation)."""
    p = Problem("guesses")
    speed = p.state("v", bounds=(10.0, 350.0))
    mass = p.state("m", bounds=(2.0, None))
    angle = p.state("gamma", bounds=(-1.0, 1.0))
    height = p.state("h", bounds=(0.0, 1000.0), initial=5.0)
    u = p.control("u", bounds=(-1.0, 1.0))
    p.dynamics({speed: u, mass: -u**2, angle: u / speed, height: speed * angle})
    p.final_time(fixed=1.0)
    p.minimize_energy()
    start, end, _ = p.straight_line()
    assert start.tolist() == [10.0, 2.0, 0.0, 5.0]
    assert end.tolist() == start.tolist()


def test_a_scale_far_below_the_plans_size_follows_the_plan():
    """A cart pushed 100 m in 10 s against quadratic drag, its speed stated only by its ends (0.1 m/s): scaled by 0.1,
    a speed near 14 m/s has its trust region, its defects and its mesh error judged in tenths of a metre per second
    (the plan was refined to 62 intervals, its local error then 5e-5 speed scales). At the first nearly feasible
    plan the speed's scale grows to its size, and the plan stays on the stated 30 intervals at IPOPT's optimum."""
    p = Problem("fast-cart")
    x = p.state("x", initial=0.0, final=100.0, unit="m")
    v = p.state("v", initial=0.1, final=0.1, unit="m/s")
    u = p.control("u", bounds=(-10.0, 10.0), unit="m/s^2")
    p.dynamics({x: v, v: u - 0.02 * v**2})
    p.final_time(fixed=10.0)
    p.minimize_energy()
    p.transcription(30)
    assert p.state_scales() == pytest.approx([100.0, 0.1])
    solution = p.solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    first = solution.repair_rounds[0].repair
    assert "scales following the plan (v 0.1 -> " in first and len(solution.nodes.t) == 31, first
    grown = float(first.split("v 0.1 -> ")[1].split(")")[0])
    assert grown == pytest.approx(np.max(np.abs(solution.nodes.columns["v"])), rel=0.2)
    answer = solve_with_ipopt(transcribe(p))
    assert answer.success and solution.objective == pytest.approx(answer.objective, rel=1e-6)


def test_a_run_that_ends_short_names_the_estimated_scales_its_plan_outgrew():
    """The fast cart stopped after three iterations: its speed, scaled by its boundary values (0.1 m/s), already
    exceeds four times that, and the message says so and what to do; with the same scale stated, it says nothing of
    scales (the user chose it)."""
    def cart(scale):
        p = Problem("fast-cart")
        x = p.state("x", initial=0.0, final=100.0)
        v = p.state("v", initial=0.1, final=0.1, scale=scale)
        u = p.control("u", bounds=(-10.0, 10.0))
        p.dynamics({x: v, v: u - 0.02 * v**2})
        p.final_time(fixed=10.0)
        p.minimize_energy()
        p.transcription(30)
        return p.solve(max_iterations=3)

    estimated, stated = cart(None), cart(0.1)
    assert estimated.status == stated.status == "max_iterations"
    reached = float(np.max(np.abs(estimated.nodes.columns["v"])))
    assert reached > 0.4
    assert f"the last plan outgrew the scales estimated for v (0.1, reached {reached:.3g}): state their sizes " \
        "(p.state(..., scale=))" in estimated.message, estimated.message
    assert "outgrew" not in stated.message, stated.message


def test_a_plan_that_ran_away_is_not_advised_as_a_scale_to_state():
    """A plan a million times beyond a state's scale ran away (Dymos' launch to orbit without a floor on its mass flew
    through zero mass to 1e73 m): the advice says so, names the state and does not offer its size as a scale."""
    p = Problem("runaway")
    x = p.state("x", initial=0.0, final=1.0)
    u = p.control("u", bounds=(-1.0, 1.0))
    p.dynamics({x: u})
    p.final_time(fixed=1.0)
    p.minimize_energy()
    p.transcription(4)
    program = transcribe(p)
    z = np.array(program.initial_guess(), dtype=float)
    advice = scale_advice(program, 1e9 * z)
    assert advice.startswith("the last plan ran away (x ") and "scale=" not in advice, advice
    outgrown = scale_advice(program, 10.0 * z)
    assert outgrown.startswith("the last plan outgrew the scales estimated for x (1, reached 10)"), outgrown


def test_a_final_condition_blind_at_the_guess_is_reached_off_a_saddle_of_the_violation():
    """cos(phi) cos(psi) = cos(0.3) at the end of two integrators started at rest: on the straight-line guess (no turn)
    the condition's gradient vanishes, every linearization misses it, and phase 1 stalls where the violation is at
    a maximum. That is no certificate of infeasibility: phase 1 steps off along the violation's negative curvature
    and the plan reaches the least energy, 0.09 (a turn of 0.3 rad on one axis at a constant rate)."""
    p = Problem("blind-final-condition")
    phi, psi = p.state("phi", initial=0.0), p.state("psi", initial=0.0)
    a, b = p.control("a", bounds=(-1.0, 1.0)), p.control("b", bounds=(-1.0, 1.0))
    p.dynamics({phi: a, psi: b})
    p.boundary_constraint("turn", ca.cos(phi) * ca.cos(psi) - math.cos(0.3), at="final")
    p.final_time(fixed=1.0)
    p.minimize_energy()
    p.transcription(20)
    solution = p.solve()
    assert solution.status == "converged", solution.message
    assert solution.objective == pytest.approx(0.09, rel=1e-6)
    assert "stepped off a saddle of the violation" in solution.message


def test_a_sum_of_squared_fit_residuals_started_at_zero_gets_a_scale_for_its_epigraph():
    """Fit y' = -k y, y(0) = 1, to ten samples of exp(-t) (with a ripple), each residual a parameter tied to its
    sample by a point equality, the cost their sum of squares: zero, with a zero gradient, at the guess. Scaled by its
    first-order change alone (the 1e-6 floor), the cost's epigraph variable crawled for some twenty iterations; its
    second-order change (the residuals' own scales) sizes it, and the fit matches IPOPT's on the same program."""
    samples = [math.exp(-k / 10) + 0.01 * math.sin(7 * k) for k in range(1, 11)]

    def build() -> Problem:
        p = Problem("fit")
        y = p.state("y", initial=1.0)
        rate = p.parameter("k", bounds=(0.0, None))
        p.dynamics({y: -rate * y})
        p.final_time(fixed=1.0)
        residuals = [p.parameter(f"e{k}") for k in range(1, 11)]
        for k, (e, sample) in enumerate(zip(residuals, samples, strict=True), start=1):
            p.point_equality(f"sample{k}", y - sample - e, at=k / 10)
        p.minimize_terminal(sum(e**2 for e in residuals))
        p.transcription(10)
        return p

    solution = build().solve()
    assert solution.status == "converged", solution.message
    # both within their KKT tolerances of the optimum (1e-6 of the objective's unit)
    assert solution.objective == pytest.approx(solve_with_ipopt(transcribe(build())).objective, rel=1e-5)
    assert solution.iterations < 12


def _speed_limited(unit: float) -> Problem:
    """Rest to rest over 1 m in 1 s at least energy, the speed held to 1.2 m/s by ``unit * (v^2 - 1.2^2) <= 0``
    (unconstrained, it peaks at 1.5 m/s): one constraint stated in any unit."""
    p = Problem("speed-limited")
    x, v = p.state("x", initial=0.0, final=1.0), p.state("v", initial=0.0, final=0.0)
    u = p.control("u", bounds=(-20.0, 20.0))
    p.dynamics({x: v, v: u})
    p.path_constraint("speed", unit * (v * v - 1.2**2))
    p.final_time(fixed=1.0)
    p.minimize_integral(u * u)
    p.transcription(20)
    return p


def test_a_path_constraint_is_solved_the_same_in_whatever_unit_it_is_stated():
    """A path inequality's rows are divided by its magnitude (its change when the states and controls move by their
    scales, to second order: the straight line is at rest, where v^2 has no slope), kept at most ten times stricter
    than it. Left in their stated unit, the same limit took 9 iterations, 16 with four repair rounds times 1e8 (a
    violation of 1e4 of its units drowned the merit) and ended unverified after 187 times 1e-6 (below the
    feasibility tolerance everywhere)."""
    solutions = {unit: _speed_limited(unit).solve() for unit in (1e-6, 1.0, 1e8)}
    for solution in solutions.values():
        assert solution.status == "converged" and not solution.repair_rounds[1:], solution.message
        assert solution.objective == pytest.approx(solutions[1.0].objective, rel=1e-6)
        assert solution.iterations <= 8
    # times 1 and times 1e8, the rows are both ten times stricter than the magnitude: the same program
    assert abs(solutions[1e8].iterations - solutions[1.0].iterations) <= 1
    assert transcribe(_speed_limited(1e8)).path_divisors == pytest.approx(
        1e8 * transcribe(_speed_limited(1.0)).path_divisors, rel=1e-12)
    speed = np.abs(solutions[1.0].dense.columns["v"])
    assert speed.max() <= 1.2 * (1 + 1e-6)
    assert solutions[1.0].objective == pytest.approx(solve_with_ipopt(transcribe(_speed_limited(1.0))).objective,
                                                     rel=1e-6)


def _bead(unit: float) -> Problem:
    """A point pushed through 1 rad of the unit circle in 1 s, from rest to rest, at least energy, kept on the circle
    by ``unit * (x ux + y uy + vx^2 + vy^2) == 0`` (the radius's second derivative) from a start on it."""
    p = Problem("bead")
    x, y = p.state("x", initial=1.0, final=math.cos(1.0)), p.state("y", initial=0.0, final=math.sin(1.0))
    vx, vy = p.state("vx", initial=0.0, final=0.0), p.state("vy", initial=0.0, final=0.0)
    ux, uy = p.control("ux"), p.control("uy")
    p.dynamics({x: vx, y: vy, vx: ux, vy: uy})
    p.path_equality("on_circle", unit * (ux * x + uy * y + vx**2 + vy**2))
    p.final_time(fixed=1.0)
    p.minimize_energy()
    p.transcription(20)
    return p


def test_a_path_equality_is_solved_the_same_in_whatever_unit_it_is_stated():
    """A path equality's rows are divided as an inequality's are. Left in their stated unit, the bead's equality ended
    max_iterations times 1e-6 (its violation under the tolerance, the plan off the circle) and unverified times 1e8
    (phase 1 stalled with the defects at 0.05)."""
    solutions = [_bead(unit).solve() for unit in (1e-6, 1.0, 1e8)]
    for solution in solutions:
        assert solution.status == "converged", solution.message
        assert solution.objective == pytest.approx(solutions[1].objective, rel=1e-6)
    radius = np.hypot(solutions[1].dense.columns["x"], solutions[1].dense.columns["y"])
    assert np.max(np.abs(radius - 1.0)) < 1e-4


@pytest.mark.parametrize("zero_cost", ["terminal", "integral"])
def test_a_boundary_value_problem_stated_with_a_zero_cost_converges(zero_cost):
    """COPS 3.0's flow in a channel (Dolan, More & Munson 2004), R = 10: the fourth derivative of u is
    R (u' u'' - u u'''), u(0) = u'(0) = 0, u(1) = 1, u'(1) = 0, a boundary-value problem a user states with a zero
    cost. The penalty weights, counted in the objective's size, were 1e-11 (steps refused with ratio -1 until they
    climbed back), and the KKT residuals, relative to 1e-12, never met the tolerance: ``max_iterations`` with the
    solution in hand. Both now count in absolute units, and u''(0) is SciPy's solve_bvp value 10.0367718 to the
    grid's accuracy."""
    p = Problem("flow in a channel")
    u1 = p.state("u1", initial=0.0, final=1.0)
    u2 = p.state("u2", initial=0.0, final=0.0)
    u3, u4 = p.state("u3"), p.state("u4")
    p.dynamics({u1: u2, u2: u3, u3: u4, u4: 10.0 * (u2 * u3 - u1 * u4)})
    p.final_time(fixed=1.0)
    if zero_cost == "terminal":
        p.minimize_terminal(0 * u1)
    else:
        p.minimize_integral(0 * u1)
    p.transcription(20)
    sol = p.solve(max_iterations=100)
    assert sol.status == "converged", sol.message
    assert sol.nodes.columns["u3"][0] == pytest.approx(10.0367718, rel=1e-4)


@pytest.mark.parametrize(("method", "where"), [("hermite-simpson", "across interval"), ("chebyshev", "at node")])
def test_a_run_that_ends_with_its_defects_open_names_the_state_and_the_interval(method, where):
    """Rao and Mease's hypersensitive problem over tf = 1000 on 10 intervals, stopped after 3 iterations: the message
    names the worst dynamics defect by its state and interval (node, for a pseudospectral grid), which says where
    the grid is too coarse, not only how far the defects are from closed."""
    p = Problem("hypersensitive")
    x = p.state("x", initial=1.0, final=1.5)
    u = p.control("u")
    p.dynamics({x: -x**3 + u})
    p.final_time(fixed=1000.0)
    p.minimize_integral(0.5 * (x**2 + u**2))
    p.transcription(10, method=method)
    solution = p.solve(max_iterations=3)
    assert solution.status == "max_iterations"
    named = re.search(rf"dynamics_defects by [^;]*\(worst: x {where} (\d+)\)", solution.message)
    assert named, solution.message
    assert 0 <= int(named.group(1)) <= 10
