"""Two problems of OpenSCvx 0.5.2's examples solved by convexguid and by OpenSCvx on the same numbers, timed in the
same run, each plan judged on the same yardsticks on its own dense propagation; writes validation/BENCHMARKS_ocp.md.
The proximity operation (examples/proxops_openscvx.py) and the 6-DoF powered descent (examples/rocket_6dof_pdg.py),
the latter with IPOPT's final mass on convexguid's transcription beside them.

OpenSCvx (JAX) is not a convexguid dependency: give the Python that has it, e.g. a virtual environment made with
``python -m venv --system-site-packages venv && venv/bin/pip install openscvx``:

    python -m convexguid.benches.openscvx --openscvx-python venv/bin/python
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.integrate import trapezoid

from convexguid.bench_common import bench_document, markdown_grid
from convexguid.outputs import write_text_atomic

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
"""The checkout's examples folder, whose problem modules this benchmark solves."""

# What every OpenSCvx script starts and ends with: openscvx imported before diffrax (it sets EQX_ON_ERROR, without
# which JAX cannot export the discretization), the clock started after the imports, then set-up, solve and
# post-process timed apart, and the propagated trajectory (x_full, u_full on t_full) printed as JSON
OPENSCVX_HEAD = r'''
import json, sys, time
import numpy as np
import openscvx as ox
import diffrax as dfx
t0 = time.perf_counter()
'''
OPENSCVX_TAIL = r'''
problem.initialize()
setup = time.perf_counter() - t0
t0 = time.perf_counter(); problem.solve(); solve = time.perf_counter() - t0
t0 = time.perf_counter(); res = problem.post_process(); post = time.perf_counter() - t0
print()
json.dump({"setup_s": setup, "solve_s": solve, "post_process_s": post, "converged": bool(res.converged),
           "iterations": len(res.X) - 1, "t": np.asarray(res.t_full).ravel().tolist(),
           "x": np.asarray(res.x_full).tolist(), "u": np.asarray(res.u_full).tolist()}, sys.stdout)
'''

# examples/spacecraft/proxops_cw.py's numbers and settings: 5 nodes, zero-order hold, Dopri8, lam_vb 0.1, the cone over
# the last two intervals, the entrance at the middle node; no cost term
OPENSCVX_PROXOPS = r'''
nodes, n = 5, np.sqrt(3.986004418e14 / 6.778e6**3)
r = ox.State("position", shape=(3,)); r.max = np.full(3, 100.0); r.min = -r.max
r.initial = np.array([0.0, -100.0, 0.0]); r.final = np.zeros(3)
v = ox.State("velocity", shape=(3,)); v.max = np.full(3, 2.0); v.min = -v.max
v.initial = [0.0, 2.0, 0.0]; v.final = np.zeros(3); v.guess = np.zeros((nodes, 3))
a = ox.Control("accel", shape=(3,), parameterization="ZOH")
a.max = np.full(3, 0.1); a.min = -a.max; a.guess = np.zeros((nodes, 3))
cons = [c for s in (r, v) for c in (ox.ctcs(s <= s.max), ox.ctcs(s.min <= s))]
cons.append(ox.ctcs(ox.linalg.Norm(r[1:]) <= np.tan(np.radians(20.0)) * (-r[0])).over((nodes - 3, nodes - 1)))
cons.append((-r[0] >= 20.0).at([nodes - 3]))
dyn = {"position": v, "velocity": ox.Concat(3 * n**2 * r[0] + 2 * n * v[1] + a[0], -2 * n * v[0] + a[1],
                                            -(n**2) * r[2] + a[2])}
problem = ox.Problem(dynamics=dyn, states=[r, v], controls=[a], constraints=cons, N=nodes,
                     time=ox.Time(initial=0.0, final=("free", 180.0), min=0.0, max=180.0),
                     algorithm={"lam_vb": 1e-1}, discretizer={"ode_solver": "Dopri8"})
'''

