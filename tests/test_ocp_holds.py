"""Zero- and first-order-hold transcriptions of a user's problem (convexguid.ocp.hold) against closed forms.

* The node-to-node map of the Clohessy-Wiltshire dynamics under a held acceleration converges to the exact
  discretization (the matrix exponential of the augmented system) at fourth order in the Runge-Kutta step.
* A rest-to-rest double integrator at minimum energy: the SCP's plan is the weighted least-norm solution of the
  discrete problem, computed here in closed form (a zero-order hold's and a first-order hold's input matrices
  integrated by hand).
* A finer grid carries the plan over unchanged (the same defects, the same objective).
* OpenSCvx's proximity operation (examples/proxops_openscvx.py): verified, IPOPT's fuel on the same NLP, and the
  same answer when the mean motion moves by 1e-12.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from example_modules import load_example
from scipy.linalg import expm

from convexguid.errors import SpecError
from convexguid.ocp import Problem
from convexguid.ocp.chebyshev import MAP_EPSILON
from convexguid.ocp.hold import FirstOrderHoldProgram, ZeroOrderHoldProgram
from convexguid.ocp.reference import solve_with_ipopt
from convexguid.ocp.solve import transcribe
from convexguid.transcription.mapped_chebyshev import MappedChebyshev


def _proxops():
    return load_example("proxops_openscvx")


def _double_integrator(method: str, intervals: int = 8) -> Problem:
    from test_ocp import double_integrator

    return double_integrator(method, intervals, duration=2.0)


@pytest.mark.parametrize("method", ["zoh", "foh"])
def test_the_clohessy_wiltshire_flow_is_the_exact_discretization_to_fourth_order(method):
    px = _proxops()
    n, h = px.MEAN_MOTION, 9.0
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    A[3, 0], A[3, 4], A[4, 3], A[5, 2] = 3 * n**2, 2 * n, -2 * n, -(n**2)
    # augmented with the control and (first-order hold) its rate across the interval
    augmented = np.zeros((12, 12))
    augmented[:6, :6], augmented[3:6, 6:9], augmented[6:9, 9:12] = A, np.eye(3), np.eye(3) / h
    x0, start = np.array([3.0, -80.0, 2.0, 0.1, 1.5, -0.2]), np.array([0.05, -0.1, 0.02])
    end = np.array([-0.08, 0.03, 0.1]) if method == "foh" else start
    exact = (expm(augmented * h) @ np.concatenate([x0, start, end - start]))[:6]
    errors = []
    for substeps in (4, 16):
        problem = px.build(20, method)
        problem.transcription(20, method, substeps)
        errors.append(np.abs(np.asarray(transcribe(problem).flow(x0, start, end, 0.0, h)).ravel() - exact).max())
    assert errors[0] <= 1e-8 * np.abs(exact).max()  # the default four steps on a 9 s interval
    assert errors[1] <= max(errors[0] / 4**3.5, 1e-12 * np.abs(exact).max())  # fourth order, to round-off


def _least_norm_energy(method: str, intervals: int, tf: float) -> float:
    """min h sum_j w_j u_j^2 subject to reaching (1, 0) from rest, on the discrete double integrator."""
    h = tf / intervals
    phi = np.array([[1.0, h], [0.0, 1.0]])
    if method == "zoh":
        inputs = [(np.array([h**2 / 2, h]), 0)]  # x_{k+1} = phi x_k + gamma u_k
        count, weights = intervals, np.ones(intervals)
    else:  # x_{k+1} = phi x_k + gamma_0 u_k + gamma_1 u_{k+1}
        inputs = [(np.array([h**2 / 3, h / 2]), 0), (np.array([h**2 / 6, h / 2]), 1)]
        count, weights = intervals + 1, np.r_[0.5, np.ones(intervals - 1), 0.5]
    C = np.zeros((2, count))
    for k in range(intervals):
        carried = np.linalg.matrix_power(phi, intervals - 1 - k)
        for gamma, offset in inputs:
            C[:, k + offset] += carried @ gamma
    W = h * weights
    u = (C / W).T @ np.linalg.solve((C / W) @ C.T, np.array([1.0, 0.0]))
    return float(W @ u**2)


@pytest.mark.parametrize("method", ["zoh", "foh"])
def test_minimum_energy_is_the_discrete_least_norm_solution(method):
    solution = _double_integrator(method).solve()
    assert solution.ok and solution.kkt["met"], solution.message
    assert solution.objective == pytest.approx(_least_norm_energy(method, 8, 2.0), rel=1e-8)
    # the dense re-propagation of the held control arrives where the plan does
    assert solution.verification.final_state_error <= 1e-9


@pytest.mark.parametrize("program_type", [ZeroOrderHoldProgram, FirstOrderHoldProgram])
def test_a_finer_grid_carries_the_plan_over(program_type):
    problem = _double_integrator(program_type.method)
    program = program_type(problem)
    z = program.initial_guess() + np.random.default_rng(3).normal(0.0, 0.1, program.num_variables)
    fine, carried = program.refined(z)
    assert fine.N == 2 * program.N
    coarse_defects = program.evaluate(z).equalities[0].values.reshape(program.N, -1)
    fine_defects = fine.evaluate(carried).equalities[0].values.reshape(fine.N, -1)
    # the new node inside each interval lies on the flow: the second half carries the whole interval's defect
    assert np.abs(fine_defects[0::2]).max() <= 1e-12
    assert np.allclose(fine_defects[1::2], coarse_defects, atol=1e-12)
    if program_type is ZeroOrderHoldProgram:  # the rectangle rule on a held control: the same energy
        energy = program.residual_weights() @ program.evaluate(z).residuals ** 2
        assert fine.residual_weights() @ fine.evaluate(carried).residuals ** 2 == pytest.approx(energy, rel=1e-12)


def test_openscvx_proximity_operation_is_verified_and_ipopts_optimum():
    px = _proxops()
    solution = px.build().solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    checks = {c.name: c for c in solution.verification.checks}
    assert checks["approach_cone"].violation <= 1e-6 and checks["cone_entrance"].violation <= 1e-6
    dense = solution.dense.columns
    assert np.abs(np.column_stack([dense["ax"], dense["ay"], dense["az"]])).max() <= px.A_MAX + 1e-12
    answer = solve_with_ipopt(transcribe(px.build()))
    assert answer.success, answer.status
    assert solution.objective == pytest.approx(answer.objective, rel=1e-5)


def test_openscvx_proximity_operation_does_not_hang_on_round_off(monkeypatch):
    px = _proxops()
    fuels = []
    for scale in (1.0, 1 + 1e-12, 1 - 1e-12):
        monkeypatch.setattr(px, "MEAN_MOTION", _proxops().MEAN_MOTION * scale)
        solution = px.build().solve()
        assert solution.ok, solution.message
        fuels.append(solution.objective)
    assert max(fuels) - min(fuels) <= 1e-8 * fuels[0]


@pytest.mark.parametrize(("arguments", "message"), [
    ({"intervals": 10, "method": "rk4"}, r"^demo: transcription: method: expected one of hermite-simpson, zoh, foh"),
    ({"intervals": 10, "method": "zoh", "substeps": 0}, r"^demo: transcription: substeps: expected an integer >= 1"),
])
def test_a_wrong_transcription_is_one_line(arguments, message):
    with pytest.raises(SpecError, match=message):
        Problem("demo").transcription(**arguments)


def test_a_parameter_is_planned_with_the_trajectory():
    """The farthest a rest-to-rest double integrator with |u| <= 1 goes in 2 s, the distance a parameter the plan
    chooses (x(t_f) = d, maximise d): bang-bang, d = t_f^2 / 4 = 1 (the switch at a node of a zero-order hold)."""
    p = Problem("farthest")
    x = p.state("x", initial=0.0)
    v = p.state("v", initial=0.0, final=0.0)
    distance = p.parameter("d", bounds=(0.0, 5.0), guess=0.5)
    u = p.control("u", bounds=(-1.0, 1.0))
    p.dynamics({x: v, v: u})
    p.boundary_constraint("arrive", x - distance)
    p.final_time(fixed=2.0)
    p.minimize_terminal(-distance)
    p.transcription(20, "zoh")
    solution = p.solve()
    assert solution.ok and solution.kkt["met"], solution.message
    assert solution.figures.parameters["d"] == pytest.approx(1.0, abs=1e-8)
    assert solution.objective == pytest.approx(-1.0, abs=1e-8)
    assert np.ptp(solution.dense.columns["d"]) == 0.0  # constant along the flight
    with pytest.raises(SpecError, match=r"^farthest: dynamics: d is a parameter"):
        p.dynamics({distance: 1.0})


@pytest.mark.parametrize("order", [8, 16])
def test_the_mapped_chebyshev_grid_is_spectrally_accurate_on_the_brachistochrone(order):
    """Pseudospectral collocation on the mapped Chebyshev grid: the cycloid's time to 1e-8 with 9 and 17 nodes
    (Hermite-Simpson needs 30 intervals for 1e-6), verified by the dense check between the nodes."""
    from test_ocp import cycloid_time

    brachistochrone = load_example("brachistochrone")
    problem = brachistochrone.build(order)
    problem.transcription(order, "chebyshev")
    solution = problem.solve()
    assert solution.ok and solution.kkt["met"], solution.message
    assert solution.figures.final_time_s == pytest.approx(cycloid_time(2.0, 2.0, brachistochrone.G), rel=1e-8)
    # the nodes' times are the grid's (clustered at the ends, not equally spaced), and the size counts its rows:
    # collocation at all order + 1 nodes (3 states), the fixed initial state and final position (5 values)
    grid = MappedChebyshev(order, MAP_EPSILON).nodes
    assert solution.nodes.t == pytest.approx(0.5 * (grid + 1.0) * solution.figures.final_time_s, rel=1e-12)
    assert solution.size.num_equality_constraints == 3 * (order + 1) + 5


def test_a_point_constraint_off_the_chebyshev_nodes_is_refused():
    p = _double_integrator("chebyshev", 8)
    p.point_constraint("halfway", p.states[0].symbol - 0.4, at=0.3)
    with pytest.raises(SpecError, match=r"point_constraint 'halfway': at = 0.3 of the final time is not a node of "
                                        r"the 8-interval mapped Chebyshev grid"):
        p.solve()


def test_a_path_equality_holds_between_the_nodes_of_a_hold():
    """A thrust of fixed magnitude, u_x^2 + u_y^2 = 1 (a nonconvex equality, linearized by the engine), from rest
    to a point 1 m away along the diagonal in minimum time, the arrival speed free: full thrust along the line,
    t = sqrt(2 x 1 m / 1 m/s^2). A zero-order hold keeps the equality between the nodes as well (the dense check
    judges |u_x^2 + u_y^2 - 1| there)."""
    p = Problem("unit-thrust")
    x, y = p.state("x", initial=0.0, final=math.sqrt(0.5)), p.state("y", initial=0.0, final=math.sqrt(0.5))
    vx, vy = p.state("vx", initial=0.0), p.state("vy", initial=0.0)
    ux, uy = p.control("ux", bounds=(-1.0, 1.0), guess=0.6), p.control("uy", bounds=(-1.0, 1.0), guess=0.8)
    p.dynamics({x: vx, y: vy, vx: ux, vy: uy})
    p.path_equality("unit_thrust", ux**2 + uy**2 - 1.0)
    p.final_time(bounds=(0.5, 5.0), guess=2.0)
    p.minimize_time()
    p.transcription(10, "zoh")
    solution = p.solve()
    assert solution.ok and solution.kkt["met"], solution.message
    assert solution.figures.final_time_s == pytest.approx(math.sqrt(2.0), rel=1e-9)
    dense = solution.dense.columns
    assert np.abs(dense["ux"] ** 2 + dense["uy"] ** 2 - 1.0).max() <= 1e-9
    # IPOPT on the same NLP from the same start does no better (within the KKT tolerance of the objective)
    assert solution.objective <= solve_with_ipopt(transcribe(p)).objective * (1 + 1e-6)
