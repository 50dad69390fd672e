"""Maneuvers in phases (convexguid.ocp.Phases): analytic answers, two published multi-phase problems against their
published figures and IPOPT on the same transcription, and statements refused with one line."""

from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from example_modules import EXAMPLES, load_example

from convexguid.errors import SpecError
from convexguid.ocp import Phases, Problem
from convexguid.ocp.reference import solve_with_ipopt
from convexguid.ocp.solve import transcribe


def _example(name: str):
    return load_example(f"phases/{name}")


def _leg(name: str, start: float | None = None, end: float | None = None) -> tuple[Problem, object]:
    """A double integrator from rest to rest in 1 s, least control energy (its position's ends as given)."""
    p = Problem(name)
    x = p.state("x", initial=start, final=end, scale=2.0)
    v = p.state("v", initial=0.0, final=0.0, scale=2.0)
    u = p.control("u", scale=10.0)
    p.dynamics({x: v, v: u})
    p.final_time(fixed=1.0)
    p.minimize_energy()
    p.transcription(10)
    return p, x


def _hold_point(link_square: float | None = None, at_least: float | None = None, squared: bool = False) -> Phases:
    first, x1 = _leg("to_hold", start=0.0)
    second, _ = _leg("from_hold", end=2.0)
    plan = Phases("hold-point", [first, second])
    plan.connect(first, second, ["x"])
    if link_square is not None:
        plan.link("hold_at", first.end(x1) ** 2 - link_square)
    if at_least is not None:
        hold = first.end(x1)
        plan.link_constraint("hold_beyond", at_least**2 - hold**2 if squared else at_least - hold)
    return plan


def test_a_hold_point_between_two_legs_is_where_the_energy_is_least():
    """Rest to rest over d in T costs integral u^2 = 12 d^2 / T^3; two legs of 1 s with the hold point free stop
    halfway (12 + 12 = 24). Stated by a nonlinear link, x_hold^2 = 2.25, the hold is at 1.5: 12 (1.5^2 + 0.5^2) = 30.
    Hermite-Simpson is exact for these cubic paths."""
    free = _hold_point().solve()
    assert free.status == "converged", free.message
    assert free.objective == pytest.approx(24.0, rel=1e-7)
    held = _hold_point(2.25).solve()
    assert held.status == "converged", held.message
    assert held.objective == pytest.approx(30.0, rel=1e-7)
    nodes = held.nodes
    first_leg = nodes.columns["phase"] == 0
    assert nodes.columns["x"][first_leg][-1] == pytest.approx(1.5, abs=1e-8)
    assert nodes.t[-1] == pytest.approx(2.0) and held.figures.final_time_s == pytest.approx(2.0)
    assert held.figures.phases["from_hold"]["start_s"] == pytest.approx(1.0)
    assert held.verification.passed and "link_hold_at_error" in held.verification.final_errors
    # the same hold as an inequality, x_hold >= 1.5 (a hard linear row) or x_hold^2 >= 2.25 (linearized)
    for squared in (False, True):
        beyond = _hold_point(at_least=1.5, squared=squared).solve()
        assert beyond.status == "converged", beyond.message
        assert beyond.objective == pytest.approx(30.0, rel=1e-7)


def test_two_burn_orbit_raise_matches_dymos_and_ipopt_on_the_same_transcription():
    """Burn, coast (no control), burn: Dymos' documented delta-v 0.3995 (its tests allow 2e-3); IPOPT on the same
    three-phase program from the same guess reaches the same optimum."""
    module = _example("two_burn_orbit_raise")
    solution = module.build().solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    deltav = solution.nodes.columns["deltav"][-1]
    assert deltav == pytest.approx(module.PUBLISHED, rel=1e-3)
    answer = solve_with_ipopt(transcribe(module.build()))
    assert answer.success
    assert deltav == pytest.approx(answer.objective, rel=1e-6)
    # the coast has neither the engine's states nor a control: NaN in its rows of the joined table
    coast = solution.nodes.columns["phase"] == 1
    columns = solution.nodes.columns
    assert np.isnan(columns["u"][coast]).all() and np.isnan(columns["deltav"][coast]).all()
    durations = [solution.figures.phases[name]["duration_s"] for name in ("burn1", "coast", "burn2")]
    assert sum(durations) == pytest.approx(solution.figures.final_time_s)


