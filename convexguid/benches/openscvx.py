"""The proximity-operations problem solved by convexguid (examples/proxops_openscvx.py) and by OpenSCvx on the same
numbers, timed in the same run, each plan judged on the same dense re-propagation; writes
validation/BENCHMARKS_ocp.md.

OpenSCvx (JAX) is not a convexguid dependency: give the Python that has it, e.g. a virtual environment made with
``python -m venv --system-site-packages venv && venv/bin/pip install openscvx``:

    python -m convexguid.benches.openscvx --openscvx-python venv/bin/python
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import trapezoid

from convexguid.bench_common import bench_document, markdown_grid
from convexguid.outputs import write_text_atomic

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
"""The checkout's examples folder, whose problem modules this benchmark solves."""

# OpenSCvx's statement of the problem, in its API (OpenSCvx 0.5.2, examples/spacecraft/proxops_cw.py's numbers:
# 5 nodes, ZOH, the cone over the last two intervals, the entrance at the middle node; no cost term)
OPENSCVX_RUN = r'''
import json, sys, time
import numpy as np
from scipy.integrate import trapezoid
import openscvx as ox
t0 = time.perf_counter()
nodes, n = 5, np.sqrt(3.986004418e14 / 6.778e6**3)
r = ox.State("position", shape=(3,)); r.max = np.full(3, 100.0); r.min = -r.max
r.initial = np.array([0.0, -100.0, 0.0]); r.final = np.zeros(3)
v = ox.State("velocity", shape=(3,)); v.max = np.full(3, 2.0); v.min = -v.max
v.initial = [0.0, 2.0, 0.0]; v.final = np.zeros(3); v.guess = np.zeros((nodes, 3))
a = ox.Control("accel", shape=(3,)); a.max = np.full(3, 0.1); a.min = -a.max; a.guess = np.zeros((nodes, 3))
cons = [c for s in (r, v) for c in (ox.ctcs(s <= s.max), ox.ctcs(s.min <= s))]
cons.append(ox.ctcs(ox.linalg.Norm(r[1:]) <= np.tan(np.radians(20.0)) * (-r[0])).over((nodes - 3, nodes - 1)))
cons.append((-r[0] >= 20.0).at([nodes - 3]))
dyn = {"position": v, "velocity": ox.Concat(3 * n**2 * r[0] + 2 * n * v[1] + a[0], -2 * n * v[0] + a[1],
                                            -(n**2) * r[2] + a[2])}
problem = ox.Problem(dynamics=dyn, states=[r, v], controls=[a], constraints=cons, N=nodes,
                     time=ox.Time(initial=0.0, final=("free", 180.0), min=0.0, max=180.0))
problem.initialize()
setup = time.perf_counter() - t0
t0 = time.perf_counter(); problem.solve(); solve = time.perf_counter() - t0
t0 = time.perf_counter(); res = problem.post_process(); post = time.perf_counter() - t0
json.dump({"setup_s": setup, "solve_s": solve, "post_process_s": post, "converged": bool(res.converged),
           "t": np.asarray(res.t_full).ravel().tolist(), "x": np.asarray(res.x_full).tolist(),
           "u": np.asarray(res.u_full).tolist()}, sys.stdout)
'''


def judge(t: np.ndarray, x: np.ndarray, u: np.ndarray) -> dict:
    """The same yardsticks for both plans, on their own dense propagation: fuel (trapezoid on |a|), the largest
    cone excess over the second half (m, lateral distance beyond the cone), the entrance depth at half time, the
    largest acceleration and the final position and speed errors."""
    tf = t[-1]
    second = t >= 0.5 * tf - 1e-9
    lateral = np.hypot(x[second, 1], x[second, 2])
    cone = float(np.max(lateral - np.tan(np.radians(20.0)) * (-x[second, 0])))
    return {"final_time_s": float(tf), "fuel_mps": float(trapezoid(np.abs(u).sum(axis=1), t)),
            "cone_excess_m": cone, "entrance_depth_m": float(-np.interp(0.5 * tf, t, x[:, 0])),
            "max_accel": float(np.abs(u).max()), "final_position_error_m": float(np.linalg.norm(x[-1, :3])),
            "final_speed_error_mps": float(np.linalg.norm(x[-1, 3:6]))}


