"""The size limit of a :class:`~convexguid.ocp.problem.Problem`: its memory estimated from the statement before
anything is transcribed, and a one-line refusal above the limit (:func:`convexguid.sizes.check_size`, as the YAML
families do).

Most of a transcription's memory is CasADi's symbolic graph: each interval evaluates the dynamics a few times
(Hermite-Simpson: at the nodes and the midpoint; a hold: four Runge-Kutta stages per substep), and every
evaluation copies the rate's instructions, then its Jacobian and the Lagrangian's Hessian copy them again.
Measured on this machine (x86_64, CasADi 3.8): Betts' shuttle reentry (97 instructions, 6 states, 2 controls)
takes 48 MB on 200 Hermite-Simpson intervals, 191 MB on 800, and 319 MB on 200 zero-order-hold intervals of 4
substeps; the brachistochrone (13 instructions) 62 MB on 3000 Hermite-Simpson intervals. :data:`BYTES_PER_COPY`
bounds all four from above. A closed-form flow (``"flow"``) copies its own instructions once an interval: the
rendezvous ``lcvx`` problem (:data:`BYTES_PER_FLOW_COPY`). The
mapped Chebyshev grid couples every node with every other in each defect row.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca

from convexguid.sizes import DEFAULT_MEMORY_LIMIT_BYTES, PROCESS_BYTES, SizeEstimate, check_size

if TYPE_CHECKING:
    from convexguid.ocp.problem import Problem

BYTES_PER_COPY = 1500.0
"""Memory per copied instruction of the dynamics in one interval (graph, Jacobian and Hessian together)."""

BYTES_PER_FLOW_COPY = 450.0
"""Memory per instruction of a closed-form flow in one interval. Measured on the rendezvous ``lcvx`` problem (a
Clohessy-Wiltshire flow with a held thrust, affine: no Hessian is built): 337 bytes coplanar on 2400 intervals,
390 in three dimensions on 10 000."""

BYTES_PER_SPECTRAL_TERM = 300.0
"""Memory per term of the Chebyshev differentiation in the defect rows ((nodes)^2 x states of them)."""


def estimate_size(problem: Problem) -> SizeEstimate:
    """The peak memory of solving ``problem`` as stated, from its size and its dynamics' instruction count."""
    from convexguid.scp.lagrangian import MAX_DENSE_SIZE  # the engine loads at the first solve, not with ocp

    nx, nu, N = len(problem.states), len(problem.controls), problem.intervals
    flow = problem.method == "flow"  # one copy of the closed-form flow an interval, no Runge-Kutta stages
    copied = (ca.vertcat(*(problem.transitions.get(v.name, v.symbol) for v in problem.states)) if flow
              else problem.rate_vector())
    instructions = ca.Function("copied", [problem.state_vector(), problem.control_vector(), problem.time],
                               [copied]).n_instructions() + nx + nu
    copies = {"flow": 1, "hermite-simpson": 3, "chebyshev": 1}.get(problem.method, 4 * problem.substeps)
    graph = (BYTES_PER_FLOW_COPY if flow else BYTES_PER_COPY) * instructions * copies * (N + 1)
    of = "flow's" if flow else "dynamics'"
    if problem.method == "chebyshev":
        graph += BYTES_PER_SPECTRAL_TERM * (N + 1) ** 2 * nx
    variables = (N + 1) * (nx + 2 * nu) + 1
    # up to MAX_DENSE_SIZE variables the SCP's end game holds a few dense n x n matrices
    dense = 4 * 8.0 * variables**2 if variables <= MAX_DENSE_SIZE else 0.0
    return SizeEstimate(PROCESS_BYTES + graph + dense, "transcription.intervals", N,
                        f"{N} {problem.method} intervals x {copies} copies of the {of} {instructions} instructions",
                        "give fewer intervals (problem.transcription(intervals), or --set for a build() parameter)")


def check_problem_size(problem: Problem, limit_bytes: float = DEFAULT_MEMORY_LIMIT_BYTES) -> None:
    """Refuse ``problem`` with one line if its estimate is above ``limit_bytes``."""
    check_size(problem.name, "ocp", estimate_size(problem), limit_bytes)


def check_phases_size(name: str, phases: list[Problem], limit_bytes: float = DEFAULT_MEMORY_LIMIT_BYTES) -> None:
    """Refuse a maneuver in phases with one line if its phases together are above ``limit_bytes`` (one process
    holds them all; each phase alone was checked by its own :meth:`~convexguid.ocp.problem.Problem.check`)."""
    estimates = [estimate_size(p) for p in phases]
    largest = max(range(len(phases)), key=lambda i: estimates[i].memory_bytes)
    total = PROCESS_BYTES + sum(e.memory_bytes - PROCESS_BYTES for e in estimates)
    check_size(name, "ocp", SizeEstimate(total, f"{phases[largest].name}.transcription.intervals",
                                         estimates[largest].value,
                                         f"{len(phases)} phases, the largest {estimates[largest].basis}",
                                         estimates[largest].fix), limit_bytes)