def test_goddard_rocket_in_three_phases_reaches_betts_altitude():
    """Boost, singular arc (its state equality at the nodes), coast: Betts' 18550.872 ft within 0.1%."""
    module = _example("goddard_three_phase")
    solution = module.build().solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    assert solution.nodes.columns["h"][-1] == pytest.approx(module.PUBLISHED, rel=1e-3)


def test_dymos_cannonball_from_its_own_guess_reaches_the_published_range():
    """Two phases with a design parameter (the ball's radius) and no size stated for any state: the speed is scaled
    by its guessed 150-200 m/s (scaled by 1, the iterates ran off to a range of 268978 m)."""
    module = _example("cannonball")
    flight = module.build()
    assert flight.phases[0].state_scales()[:4] == pytest.approx([100.0, 100.0, 200.0, 1.0])
    solution = flight.solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    assert solution.nodes.columns["r"][-1] == pytest.approx(module.PUBLISHED, rel=1e-3)


def test_a_guess_where_the_dynamics_are_not_a_number_ends_at_once_saying_so():
    """The cannonball's straight line between its stated ends starts at a speed of 0, where gam' = -g cos(gam)/v is
    0/0: the run stops before any subproblem, naming the blocks, and returns a plan that says so."""
    module = _example("cannonball")
    flight = module.build()
    for phase in flight.phases:
        phase.guess_nodes = None
    solution = flight.solve()
    assert solution.status == "solver_error" and solution.iterations == 0
    assert "not a number at the start point, in ascent: dynamics_defects" in solution.message


def test_a_statement_in_phases_is_refused_with_one_line():
    first, _ = _leg("a", start=0.0)
    second, _ = _leg("b", end=1.0)
    with pytest.raises(SpecError, match=r"every phase needs its own name"):
        Phases("twins", [first, _leg("a")[0]])
    plan = Phases("pair", [first, second])
    with pytest.raises(SpecError, match=r"states speed are not states of both phases"):
        plan.connect(first, second, ["speed"])
    with pytest.raises(SpecError, match=r"the second phase must come later"):
        plan.connect(second, first)
    stray = Problem("other").state("y")
    with pytest.raises(SpecError, match=r"link 'bad': uses y; a link is stated on phase ends"):
        plan.link("bad", stray)
    with pytest.raises(SpecError, match=r"a: start\(t\): expected a state of this problem"):
        first.start(first.time)
    # phases each within the size limit, together above it: one line, before anything is transcribed
    with pytest.raises(SpecError, match=r"two-burn-orbit-raise: burn1.transcription.intervals: problem too large: "
                                        r"a run needs about 3.\d+ GiB of memory \(3 phases"):
        _example("two_burn_orbit_raise").build(intervals=8000).check()
    unflowed, _ = _leg("d", start=0.0, end=1.0)
    unflowed.transcription(1, "flow")
    with pytest.raises(SpecError, match=r"d: transcription: method 'flow' needs the flow of every state; none given "
                                        r"for x, v"):
        unflowed.check()
    lonely, _ = _leg("c", start=0.0, end=1.0)
    lonely.objective = None
    with pytest.raises(SpecError, match=r"alone: objective: no phase states one"):
        Phases("alone", [lonely]).solve()