def run_convexguid(intervals: int) -> dict:
    """The example on ``intervals`` first-order-hold intervals, timed from the problem's statement to the verified
    plan (imports before the clock, as OpenSCvx's set-up is timed after its import), then the same as a command."""
    sys.path.insert(0, str(EXAMPLES))
    import proxops_openscvx

    import convexguid.ocp.solve  # noqa: F401 - the engine and SciPy load before the clock starts

    started = time.perf_counter()
    solution = proxops_openscvx.build(intervals).solve()
    wall = time.perf_counter() - started
    dense = solution.dense.columns
    t = solution.dense.t
    x = np.column_stack([dense[k] for k in ("x", "y", "z", "vx", "vy", "vz")])
    u = np.column_stack([dense[k] for k in ("ax", "ay", "az")])
    started = time.perf_counter()
    # the command a user types, from the installation this benchmark runs in (not whatever is first on PATH)
    command = Path(sys.executable).parent / "convexguid"
    process = subprocess.run([str(command), "solve", str(EXAMPLES / "proxops_openscvx.py"), "--quiet",
                              "--set", f"intervals={intervals}"], capture_output=True, text=True, check=False)
    process_s = time.perf_counter() - started
    if process.returncode != 0:
        raise RuntimeError(f"{command} solve ... --set intervals={intervals} ended with exit {process.returncode}: "
                           f"{process.stderr.strip()[-300:]}")
    return {"intervals": intervals, "wall_s": wall, "process_s": process_s, "process_exit": process.returncode,
            "status": solution.status, "verified": bool(solution.verification.passed),
            "iterations": solution.iterations, **judge(t, x, u)}


def run_openscvx(python: str) -> dict:
    started = time.perf_counter()
    process = subprocess.run([python, "-c", OPENSCVX_RUN], capture_output=True, text=True, check=True)
    process_s = time.perf_counter() - started
    out = json.loads(process.stdout.strip().splitlines()[-1])
    # OpenSCvx augments the states (time, constraint integrals) and the controls (time dilation): the first six
    # states are position and velocity, the first three controls the acceleration
    t, x, u = np.array(out["t"]), np.array(out["x"])[:, :6], np.array(out["u"])[:, :3]
    return {"setup_s": out["setup_s"], "solve_s": out["solve_s"], "post_process_s": out["post_process_s"],
            "process_s": process_s, "converged": out["converged"], **judge(t, x, u)}


def document(ours: list[dict], theirs: dict, command: str) -> str:
    rows = [[f"convexguid (this repository), {run['intervals']} FOH intervals", "min fuel",
             f"{run['wall_s']:.3f} (set-up, {run['iterations']} SCP iterations, dense check)",
             f"{run['process_s']:.2f}", run["status"] + (" (dense check passed)" if run["verified"]
                                                          else " (dense check failed)")] for run in ours]
    rows.append(["OpenSCvx 0.5.2, its 5 ZOH nodes", "none (cost 0)",
                 f"{theirs['setup_s']:.2f} set-up + {theirs['solve_s']:.3f} solve "
                 f"+ {theirs['post_process_s']:.2f} post-process", f"{theirs['process_s']:.2f}",
                 "converged" if theirs["converged"] else "not converged"])
    timing = markdown_grid(["method", "objective", "in-process time [s]", "as a process [s]", "status"],
                           ["---", "---", "---", "---:", "---"], rows)
    keys = [("final_time_s", "final time [s]", ".3f"), ("fuel_mps", "fuel, integral of |a_x|+|a_y|+|a_z| [m/s]", ".4f"),
            ("cone_excess_m", "largest distance outside the cone, second half [m]", ".2e"),
            ("entrance_depth_m", "depth below the target at half time [m] (>= 20)", ".3f"),
            ("max_accel", "largest acceleration component [m/s^2] (<= 0.1)", ".4f"),
            ("final_position_error_m", "final position error [m]", ".2e"),
            ("final_speed_error_mps", "final speed error [m/s]", ".2e")]
    answers = markdown_grid(["figure (each plan's own dense propagation)",
                             *(f"convexguid, {run['intervals']} intervals" for run in ours), "OpenSCvx"],
                            ["---", *("---:" for _ in ours), "---:"],
                            [[label, *(format(run[k], f) for run in ours), format(theirs[k], f)]
                             for k, label, f in keys])
    caption = ("The proximity operation of OpenSCvx's examples/spacecraft/proxops_cw.py, same numbers "
               "(examples/proxops_openscvx.py states it for convexguid: minimum fuel, the acceleration linear between "
               "nodes (first-order hold), 20 intervals by default; OpenSCvx: its own 5 nodes, ZOH, no cost term, so "
               "any feasible plan is its answer). Times are one run each on this machine. In-process times start "
               "after the imports on both sides (convexguid: from stating the problem to the verified plan, CasADi "
               "derivatives, SCP and dense SciPy check included); 'as a process' is the whole command a user types "
               "(Python start and imports included: `convexguid solve examples/proxops_openscvx.py`). The figures "
               "are measured the same way on each plan's own propagated trajectory, the cone over the second half "
               "of its maneuver time as examples/proxops_openscvx.py states it.")
    return bench_document("convexguid and OpenSCvx on the same proximity operation", ["numpy", "scipy", "casadi",
                          "clarabel"], command, caption, timing + "\n\n" + answers)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--openscvx-python", required=True, help="a Python interpreter that has openscvx")
    parser.add_argument("--output", type=Path, default=EXAMPLES.parent / "validation" / "BENCHMARKS_ocp.md")
    args = parser.parse_args()
    theirs = run_openscvx(args.openscvx_python)
    ours = [run_convexguid(intervals) for intervals in (20, 40)]
    text = document(ours, theirs, f"python -m convexguid.benches.openscvx --openscvx-python {args.openscvx_python}")
    write_text_atomic(args.output, text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
