"""Method ``scp_arcs``: Wang & Tang's burn/coast arcs as a maneuver in phases on :mod:`convexguid.ocp`, solved by SCP.

Each arc is a phase of a :class:`convexguid.ocp.Phases` statement (:func:`arc_phases`):

* a burn is a :class:`convexguid.ocp.Problem` with the Clohessy-Wiltshire dynamics of eq. (2) under the thrust
  acceleration :math:`a U`, the thrust direction :math:`U` its controls, :math:`|U|^2 = 1` a path equality at the
  nodes (eq. 11), transcribed by Hermite-Simpson on ``S`` equal sub-intervals with :math:`U` linear between the
  node values (eqs. 5-8: :math:`x_c = \\tfrac12(x_0 + x_1) + \\tfrac h8 (f_0 - f_1)`,
  :math:`U_c = \\tfrac12(U_0 + U_1)`, :math:`h = T_{burn}/S`), its objective its duration;
* a coast has no controls: its two nodes are mapped by the closed-form state transition matrix,
  :math:`X_{end} = \\Phi(T_{coast}) X_{start}` (eq. 9, :func:`~convexguid.dynamics.clohessy_wiltshire.cw_stm_casadi`),
  exact across its one interval;
* the arcs are continuous in the state from one to the next, :math:`\\sum T_i = t_f - t_0` and :math:`T_i \\ge 0`
  (eq. 11), the boundary states fixed at the maneuver's ends; the objective is the total burn time (eq. 10).

This is the paper's NLP with each coast's two end states carried once more (its own nodes, tied by continuity rows
to the burns or to the boundary states). The family reads and writes the paper's design vector (eq. 4,
:class:`~convexguid.families.rendezvous.arc_layout.ArcLayout`; :meth:`PhasedArcsProgram.design_vector`,
:meth:`PhasedArcsProgram.from_design_vector`) and reports the paper's counts (:meth:`PhasedArcsProgram.size`). The
Jacobians and the Lagrangian Hessian are CasADi's; the unit directions' curvature is carried into every subproblem
(:meth:`PhasedArcsProgram.curvature_model`). Started from the ``lcvx`` optimum
(:meth:`~convexguid.families.rendezvous.arc_layout.ArcsPlan.following`), the arcs may also open with a coast from
the initial state or close with one to the final state, where that optimum does (the paper's arcs start and end on
a burn, which a fixed-time rendezvous whose best burns sit inside the window cannot fly). The paper instead solves
the NLP with an exterior penalty (eq. 12).

(Before, the family wrote the same NLP by hand in numpy, with its Jacobians and sparsity patterns: 425 lines and
the Hermite-Simpson module under ``convexguid.transcription``. From the ``lcvx`` start the two plan the paper's
cases to the same burn time within 1.5e-13 (relative) and the same node directions within 1.3e-12, through the same
iterations and checks; their convex subproblems differ, so what reads the interior-point solver's answers to
round-off, the flown final-state error (4e-8 relative) and the KKT residuals, is not bit for bit the same.)

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003, eqs. (2)-(11).
"""

from __future__ import annotations

import math
from functools import cached_property

import casadi as ca
import numpy as np

from convexguid.dynamics.clohessy_wiltshire import cw_stm_casadi
from convexguid.families.rendezvous.arc_layout import ArcLayout, ArcsPlan
from convexguid.families.rendezvous.case import Rendezvous
from convexguid.ocp import Phases, Problem
from convexguid.ocp.phased import Link, PhasedProgram
from convexguid.ocp.solve import transcribe
from convexguid.scp.problem import CurvatureModel, ProgramSize

AXES = ("x", "y", "z")

SHORTEST_ARC = math.ulp(0.0)
"""The lower bound of every arc's duration: :math:`T_i \\ge 0` (eq. 11) as the positive lower bound
:meth:`~convexguid.ocp.problem.Problem.final_time` takes (the least positive number: an arc may shrink to nothing)."""


