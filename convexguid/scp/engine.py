"""The sequential convex programming loop shared by every problem family.

Each iteration reads as a recipe: evaluate the nonlinear maps and their Jacobians
at the iterate (convexify), assemble the trust-region subproblem with penalized
slacks (:mod:`convexguid.scp.assembly`), solve it with the chosen backend, and
accept or reject the step from the ratio of actual to predicted decrease of the
exact-penalty merit function

.. math::

    \\phi(x) = f(x) + \\rho \\Big( \\sum \\max(0, g(x)) + \\sum |e(x)| \\Big).

The objective's residuals are linearized (Gauss-Newton), so the subproblem is a
convex QP whose fixed point is a KKT point of the nonlinear program. A program may
also supply the curvature of its equality constraints, a nonnegative diagonal
:math:`H \\approx \\sum_i \\lambda_i \\nabla^2 e_i(x)` evaluated with the multipliers of the
previous subproblem (``lagrangian_curvature``); it enters the model as
:math:`\\tfrac12 d^T H d`, an S\\ :math:`\\ell_1`\\ QP step (Fletcher 1985). Without it a purely
linear objective gives linear programs, which crawl when the optimum is not a vertex. The trust
radius shrinks on poor agreement and grows when the model is trusted and the step
reaches the radius (the classical rule, e.g. Nocedal & Wright, Alg. 4.1).

Stops with ``converged`` when the scaled step or the predicted decrease falls
below the tolerance at a feasible iterate. Stalling with constraints violated
first multiplies the penalty weight by ten (an exact penalty needs a weight above
the multipliers), up to ``penalty_max``; ``infeasible`` when the iterates still stall
with constraints violated (or the hard linear constraints are inconsistent);
``max_iterations``; or ``solver_error`` when the backend fails numerically more than
:data:`MAX_BACKEND_FAILURES` times in a row (each failure is retried with a smaller trust region).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from convexguid.backends import make_backend
from convexguid.scp.assembly import SubproblemAssembler
from convexguid.scp.problem import Evaluation, NonconvexProgram, SCPSettings


@dataclass(frozen=True)
class IterationRecord:
    """One row of the iteration table."""

    iteration: int
    objective: float
    violation: float
    step: float
    trust_radius: float
    ratio: float
    accepted: bool
    solver_status: str
    solver_iterations: int
    time_s: float


@dataclass
class SCPResult:
    """Outcome of :func:`solve_scp`."""

    x: np.ndarray
    status: str
    objective: float
    max_violation: float
    violations: dict[str, float]
    iterations: int
    history: list[IterationRecord] = field(default_factory=list)
    message: str = ""
    wall_time_s: float = 0.0
    convexify_time_s: float = 0.0
    solver_time_s: float = 0.0

    @property
    def overhead_time_s(self) -> float:
        return max(0.0, self.wall_time_s - self.convexify_time_s - self.solver_time_s)

    def timing(self) -> dict[str, float]:
        """The time split reported in a solution's summary (``timing``), s."""
        return {"scp_s": self.wall_time_s, "convexify_s": self.convexify_time_s,
                "solver_s": self.solver_time_s, "overhead_s": self.overhead_time_s}


MAX_BACKEND_FAILURES = 3
"""Consecutive numerical failures of the convex solver (each retried with a 4x smaller trust region) tolerated."""


def objective_value(ev: Evaluation, weights: np.ndarray, cost: np.ndarray, x: np.ndarray) -> float:
    """:math:`f(x) = \\sum_i w_i r_i^2 + c^T x`."""
    return float(weights @ ev.residuals**2 + cost @ x)


def violation_by_block(ev: Evaluation) -> dict[str, float]:
    """Worst violation of each nonlinear constraint block, in its own unit."""
    out = {b.name: float(np.max(b.values, initial=0.0)) for b in ev.inequalities}
    out.update({b.name: float(np.max(np.abs(b.values), initial=0.0)) for b in ev.equalities})
    return {k: max(v, 0.0) for k, v in out.items()}


def _penalty_sum(ev: Evaluation) -> float:
    total = sum(float(np.maximum(b.values, 0.0).sum()) for b in ev.inequalities)
    return total + sum(float(np.abs(b.values).sum()) for b in ev.equalities)


def _project_on_equalities(program: NonconvexProgram, x: np.ndarray) -> np.ndarray:
    """Least-change correction making ``x`` satisfy the hard linear equalities."""
    lin = program.linear_constraints()
    if lin.A.shape[0] == 0:
        return x
    correction, *_ = np.linalg.lstsq(lin.A, lin.b - lin.A @ x, rcond=None)
    return x + correction


