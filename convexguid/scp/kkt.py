"""First-order optimality (KKT) residuals of the nonlinear program, in the problem's own units: the engine stops on
the Karush-Kuhn-Tucker conditions of

.. math::

    \\min_x f(x) = r^T W r + c^T x \\quad\\text{s.t.}\\quad Ax = b,\\; Gx \\le h,\\; M r(x) \\le m,\\;
    g(x) \\le 0,\\; e(x) = 0,\\; F_i x + f_i \\in \\mathcal Q_i

at the iterate, with the multipliers of the last subproblem (Nocedal & Wright, *Numerical Optimization*, 2nd ed.,
Thm. 12.1, eqs. 12.34):

* stationarity: :math:`\\nabla f + A^T\\lambda_A + G^T\\mu_G + J_r^T M^T \\nu + J_g^T \\mu + J_e^T \\lambda
  - \\sum_i F_i^T y_i = 0` (:math:`y_i \\in \\mathcal Q_i`, the cones' duals), each component times its variable's
  scale :math:`\\sigma_i`, in the objective's units;
* feasibility: the worst violation of any constraint, in that constraint's own unit;
* complementarity: :math:`\\max_j |\\mu_j g_j(x)|` over every inequality and :math:`|y_i^T (F_i x + f_i)|` over
  every cone, in the objective's units.

Stationarity and complementarity are judged relative to :math:`\\max(|f(x)|, 10^{-3} s_f)`, :math:`s_f` the
objective's size at the start (:math:`|f(x_0)|`, or :math:`|c|^T \\sigma` if larger), and absolutely when both are 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from convexguid.scp.lagrangian import CurvatureWeights, Multipliers, lagrangian_gradient
from convexguid.scp.problem import Evaluation, LinearConstraints, OutputConstraints, per_block


@dataclass(frozen=True)
class KKTResiduals:
    """KKT residuals at one iterate (absolute, in their units) and the objective unit they are judged against."""

    stationarity: float
    feasibility: float
    complementarity: float
    objective_unit: float

    @property
    def relative_stationarity(self) -> float:
        return self.stationarity / self.objective_unit

    @property
    def relative_complementarity(self) -> float:
        return self.complementarity / self.objective_unit

    def met(self, tolerance: float, feasibility_tolerance: float) -> bool:
        """Stationarity and complementarity within ``tolerance`` (relative), feasibility within its own."""
        return (self.relative_stationarity <= tolerance and self.relative_complementarity <= tolerance
                and self.feasibility <= feasibility_tolerance)

    def summary(self, tolerance: float, feasibility_tolerance: float) -> dict:
        """The ``kkt`` object of a solution's summary."""
        return {"stationarity": self.stationarity, "stationarity_relative": self.relative_stationarity,
                "feasibility": self.feasibility, "complementarity": self.complementarity,
                "complementarity_relative": self.relative_complementarity, "objective_unit": self.objective_unit,
                "tolerance": tolerance, "feasibility_tolerance": feasibility_tolerance,
                "met": self.met(tolerance, feasibility_tolerance)}


def kkt_residuals(x: np.ndarray, raw: Evaluation, multipliers: Multipliers, *, weights: np.ndarray,
                  cost: np.ndarray, linear: LinearConstraints, outputs: OutputConstraints, scale: np.ndarray,
                  objective: float, objective_size: float, feasibility: float) -> KKTResiduals:
    """The KKT residuals of the program at ``x`` (``raw``: its evaluation there, with Jacobians), relative to the
    larger of the objective and a thousandth of its size at the start (``objective_size``: the engine's)."""
    omega = multipliers.residual_weights(raw.residuals, weights, outputs)
    gradient = cost + lagrangian_gradient(raw, CurvatureWeights(omega, multipliers.inequality, multipliers.equality))
    A, G = linear.A, linear.G  # dense or sparse, as the program gives them
    if A.shape[0]:
        gradient = gradient + A.T @ multipliers.linear_equality
    if G.shape[0]:
        gradient = gradient + G.T @ multipliers.linear_inequality
    for block, duals in _cone_duals(raw, multipliers):
        gradient = gradient - block.jacobian.T @ duals  # the cone v(x) in Q: -F^T y, y in Q
    stationarity = float(np.max(np.abs(gradient * scale), initial=0.0))
    products = [multipliers.linear_inequality * linear.gap(x), multipliers.output * outputs.gap(raw.residuals)]
    products += [mu * block.values for block, mu in per_block(raw.inequalities, multipliers.inequality)]
    for block, duals in _cone_duals(raw, multipliers):
        ends = np.cumsum(block.sizes)
        products.append(np.array([duals[end - size: end] @ block.values[end - size: end]
                                  for end, size in zip(ends, block.sizes, strict=True)]))
    complementarity = float(np.max(np.abs(np.concatenate(products)), initial=0.0))
    unit = max(abs(objective), 1e-3 * objective_size)
    # an objective without a size (a boundary-value problem stated with a zero cost) makes them absolute: relative to
    # 1e-12, a round-off of 9e-16 was a stationarity of 9e-4 and the run never ended
    unit = max(unit, 1e-12) if unit > 0 else 1.0
    return KKTResiduals(stationarity, feasibility, complementarity, unit)


def _cone_duals(raw: Evaluation, multipliers: Multipliers):
    """Each cone block with its rows' duals (zero when the multipliers came from a step that saw no cone active:
    the end game's)."""
    rows = sum(block.values.size for block in raw.cones)
    return per_block(raw.cones, multipliers.cone if multipliers.cone.size == rows else np.zeros(rows))
