"""Is the iterate a minimum? The KKT residuals, the certificate a subproblem gives its own iterate, and the check that a
KKT point is no saddle (with the step off one that is). A small step proves nothing (a collapsed trust region also takes
small steps): a run ends ``converged`` only through :func:`finish_optimal`, at an iterate whose KKT residuals hold with
the multipliers of a subproblem or of a fitted estimate and whose reduced Hessian has no negative curvature worth
following. The residuals, in the problem's own units, are those of the Karush-Kuhn-Tucker conditions of

.. math::

    \\min_x f(x) = r^T W r + c^T x \\quad\\text{s.t.}\\quad Ax = b,\\; Gx \\le h,\\; M r(x) \\le m,\\;
    g(x) \\le 0,\\; e(x) = 0,\\; F_i x + f_i \\in \\mathcal Q_i

at the iterate (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Thm. 12.1, eqs. 12.34):

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

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from convexguid.backends.base import BackendResult, Cones, ConicProgram
from convexguid.backends.registry import make_backend
from convexguid.scp.lagrangian import Multipliers, WorkingSet, lagrangian_gradient, objective_gradient
from convexguid.scp.merit import max_violation
from convexguid.scp.problem import Evaluation, per_block, stacked_values

if TYPE_CHECKING:
    from convexguid.scp.endgame import LocalModel
    from convexguid.scp.engine import SCPAlgorithm
    from convexguid.scp.state import IterationState

MAX_ESCAPES = 2
"""Steps off a saddle (a stationary point with negative curvature) one run may take."""


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


def measure_kkt(algo: SCPAlgorithm, state: IterationState) -> None:
    """The KKT residuals at the iterate with the state's multipliers (none yet, or phase 1: left unmeasured)."""
    if state.multipliers is None or algo.phase1:
        return
    x, raw, multipliers, linear, outputs = state.x, state.raw, state.multipliers, algo.linear, algo.outputs
    gradient = algo.cost + lagrangian_gradient(raw, multipliers.curvature_weights(raw.residuals, algo.weights, outputs))
    for M, y in ((linear.A, multipliers.linear_equality), (linear.G, multipliers.linear_inequality)):  # dense or sparse
        if M.shape[0]:
            gradient = gradient + M.T @ y
    products = [multipliers.linear_inequality * linear.gap(x), multipliers.output * outputs.gap(raw.residuals)]
    products += [mu * block.values for block, mu in per_block(raw.inequalities, multipliers.inequality)]
    for block, duals in _cone_duals(raw, multipliers):
        gradient = gradient - block.jacobian.T @ duals  # the cone v(x) in Q: -F^T y, y in Q
        ends = np.cumsum(block.sizes)
        products.append(np.array([duals[end - size: end] @ block.values[end - size: end]
                                  for end, size in zip(ends, block.sizes, strict=True)]))
    stationarity = float(np.max(np.abs(gradient * algo.scale), initial=0.0))
    complementarity = float(np.max(np.abs(np.concatenate(products)), initial=0.0))
    unit = max(abs(state.objective), 1e-3 * algo.objective_size)
    # an objective without a size (a boundary-value problem stated with a zero cost) makes them absolute: relative to
    # 1e-12, a round-off of 9e-16 was a stationarity of 9e-4 and the run never ended
    unit = max(unit, 1e-12) if unit > 0 else 1.0
    state.kkt = KKTResiduals(stationarity, max_violation(state.ev), complementarity, unit)


def _cone_duals(raw: Evaluation, multipliers: Multipliers):
    """Each cone block with its rows' duals (zero from a step that saw no cone active: the end game's)."""
    rows = sum(block.values.size for block in raw.cones)
    return per_block(raw.cones, multipliers.cone if multipliers.cone.size == rows else np.zeros(rows))


def kkt_met(algo: SCPAlgorithm, state: IterationState) -> bool:
    """The measured residuals are within the settings' tolerances (never in phase 1)."""
    s = algo.settings
    return not algo.phase1 and state.kkt is not None and state.kkt.met(s.kkt_tolerance, s.feasibility_tolerance)


def certified_here(algo: SCPAlgorithm, state: IterationState, result: BackendResult, predicted: float) -> bool:
    """Whether the subproblem just solved at the iterate proves it a KKT point (then the run ends there): its
    multipliers meet the KKT tolerance and the decrease it still ``predicted`` is within the same tolerance of the
    objective (why, measured: docs/engine.md, 'KKT certificates and the polish')."""
    measure_kkt(algo, state)
    if not kkt_met(algo, state) or predicted > algo.settings.kkt_tolerance * state.kkt.objective_unit:
        return False
    algo.record(state, 0.0, float("nan"), False, replace(result, status="kkt"))
    finish_optimal(algo, state)
    return True