# examples/rocket/6DoF_pdg.py's numbers: 5 nodes, first-order hold, its bounds, boundary values, thrust guess, eight
# CTCS path constraints (0.1 on the first term of five), time and algorithm settings, float64; its solver setting
# (cvxpygen's generated QOCO) needs cvxpygen and a compiler: here QOCO through CVXPY, OpenSCvx's default
OPENSCVX_6DOF = r'''
nodes, w_max, rad = 5, 0.3752, np.pi / 180.0
def state(name, size, bound, initial, final):
    s = ox.State(name, shape=(size,)); s.min, s.max = list(bound[0]), list(bound[1])
    s.initial, s.final = initial, final
    return s
m = state("mass", 1, ([1.0], [2.0]), [2.0], [ox.Maximize(1.5)])
r = state("position", 3, ([-10.0] * 3, [10.0] * 3), [ox.Free(7.5), ox.Free(4.5), ox.Free(2.5)],
          [ox.Free(0.0), ox.Free(0.0), 0.0])
v = state("velocity", 3, ([-3.0] * 3, [3.0] * 3), [-0.5, -2.8, 0.0], [-0.1, 0.0, 0.0])
q = state("attitude", 4, ([-1.0] * 4, [1.0] * 4), [ox.Free(0.0)] * 3 + [ox.Free(1.0)], [0.0, 0.0, 0.0, 1.0])
w = state("angular_velocity", 3, ([-w_max] * 3, [w_max] * 3), [1e-8, 0.0, 0.0], [1e-8, 0.0, 0.0])
T = ox.Control("thrust", shape=(3,)); T.min, T.max = [-6.5] * 3, [6.5] * 3
T.guess = np.outer(np.linspace(2.0, 1.0, nodes), [1.0, 0.0, 0.0])
q1, q2, q3, q4 = (q[i] for i in range(4))
w1, w2, w3 = (w[i] for i in range(3))
to_inertial = ox.Block([[q4**2 + q1**2 - q2**2 - q3**2, 2 * (q1 * q2 - q4 * q3), 2 * (q4 * q2 + q1 * q3)],
                        [2 * (q4 * q3 + q1 * q2), q4**2 - q1**2 + q2**2 - q3**2, 2 * (q2 * q3 - q4 * q1)],
                        [2 * (q1 * q3 - q4 * q2), 2 * (q4 * q1 + q2 * q3), q4**2 - q1**2 - q2**2 + q3**2]])
def cross(a, b):
    return ox.Concat(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
J = ox.Diag(np.array([0.168 * 2e-2, 0.168, 0.168]))
aero = -0.5 * 1.0 * ox.linalg.Norm(v) * 0.5 * ox.Diag(ox.Concat(0.5, 1.0, 1.0)) @ to_inertial.T @ v
dyn = {"mass": -ox.linalg.Norm(T) / 30.0 - 0.01, "position": v,
       "velocity": to_inertial @ (T + aero) / m[0] + ox.Concat(-1.0, 0.0, 0.0),
       "attitude": 0.5 * ox.Concat(w1 * q4 - w2 * q3 + w3 * q2, w1 * q3 - w3 * q1 + w2 * q4,
                                   w2 * q1 - w1 * q2 + w3 * q4, -(w1 * q1 + w2 * q2 + w3 * q3)),
       "angular_velocity": ox.Inv(J) @ (cross(ox.Concat(-0.25, 0.0, 0.0), T)
                                        + cross(ox.Concat(0.05, 0.0, 0.0), aero) - cross(w, J @ w))}
states = [m, r, v, q, w]
cons = [c for s in states for c in (ox.ctcs(s <= s.max), ox.ctcs(s.min <= s))]
cons += [(r == np.array([7.5, 4.5, 2.5])).convex().at([0]), (r[0:2] == np.zeros(2)).convex().at([nodes - 1]),
         ox.ctcs(m - 1.0 >= 0),
         ox.ctcs(0.1 * ox.linalg.Norm(r[1:]) - ox.Tan(ox.Constant(np.array(75 * rad))) * r[0] <= 0),
         ox.ctcs(0.1 * ox.linalg.Norm(v) ** 2 - 3.0**2 <= 0),
         ox.ctcs(ox.Cos(ox.Constant(np.array(75 * rad))) - 1.0 + 2.0 * (q2**2 + q3**2) <= 0),
         ox.ctcs(ox.linalg.Norm(w) ** 2 - w_max**2 <= 0),
         ox.ctcs(0.1 * ox.linalg.Norm(T) - T[0] / ox.Cos(ox.Constant(np.array(20 * rad))) <= 0),
         ox.ctcs(0.1 * ox.linalg.Norm(T) ** 2 - 6.5**2 <= 0),
         ox.ctcs(0.1 * 1.5**2 - ox.linalg.Norm(T) ** 2 <= 0)]
problem = ox.Problem(
    dynamics=dyn, states=states, controls=[T], constraints=cons, N=nodes, float_dtype="float64",
    time=ox.Time(initial=0.0, final=ox.Free(10.0), min=0.0, max=10.0, time_dilation_min=2.0, time_dilation_max=20.0),
    algorithm={"autotuner": ox.ConstantProximalWeight(), "lam_cost": 1e-2, "lam_vc": 1e1, "lam_prox": 1e0,
               "ep_tr": 5e-3, "ep_vc": 1e-6},
    discretizer={"diffrax_kwargs": {"stepsize_controller": dfx.StepTo(np.linspace(0.0, 1 / (nodes - 1), 3))}})
problem.settings.dev.printing = False
'''


