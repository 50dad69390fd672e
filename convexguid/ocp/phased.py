"""A maneuver in phases as one program for the SCP engine, and its dense check.

Each phase is transcribed on its own (its method, grid, duration, margins); the decision vector is theirs end to
end, :math:`z = [z_1, \\dots, z_P]`, and every block of the engine's interface is theirs side by side (block
diagonal Jacobians, the phase's name before each block's). The links between phases are written on the phases'
end values, which are entries of ``z`` (a state at a phase's first or last node, its final time): a link affine in
them (the continuity of a state) is a hard row of :math:`Az = b` (an inequality one of :math:`Gz \\le h`); any
other is an equality or inequality the engine linearizes, divided by its magnitude (the change of its value when
every entry it uses moves by its own scale, at the first guess), as the defects are in the states' scales.

The dense check flies every phase from its own planned first node (:class:`~convexguid.ocp.check.DenseChecker`)
and judges each link on the flown ends: a phase whose own check fails is repaired as a single problem would be
(tightened or refined), and a link broken on the flown ends refines the phases whose end it uses, since the
drift is theirs.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import casadi as ca
import numpy as np
import scipy.sparse as sp

from convexguid.ocp.check import FINAL_TOLERANCE, DenseChecker
from convexguid.ocp.curvature import ElementCurvature
from convexguid.ocp.element_hessian import ElementHessian, element_hessian
from convexguid.ocp.parts import SparsityPattern, SymbolicNLP
from convexguid.ocp.transcription import Transcription
from convexguid.scp.check_repair import Check, Repair
from convexguid.scp.problem import (
    ConeBlock,
    ConstraintBlock,
    CurvatureModel,
    Evaluation,
    LinearConstraints,
    OutputConstraints,
)
from convexguid.verification import Verification


@dataclass(frozen=True)
class Link:
    """``expression == 0`` (or ``<= 0``, ``equality`` False) on the phases' end values
    (:meth:`~convexguid.ocp.problem.Problem.start`, :meth:`~convexguid.ocp.problem.Problem.end`)."""

    name: str
    expression: ca.SX
    equality: bool = True


@dataclass(frozen=True)
class Weights:
    """One phase's share of the engine's multipliers (what :meth:`Transcription.lagrangian_hessian` reads)."""

    equality: np.ndarray
    inequality: np.ndarray


def _shifted(matrix: sp.coo_matrix, column: int, width: int) -> sp.coo_matrix:
    """``matrix`` placed at ``column`` of a ``width``-column matrix (the same entries, in the same order)."""
    return sp.coo_matrix((matrix.data, (matrix.row, matrix.col + column)), shape=(matrix.shape[0], width))


class PhasedProgram:
    """The phases' transcriptions and their links as one :class:`~convexguid.scp.problem.NonconvexProgram`."""

    def __init__(self, phases: list[Transcription], links: tuple[Link, ...], guess: np.ndarray | None = None):
        self.phases = tuple(phases)
        self.links = links
        self.offsets = np.concatenate([[0], np.cumsum([t.num_variables for t in self.phases])]).astype(int)
        self.num_variables = int(self.offsets[-1])
        self._guess = guess
        self._build_links()
        self.affine = all(t.affine for t in self.phases) and not self.nonlinear

    def with_phases(self, phases: list[Transcription]) -> PhasedProgram:
        """The same links on other transcriptions of the phases (a repair's)."""
        return PhasedProgram(phases, self.links)

    def pieces(self, z: np.ndarray) -> list[np.ndarray]:
        """Each phase's part of ``z``."""
        return [np.asarray(z[a:b]) for a, b in zip(self.offsets[:-1], self.offsets[1:], strict=True)]

    def names(self) -> list[str]:
        return [t.problem.name for t in self.phases]

    def final_time(self, z: np.ndarray) -> float:
        """The maneuver's duration: the phases' durations added."""
        return sum(t.final_time(piece) for t, piece in zip(self.phases, self.pieces(z), strict=True))

    def final_values(self, z: np.ndarray) -> dict[str, float]:
        """The last phase's last node's states by name."""
        return self.phases[-1].final_values(self.pieces(z)[-1])

    # --- links --------------------------------------------------------------------------------------------------
    def _reference_index(self, name: str) -> tuple[int, str, int]:
        """``(phase, "start" or "end", state index or -1 for the duration)`` of an end reference's name."""
        for i, t in enumerate(self.phases):
            if name in t.problem.ends:
                return (i, *t.problem.ends[name])
        raise KeyError(name)

    def phases_ending_in(self, link: Link) -> set[int]:
        """The phases whose end values (not start values) ``link`` uses."""
        ends = (self._reference_index(str(s)) for s in ca.symvar(ca.SX(link.expression)))
        return {phase for phase, which, _ in ends if which == "end"}

    def _reference_in_z(self, z: ca.SX, name: str):
        i, which, index = self._reference_index(name)
        t, offset = self.phases[i], self.offsets[i]
        if index < 0:
            return z[offset + t.num_variables - 1] if t.free_time else ca.DM(t.problem.tf)
        return z[offset + (0 if which == "start" else t.N) * t.nx + index]

    def _build_links(self) -> None:
        expressions = [ca.SX(link.expression) for link in self.links]
        rows = ca.vertcat(*expressions) if expressions else ca.SX(0, 1)
        per_row = [link for link, e in zip(self.links, expressions, strict=True) for _ in range(e.shape[0])]
        self.link_names = [link.name for link in per_row]
        self.link_equality = np.array([link.equality for link in per_row], dtype=bool)
        references = ca.symvar(rows)
        self._references = [str(r) for r in references]
        z = ca.SX.sym("z", self.num_variables)
        rows_in_z = ca.substitute(rows, ca.vertcat(*references), ca.vertcat(*(
            self._reference_in_z(z, name) for name in self._references))) if references else rows
        jacobian = ca.jacobian(rows_in_z, z)
        affine = np.array([not ca.depends_on(jacobian[r, :], z) for r in range(rows.shape[0])], dtype=bool)
        guess = self.initial_guess()
        value, slope = (np.asarray(v, dtype=float) for v in ca.Function("links", [z], [rows_in_z, jacobian])(guess))
        magnitude = np.abs(slope) @ self.variable_scale()
        self.link_magnitudes = np.where(magnitude > 0, magnitude, 1.0)
        # the affine links: hard rows A z = b or G z <= h (their value is slope z - b, exactly)
        offset = slope @ guess - value.ravel()
        self._affine = {equality: (sp.coo_matrix(slope[affine & (self.link_equality == equality)]),
                                   offset[affine & (self.link_equality == equality)]) for equality in (True, False)}
        # the others: an equality block and an inequality block the engine linearizes, each row in its magnitude
        self._symbols, self._blocks = z, {}
        for equality in (True, False):
            chosen = np.flatnonzero(~affine & (self.link_equality == equality))
            block = rows_in_z[chosen.tolist(), 0] / ca.DM(self.link_magnitudes[chosen])
            self._blocks[equality] = (block, ca.Function("nonlinear_links", [z], [block, ca.jacobian(block, z)]),
                                      SparsityPattern(ca.jacobian(block, z).sparsity()))
        self.nonlinear = any(self._blocks[e][0].shape[0] for e in (True, False))
        self._on_ends = ca.Function("links_on_ends", [ca.vertcat(*references)] if references else [ca.SX(0, 1)],
                                    [rows / ca.DM(self.link_magnitudes)])

    def link_errors(self, starts: list[np.ndarray], ends: list[np.ndarray], durations: list[float]) -> np.ndarray:
        """How far each link row is broken, in its magnitude, on given phase ends (the flown ones in the dense
        check): an equality's absolute value, an inequality's excess."""
        values = []
        for name in self._references:
            i, which, index = self._reference_index(name)
            values.append(durations[i] if index < 0 else (starts if which == "start" else ends)[i][index])
        errors = np.asarray(self._on_ends(np.array(values)), dtype=float).ravel()
        return np.where(self.link_equality, np.abs(errors), np.maximum(errors, 0.0))

    # --- NonconvexProgram ---------------------------------------------------------------------------------------
    def initial_guess(self) -> np.ndarray:
        if self._guess is not None:
            return self._guess
        return np.concatenate([t.initial_guess() for t in self.phases])

    def variable_scale(self) -> np.ndarray:
        return np.concatenate([t.variable_scale() for t in self.phases])

    def residual_weights(self) -> np.ndarray:
        return np.concatenate([t.residual_weights() for t in self.phases])

    def linear_cost(self) -> np.ndarray:
        return np.concatenate([t.linear_cost() for t in self.phases])

    def linear_constraints(self) -> LinearConstraints:
        parts = [t.linear_constraints() for t in self.phases]
        (A_link, b_link), (G_link, h_link) = self._affine[True], self._affine[False]
        A = sp.vstack([sp.block_diag([sp.coo_matrix(c.A) for c in parts]), A_link]).tocoo()
        G = sp.vstack([sp.block_diag([sp.coo_matrix(c.G) for c in parts]), G_link]).tocoo()
        return LinearConstraints(A, np.concatenate([*(c.b for c in parts), b_link]), G,
                                 np.concatenate([*(c.h for c in parts), h_link]))

    def output_constraints(self) -> OutputConstraints:
        return OutputConstraints.none(self.residual_weights().size)

    def evaluate(self, z: np.ndarray, jacobians: bool = True) -> Evaluation:
        n = self.num_variables
        residuals, residual_jacobians, inequalities, equalities, cones = [], [], [], [], []
        for t, offset, piece in zip(self.phases, self.offsets, self.pieces(z), strict=False):
            ev = t.evaluate(piece, jacobians)
            residuals.append(ev.residuals)
            if jacobians:
                residual_jacobians.append(_shifted(sp.coo_matrix(ev.residual_jacobian), offset, n))
            for blocks, out in ((ev.inequalities, inequalities), (ev.equalities, equalities)):
                out += [ConstraintBlock(f"{t.problem.name}: {b.name}", b.values,
                                        _shifted(b.jacobian, offset, n) if jacobians else None, b.unit, b.labels)
                        for b in blocks]
            cones += [ConeBlock(f"{t.problem.name}: {c.name}", c.values,
                                _shifted(c.jacobian, offset, n) if jacobians else None, c.sizes, c.unit)
                      for c in ev.cones]
        for equality, out in ((True, equalities), (False, inequalities)):
            block, function, pattern = self._blocks[equality]
            if block.shape[0]:
                value, jacobian = function(z)
                out.append(ConstraintBlock("links" if equality else "link_constraints",
                                           np.asarray(value, dtype=float).ravel(),
                                           pattern.coo(jacobian) if jacobians else None))
        residual_jacobian = (sp.vstack(residual_jacobians).tocoo() if residual_jacobians else None)
        return Evaluation(np.concatenate(residuals), residual_jacobian, tuple(inequalities), tuple(equalities),
                          tuple(cones))

    @cached_property
    def _row_counts(self) -> list[tuple[int, int]]:
        """Each phase's equality and (nonlinear) inequality rows, in the order of :meth:`evaluate`."""
        counts = []
        for t, piece in zip(self.phases, self.pieces(self.initial_guess()), strict=True):
            ev = t.evaluate(piece, jacobians=False)
            counts.append((sum(b.values.size for b in ev.equalities), sum(b.values.size for b in ev.inequalities)))
        return counts

    @cached_property
    def _link_hessian(self) -> ElementHessian:
        """The nonlinear links' curvature (equalities, then inequalities), each link its own element."""
        links = ca.vertcat(self._blocks[True][0], self._blocks[False][0])
        return element_hessian(self._symbols, links, np.arange(links.shape[0]))

    def _shares(self, weights) -> tuple[list[Weights], Weights]:
        """Each phase's share of the engine's multipliers, and the links' (after every phase's)."""
        shares, equality, inequality = [], 0, 0
        for m_eq, m_in in self._row_counts:
            shares.append(Weights(weights.equality[equality: equality + m_eq],
                                  weights.inequality[inequality: inequality + m_in]))
            equality, inequality = equality + m_eq, inequality + m_in
        # the links' inequality rows come before the cones' (the engine lists the cones last)
        links = inequality + self._blocks[False][0].shape[0]
        return shares, Weights(weights.equality[equality:], weights.inequality[inequality: links])

    def lagrangian_hessian(self, z: np.ndarray, weights) -> sp.csr_matrix:
        """The phases' exact Lagrangian Hessians side by side, and the nonlinear links' curvature."""
        shares, links = self._shares(weights)
        hessian = sp.block_diag([t.lagrangian_hessian(piece, share) for t, piece, share
                                 in zip(self.phases, self.pieces(z), shares, strict=True)]).tocsr()
        if self.nonlinear:
            hessian = hessian + self._link_hessian.matrix(z, np.concatenate([links.equality, links.inequality]))
        return hessian

    def curvature_model(self) -> CurvatureModel | None:
        """The phases' convex curvature models side by side (:meth:`Transcription.curvature_model`), and the
        nonlinear links', each link its own element; None when every map is affine."""
        models = [t.curvature_model() for t in self.phases]
        links = self._link_curvature
        if links.empty and all(model is None for model in models):
            return None
        placed = [(model, offset) for model, offset in zip(models, self.offsets[:-1], strict=True) if model is not None]
        rows = np.concatenate([model.rows + offset for model, offset in placed] + [links.rows])
        cols = np.concatenate([model.cols + offset for model, offset in placed] + [links.cols])

        def values(z: np.ndarray, weights) -> np.ndarray:
            shares, link_weights = self._shares(weights)
            parts = [model.values(piece, share) for model, piece, share
                     in zip(models, self.pieces(z), shares, strict=True) if model is not None]
            return np.concatenate(parts + [links.values(z, np.concatenate([link_weights.equality,
                                                                           link_weights.inequality]))])

        return CurvatureModel(rows, cols, values)

    @cached_property
    def _link_curvature(self) -> ElementCurvature:
        """Each nonlinear link its own element."""
        return ElementCurvature(self._link_hessian)

    def symbolic_nlp(self) -> SymbolicNLP:
        """Every phase's NLP on its part of one decision vector, and the links (the IPOPT reference reads it)."""
        z = ca.SX.sym("z", self.num_variables)
        objective, blocks = 0, []
        for t, a, b in zip(self.phases, self.offsets[:-1], self.offsets[1:], strict=True):
            nlp = t.symbolic_nlp(z[int(a): int(b)])
            objective += nlp.objective
            blocks += [(f"{t.problem.name}: {name}", e, lower, upper) for name, e, lower, upper in nlp.blocks]
        for equality in (True, False):
            (matrix, right), block = self._affine[equality], self._blocks[equality][0]
            lower = 0.0 if equality else -np.inf
            name = "links" if equality else "link_constraints"
            blocks += [(name, ca.substitute(block, self._symbols, z), lower, 0.0),
                       (f"linear_{name}", ca.DM(matrix.toarray()) @ z - right, lower, 0.0)]
        return SymbolicNLP(z, objective, tuple(blocks))