def solve_scp(program: NonconvexProgram, settings: SCPSettings,
              log: Callable[[IterationRecord], None] | None = None,
              x0: np.ndarray | None = None) -> SCPResult:
    """Run the SCP loop on ``program`` from ``x0`` (default: its initial guess)."""
    start = time.perf_counter()
    weights, cost = program.residual_weights(), program.linear_cost()
    x = _project_on_equalities(program, program.initial_guess() if x0 is None else np.asarray(x0, float))
    convexify = solver_time = 0.0

    outputs = program.output_constraints()

    def evaluate(point: np.ndarray, jacobians: bool) -> tuple[Evaluation, Evaluation]:
        """The program's own evaluation, and one that also lists the output constraints' values."""
        raw = program.evaluate(point, jacobians)
        return raw, replace(raw, inequalities=outputs.blocks_at(raw.residuals) + raw.inequalities)

    def merit_at(point: np.ndarray, ev: Evaluation) -> float:
        return objective_value(ev, weights, cost, point) + rho * _penalty_sum(ev)

    t = time.perf_counter()
    raw, ev = evaluate(x, jacobians=True)
    convexify += time.perf_counter() - t
    curvature = getattr(program, "lagrangian_curvature", None)
    assembler = SubproblemAssembler(program.num_variables, raw, program.linear_constraints(), outputs,
                                    program.variable_scale(), cost, weights, curvature=curvature is not None)
    multipliers: dict[str, np.ndarray] = {}
    radius, rho = settings.trust_region, settings.penalty
    merit = merit_at(x, ev)
    backend = None
    history: list[IterationRecord] = []
    failures = 0
    status, message = "max_iterations", f"no convergence in {settings.max_iterations} iterations"

    for it in range(1, settings.max_iterations + 1):
        hessian = None
        if curvature is not None and multipliers:
            hessian = np.maximum(curvature(x, multipliers), 0.0)
        program_k = assembler.build(x, raw, radius, rho, hessian)
        if backend is None:
            backend = make_backend(settings.backend, program_k, settings.backend_tolerance)
        else:
            backend.update(program_k)
        res = backend.solve()
        solver_time += res.solve_time_s
        if not res.usable:
            if res.status == "infeasible":
                status, message = "infeasible", "the hard linear constraints (boundary conditions) are inconsistent"
                break
            failures += 1
            if failures > MAX_BACKEND_FAILURES:
                status, message = "solver_error", f"backend {settings.backend} returned {res.status} " \
                                                  f"{failures} times in a row"
                break
            # a numerical failure of the backend: retry a smaller, better-conditioned subproblem
            radius = max(0.25 * radius, settings.trust_region_min)
            history.append(IterationRecord(it, objective_value(ev, weights, cost, x), _max_violation(ev), 0.0, radius,
                                           float("nan"), False, res.status, res.iterations,
                                           time.perf_counter() - start))
            if log is not None:
                log(history[-1])
            continue
        failures = 0
        d = assembler.step(res.x)
        if curvature is not None and res.z is not None:
            multipliers = _split_by_block(assembler.equality_multipliers(res.z), raw)
        predicted = merit - (program_k.objective(res.x) + cost @ x)
        t = time.perf_counter()
        x_new = x + d
        raw_new, ev_new = evaluate(x_new, jacobians=False)
        merit_new = merit_at(x_new, ev_new)
        convexify += time.perf_counter() - t
        ratio = _ratio(merit - merit_new, predicted)
        if ratio < settings.expand_ratio and (raw.equalities or raw.inequalities):
            # Second-order correction: the linear model cannot see the curvature of the
            # constraints, so a good step can look bad (Maratos effect). Re-solve the same
            # subproblem with each constraint's constant shifted to what the trial point
            # showed, and judge the corrected step against the original prediction.
            backend.update(assembler.build(x, _shifted_constants(raw, raw_new, d), radius, rho, hessian))
            res_soc = backend.solve()
            solver_time += res_soc.solve_time_s
            if res_soc.usable:
                t = time.perf_counter()
                x_soc = x + assembler.step(res_soc.x)
                _, ev_soc = evaluate(x_soc, jacobians=False)
                merit_soc = merit_at(x_soc, ev_soc)
                convexify += time.perf_counter() - t
                ratio_soc = _ratio(merit - merit_soc, predicted)
                if ratio_soc > ratio:
                    x_new, ev_new, merit_new, ratio = x_soc, ev_soc, merit_soc, ratio_soc
                    d = x_new - x
        step = float(np.max(np.abs(d) / program.variable_scale()))
        accepted = ratio >= settings.accept_ratio
        if accepted:
            t = time.perf_counter()
            x, merit = x_new, merit_new
            raw, ev = evaluate(x, jacobians=True)
            convexify += time.perf_counter() - t
        at_boundary = step >= 0.99 * radius
        if ratio < settings.shrink_ratio:
            radius = max(0.25 * step, settings.trust_region_min) if step > 0 else radius * 0.25
        elif ratio > settings.expand_ratio and at_boundary:
            radius = min(2.0 * radius, settings.trust_region_max)
        record = IterationRecord(it, objective_value(ev, weights, cost, x), _max_violation(ev), step, radius,
                                 ratio, accepted, res.status, res.iterations, time.perf_counter() - start)
        history.append(record)
        if log is not None:
            log(record)
        small_step = step <= settings.tolerance
        small_decrease = 0 <= predicted <= settings.tolerance * max(1.0, abs(merit))
        if small_step or small_decrease or radius <= settings.trust_region_min:
            if _max_violation(ev) <= settings.feasibility_tolerance:
                status, message = "converged", "step and predicted decrease below tolerance"
                break
            if rho < settings.penalty_max:
                # A stationary point of the penalty function that violates the constraints:
                # the penalty is below the multipliers; raise it and go on.
                rho = min(10.0 * rho, settings.penalty_max)
                merit = merit_at(x, ev)
                radius = max(radius, settings.trust_region)
                continue
            status = "infeasible"
            message = "iterates stalled with constraints violated: " + _describe_violations(ev)
            break

    if status == "max_iterations" and _max_violation(ev) > settings.feasibility_tolerance:
        message += "; constraints still violated: " + _describe_violations(ev)
    return SCPResult(x=x, status=status, objective=objective_value(ev, weights, cost, x),
                     max_violation=_max_violation(ev), violations=violation_by_block(ev),
                     iterations=len(history), history=history, message=message,
                     wall_time_s=time.perf_counter() - start, convexify_time_s=convexify,
                     solver_time_s=solver_time)