def judge_proxops(t: np.ndarray, x: np.ndarray, u: np.ndarray) -> dict:
    """Fuel (trapezoid on |a|), the largest cone excess over the second half (m, lateral distance beyond the cone),
    the entrance depth at half time, the largest acceleration and the final position and speed errors."""
    tf = t[-1]
    second = t >= 0.5 * tf - 1e-9
    lateral = np.hypot(x[second, 1], x[second, 2])
    cone = float(np.max(lateral - np.tan(np.radians(20.0)) * (-x[second, 0])))
    return {"final_time_s": float(tf), "fuel_mps": float(trapezoid(np.abs(u).sum(axis=1), t)),
            "cone_excess_m": cone, "entrance_depth_m": float(-np.interp(0.5 * tf, t, x[:, 0])),
            "max_accel": float(np.abs(u).max()), "final_position_error_m": float(np.linalg.norm(x[-1, :3])),
            "final_speed_error_mps": float(np.linalg.norm(x[-1, 3:6]))}


def judge_descent(t: np.ndarray, x: np.ndarray, u: np.ndarray) -> dict:
    """Final mass and time, final position and velocity errors, the largest excess over each path constraint as
    examples/rocket_6dof_pdg.py writes them (positive: broken; each in the units of its norm form) and the largest
    thrust component."""
    pdg = _example("rocket_6dof_pdg")
    r, v, q, w, thrust = x[:, 1:4], x[:, 4:7], x[:, 7:11], x[:, 11:14], np.linalg.norm(u, axis=1)
    excess = {"body_rate": np.linalg.norm(w, axis=1) - pdg.W_MAX,
              "thrust_min": math.sqrt(pdg.WEIGHT) * pdg.T_MIN - thrust,
              "glide_slope": pdg.WEIGHT * np.hypot(r[:, 1], r[:, 2]) - math.tan(pdg.GLIDE_SLOPE) * r[:, 0],
              "tilt": math.cos(pdg.TILT_MAX) - 1 + 2 * (q[:, 1] ** 2 + q[:, 2] ** 2),
              "gimbal": pdg.WEIGHT * thrust - u[:, 0] / math.cos(pdg.GIMBAL_MAX)}
    return {"final_mass": float(x[-1, 0]), "final_time_s": float(t[-1]),
            "final_position_error": float(np.linalg.norm(r[-1])),
            "final_velocity_error": float(np.linalg.norm(v[-1] - pdg.FINAL_V)),
            **{f"{name}_excess": float(e.max()) for name, e in excess.items()},
            "max_thrust_component": float(np.abs(u).max())}


