"""Second-order cones kept exact (convexguid.scp ConeBlock, convexguid.ocp cone_constraint) and the objectives that
use them, against closed forms and IPOPT.

* The engine alone: the point of a circle nearest a point (a distance cone, a nonlinear equality), in closed form.
* The 2-norm fuel of a double integrator's rest-to-rest transfer is its 1-norm fuel along one axis, and on a
  diagonal the 1-norm's over sqrt(2) (one engine that turns, against a thruster pair per axis) and what cvxpy finds
  on the same discrete problem written by hand.
* A cone stated on a nonlinear expression is refused, naming it.
* The powered descent by lossless convexification (examples/powered_descent.py): verified, ||u|| = sigma at every
  node (the relaxation is lossless), and the final mass IPOPT finds on the nonconvex problem it relaxes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from example_modules import load_example

from convexguid.errors import SpecError
from convexguid.ocp import Problem
from convexguid.ocp.reference import solve_with_ipopt
from convexguid.ocp.solve import transcribe
from convexguid.scp.engine import solve_scp
from convexguid.scp.problem import (
    ConeBlock,
    ConstraintBlock,
    Evaluation,
    LinearConstraints,
    OutputConstraints,
    SCPSettings,
)


class _NearestOnCircle:
    """min t s.t. ||(x, y) - (3, 4)|| <= t (a cone) and x^2 + y^2 = 1 (nonlinear): t = 4 at (0.6, 0.8)."""

    num_variables = 3

    def initial_guess(self):
        return np.array([10.0, 1.0, 0.0])

    def variable_scale(self):
        return np.ones(3)

    def residual_weights(self):
        return np.zeros(0)

    def linear_cost(self):
        return np.array([1.0, 0.0, 0.0])

    def linear_constraints(self):
        return LinearConstraints.none(3)

    def output_constraints(self):
        return OutputConstraints.none(0)

    def evaluate(self, v, jacobians=True):
        t, x, y = v
        circle = ConstraintBlock("circle", np.array([x**2 + y**2 - 1.0]),
                                 np.array([[0.0, 2 * x, 2 * y]]) if jacobians else None)
        cone = ConeBlock("distance", np.array([t, x - 3.0, y - 4.0]), sp.coo_matrix(np.eye(3)), (3,))
        return Evaluation(np.zeros(0), np.zeros((0, 3)) if jacobians else None, (), (circle,), (cone,))

    def lagrangian_hessian(self, v, weights):
        """The circle's curvature (the cone is affine), weighted: the end game's."""
        return np.diag([0.0, 2.0, 2.0]) * weights.equality[0]


def test_the_engine_keeps_a_cone_exact():
    program = _NearestOnCircle()
    result = solve_scp(program, SCPSettings(max_iterations=100))
    assert result.status == "converged", result.message
    assert result.x[0] == pytest.approx(4.0, rel=1e-6)
    # the distance is flat in the angle at the optimum: the point itself is known to the root of that
    assert result.x[1:] == pytest.approx([0.6, 0.8], abs=1e-3)
    cone = program.evaluate(result.x).cones[0]
    # exact to the convex solver's own tolerance (a linearized cone would be off by the step's square)
    assert cone.violations().max() <= SCPSettings().backend_tolerance


def _transfer(norm: int, target: tuple[float, float]) -> Problem:
    p = Problem(f"transfer-{norm}")
    x = p.state("x", initial=0.0, final=target[0])
    y = p.state("y", initial=0.0, final=target[1])
    vx = p.state("vx", initial=0.0, final=0.0)
    vy = p.state("vy", initial=0.0, final=0.0)
    ax, ay = p.control("ax", bounds=(-1.0, 1.0)), p.control("ay", bounds=(-1.0, 1.0))
    p.dynamics({x: vx, y: vy, vx: ax, vy: ay})
    p.final_time(fixed=4.0)
    p.minimize_fuel(norm)
    p.transcription(20, "zoh")
    return p


def test_two_norm_fuel_is_the_one_norm_along_an_axis_and_less_on_a_diagonal():
    along = [_transfer(norm, (2.0, 0.0)).solve() for norm in (1, 2)]
    diagonal = [_transfer(norm, (2.0, 2.0)).solve() for norm in (1, 2)]
    for solution in (*along, *diagonal):
        assert solution.ok, solution.message
    assert along[1].objective == pytest.approx(along[0].objective, rel=1e-6)
    # the same thrust history turned by 45 deg: sqrt(2) times the 1-norm's per-axis fuel becomes 2 per axis
    assert diagonal[1].objective == pytest.approx(diagonal[0].objective / math.sqrt(2), rel=1e-4)
    assert diagonal[1].objective == pytest.approx(_two_norm_fuel_by_cvxpy((2.0, 2.0)), rel=1e-6)


def _two_norm_fuel_by_cvxpy(target: tuple[float, float], intervals: int = 20, tf: float = 4.0) -> float:
    """The same transfer as a convex program written directly: exact zero-order-hold double integrator per axis,
    min h sum_k ||u_k||, |u_k,i| <= 1."""
    import cvxpy as cp

    h = tf / intervals
    u = cp.Variable((intervals, 2))
    constraints = [cp.abs(u) <= 1.0]
    for axis in range(2):
        # x_N = sum_k (h^2/2 + (N - 1 - k) h^2) u_k, v_N = h sum_k u_k
        weights = h**2 / 2 + (intervals - 1 - np.arange(intervals)) * h**2
        constraints += [weights @ u[:, axis] == target[axis], cp.sum(u[:, axis]) == 0.0]
    problem = cp.Problem(cp.Minimize(h * cp.sum(cp.norm(u, 2, axis=1))), constraints)
    problem.solve(solver=cp.CLARABEL)
    return float(problem.value)


@pytest.mark.parametrize(("vector", "bound", "message"), [
    (lambda x, v: [x**2], lambda x, v: 1.0, r"vector entry 1 \(sq\(x\)\) is not affine"),
    (lambda x, v: [x, v], lambda x, v: x * v, r"bound \(\(x\*v\)\) is not affine"),
])
def test_a_nonconvex_cone_is_refused_naming_the_entry(vector, bound, message):
    p = Problem("demo")
    x, v = p.state("x"), p.state("v")
    with pytest.raises(SpecError, match=rf"^demo: cone_constraint 'c': {message}"):
        p.cone_constraint("c", vector(x, v), bound(x, v))


def _powered_descent():
    return load_example("powered_descent")


def test_powered_descent_is_lossless_and_ipopts_mass_on_the_nonconvex_problem():
    descent = _powered_descent()
    solution = descent.build().solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    nodes = solution.nodes.columns
    acceleration = np.sqrt(nodes["ux"] ** 2 + nodes["uy"] ** 2 + nodes["uz"] ** 2)
    assert np.max(np.abs(nodes["sigma"] - acceleration) / nodes["sigma"]) <= 1e-6  # lossless at every node
    final_mass = math.exp(-solution.objective)
    nonconvex = solve_with_ipopt(transcribe(descent.build_nonconvex()))
    assert nonconvex.success, nonconvex.status
    # the same 30 intervals, the thrust held linear as T in one and as T/m in the other: 3e-6 apart
    assert final_mass == pytest.approx(-nonconvex.objective, rel=2e-5)
    dense = solution.dense.columns
    glide = np.hypot(dense["ry"], dense["rz"]) - dense["rx"] / math.tan(descent.GLIDE_SLOPE)
    assert glide.max() <= 1e-6


def test_the_nonconvex_descent_converges_with_its_cones_in_the_curved_step():
    """The SCP on the nonconvex statement (thrust in an annulus, mass a state, thrust and glide-slope cones) ends
    converged and verified at IPOPT's final mass on the same transcription; before the curved subproblem kept cones
    it crawled to ``unverified`` after 156 iterations."""
    problem = _powered_descent().build_nonconvex()
    solution = problem.solve()
    assert solution.status == "converged" and solution.verification.passed, solution.message
    reference = solve_with_ipopt(transcribe(problem))
    assert reference.success, reference.status
    assert solution.objective == pytest.approx(reference.objective, rel=1e-7)


def test_fitted_multipliers_give_a_cone_on_its_boundary_its_dual():
    """At the circle program's optimum the distance cone holds with equality: its fitted dual is
    mu (1, -v1/|v1|) with mu = 1 (the objective's weight on t), and those multipliers prove the point a KKT point."""
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.optimality import fitted_multipliers, kkt_met, measure_kkt

    program = _NearestOnCircle()
    algo = SCPAlgorithm(program, SCPSettings())
    state = algo.initialize(np.array([4.0, 0.6, 0.8]))
    state.multipliers = fitted_multipliers(algo, state)
    cone = program.evaluate(state.x).cones[0].values
    assert state.multipliers.cone == pytest.approx(np.concatenate([[1.0], -cone[1:] / np.linalg.norm(cone[1:])]))
    measure_kkt(algo, state)
    assert kkt_met(algo, state)