def _ratio(actual: float, predicted: float) -> float:
    """Actual over predicted decrease of the merit function."""
    return actual / predicted if predicted > 0 else (1.0 if actual >= 0 else -1.0)


def _shifted_constants(at_x: Evaluation, at_trial: Evaluation, d: np.ndarray) -> Evaluation:
    """Constraint blocks at ``x`` whose values are :math:`c(x + d) - \\nabla c(x)\\, d` (Jacobians kept).

    Linearizing these about ``x`` gives :math:`c(x + d) + \\nabla c(x)(d' - d)`: the subproblem
    solved again with them (Fletcher's second-order correction) steers the new step ``d'`` so
    that the curvature error seen at the trial point is cancelled to first order.
    Nocedal & Wright, *Numerical Optimization*, 2nd ed., Sec. 15.6; Fletcher, *Practical Methods
    of Optimization*, 2nd ed., Sec. 14.4.
    """

    def shift(blocks_x, blocks_trial):
        return tuple(replace(bx, values=bt.values - bx.jacobian @ d) for bx, bt in zip(blocks_x, blocks_trial,
                                                                                      strict=True))

    return replace(at_x, inequalities=shift(at_x.inequalities, at_trial.inequalities),
                   equalities=shift(at_x.equalities, at_trial.equalities))


def _split_by_block(values: np.ndarray, ev: Evaluation) -> dict[str, np.ndarray]:
    """Equality multipliers by block name."""
    out, start = {}, 0
    for block in ev.equalities:
        out[block.name] = values[start: start + block.values.size]
        start += block.values.size
    return out


def _max_violation(ev: Evaluation) -> float:
    return max(violation_by_block(ev).values(), default=0.0)


def _describe_violations(ev: Evaluation) -> str:
    units = {b.name: b.unit for b in (*ev.inequalities, *ev.equalities)}
    parts = [f"{k} by {v:.3g} {units[k]}".rstrip() for k, v in violation_by_block(ev).items() if v > 0]
    return "; ".join(parts) or "none"


def merge_results(first: SCPResult, second: SCPResult) -> SCPResult:
    """``second`` continued from ``first`` (e.g. after adding constraint points): histories and times add up."""
    history = first.history + [replace(r, iteration=r.iteration + first.iterations) for r in second.history]
    return replace(second, history=history, iterations=len(history),
                   wall_time_s=first.wall_time_s + second.wall_time_s,
                   convexify_time_s=first.convexify_time_s + second.convexify_time_s,
                   solver_time_s=first.solver_time_s + second.solver_time_s)