def state_scales(case: Rendezvous) -> np.ndarray:
    """Each state's scale (the trust region is a box in these units, the defects are divided by them): the largest
    boundary position, and the largest boundary velocity or a tenth of the velocity the engine can change over the
    maneuver, whichever is larger."""
    d = case.dim
    pos = max(np.abs(case.x0[:d]).max(), np.abs(case.xf[:d]).max(), 1.0)
    vel = max(np.abs(case.x0[d:]).max(), np.abs(case.xf[d:]).max(), case.accel * case.duration / 10)
    return np.concatenate([np.full(d, pos), np.full(d, vel)])


def cw_states(p: Problem, case: Rendezvous, initial: np.ndarray | None = None,
              final: np.ndarray | None = None) -> ca.SX:
    """The relative position and velocity as states of ``p`` (their scales :func:`state_scales`), fixed to
    ``initial`` and ``final`` where given; the column of them."""
    d, scales = case.dim, state_scales(case)
    labels = [*AXES[:d], *(f"v{axis}" for axis in AXES[:d])]
    return ca.vertcat(*(p.state(label, initial=None if initial is None else float(initial[i]),
                                final=None if final is None else float(final[i]), scale=float(scales[i]),
                                unit="m" if i < d else "m/s") for i, label in enumerate(labels)))


def arc_problem(case: Rendezvous, name: str, burn: bool, subintervals: int, initial: np.ndarray | None = None,
                final: np.ndarray | None = None) -> Problem:
    """One arc as a :class:`~convexguid.ocp.Problem` (see the module docstring), its states fixed to ``initial``
    and ``final`` where given. Its duration is free from :data:`SHORTEST_ARC` up; its guess, the maneuver's
    duration, is only the duration's scale (every arc's, as in the paper's design vector): the start is assembled
    from a design vector (:meth:`PhasedArcsProgram.from_design_vector`)."""
    p = Problem(name)
    d, x = case.dim, cw_states(p, case, initial, final)
    A, B = case.matrices()
    rates = ca.mtimes(ca.sparsify(ca.DM(A)), x)
    if burn:  # eq. (2) under full thrust along U, |U| = 1 at the nodes (eq. 11), Hermite-Simpson (eqs. 5-8)
        u = ca.vertcat(*(p.control(f"u{axis}", scale=1.0) for axis in AXES[:d]))
        rates += ca.mtimes(ca.sparsify(ca.DM(B)), u)
        p.path_equality("unit_thrust_direction", ca.sumsqr(u) - 1, at_midpoints=False, scale=1.0)
        p.minimize_time()
        p.transcription(subintervals, control="linear")
    else:  # the free motion in closed form (eq. 9), exact across one interval
        after = ca.mtimes(cw_stm_casadi(case.mean_motion, p.time, d), x)
        p.flow({x[i]: after[i] for i in range(case.nx)})
        p.transcription(1, "flow")
    p.dynamics({x[i]: rates[i] for i in range(case.nx)})
    p.final_time(bounds=(SHORTEST_ARC, None), guess=case.duration)
    return p


def arc_phases(case: Rendezvous, layout: ArcLayout) -> Phases:
    """The arcs of ``layout`` as phases in time order: each continuous in the state with the next, their durations
    adding up to the maneuver's (see the module docstring)."""
    arcs = layout.arcs()
    phases = [arc_problem(case, f"{kind}{index + 1}", kind == "burn", layout.subintervals,
                          case.x0 if i == 0 else None, case.xf if i == len(arcs) - 1 else None)
              for i, (kind, index) in enumerate(arcs)]
    statement = Phases(case.name, phases)
    for first, second in zip(phases[:-1], phases[1:], strict=True):
        statement.connect(first, second)
    statement.link("total_time", sum(p.duration for p in phases) - case.duration)
    return statement