def finish_optimal(algo: SCPAlgorithm, state: IterationState) -> None:
    """A KKT point: converged ("KKT conditions met", then any steps off saddles), unless the reduced Hessian has
    negative curvature worth following (then :func:`off_saddle` steps off it)."""
    unit = state.kkt.objective_unit if state.kkt is not None else max(abs(state.objective), 1e-12)
    if algo.phase1 or off_saddle(algo, state, unit, "a saddle") != "stepped":
        state.finish("converged", "; ".join(["KKT conditions met", *state.escape_log]))


def off_saddle(algo: SCPAlgorithm, state: IterationState, unit: float, what: str) -> str:
    """``"stepped"`` when the run stepped off ``what`` (a saddle of the merit, or in phase 1 of the violation) along
    the working set's negative curvature (:func:`escape_saddle`), ``"saddle"`` when that curvature promises more than
    the KKT tolerance of ``unit`` within the first trust radius but no step along it pays, else ``""`` (why:
    docs/engine.md, 'KKT certificates and the polish' and 'Restoration and phase 1')."""
    models = algo.second_order
    # with a cone active the working set leaves out a constraint that holds: its negative curvature may point out
    # of the cone, no proof of a saddle (measured: docs/engine.md, 'KKT certificates and the polish')
    if (models is None or state.escapes >= MAX_ESCAPES or state.multipliers is None
            or state.multipliers.cone_active()):
        return ""
    model = models.at(state, models.working_set(state))
    newton = model.newton()
    gain = 0.5 * max(-newton.smallest_eigenvalue, 0.0) * algo.trust_region.initial**2
    if not (newton.shift and gain > algo.settings.kkt_tolerance * unit):
        return ""
    if escape_saddle(algo, state, model, newton.negative_direction, newton.smallest_eigenvalue, unit):
        state.escape_log.append(f"stepped off {what} (reduced-Hessian eigenvalue {newton.smallest_eigenvalue:.3g}) "
                                f"at iteration {state.iteration}")
        return "stepped"
    state.escape_log.append(f"the working set's reduced Hessian has a negative eigenvalue "
                            f"({newton.smallest_eigenvalue:.3g}) at iteration {state.iteration}, but the merit rises "
                            "both ways along its direction, from the first trust radius down")
    return "saddle"


ESCAPE_SHARE = 0.1
"""The share of the decrease a direction's negative curvature promises that a step off a saddle must deliver."""


def escape_saddle(algo: SCPAlgorithm, state: IterationState, model: LocalModel, direction: np.ndarray,
                  curvature: float, unit: float) -> bool:
    """Step off a saddle along its direction of negative curvature (scaled ``direction``, reduced-Hessian eigenvalue
    ``curvature``) and go on; False (and no step) where the merit function drops neither way. Each trial point, brought
    back onto the working set to first order (:meth:`~convexguid.scp.endgame.LocalModel.correction`), is tried both ways
    from the initial trust radius :math:`r` down, halved while the promised decrease :math:`\\tfrac12 |\\lambda| r^2` is
    above the KKT tolerance of the objective (``unit``); the run goes on from the first point whose merit is lower by
    :data:`ESCAPE_SHARE` of that promise (docs/engine.md, 'KKT certificates and the polish')."""
    models = algo.second_order
    radius = algo.trust_region.initial
    while (promised := 0.5 * -curvature * radius**2) > algo.settings.kkt_tolerance * unit:
        for sign in (1.0, -1.0):
            u = sign * radius * direction
            tried = algo.trial(state, state.x + u * algo.scale, state.penalty, state.merit, promised)
            u = models.onto_equalities(state.x, u + model.correction(
                model.working.values(tried.raw, models.linear, algo.outputs, tried.x)))
            tried = algo.trial(state, state.x + u * algo.scale, state.penalty, state.merit, promised)
            if tried.merit < state.merit - ESCAPE_SHARE * promised:
                state.escapes += 1
                algo.move_to(state, tried.x, state.penalty)
                state.radius = algo.trust_region.initial
                state.kkt = None
                return True
        radius *= 0.5
    return False


NEAR_ACTIVE = 1e-6
"""An inequality this close to its bound (in its own unit) may carry a multiplier in the fitted estimate."""