class Case(NamedTuple):
    """One problem: convexguid's example module and the settings it runs with, its state and control columns in
    OpenSCvx's order (OpenSCvx appends time and constraint integrals to the states, time dilation to the controls),
    OpenSCvx's statement and the yardsticks."""

    example: str
    settings: dict
    states: tuple[str, ...]
    controls: tuple[str, ...]
    openscvx: str
    judge: Callable[[np.ndarray, np.ndarray, np.ndarray], dict]


def proxops(intervals: int) -> Case:
    return Case("proxops_openscvx", {"intervals": intervals}, ("x", "y", "z", "vx", "vy", "vz"), ("ax", "ay", "az"),
                OPENSCVX_PROXOPS, judge_proxops)


DESCENT = Case("rocket_6dof_pdg", {}, ("m", "r1", "r2", "r3", "v1", "v2", "v3", "q1", "q2", "q3", "q4", "w1", "w2",
                                       "w3"), ("T1", "T2", "T3"), OPENSCVX_6DOF, judge_descent)


def _example(name: str):
    """The module of examples/``name``.py."""
    if str(EXAMPLES) not in sys.path:
        sys.path.insert(0, str(EXAMPLES))
    return importlib.import_module(name)


def run_convexguid(case: Case) -> dict:
    """The example with ``case.settings``, timed from the problem's statement to the verified plan (imports before
    the clock, as OpenSCvx's set-up is timed after its import), then the same as a command."""
    build = _example(case.example).build
    import convexguid.ocp.solve  # noqa: F401 - the engine and SciPy load before the clock starts

    started = time.perf_counter()
    solution = build(**case.settings).solve()
    wall = time.perf_counter() - started
    dense = solution.dense.columns
    x = np.column_stack([dense[k] for k in case.states])
    u = np.column_stack([dense[k] for k in case.controls])
    # the command a user types, from the installation this benchmark runs in (not whatever is first on PATH)
    command = [str(Path(sys.executable).parent / "convexguid"), "solve", str(EXAMPLES / f"{case.example}.py"),
               "--quiet", *(a for k, value in case.settings.items() for a in ("--set", f"{k}={value}"))]
    started = time.perf_counter()
    process = subprocess.run(command, capture_output=True, text=True, check=False)
    process_s = time.perf_counter() - started
    if process.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} ended with exit {process.returncode}: "
                           f"{process.stderr.strip()[-300:]}")
    return {**case.settings, "wall_s": wall, "process_s": process_s, "status": solution.status,
            "verified": bool(solution.verification.passed), "iterations": solution.iterations,
            **case.judge(solution.dense.t, x, u)}


def run_openscvx(python: str, case: Case) -> dict:
    started = time.perf_counter()
    process = subprocess.run([python, "-c", OPENSCVX_HEAD + case.openscvx + OPENSCVX_TAIL], capture_output=True,
                             text=True, check=True)
    process_s = time.perf_counter() - started
    out = json.loads(process.stdout.strip().splitlines()[-1])
    t, x, u = np.array(out["t"]), np.array(out["x"]), np.array(out["u"])
    return {**{k: out[k] for k in ("setup_s", "solve_s", "post_process_s", "converged", "iterations")},
            "process_s": process_s, **case.judge(t, x[:, :len(case.states)], u[:, :len(case.controls)])}


def ipopt_final_mass() -> dict:
    """IPOPT (exact Hessian, through CasADi) on convexguid's transcription of the 6-DoF descent, from its guess, as
    convexguid.benches.ocp_examples runs it: its final mass and time at the nodes (not re-propagated)."""
    from convexguid.ocp.reference import solve_with_ipopt
    from convexguid.ocp.solve import transcribe

    program = transcribe(_example("rocket_6dof_pdg").build())
    answer = solve_with_ipopt(program)
    return {"status": answer.status, "iterations": answer.iterations, "setup_s": answer.setup_s,
            "solve_s": answer.solve_s, "final_mass": -answer.objective, "final_time_s": program.final_time(answer.z)}


