"""The sequential convex programming iteration shared by every problem family. :class:`SCPAlgorithm` is an explicit
state machine: :meth:`~SCPAlgorithm.initialize` turns a start point into an
:class:`~convexguid.scp.state.IterationState`, and each :meth:`~SCPAlgorithm.step`

1. convexifies: the nonlinear maps and their Jacobians at the iterate (already in the state);
2. assembles the trust-region subproblem with penalized slacks (:mod:`convexguid.scp.choice`) and solves it (a
   numerical failure is retried with a smaller radius);
3. judges the step by the ratio of actual to predicted decrease of the exact-penalty merit
   :math:`\\phi(x) = f(x) + \\rho \\big( \\sum \\max(0, g(x)) + \\sum |e(x)| \\big)`, with a
   :class:`~convexguid.scp.policies.SecondOrderCorrection` when it is poor and else the
   :class:`~convexguid.scp.policies.FunnelPolicy`;
4. accepts or rejects, and updates the radius (:class:`~convexguid.scp.policies.TrustRegionPolicy`);
5. stops, or raises the penalty (:class:`~convexguid.scp.policies.PenaltyPolicy`) when a step shows it below the
   multipliers or the iterates stall with constraints violated.

The objective's residuals are linearized (Gauss-Newton); a program may add a convex model of its constraints'
curvature (``curvature_model``, weighted by the last multipliers: an S :math:`\\ell_1` QP step, Fletcher 1985). Near a
feasible point the end game adds Newton's step (:mod:`convexguid.scp.endgame`) and the curved subproblem
(:mod:`convexguid.scp.curved`). Statuses: ``converged`` only at a feasible KKT point (:mod:`convexguid.scp.optimality`);
``unverified`` when its KKT residuals stay above tolerance after :data:`POLISH_ITERATIONS` more stalls; ``infeasible``
only with a certificate (:mod:`convexguid.scp.restoration`); ``max_iterations``; ``solver_error`` after more than
``max_backend_failures`` backend failures in a row. Each mechanism, measured: docs/engine.md.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from convexguid.backends import ConicProgram, make_backend
from convexguid.backends.base import Backend, BackendResult
from convexguid.progress import report
from convexguid.scp.assembly import SubproblemAssembler
from convexguid.scp.choice import SubproblemChoice, choose_subproblem
from convexguid.scp.condensed import CondensedAssembler
from convexguid.scp.curved import CurvedModel, CurvedSubproblem
from convexguid.scp.endgame import Candidate, SecondOrderModels, linearized_violation, newton_candidate
from convexguid.scp.evaluations import ProgramEvaluations, not_finite
from convexguid.scp.lagrangian import MAX_DENSE_SIZE, has_jacobian
from convexguid.scp.merit import decrease_ratio, describe_violations, max_violation, penalty_sum, violation_by_block
from convexguid.scp.optimality import (
    certified_by_fitted_multipliers,
    certified_here,
    finish_optimal,
    kkt_met,
    measure_kkt,
    off_saddle,
)
from convexguid.scp.policies import Funnel, FunnelPolicy, PenaltyPolicy, SecondOrderCorrection, TrustRegionPolicy
from convexguid.scp.problem import CurvatureModel, Evaluation, NonconvexProgram, SCPSettings
from convexguid.scp.restoration import restore_start, run_phase1
from convexguid.scp.state import IterationRecord, IterationState, SCPResult, merge_results

__all__ = ["IterationRecord", "SCPAlgorithm", "SCPResult", "merge_results", "solve_scp"]

Log = Callable[[IterationRecord], None]

NEARLY_FEASIBLE = 100.0
"""A first stall with the violation within this factor of the feasibility tolerance goes to phase 1 at once (it may
be the subproblem's round-off: docs/engine.md, 'Restoration and phase 1'); a later stall raises the penalty."""

RESTORED = 0.01
"""Phase 1 ends once the violation is within this share of the feasibility tolerance: it seeks a feasible point, not
the violation's minimum (measured: docs/engine.md, 'Restoration and phase 1')."""

PINNED = 0.9
"""A linear subproblem's step of at least this share of the trust radius reached it (see ``IterationState.pinned``)."""

STIFF = 1.5
"""A linear step inside the trust region whose merit fell more than this many times its prediction counts as pinned: a
model stiffer than the problem held it back (Luus' singular arc: ratios near 2; docs/engine.md, 'Curved subproblem')."""

POLISH_ITERATIONS = 40
"""More stalls a feasible point short of the KKT tolerance may polish through before it is reported ``unverified`` (at
20 a run along a long flat valley ended so: docs/engine.md, 'KKT certificates and the polish')."""


class Trial(NamedTuple):
    """A trial point: ``raw`` the program's evaluation there, ``ev`` the merit's (see ``SCPAlgorithm._evaluate``)."""

    x: np.ndarray
    raw: Evaluation
    ev: Evaluation
    merit: float
    ratio: float


class SCPAlgorithm:
    """The SCP loop on one program: ``state = initialize(x0)``, then ``step(state)`` until finished. ``phase1`` marks
    the elastic phase-1 run, where a stall with constraints violated ends ``infeasible`` (the certificate)."""

    def __init__(self, program: NonconvexProgram, settings: SCPSettings, log: Log | None = None,
                 phase1: bool = False) -> None:
        self.program, self.settings, self.log, self.phase1 = program, settings, log, phase1
        self.trust_region = TrustRegionPolicy.from_settings(settings)
        self.penalty = PenaltyPolicy.from_settings(settings)
        self.correction = SecondOrderCorrection.from_settings(settings)
        self.funnel = FunnelPolicy()
        self.weights, self.cost = program.residual_weights(), program.linear_cost()
        if phase1:  # the elastic program: the objective dropped, the violation alone minimised
            self.weights, self.cost = np.zeros_like(self.weights), np.zeros(program.num_variables)
        self.outputs = program.output_constraints()
        self.linear = program.linear_constraints()  # fixed for the run: read once
        self.scale = program.variable_scale()
        self.evaluations = ProgramEvaluations(program)
        self.guarded = program.guarded_bounds() if hasattr(program, "guarded_bounds") else None
        self.curvature: CurvatureModel | None = (program.curvature_model() if hasattr(program, "curvature_model")
                                                 else None)  # None: affine constraints
        self.second_order: SecondOrderModels | None = None
        self.curved: CurvedSubproblem | None = None
        self.assembler: SubproblemAssembler | CondensedAssembler | None = None
        self.choice: SubproblemChoice | None = None
        self.backend: Backend | None = None
        self.feasibility_backend: Backend | None = None  # the least violation in the step's region
        self.objective_size = 0.0

    def _evaluate(self, state: IterationState | None, x: np.ndarray, jacobians: bool) -> tuple[Evaluation, Evaluation]:
        """The program's own evaluation, and one that also lists the output constraints' values and the cones'
        violations (what the merit function and the reports count)."""
        t = time.perf_counter()
        raw = self.evaluations(x, jacobians)
        ev = replace(raw, inequalities=self.outputs.blocks_at(raw.residuals) + raw.inequalities
                     + tuple(cone.as_inequality() for cone in raw.cones))
        if state is not None:
            state.convexify_time_s += time.perf_counter() - t
        return raw, ev

    def objective(self, ev: Evaluation, x: np.ndarray) -> float:
        """:math:`f(x) = \\sum_i w_i r_i^2 + c^T x`."""
        return float(self.weights @ ev.residuals**2 + self.cost @ x)

    def merit(self, ev: Evaluation, x: np.ndarray, rho: float) -> float:
        return self.objective(ev, x) + rho * penalty_sum(ev)

    def initialize(self, x0: np.ndarray | None = None, penalty: float | None = None) -> IterationState:
        """The state at ``x0`` (default: the program's guess) moved onto the hard linear constraints; if no point
        meets them the state is finished at once as ``infeasible``, with the elastic program's certificate
        (:func:`~convexguid.scp.restoration.restore_start`)."""
        started = time.perf_counter()
        x = np.asarray(self.program.initial_guess() if x0 is None else x0, dtype=float)
        restored = restore_start(self.program, x)
        x = restored.x if restored.feasible else x
        raw, ev = self._evaluate(None, x, jacobians=True)
        objective = self.objective(ev, x)
        # the unit of the penalty weights (PenaltyPolicy): a terminal cost that is zero at the start has a size
        self.objective_size = max(abs(objective), float(np.abs(self.cost) @ self.scale))
        rho = self.penalty.initial(self.objective_size) if penalty is None else penalty
        radius = self.settings.trust_region_max if getattr(self.program, "affine", False) else self.trust_region.initial
        funnel = self.funnel.initial(penalty_sum(ev), warm=penalty is not None) if self.settings.funnel else None
        state = IterationState(x=x, raw=raw, ev=ev, objective=objective, merit=self.merit(ev, x, rho), penalty=rho,
                               radius=radius, started=started, funnel=funnel)
        if not restored.feasible:
            state.finish("infeasible", "certificate: " + restored.certificate)
        elif broken := not_finite(raw):
            state.finish("solver_error", f"the problem or its derivatives are not a number at the start point, in "
                                         f"{broken}: a division by zero, a root of a negative number or a norm's "
                                         "derivative at zero there? Start such a state away from it (a bound, a guess)")
        if self.assembler is None:
            # the assembly and the backend, decided once from the first evaluation (backend: auto)
            n = self.program.num_variables
            self.choice = choose_subproblem(self.settings.backend, n, raw, self.weights)
            assembler = CondensedAssembler if self.choice.condensed else SubproblemAssembler
            pattern = None if self.curvature is None else (self.curvature.rows, self.curvature.cols)
            self.assembler = assembler(n, raw, self.linear, self.outputs, self.scale, self.cost, self.weights, pattern)
            if (self.settings.second_order and hasattr(self.program, "lagrangian_hessian")
                    and has_jacobian(raw) and n <= MAX_DENSE_SIZE):
                self.second_order = SecondOrderModels(self)
                self.curved = CurvedSubproblem(self)
        return state

    @property
    def solver_label(self) -> str:
        """The backend as the summary shows it: the setting, resolved (``auto -> daqp (condensed)``)."""
        return self.choice.label if self.choice is not None else self.settings.backend

    def _solve_subproblem(self, state: IterationState, ev: Evaluation, hessian: np.ndarray | None,
                          curved: CurvedModel | None = None) -> tuple[BackendResult, float]:
        """The backend's answer and the model's merit after its step (the curved subproblem's for ``curved``)."""
        if curved is not None:
            return self.curved.solve(state, ev, curved)
        program_k = self.assembler.build(state.x, ev, self.box(state), state.penalty, hessian)
        self.backend, result, model = self.solved(state, program_k, self.backend, self.choice.backend,
                                                  self.choice.fallback)
        return result, model

    def box(self, state: IterationState) -> float | np.ndarray:
        """The subproblem's limits on the scaled step (:meth:`~convexguid.scp.policies.TrustRegionPolicy.box`)."""
        return self.trust_region.box(state.radius, state.x, self.scale, self.guarded)

    def solved(self, state: IterationState, program_k: ConicProgram, backend: Backend | None, name: str,
               fallback: str | None = None, like: Backend | None = None) -> tuple[Backend, BackendResult, float]:
        """``program_k`` solved by ``backend`` (made at the first call from ``name`` and ``fallback``, or as the
        sibling of ``like``, a backend of that name on the same pattern; then only updated), its time counted;
        returns the backend, its answer and the model's merit after the step."""
        if backend is None and like is not None:
            backend = like.sibling(program_k)  # set for program_k: the update below only repeats it
        if backend is None:
            backend = make_backend(name, program_k, self.settings.backend_tolerance, fallback=fallback,
                                   iterative_refinement=self.settings.iterative_refinement)
        else:
            backend.update(program_k)
        result = backend.solve()
        state.solver_time_s += result.solve_time_s
        if not result.usable:
            return backend, result, float("nan")
        value = result.objective + program_k.constant if result.exact_objective else program_k.objective(result.x)
        return backend, result, value + self.cost @ state.x

    def record(self, state: IterationState, step: float, ratio: float, accepted: bool,
               result: BackendResult) -> None:
        record = IterationRecord(state.iteration, state.objective, max_violation(state.ev), step, state.radius, ratio,
                                 accepted, result.status, result.iterations, time.perf_counter() - state.started,
                                 state.penalty)
        state.history.append(record)
        if self.log is not None:
            self.log(record)

    def step(self, state: IterationState) -> IterationState:
        """One SCP iteration (see the module docstring); returns ``state`` updated."""
        if state.finished:
            return state
        report("SCP phase-1 iteration" if self.phase1 else "SCP iteration", state.iteration + 1)
        state.iteration += 1
        self._relax_penalty(state)
        # 1-2. convexify, solve: the curved subproblem if wanted; the linear one if not, if it fails or sees no decrease
        curved = self.curved.model(state) if self.curved is not None else None
        hessian = self._curvature_values(state)
        result, model = self._solve_subproblem(state, state.raw, hessian, curved)
        if curved is not None and (not result.usable or not state.merit - model > 0):
            curved = None
            result, model = self._solve_subproblem(state, state.raw, hessian)
        if not result.usable:
            self._backend_failed(state, result)
            return self._check_limit(state)
        state.failures = 0
        assembler = self.curved.assembler if curved is not None else self.assembler
        d, predicted = assembler.step(result.x), state.merit - model
        newton = None
        if result.z is not None:
            state.multipliers, state.augmented = assembler.multipliers(result.z), curved is not None
            if certified_here(self, state, result, predicted):
                return self._check_limit(state)
            t = time.perf_counter()
            newton = newton_candidate(self, state)
            state.convexify_time_s += time.perf_counter() - t
        # 3. judge the step, corrected when its ratio is poor
        trial = self.trial(state, state.x + d, state.penalty, state.merit, predicted)
        linearized = linearized_violation(state.raw, self.outputs, d)
        predicted_objective = state.objective - (model - state.penalty * linearized)
        if self.correction.wanted(trial.ratio, state.raw, trial.raw):
            shifted = SecondOrderCorrection.shifted(state.raw, trial.raw, d)
            corrected, _ = self._solve_subproblem(state, shifted, hessian, curved)
            if corrected.usable:
                x_soc = state.x + assembler.step(corrected.x)
                soc = self.trial(state, x_soc, state.penalty, state.merit, predicted)
                if soc.ratio > trial.ratio:
                    trial, d = soc, soc.x - state.x
        step = float(np.max(np.abs(d) / self.scale, initial=0.0))
        if curved is None:
            held = step >= PINNED * state.radius or trial.ratio > STIFF  # by the region, or by a stiff model
            state.pinned = state.pinned + 1 if held else 0
        if newton is not None:
            if not newton.accepted:
                state.newton_radius, state.newton_earned = 0.25 * newton.step, 0.0
            elif (newton.ratio >= self.trust_region.expand or trial.ratio < self.settings.accept_ratio
                  or newton.merit <= self.merit(trial.ev, trial.x, newton.penalty)):
                # the quadratic model predicted its merit well, or it does at least as well as the first-order point
                self._take_newton(state, newton, result)
                return self._check_limit(state)
        # 4. accept or reject, update the radius
        accepted, ratio, state.funnel = self.judged(state, trial, predicted_objective, linearized)
        steer = self._penalty_too_low(state, step, linearized, accepted, trial.ev, hessian)
        if accepted:
            self.move_to(state, trial.x, state.penalty, trial.merit)
            measure_kkt(self, state)
        state.radius = self.trust_region.update(state.radius, ratio, step)
        if curved is not None and not accepted and step < state.radius:
            state.curved_refused_at = state.x.copy()  # the same curved QP would give the same step: not again here
        self.record(state, step, ratio, accepted, result if curved is None else replace(result, status="curved"))
        # 5. stop, or raise the penalty
        if self.phase1 and accepted and max_violation(state.ev) <= RESTORED * self.settings.feasibility_tolerance:
            state.finish("converged", "feasibility restored")
        elif accepted and kkt_met(self, state):
            finish_optimal(self, state)
        elif accepted and curved is not None and certified_by_fitted_multipliers(self, state):
            pass  # the curved subproblem's own multipliers carry its augmentation (:mod:`convexguid.scp.curved`)
        elif self.funnel.holds(state.funnel) and max_violation(state.ev) > self.settings.feasibility_tolerance:
            run_phase1(self, state)  # only less violation passes the point the funnel left: restore feasibility
        elif self._small(state, step, predicted):
            self._stalled(state)
        elif steer:
            self._raise_penalty(state)
        return self._check_limit(state)

    def _backend_failed(self, state: IterationState, result: BackendResult) -> None:
        """Numerical trouble (``d = 0`` is feasible: the start meets the hard constraints): retry a smaller
        subproblem, and end the run after more than ``max_backend_failures`` in a row."""
        state.failures += 1
        state.radius = self.trust_region.after_failure(state.radius)
        self.record(state, 0.0, float("nan"), False, result)
        if state.failures > self.settings.max_backend_failures:
            broken = not_finite(state.raw)
            why = (f"; the linearization at the iterate is not a number in {broken}: a derivative undefined there (a "
                   "norm or a root at zero?)") if broken else ""
            state.finish("solver_error", f"backend {self.solver_label} returned {result.status} {state.failures} "
                                         f"times in a row{why}")

    def _penalty_too_low(self, state: IterationState, step: float, linearized: float, accepted: bool,
                         ev_new: Evaluation, hessian: np.ndarray | None) -> bool:
        """Whether the step shows the weight below the multipliers, away from feasibility (above :data:`NEARLY_FEASIBLE`
        tolerances) and outside phase 1 (:meth:`~convexguid.scp.policies.PenaltyPolicy.steered`)."""
        if self.phase1 or max_violation(state.ev) <= NEARLY_FEASIBLE * self.settings.feasibility_tolerance:
            state.kept = 0
            return False
        violation, inside = penalty_sum(state.ev), step < PINNED * state.radius
        steer, state.kept = self.penalty.steered(violation, linearized, penalty_sum(ev_new) if accepted else None,
                                                 inside, state.kept)
        if not steer and not inside and linearized > self.penalty.retained * violation:
            # a step held by the region that kept the violation: was that the region, or the weight?
            steer = self.penalty.short_of_feasibility(violation, linearized, self._least_violation(state, hessian))
        return steer

    def _least_violation(self, state: IterationState, hessian: np.ndarray | None) -> float:
        """The linearized violation after the step that removes the most of it in the same trust region: the
        subproblem with the weight at its ceiling, solved by a backend of its own (so the step's warm start stays)."""
        ceiling = self.penalty.maximum * self.penalty.scale(self.objective_size)
        program_k = self.assembler.build(state.x, state.raw, self.box(state), ceiling, hessian)
        self.feasibility_backend, result, _ = self.solved(state, program_k, self.feasibility_backend,
                                                           self.choice.backend, like=self.backend)
        return (linearized_violation(state.raw, self.outputs, self.assembler.step(result.x)) if result.usable
                else penalty_sum(state.ev))

    def _raise_penalty(self, state: IterationState) -> bool:
        """Raise the penalty weight by its factor (False at its maximum); the merit and the radius follow."""
        rho = self.penalty.escalated(state.penalty, self.objective_size)
        if rho is None:
            return False
        state.penalty, state.kept = rho, 0
        state.merit = self.merit(state.ev, state.x, rho)
        state.radius = self.trust_region.after_penalty_change(state.radius)
        return True

    def judged(self, state: IterationState, trial: Trial, predicted_objective: float,
               linearized: float) -> tuple[bool, float, Funnel | None]:
        """``(accepted, ratio, funnel)`` of a trial point: the merit's ratio test, or else the funnel, whose
        ratio then updates the radius (:class:`~convexguid.scp.policies.FunnelPolicy`); ``linearized`` is the
        violation the step's linearization predicted, ``predicted_objective`` the objective's predicted decrease."""
        accepted = trial.ratio >= self.settings.accept_ratio
        if state.funnel is None or self.phase1:
            return accepted, trial.ratio, state.funnel
        violation = penalty_sum(state.ev)
        return self.funnel.decide(state.funnel, accepted, trial.ratio, violation, penalty_sum(trial.ev),
                                  state.objective, state.objective - self.objective(trial.ev, trial.x),
                                  predicted_objective, violation - linearized)

    def _curvature_values(self, state: IterationState) -> np.ndarray | None:
        """The program's convex curvature model at the iterate, weighted by the state's multipliers (if both)."""
        m = state.multipliers
        if self.curvature is None or m is None:
            return None
        t = time.perf_counter()
        values = self.curvature.values(state.x, m.curvature_weights(state.raw.residuals, self.weights, self.outputs))
        state.convexify_time_s += time.perf_counter() - t
        return values

    def _relax_penalty(self, state: IterationState) -> None:
        """Near a feasible point, let the penalty weight follow the multipliers, but not a curved subproblem's, which
        understate it (:meth:`~convexguid.scp.policies.PenaltyPolicy.relaxed`; docs/engine.md, 'Penalty weight')."""
        if (self.phase1 or state.multipliers is None or state.augmented
                or max_violation(state.ev) > self.settings.second_order_violation):
            return
        target = self.penalty.relaxed(state.penalty, state.multipliers.largest(), self.objective_size)
        if target is not None:
            state.penalty, state.merit = target, self.merit(state.ev, state.x, target)

    def _small(self, state: IterationState, step: float, predicted: float) -> bool:
        """The step, or the decrease the model predicted for it, is below the tolerance (or the radius collapsed)."""
        # phase 1's merit is the violation itself: a decrease is small only relative to what is left to remove
        unit = abs(state.merit) if self.phase1 else max(1.0, abs(state.merit))
        small_decrease = 0 <= predicted <= self.settings.tolerance * unit
        return step <= self.settings.tolerance or small_decrease or self.trust_region.collapsed(state.radius)

    def trial(self, state: IterationState, x: np.ndarray, rho: float, merit: float, predicted: float) -> Trial:
        """The trial point ``x`` evaluated (no Jacobians), its merit with weight ``rho`` and the ratio of its actual
        decrease from ``merit`` to the ``predicted`` one."""
        raw, ev = self._evaluate(state, x, jacobians=False)
        merit_x = self.merit(ev, x, rho)
        return Trial(x, raw, ev, merit_x, decrease_ratio(merit - merit_x, predicted))

    def move_to(self, state: IterationState, x: np.ndarray, penalty: float, merit: float | None = None) -> None:
        """Make ``x`` the iterate: its evaluation with Jacobians, objective, merit (``merit`` or at ``penalty``)."""
        state.x, state.penalty = x, penalty
        state.raw, state.ev = self._evaluate(state, x, jacobians=True)
        state.objective = self.objective(state.ev, x)
        state.merit = self.merit(state.ev, x, penalty) if merit is None else merit

    def _take_newton(self, state: IterationState, newton: Candidate, result: BackendResult) -> None:
        """Move to Newton's trial point (its penalty weight and working-set multipliers come along)."""
        if newton.ratio >= self.trust_region.expand:
            # a whole well-predicted step frees Newton's radius, a cut one doubles it (Nocedal & Wright, Alg. 4.1)
            state.newton_radius = np.inf if newton.whole else 2.0 * state.newton_radius
        self.move_to(state, newton.x, newton.penalty)
        state.funnel, state.multipliers, state.augmented = newton.funnel, newton.multipliers, False
        measure_kkt(self, state)
        state.radius = self.trust_region.update(state.radius, newton.ratio, newton.step)
        if not newton.whole and newton.ratio >= self.trust_region.expand:
            # a well-predicted cut step: room for the whole step next time, which the ratio test then judges
            state.newton_earned = min(newton.length, self.trust_region.maximum)
            state.radius = max(state.radius, state.newton_earned)
        self.record(state, newton.step, newton.ratio, True, replace(result, status="newton"))
        if kkt_met(self, state):
            finish_optimal(self, state)
        elif newton.whole and self._small(state, newton.step, newton.predicted):
            # only a whole Newton step that is small says the iterates stopped (a cut one may just be short)
            self._stalled(state)

    def _stalled(self, state: IterationState) -> None:
        """The iterates stopped moving: converged at a feasible KKT point (a small step is no proof of it: a feasible
        stall short of the KKT tolerance polishes on), else raise the penalty, restore feasibility or certify."""
        s = self.settings
        if max_violation(state.ev) <= s.feasibility_tolerance:
            why = ("trust region collapsed: no decrease found near a feasible point"
                   if self.trust_region.collapsed(state.radius) else "step and predicted decrease below tolerance")
            if state.kkt is None:
                measure_kkt(self, state)
            if state.kkt is None and not self.phase1:
                state.finish("unverified", f"{why}; not proved optimal: the backend reported no multipliers")
            elif state.kkt is None or kkt_met(self, state):
                finish_optimal(self, state)
            elif certified_by_fitted_multipliers(self, state):
                pass  # finished: the fitted multipliers make it a KKT point
            elif self.second_order is not None and state.polish < POLISH_ITERATIONS and not (
                    self.trust_region.collapsed(state.radius) and state.reopened_at is not None
                    and np.array_equal(state.reopened_at, state.x)):
                # a small step is no proof of optimality: polish on (the curved subproblem); a region collapsed on
                # round-off-sized decreases opens again, once at a point (docs/engine.md, 'Polish')
                state.polish += 1
                if self.trust_region.collapsed(state.radius):
                    state.radius, state.reopened_at = self.trust_region.initial, state.x.copy()
            else:
                state.finish("unverified", f"{why}; not proved optimal: KKT residuals above tolerance "
                                           f"{s.kkt_tolerance:g} (stationarity {state.kkt.relative_stationarity:.2g}, "
                                           f"complementarity {state.kkt.relative_complementarity:.2g} relative)")
            return
        if self.phase1:
            # a stationary point of the violation certifies infeasibility only if it is a minimum of the violation
            saddle = off_saddle(self, state, penalty_sum(state.ev), "a saddle of the violation")
            stall = "the elastic phase-1 problem stalls with the constraints still violated: " + describe_violations(
                state.ev)
            if saddle == "saddle":
                state.finish("unverified", f"{stall}; no certificate of infeasibility, the point is not proved a "
                                           f"minimum of the violation: {state.escape_log[-1]}")
            elif not saddle:  # not "stepped" off it
                state.finish("infeasible", stall)
            return
        # an infeasible stationary point of the penalty function: the penalty is below the multipliers; at the largest
        # penalty, or stalled by round-off just above the tolerance (a first try), restore feasibility directly
        first_try = max_violation(state.ev) <= NEARLY_FEASIBLE * s.feasibility_tolerance and state.phase1_runs == 0
        if first_try or not self._raise_penalty(state):
            run_phase1(self, state)

    def _check_limit(self, state: IterationState) -> IterationState:
        if not state.finished and state.iteration >= self.settings.max_iterations:
            message = f"no convergence in {self.settings.max_iterations} iterations"
            if max_violation(state.ev) > self.settings.feasibility_tolerance:
                message += "; constraints still violated: " + describe_violations(state.ev)
            state.finish("max_iterations", message)
        return state

    def result(self, state: IterationState) -> SCPResult:
        s = self.settings
        return SCPResult(x=state.x, status=state.status or "max_iterations", objective=state.objective,
                         max_violation=max_violation(state.ev), violations=violation_by_block(state.ev),
                         iterations=state.iteration, history=state.history, message=state.message,
                         wall_time_s=time.perf_counter() - state.started, convexify_time_s=state.convexify_time_s,
                         solver_time_s=state.solver_time_s, solver=self.solver_label,
                         kkt=None if state.kkt is None else state.kkt.summary(s.kkt_tolerance, s.feasibility_tolerance),
                         notes=tuple(state.escape_log), penalty=state.penalty)

    def run(self, x0: np.ndarray | None = None, penalty: float | None = None,
            until: Callable[[IterationState], bool] | None = None) -> SCPResult:
        """The loop from ``x0`` to its end; ``penalty`` starts the penalty weight (default: the policy's start);
        ``until``, asked after each iteration that did not end the run, stops it as ``stopped`` when it answers True."""
        state = self.initialize(x0, penalty)
        while not state.finished:
            self.step(state)
            if until is not None and not state.finished and until(state):
                state.finish("stopped", "stopped by its caller")
        return self.result(state)


def solve_scp(program: NonconvexProgram, settings: SCPSettings, log: Log | None = None,
              x0: np.ndarray | None = None) -> SCPResult:
    """Run the SCP loop on ``program`` from ``x0`` (default: its initial guess)."""
    return SCPAlgorithm(program, settings, log).run(x0)