def fitted_multipliers(algo: SCPAlgorithm, state: IterationState) -> Multipliers | None:
    """The multipliers that best satisfy stationarity at the iterate by the measure the certificate judges, its largest
    scaled component, :math:`\\min \\|S(\\nabla f + A_W^T y)\\|_\\infty` (:func:`smallest_largest_residual`):
    nonnegative on the inequalities within :data:`NEAR_ACTIVE` of their bounds, free on the equalities, zero elsewhere;
    a second-order cone within :data:`NEAR_ACTIVE` of its boundary (not at its apex) is the inequality
    :math:`\\|v_{1:}\\| - v_0 \\le 0` there, whose multiplier :math:`\\mu` is the cone dual
    :math:`\\mu (1, -v_{1:}/\\|v_{1:}\\|)` (:func:`_cone_rows`). Where the active constraints are degenerate the
    subproblem's own multipliers can miss by far more (docs/engine.md, 'KKT certificates and the polish')."""
    raw, linear, outputs = state.raw, algo.linear, algo.outputs
    gap, out, values = linear.gap(state.x), outputs.gap(raw.residuals), stacked_values(raw.inequalities)
    size = sum(b.values.size for b in raw.equalities)
    working = WorkingSet(gap >= -NEAR_ACTIVE, out >= -NEAR_ACTIVE, values >= -NEAR_ACTIVE, np.ones(size, dtype=bool))
    rows = working.rows(raw, linear, outputs)
    cone_rows, cone_duals = _cone_rows(raw, state.x.size)
    if rows.shape[0] + cone_rows.shape[0] == 0:
        return None
    free = linear.A.shape[0]
    signed = rows.shape[0] - free - size
    lower = np.concatenate([np.full(free, -np.inf), np.zeros(signed), np.full(size, -np.inf),
                            np.zeros(cone_rows.shape[0])])
    target = -objective_gradient(raw, algo.weights, algo.cost) * algo.scale
    matrix = sp.vstack([sp.csr_matrix(rows), cone_rows]).multiply(algo.scale[None, :]).T
    y = smallest_largest_residual(sp.csc_matrix(matrix), target, lower)
    if y is None:
        return None
    estimate = working.multipliers(y[: rows.shape[0]], free)
    return replace(estimate, cone=cone_duals @ y[rows.shape[0]:]) if raw.cones else estimate


def smallest_largest_residual(matrix: sp.csc_matrix, target: np.ndarray, lower: np.ndarray) -> np.ndarray | None:
    """:math:`\\min_y \\|M y - t\\|_\\infty` with :math:`y_i \\ge` ``lower`` where that is finite (0 or
    :math:`-\\infty`), as the linear program :math:`\\min s` over :math:`-s \\le (M y - t)_j \\le s` (Clarabel,
    sparse): its :math:`y` (the signed entries clipped at 0), or None when Clarabel does not solve it. The largest
    residual is the objective, so Clarabel's gap tolerance bounds it; where the minimizers form a face (degenerate
    active constraints) it returns a point inside it. The 2-norm's minimizer, the fit before, left the 6-DoF descent's
    optimum 1.2e-6 to 1.5e-6 from the 1e-6 tolerance for 30 iterations (measured: docs/engine.md, 'KKT certificates
    and the polish')."""
    m, n = matrix.shape
    signed = np.flatnonzero(np.isfinite(lower))
    sign_rows = sp.csr_matrix((-np.ones(signed.size), (np.arange(signed.size), signed)), shape=(signed.size, n + 1))
    bound = sp.csr_matrix(-np.ones((m, 1)))  # M y - s <= t and -M y - s <= -t
    rows = sp.vstack([sign_rows, sp.hstack([matrix, bound]), sp.hstack([-matrix, bound])], format="csc")
    q = np.zeros(n + 1)
    q[n] = 1.0
    program = ConicProgram(sp.csc_matrix((n + 1, n + 1)), q, rows, np.concatenate([-lower[signed], target, -target]),
                           Cones(nonneg=signed.size + 2 * m))
    result = make_backend("clarabel", program, tolerance=1e-10).solve()
    if result.x is None:
        return None
    y = result.x[:n].copy()
    y[signed] = np.maximum(y[signed], lower[signed])
    return y


def _cone_rows(raw, n: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """The gradient of :math:`\\|v_{1:}\\| - v_0` for each cone within :data:`NEAR_ACTIVE` of its boundary (one row
    each), and the map from their multipliers to the cone rows' duals, :math:`\\mu (1, -v_{1:}/\\|v_{1:}\\|)`."""
    total = sum(block.values.size for block in raw.cones)
    gradients, columns, start = [], [], 0
    for block in raw.cones:
        jacobian = sp.csr_matrix(block.jacobian)
        first = 0
        for size in block.sizes:
            v = block.values[first: first + size]
            norm = float(np.linalg.norm(v[1:]))
            if norm > 0 and norm - v[0] >= -NEAR_ACTIVE:
                direction = v[1:] / norm
                gradients.append(sp.csr_matrix(direction @ jacobian[first + 1: first + size] - jacobian[first]))
                dual = np.zeros(total)
                dual[start + first] = 1.0
                dual[start + first + 1: start + first + size] = -direction
                columns.append(dual)
            first += size
        start += block.values.size
    if not gradients:
        return sp.csr_matrix((0, n)), np.zeros((total, 0))
    return sp.vstack(gradients).tocsr(), np.column_stack(columns)


def certified_by_fitted_multipliers(algo: SCPAlgorithm, state: IterationState) -> bool:
    """Whether the :func:`fitted_multipliers` make the iterate a KKT point (then the run ends there)."""
    estimate = None if algo.phase1 or state.multipliers is None else fitted_multipliers(algo, state)
    if estimate is None:
        return False
    kept = state.multipliers, state.kkt
    state.multipliers = estimate
    measure_kkt(algo, state)
    if kkt_met(algo, state):
        finish_optimal(algo, state)
        return True
    state.multipliers, state.kkt = kept
    return False