def test_a_campaign_runs_a_maneuver_in_phases(tmp_path):
    """problems/campaigns/two_burn_orbit_raise_vs_radius.yaml on two of its radii: each row the three-phase plan a
    direct solve of the module gives, and a farther orbit costs more delta-v."""
    import pyarrow.parquet as pq
    import yaml

    from convexguid.campaign.run import run_campaign

    source = Path(__file__).resolve().parents[1] / "problems" / "campaigns" / "two_burn_orbit_raise_vs_radius.yaml"
    data = yaml.safe_load(source.read_text())
    data["problem"] = str(EXAMPLES / "phases" / "two_burn_orbit_raise.py")
    data["grid"][0]["values"] = [2.0, 3.0]
    path = tmp_path / "campaign.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    result = run_campaign(path, tmp_path / "out", serial=True)
    rows = pq.read_table(result.table).to_pylist()
    assert result.ok and [r["status"] for r in rows] == ["converged", "converged"]
    direct = _example("two_burn_orbit_raise").build(r_target=3.0).solve()
    assert rows[1]["objective"] == pytest.approx(direct.objective, rel=1e-9)
    assert rows[0]["objective"] < rows[1]["objective"]


def _cw_phase(name: str, duration: float, method: str, intervals: int, thrust: bool, ends: dict, sign: float = 1.0):
    """A planar Clohessy-Wiltshire phase (mean motion 0.0011 rad/s) with its flow in closed form (the state
    transition matrix; ``sign`` -1 spoils one entry); thrust: a box of 0.05 m/s^2 per axis, least fuel."""
    n = 0.0011
    p = Problem(name)
    x, y, vx, vy = (p.state(k, initial=ends.get(("initial", k)), final=ends.get(("final", k)),
                            scale=1000.0 if k in "xy" else 2.0) for k in ("x", "y", "vx", "vy"))
    rates = {x: vx, y: vy, vx: 3 * n**2 * x + 2 * n * vy, vy: -2 * n * vx}
    if thrust:
        ux, uy = p.control("ux", bounds=(-0.05, 0.05)), p.control("uy", bounds=(-0.05, 0.05))
        rates[vx], rates[vy] = rates[vx] + ux, rates[vy] + uy
        p.minimize_fuel()
    p.dynamics(rates)
    c, s, t = ca.cos(n * p.time), ca.sin(n * p.time), p.time
    p.flow({x: (4 - 3 * c) * x + s / n * vx + 2 * (1 - c) / n * vy,
            y: 6 * (s - n * t) * x + y - 2 * (1 - c) / n * vx + (4 * s - 3 * n * t) / n * vy,
            vx: 3 * n * s * x + c * vx + 2 * s * vy,
            vy: -6 * n * (1 - c) * x - 2 * sign * s * vx + (4 * c - 3) * vy})
    p.final_time(fixed=duration)
    p.transcription(intervals, method)
    return p


def _cw_hop(coast_method: str, coast_intervals: int, sign: float = 1.0) -> Phases:
    """Burn 100 s, coast 1500 s, burn 100 s: from 1 km behind the target to it, at rest at both ends."""
    start = {("initial", k): v for k, v in zip(("x", "y", "vx", "vy"), (0.0, -1000.0, 0.0, 0.0), strict=True)}
    stop = {("final", k): 0.0 for k in ("x", "y", "vx", "vy")}
    burn1 = _cw_phase("burn1", 100.0, "zoh", 10, True, start)
    coast = _cw_phase("coast", 1500.0, coast_method, coast_intervals, False, {}, sign)
    burn2 = _cw_phase("burn2", 100.0, "zoh", 10, True, stop)
    hop = Phases("cw-hop", [burn1, coast, burn2])
    hop.connect(burn1, coast)
    hop.connect(coast, burn2)
    return hop


def test_a_coast_by_its_closed_form_flow_is_the_collocated_coast_in_one_interval():
    """The coast mapped by the Clohessy-Wiltshire state transition matrix across one 1500 s interval plans the
    fuel a 40-interval Runge-Kutta coast plans (to 1e-8); a flow that is not the dynamics' (one entry's sign
    flipped) is caught by the dense check, which integrates the stated dynamics."""
    exact = _cw_hop("flow", 1).solve()
    assert exact.status == "converged", exact.message
    assert exact.figures.phases["coast"]["intervals"] == 1
    stepped = _cw_hop("zoh", 40).solve()
    assert exact.objective == pytest.approx(stepped.objective, rel=1e-8)
    wrong = _cw_hop("flow", 1, sign=-1.0).solve()
    assert wrong.status != "converged" and not wrong.verification.passed