def ours_row(run: dict, label: str, objective: str) -> list[str]:
    return [f"convexguid (this repository), {label}", objective,
            f"{run['wall_s']:.3f} (set-up, {run['iterations']} SCP iterations, dense check)", f"{run['process_s']:.2f}",
            run["status"] + (" (dense check passed)" if run["verified"] else " (dense check failed)")]


def theirs_row(run: dict, label: str, objective: str) -> list[str]:
    return [f"OpenSCvx 0.5.2, {label}", objective,
            f"{run['setup_s']:.2f} set-up + {run['solve_s']:.3f} solve ({run['iterations']} SCP iterations) "
            f"+ {run['post_process_s']:.2f} post-process", f"{run['process_s']:.2f}",
            "converged" if run["converged"] else "not converged"]


def tables(rows: list[list[str]], keys: list[tuple[str, str, str]], plans: list[tuple[str, dict]]) -> str:
    """The timing table of ``rows`` and the answers table: one line per figure of ``keys`` (key, label, format),
    one column per plan of ``plans`` (heading, figures)."""
    timing = markdown_grid(["method", "objective", "in-process time [s]", "as a process [s]", "status"],
                           ["---", "---", "---", "---:", "---"], rows)
    answers = markdown_grid(["figure (each plan's own dense propagation)", *(name for name, _ in plans)],
                            ["---", *("---:" for _ in plans)],
                            [[label, *(format(run[k], f) for _, run in plans)] for k, label, f in keys])
    return timing + "\n\n" + answers


def proxops_section(ours: list[dict], theirs: dict) -> str:
    rows = [*(ours_row(run, f"{run['intervals']} FOH intervals", "min fuel") for run in ours),
            theirs_row(theirs, "its 5 nodes, ZOH", "none (cost 0)")]
    keys = [("final_time_s", "final time [s]", ".3f"), ("fuel_mps", "fuel, integral of |a_x|+|a_y|+|a_z| [m/s]", ".4f"),
            ("cone_excess_m", "largest distance outside the cone, second half [m]", ".2e"),
            ("entrance_depth_m", "depth below the target at half time [m] (>= 20)", ".3f"),
            ("max_accel", "largest acceleration component [m/s^2] (<= 0.1)", ".4f"),
            ("final_position_error_m", "final position error [m]", ".2e"),
            ("final_speed_error_mps", "final speed error [m/s]", ".2e")]
    return tables(rows, keys, [*((f"convexguid, {run['intervals']} intervals", run) for run in ours),
                               ("OpenSCvx", theirs)])


def descent_section(ours: dict, theirs: dict, ipopt: dict) -> str:
    rows = [ours_row(ours, "20 ZOH intervals", "max final mass"),
            theirs_row(theirs, "its 5 FOH nodes", "max final mass (weight 0.01)"),
            ["IPOPT on convexguid's transcription (20 ZOH intervals)", "max final mass",
             f"{ipopt['setup_s']:.3f} set-up + {ipopt['solve_s']:.3f} solve ({ipopt['iterations']} iterations)", "-",
             f"{ipopt['status']}: final mass {ipopt['final_mass']:.6f}, final time {ipopt['final_time_s']:.4f} "
             "(at the nodes, not re-propagated)"]]
    keys = [("final_mass", "final mass", ".6f"), ("final_time_s", "final time", ".4f"),
            ("final_position_error", "final position error, |r(tf)|", ".2e"),
            ("final_velocity_error", "final velocity error, |v(tf) - (-0.1, 0, 0)|", ".2e"),
            ("body_rate_excess", "largest excess of |w| - 0.3752", ".2e"),
            ("thrust_min_excess", "largest excess of sqrt(0.1) 1.5 - |T| (minimum thrust 0.474)", ".2e"),
            ("glide_slope_excess", "largest excess of 0.1 |(r2, r3)| - tan(75 deg) r1 (glide slope)", ".2e"),
            ("tilt_excess", "largest excess of cos(75 deg) - 1 + 2 (q2^2 + q3^2) (tilt)", ".2e"),
            ("gimbal_excess", "largest excess of 0.1 |T| - T1 / cos(20 deg) (gimbal)", ".2e"),
            ("max_thrust_component", "largest |T_i| (<= 6.5)", ".4f")]
    return tables(rows, keys, [("convexguid", ours), ("OpenSCvx", theirs)])