@dataclass(frozen=True)
class PhasedTrack:
    """The dense check of every phase (its verification and track), in order, and each link row's error on the
    flown ends (:meth:`PhasedProgram.link_errors`)."""

    phases: tuple[Check, ...]
    link_errors: np.ndarray


class PhasedChecker:
    """:class:`~convexguid.scp.check_repair.PlanChecker` of a :class:`PhasedProgram`."""

    def __init__(self, points: int = 20) -> None:
        self.single = DenseChecker(points)

    def check(self, program: PhasedProgram, z: np.ndarray) -> Check:
        checks = tuple(self.single.check(t, piece) for t, piece in zip(program.phases, program.pieces(z),
                                                                        strict=True))
        tracks = [c.track for c in checks]
        errors = program.link_errors([tr.x[0] for tr in tracks], [tr.x[-1] for tr in tracks],
                                     [float(tr.t[-1]) for tr in tracks])
        named = list(zip(program.names(), checks, strict=True))
        final_errors = {f"{name}.{key}": value for name, c in named
                        for key, value in c.verification.final_errors.items()}
        for label, error in zip(program.link_names, errors, strict=True):
            final_errors[f"link_{label}_error"] = max(final_errors.get(f"link_{label}_error", 0.0), float(error))
        constraint_checks = tuple(replace(k, name=f"{name}.{k.name}")
                                  for name, c in named for k in c.verification.checks)
        passed = all(c.verification.passed for c in checks) and float(errors.max(initial=0.0)) <= FINAL_TOLERANCE
        verification = Verification(sum(c.verification.grid_points for c in checks), constraint_checks,
                                    max(final_errors.values(), default=0.0), final_errors, passed,
                                    checks[0].verification.tolerances,
                                    tuple(f"{name}: {r}" for name, c in named for r in c.verification.remarks))
        return Check(verification, PhasedTrack(checks, errors))

    def repair(self, program: PhasedProgram, z: np.ndarray, check: Check, attempt: int) -> Repair | None:
        """Repair each phase whose own check failed as a single problem's; refine each phase whose end a link
        broken on the flown ends uses (the drift is that phase's). None when any of them has no repair left."""
        checks, errors = check.track.phases, check.track.link_errors
        broken = {program.link_names[r] for r in np.flatnonzero(errors > FINAL_TOLERANCE)}
        drifted = {i for link in program.links if link.name in broken for i in program.phases_ending_in(link)}
        phases, starts, notes = list(program.phases), program.pieces(z), []
        for i, (t, piece, c) in enumerate(zip(program.phases, starts, checks, strict=True)):
            if c.verification.passed and i not in drifted:
                continue
            repair = self.single.repair(t, piece, c, attempt) if not c.verification.passed else \
                self.single.refine(t, piece, c)
            if repair is None:
                return None
            phases[i], starts[i] = repair.program, repair.x0
            notes.append(f"{t.problem.name}: {repair.description}")
        return Repair(program.with_phases(phases), np.concatenate(starts), "; ".join(notes))