def _planar_transfer(name: str, start: float, duration: float, intervals: int, ends: dict) -> Problem:
    """A planar double integrator (zero-order hold) with one engine: thrust magnitude at most 1 m/s^2 (a cone), least
    fuel (the thrust's 2-norm), and a keep-out disc of radius 0.5 m about (1, 0.2) m; the time from ``start``."""
    p = Problem(name)
    x, y, vx, vy = (p.state(k, initial=ends.get(("initial", k)), final=ends.get(("final", k)), scale=2.0)
                    for k in ("x", "y", "vx", "vy"))
    ux, uy = p.control("ux", scale=1.0), p.control("uy", scale=1.0)
    p.dynamics({x: vx, y: vy, vx: ux, vy: uy})
    p.cone_constraint("thrust", [ux, uy], 1.0, unit="m/s^2")
    p.path_constraint("keep_out", 0.25 - (x - 1.0) ** 2 - (y - 0.2) ** 2, unit="m^2")
    p.final_time(fixed=duration)
    p.minimize_fuel(norm=2)
    p.transcription(intervals, "zoh")
    return p


def test_a_maneuver_cut_in_two_phases_is_the_same_program_as_in_one():
    """The same least-fuel transfer (thrust cone, keep-out disc, zero-order hold) over 4 s on 16 intervals, stated
    whole and as two phases of 2 s and 8 intervals joined by continuity: the same transcribed program, so the same
    fuel (to 1e-7) after the same repair rounds. IPOPT on the two-phase program as stated is within 1e-3 below."""
    start = {("initial", k): v for k, v in zip(("x", "y", "vx", "vy"), (0.0, 0.0, 0.0, 0.0), strict=True)}
    stop = {("final", k): v for k, v in zip(("x", "y", "vx", "vy"), (2.0, 0.0, 0.0, 0.0), strict=True)}
    whole = _planar_transfer("whole", 0.0, 4.0, 16, {**start, **stop}).solve()
    assert whole.status == "converged", whole.message
    # its thrust cone holds with equality: the end game's working set, which knows no cones, proves no saddle
    # (before, the run stepped off two false ones and ended 2.2e-4 higher after a repair)
    assert "saddle" not in whole.message
    first, second = _planar_transfer("first", 0.0, 2.0, 8, start), _planar_transfer("second", 2.0, 2.0, 8, stop)
    halves = Phases("halves", [first, second])
    halves.connect(first, second)
    split = halves.solve()
    assert split.status == "converged", split.message
    assert split.objective == pytest.approx(whole.objective, rel=1e-7)
    assert len(split.repair_rounds) == len(whole.repair_rounds)
    answer = solve_with_ipopt(transcribe(halves))
    assert answer.success and answer.objective <= split.objective <= answer.objective * (1 + 1e-3)
    assert split.verification.passed and "first.keep_out" in {c.name for c in split.verification.checks}


def test_a_link_broken_on_the_flown_ends_refines_the_phase_that_drifted():
    """The orbit raise on 4 intervals a phase: the coast (no stated end values, so its own check passes) drifts
    between its 4 nodes, and the continuity into the second burn, judged on the flown ends, breaks; the repair
    refines the coast where its error is, and the plan verifies at Dymos' delta-v."""
    solution = _example("two_burn_orbit_raise").build(intervals=4).solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    first, repaired = solution.repair_rounds[0], solution.repair_rounds[1]
    assert not first.passed and "link_coast." in first.worst
    assert repaired.repair.startswith("coast: ") and "burn" not in repaired.repair
    assert solution.figures.phases["coast"]["intervals"] > 4 == solution.figures.phases["burn1"]["intervals"]
    assert solution.nodes.columns["deltav"][-1] == pytest.approx(0.3995, rel=1e-3)