class PhasedArcsProgram(ArcsPlan, PhasedProgram):
    """The arcs' phases (:func:`arc_phases`) transcribed as one :class:`~convexguid.ocp.phased.PhasedProgram`,
    started from the design vector ``guess`` (default :meth:`~ArcsPlan.paper_guess`)."""

    def __init__(self, case: Rendezvous, burns: int, subintervals: int, guess: np.ndarray | None = None,
                 lead_coast: bool = False, trail_coast: bool = False) -> None:
        self.case = case
        self.layout = ArcLayout(case.nx, case.nu, burns, subintervals, lead_coast, trail_coast)
        self.statement = arc_phases(case, self.layout)
        self.statement.check()
        phases = [transcribe(p) for p in self.statement.phases]
        start = self._assembled(phases, self.paper_guess() if guess is None else guess)
        super().__init__(phases, tuple(Link(*link) for link in self.statement.links), start)

    def _assembled(self, phases: list, x: np.ndarray) -> np.ndarray:
        """The phases' vector of the design vector ``x`` (each coast's ends: burn nodes or boundary states)."""
        case, lay = self.case, self.layout
        states, directions, durations = lay.split(x)
        pieces = []
        for (kind, index), program, duration in zip(lay.arcs(), phases, durations, strict=True):
            if kind == "burn":
                nodes = lay.burn_nodes(index)
                pieces.append(program.assemble(states[nodes], directions[nodes], duration))
                continue
            leaves, reaches = lay.coast_ends(index)
            ends = np.vstack([case.x0 if leaves is None else states[leaves],
                              case.xf if reaches is None else states[reaches]])
            pieces.append(program.assemble(ends, np.zeros((1, 0)), duration))
        return np.concatenate(pieces)

    def from_design_vector(self, x: np.ndarray) -> np.ndarray:
        """This program's vector of the design vector ``x`` (eq. 4)."""
        return self._assembled(self.phases, x)

    def design_vector(self, z: np.ndarray) -> np.ndarray:
        """The design vector (eq. 4) of this program's vector ``z``."""
        arcs = list(zip(self.layout.arcs(), self.phases, self.pieces(z), strict=True))
        burns = [(t, piece) for (kind, _), t, piece in arcs if kind == "burn"]
        return self.layout.join(np.vstack([t.states(piece) for t, piece in burns]),
                                np.vstack([t.node_controls(piece) for t, piece in burns]),
                                np.array([t.final_time(piece) for _, t, piece in arcs]))

    def size(self) -> ProgramSize:
        """The paper's counts: this program's variables and equality rows less each coast's two end states and the
        two rows that fix or connect each of them (the design vector holds them once); :math:`T_i \\ge 0`."""
        eliminated = 2 * self.case.nx * self.layout.num_coasts
        lin = self.linear_constraints()
        equalities = sum(b.values.size for b in self.evaluate(self.initial_guess(), jacobians=False).equalities)
        return ProgramSize(self.num_variables - eliminated, equalities + lin.A.shape[0] - eliminated,
                           lin.G.shape[0])

    def curvature_model(self) -> CurvatureModel:
        """Diagonal curvature :math:`2\\lambda_k` of :math:`\\lambda_k(|U_k|^2 - 1)` on the direction entries
        (raised to zero where negative).

        This is the term that keeps the subproblem from gaining thrust by turning
        :math:`U_k` along the tangent of the unit sphere (a linear model sees no cost in
        it); the other constraints' curvature is left to the trust region.
        """
        columns, rows = self._directions
        nu = columns.shape[1]

        def values(z: np.ndarray, weights) -> np.ndarray:
            return np.repeat(np.maximum(2.0 * weights.equality[rows], 0.0), nu)

        return CurvatureModel(columns.ravel(), columns.ravel(), values)

    @cached_property
    def _directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Every node direction's columns in ``z``, shape ``(num_nodes, nu)``, and the equality row of its unit
        norm (the burns' path equalities among the rows of :meth:`evaluate`)."""
        columns = [offset + t.control_start + np.arange(t.num_control_values).reshape(-1, t.nu)
                   for t, offset in zip(self.phases, self.offsets[:-1], strict=True) if t.nu]
        rows, start = [], 0
        for block in self.evaluate(self.initial_guess(), jacobians=False).equalities:
            if block.name.endswith(": path_equalities"):
                rows.append(start + np.arange(block.values.size))
            start += block.values.size
        return np.vstack(columns), np.concatenate(rows)
