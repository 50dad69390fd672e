"""Cross-check ``scp_arcs`` against an independent IPOPT solve of the same burn/coast NLP (Wang & Tang 2003).

The IPOPT reference (:mod:`convexguid.families.rendezvous.reference`) writes the Hermite-Simpson
defects and the Clohessy-Wiltshire coast map again in CasADi; its optimum must match the SCP's
burn time on the paper case and satisfy the numpy transcription's constraints, and the
rendezvous benchmark must run end to end.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

ca = pytest.importorskip("casadi")

from convexguid.dynamics.clohessy_wiltshire import cw_matrices  # noqa: E402
from convexguid.families.rendezvous.arc_phases import PhasedArcsProgram  # noqa: E402
from convexguid.families.rendezvous.bench import run_rendezvous_bench  # noqa: E402
from convexguid.families.rendezvous.case import build_case  # noqa: E402
from convexguid.families.rendezvous.reference import (  # noqa: E402
    ArcsReferenceResult,
    cw_free_motion,
    solve_rendezvous_arcs_ipopt,
)
from convexguid.problem_files import load_problem  # noqa: E402
from convexguid.scp.engine import SCPResult, solve_scp  # noqa: E402
from convexguid.scp.problem import SCPSettings  # noqa: E402

PAPER = Path(__file__).resolve().parents[1] / "problems" / "wang2003_rendezvous.yaml"
BURN_TIME_RTOL = 1e-4
"""SCP burn time within 1e-4 (relative) of IPOPT's on the same NLP."""


@pytest.fixture(scope="module")
def paper_solves() -> tuple[PhasedArcsProgram, SCPResult, ArcsReferenceResult]:
    """The paper case's arcs program, its SCP solution and its IPOPT solution, both from the initial guess."""
    spec = load_problem(PAPER, [])
    disc, s = spec.discretization, spec.solver
    program = PhasedArcsProgram(build_case(spec), disc.burns, disc.subintervals_per_burn)
    settings = SCPSettings(backend=s.backend, max_iterations=s.max_iterations, tolerance=s.tolerance,
                           trust_region=s.trust_region, penalty=s.penalty)
    scp = solve_scp(program, settings)
    ipopt = solve_rendezvous_arcs_ipopt(program, program.design_vector(program.initial_guess()))
    print(f"SCP {scp.status} {scp.objective:.12g} s ({scp.iterations} it); "
          f"IPOPT {ipopt.status} {ipopt.objective:.12g} s ({ipopt.iterations} it)")
    return program, scp, ipopt


def test_ipopt_converges_to_the_scp_burn_time(paper_solves):
    _, scp, ipopt = paper_solves
    assert ipopt.success, ipopt.status
    assert scp.status == "converged"
    assert ipopt.objective == pytest.approx(scp.objective, rel=BURN_TIME_RTOL)


def test_ipopt_optimum_satisfies_the_phased_statement(paper_solves):
    """The arcs stated in phases on convexguid.ocp hold at IPOPT's optimum too: every phase's defects and unit
    directions, the continuity and total-time rows, the boundary states and T >= 0; the same burn time."""
    phased, _, ipopt = paper_solves
    z = phased.from_design_vector(ipopt.x)
    for block in phased.evaluate(z, jacobians=False).equalities:
        assert np.max(np.abs(block.values)) < 1e-8, block.name
    lin = phased.linear_constraints()
    assert np.allclose(lin.A @ z, lin.b, rtol=0, atol=1e-6)
    assert np.all(lin.G @ z <= lin.h + 1e-9)
    assert ipopt.objective == pytest.approx(phased.linear_cost() @ z, rel=1e-14)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("dt", [0.5, 600.0, 5400.0])
def test_casadi_free_motion_matches_matrix_exponential(dim, dt):
    n = 0.0011313
    state, duration = ca.SX.sym("x", 2 * dim), ca.SX.sym("t")
    propagate = ca.Function("propagate", [state, duration], [cw_free_motion(ca, n, state, duration)])
    columns = np.column_stack([np.asarray(propagate(e, dt)).ravel() for e in np.eye(2 * dim)])
    A, _ = cw_matrices(n, 0.5, dim)
    assert np.allclose(columns, expm(A * dt), rtol=1e-12, atol=1e-12 * max(1.0, dt))


def test_bench_runs_and_lists_the_methods(tmp_path):
    out = tmp_path / "bench.md"
    assert run_rendezvous_bench(load_problem(PAPER), repeat=1, output=out) == 0
    text = out.read_text()
    for method in ("lcvx", "lcvx (cvxpy statement)", "scp_arcs", "ipopt"):
        assert f"| {method} |" in text
    assert "Targets:" in text