@pytest.mark.parametrize("method", ["hermite-simpson", "foh", "chebyshev"])
def test_a_loop_from_and_back_to_its_bound_leaves_and_lands_with_the_rate_inward(method):
    """A hop that starts and ends on the ground (x >= 0, x(0) = x(T) = 0) with its speed periodic: any trajectory of
    the stated problem leaves with v(0) >= 0 and lands with v(T) <= 0, so v(0) = v(T) = 0. The collocation holds
    x >= 0 at the nodes only; its optimum (the cost weighs rising early) leaves and lands at the same upward speed
    and crosses the ground between its last two nodes. The repair adds the landing's rate condition; the plan then
    leaves and lands at rest."""
    p = Problem("hop")
    x = p.state("x", bounds=(0.0, None), initial=0.0, final=0.0)
    v = p.state("v")
    u = p.control("u", bounds=(-10.0, 10.0))
    p.dynamics({x: v, v: u})
    p.final_time(fixed=2.0)
    p.minimize_integral((3 - p.time) * (x - 1) ** 2 + 0.01 * u**2)
    p.transcription(10, method)
    hop = Phases("hop", [p])
    hop.link("v_periodic", p.end(v) - p.start(v))
    solution = hop.solve()
    assert solution.status == "converged", solution.message
    first = solution.repair_rounds[0]
    assert not first.passed and "hop.x_min" in first.worst  # the collocation's optimum crossed the ground
    assert "x_rate_final added" in solution.repair_rounds[1].repair
    speeds = solution.nodes.columns["v"]
    assert abs(speeds[0]) < 1e-6 and abs(speeds[-1]) < 1e-6
    # what the flight still crosses by at the end is its miss of the final position, within the final tolerance
    assert solution.dense.columns["x"].min() > -1e-4


def test_a_start_that_breaks_the_links_under_earth_sized_bounds_is_restored_not_certified_infeasible():
    """The Delta III launch with the scales its bounds give (two Earth radii for a position) and the engine's straight
    lines, which break the position continuity and the stage drops between the phases: the projection of that start
    onto the hard linear rows once stopped short (Clarabel's InsufficientProgress on rows with entries of 1.3e7 beside
    ones), and an elastic violation of 1e-11 was reported as a certificate that the launch is infeasible."""
    from convexguid.scp.restoration import linear_violation, restore_start

    launch = _example("delta_iii_launch")
    program = transcribe(launch.build(20, scales=((None, None),) * 4, guessed=False))
    start = program.initial_guess()
    assert linear_violation(program.linear_constraints(), start) > 1.0
    restored = restore_start(program, start)
    assert restored.feasible, restored.certificate
    assert linear_violation(program.linear_constraints(), restored.x) <= 1e-9


def test_a_nonlinear_final_condition_is_measured_at_the_users_guess():
    """x(1)^2 = 4 and sqrt(y(1)) = 2 with both states started at 0 and nothing else stated: on the straight line the
    first has no gradient and the second an infinite one, so neither gives a magnitude (1 is taken). A user's guess
    ending at x = 2 and y = 4 gives them: 2 x sigma_x = 4 sigma_x and sigma_y / (2 sqrt(y)) = sigma_y / 4."""
    def problem(guessed):
        p = Problem("final-conditions")
        x, y = p.state("x", initial=0.0), p.state("y", initial=0.0)
        u = p.control("u", bounds=(-5.0, 5.0))
        p.dynamics({x: u, y: 2 * u})
        p.boundary_constraint("square", x**2 - 4, at="final")
        p.boundary_constraint("root", ca.sqrt(y) - 2, at="final")
        p.final_time(fixed=1.0)
        p.minimize_energy()
        p.transcription(10)
        if guessed:
            share = np.linspace(0.0, 1.0, 11)[:, None]
            p.initial_guess(np.hstack([2 * share, 4 * share]), np.full((11, 1), 2.0))
        return transcribe(p)

    straight, guessed = problem(False), problem(True)
    assert [m for _, _, m in straight.boundary_equality_rows] == [1.0, 1.0]
    sigma_x, sigma_y = guessed.state_scales
    assert [m for _, _, m in guessed.boundary_equality_rows] == pytest.approx([4 * sigma_x, sigma_y / 4])
