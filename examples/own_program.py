"""Bring your own program: a nonconvex problem handed to the SCP engine directly, without convexguid.ocp.

When a formulation is not states, controls and dynamics (flat outputs on a Chebyshev grid, as the flat_attitude
family plans; a hand-built NLP), implement :class:`convexguid.scp.problem.NonconvexProgram` and run
:func:`convexguid.scp.engine.solve_scp` on it. Here, the point of the unit circle closest to p = (2, 1) below
the line y = 0.3:

    minimize (x - 2)^2 + (y - 1)^2  subject to  x^2 + y^2 = 1,  y <= 0.3.

Without the line the answer is p / |p| (y = 0.447); with it, (sqrt(1 - 0.09), 0.3). The objective is a sum of
weighted squared residuals r(z) = z - p (the engine linearizes r: Gauss-Newton), the circle a nonlinear equality
block and the line a constant inequality row (kept exact in every subproblem). docs/ocp.md, "Bring your own
program", explains each method.
Run: python examples/own_program.py
"""

import numpy as np
import scipy.sparse as sp

from convexguid.scp.engine import solve_scp
from convexguid.scp.problem import ConstraintBlock, Evaluation, LinearConstraints, OutputConstraints, SCPSettings

TARGET = np.array([2.0, 1.0])
LINE = 0.3


class ClosestPointOnCircle:
    """The program of the module docstring, as the engine reads it."""

    num_variables = 2

    def initial_guess(self) -> np.ndarray:
        return np.array([0.0, -1.0])

    def variable_scale(self) -> np.ndarray:
        return np.ones(2)  # the trust region is a box in these units

    def residual_weights(self) -> np.ndarray:
        return np.ones(2)  # objective: sum of w_i r_i(z)^2

    def linear_cost(self) -> np.ndarray:
        return np.zeros(2)  # plus c^T z

    def linear_constraints(self) -> LinearConstraints:
        # A z = b (none) and G z <= h: the line y <= 0.3
        return LinearConstraints(np.zeros((0, 2)), np.zeros(0), sp.coo_matrix(([1.0], ([0], [1])), shape=(1, 2)),
                                 np.array([LINE]))

    def output_constraints(self) -> OutputConstraints:
        return OutputConstraints.none(2)  # no bounds on the residuals

    def evaluate(self, z: np.ndarray, jacobians: bool = True) -> Evaluation:
        circle = ConstraintBlock("unit_circle", np.array([z @ z - 1.0]), 2.0 * z[None, :] if jacobians else None)
        return Evaluation(z - TARGET, np.eye(2) if jacobians else None, equalities=(circle,))


if __name__ == "__main__":
    result = solve_scp(ClosestPointOnCircle(), SCPSettings())
    print(result.status, result.message, result.x, result.iterations)