def document(proxops: tuple[list[dict], dict], descent: tuple[dict, dict, dict], command: str) -> str:
    caption = ("## The proximity operation\n\n"
               "OpenSCvx's examples/spacecraft/proxops_cw.py, same numbers (examples/proxops_openscvx.py states it "
               "for convexguid: minimum fuel, the acceleration linear between nodes (first-order hold), 20 intervals "
               "by default; OpenSCvx: the file's own 5 nodes, zero-order hold, Dopri8 and lam_vb 0.1, no cost term, so "
               "any feasible plan is its answer). Times "
               "are one run each on this machine. In-process times start after the imports on both sides "
               "(convexguid: from stating the problem to the verified plan, CasADi derivatives, SCP and dense SciPy "
               "check included); 'as a process' is the whole command a user types (Python start and imports "
               "included: `convexguid solve examples/proxops_openscvx.py`). OpenSCvx's iterations are its accepted "
               "iterates (len(result.X) - 1). The figures are measured the same way on each plan's own propagated "
               "trajectory, the cone over the second half of its maneuver time as examples/proxops_openscvx.py "
               "states it.")
    descent_caption = (
        "## The 6-DoF powered descent\n\n"
        "OpenSCvx's examples/rocket/6DoF_pdg.py, same numbers, free final time, the most mass left "
        "(examples/rocket_6dof_pdg.py states it for convexguid: 20 intervals, the thrust held constant across each "
        "(zero-order hold), the path constraints as 0.5.2 writes them, 0.1 on the first term of five, checked "
        "densely and repaired where broken between nodes; OpenSCvx: its own 5 nodes, the thrust linear between "
        "them (first-order hold), the constraints integrated over each interval (CTCS), its cost the final mass "
        "weighted 0.01 against the constraint penalties (lam_cost 1e-2, lam_vc 1e1), QOCO through CVXPY in place of "
        "the file's cvxpygen-generated QOCO). Times are one run each on this machine, timed as above "
        "(`convexguid solve examples/rocket_6dof_pdg.py`). IPOPT solves convexguid's transcription as stated (exact "
        "Hessian through CasADi, from the same guess, as python -m convexguid.benches.ocp_examples runs it); its "
        "plan is not re-propagated, so it has no column below. The figures are measured the same way on each "
        "plan's own propagation from its first node (convexguid: DOP853 through the 20 intervals, 20 points each; "
        "OpenSCvx: its post_process, every 0.01 time unit), each path constraint in the form the docstring of "
        "examples/rocket_6dof_pdg.py writes it (a positive excess is a broken constraint), in its norm form: |w| "
        "for the body rate, |T| for the minimum thrust.")
    body = (proxops_section(*proxops) + "\n\n" + descent_caption + "\n\n" + descent_section(*descent))
    return bench_document("convexguid and OpenSCvx on two of OpenSCvx's examples", ["numpy", "scipy", "casadi",
                          "clarabel", "piqp"], command, caption, body)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--openscvx-python", required=True, help="a Python interpreter that has openscvx")
    parser.add_argument("--output", type=Path, default=EXAMPLES.parent / "validation" / "BENCHMARKS_ocp.md")
    args = parser.parse_args()
    cases = [proxops(20), proxops(40)]
    theirs = run_openscvx(args.openscvx_python, cases[0]), run_openscvx(args.openscvx_python, DESCENT)
    proxops_runs = [run_convexguid(case) for case in cases]
    descent_run, ipopt = run_convexguid(DESCENT), ipopt_final_mass()
    text = document((proxops_runs, theirs[0]), (descent_run, theirs[1], ipopt),
                    f"python -m convexguid.benches.openscvx --openscvx-python {args.openscvx_python}")
    write_text_atomic(args.output, text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
