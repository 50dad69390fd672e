"""Finite-thrust minimum-burn-time rendezvous (Wang & Tang 2003): problem data, thrust plans, verification.

Find the thrust direction history :math:`u(t)` (engine on at constant acceleration
:math:`a` with :math:`|u| = 1`, or off) that takes the chaser from :math:`X_0` to
:math:`X_f` in Clohessy-Wiltshire dynamics (:mod:`convexguid.dynamics.clohessy_wiltshire`)
in the fixed time :math:`t_f - t_0` with the least total burn time. Two methods:

* ``scp_arcs`` (:mod:`convexguid.families.rendezvous.arcs`): the paper's burn/coast
  transcription, a nonconvex program solved by SCP;
* ``lcvx`` (:mod:`convexguid.families.rendezvous.lcvx`): lossless convexification on a
  fixed zero-order-hold grid, one SOCP whose optimum is global for that grid.

``scp_arcs`` is certified by ``lcvx``: both are solved and the gap reported
(:mod:`convexguid.families.rendezvous.solve`). Every plan is verified by integrating
:math:`\\dot X = AX + B\\,a u(t)` with SciPy.

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from convexguid.dynamics.clohessy_wiltshire import cw_matrices
from convexguid.errors import SolverError
from convexguid.families.rendezvous.figures import ArcsPlanFigures, LcvxPlanFigures
from convexguid.scp.engine import IterationRecord
from convexguid.solution import Trajectory
from convexguid.verification import MIN_PIECE, ConstraintCheck, Verification, piece_edges


@dataclass(frozen=True)
class Rendezvous:
    """A rendezvous case in SI units; ``dim`` = 2 (coplanar ``[x, y, vx, vy]``) or 3."""

    name: str
    mean_motion: float
    accel: float
    t0: float
    tf: float
    x0: np.ndarray
    xf: np.ndarray

    @property
    def dim(self) -> int:
        return self.x0.size // 2

    @property
    def nx(self) -> int:
        return self.x0.size

    @property
    def nu(self) -> int:
        return self.dim

    @property
    def duration(self) -> float:
        return self.tf - self.t0

    def matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``A, B`` of eq. (2), ``B`` including the thrust acceleration."""
        return cw_matrices(self.mean_motion, self.accel, self.dim)


def build_case(spec) -> Rendezvous:
    """SI arrays from a validated ``rendezvous`` spec (:mod:`convexguid.families.rendezvous.spec`)."""
    b = spec.boundary
    return Rendezvous(spec.name, spec.orbit.mean_motion_radps, spec.spacecraft.accel_mps2, b.t0_s, b.tf_s,
                      np.array(b.initial.state), np.array(b.final.state))


@dataclass(frozen=True)
class BurnArc:
    """One burn, from ``start_s`` to ``end_s``."""

    start_s: float
    end_s: float

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s


@dataclass(frozen=True)
class ThrustSegment:
    """Thrust on ``[start, end]`` with a direction/throttle ``u(t)`` smooth inside it (``|u| <= 1``)."""

    start: float
    end: float
    command: Callable[[float], np.ndarray]


@dataclass(frozen=True)
class ThrustPlan:
    """Planned :math:`u(t)`: the listed segments (sorted, disjoint), zero thrust elsewhere."""

    segments: tuple[ThrustSegment, ...]
    nu: int

    def __call__(self, t: float) -> np.ndarray:
        for seg in self.segments:
            if seg.start <= t <= seg.end:
                return seg.command(t)
        return np.zeros(self.nu)

    @classmethod
    def from_nodes(cls, times: np.ndarray, directions: np.ndarray, burns: tuple[BurnArc, ...],
                   normalize: bool) -> ThrustPlan:
        """Linear interpolation of node directions inside each burn (one segment per node interval)."""
        segments = []
        for k in range(times.size - 1):
            t_a, t_b = times[k], times[k + 1]
            inside = any(b.start_s - 1e-9 <= t_a and t_b <= b.end_s + 1e-9 for b in burns)
            if not inside or t_b <= t_a:
                continue
            segments.append(ThrustSegment(float(t_a), float(t_b),
                                          _linear_command(t_a, t_b, directions[k], directions[k + 1], normalize)))
        return cls(tuple(segments), directions.shape[1])

    @classmethod
    def from_steps(cls, grid: np.ndarray, controls: np.ndarray, threshold: float = 0.0) -> ThrustPlan:
        """Piecewise-constant ``controls[k]`` on ``[grid[k], grid[k+1]]`` (zero-order hold)."""
        segments = tuple(ThrustSegment(float(grid[k]), float(grid[k + 1]), _constant_command(controls[k]))
                         for k in range(controls.shape[0]) if np.linalg.norm(controls[k]) > threshold)
        return cls(segments, controls.shape[1])


def _linear_command(t_a: float, t_b: float, u_a: np.ndarray, u_b: np.ndarray,
                    normalize: bool) -> Callable[[float], np.ndarray]:
    def command(t: float) -> np.ndarray:
        s = (t - t_a) / (t_b - t_a)
        u = (1 - s) * u_a + s * u_b
        return u / np.linalg.norm(u) if normalize else u

    return command


def _constant_command(u: np.ndarray) -> Callable[[float], np.ndarray]:
    u = np.array(u, dtype=float)
    return lambda t: u


@dataclass(frozen=True)
class RendezvousTrack:
    """Propagated history on the dense grid: times, states, planned ``u``."""

    t: np.ndarray
    states: np.ndarray
    u: np.ndarray


def propagate_thrust(case: Rendezvous, plan: ThrustPlan, grid_points: int, rtol: float,
                     atol: float) -> RendezvousTrack:
    """Integrate :math:`\\dot X = AX + B u(t)` (DOP853) piece by piece between the plan's switch times.

    Every thrust segment and every coast between them is integrated separately, so the
    integrator never steps across a discontinuity of :math:`u`. The dense grid is the
    union of ``grid_points`` equally spaced times and the segment ends, times closer than
    :data:`~convexguid.verification.MIN_PIECE` of the horizon taken as one (a segment end that meets a
    grid time, or the next segment's start, to round-off: otherwise the grid's size, which the report
    prints, would hang on whether two times came out bit-equal).
    """
    A, B = case.matrices()
    ends = [time for s in plan.segments for time in (s.start, s.end)]
    cuts = piece_edges(ends, case.t0, case.tf)
    uniform = np.linspace(case.t0, case.tf, grid_points)
    near_cut = np.abs(uniform[:, None] - cuts[None, :]).min(axis=1) <= MIN_PIECE * (case.tf - case.t0)
    grid = np.sort(np.concatenate([uniform[~near_cut], cuts]))
    states = np.empty((grid.size, case.nx))
    states[0] = case.x0
    x = case.x0.copy()
    for t_a, t_b in zip(cuts[:-1], cuts[1:], strict=True):
        mid = 0.5 * (t_a + t_b)
        seg = next((s for s in plan.segments if s.start <= mid <= s.end), None)
        command = seg.command if seg is not None else (lambda t: np.zeros(case.nu))
        sol = solve_ivp(lambda t, y, c=command: A @ y + B @ c(t), (t_a, t_b), x, method="DOP853",
                        rtol=rtol, atol=atol, dense_output=True)
        if not sol.success:
            raise SolverError(f"dense propagation failed on [{t_a:.6g}, {t_b:.6g}] s: {sol.message}")
        inside = (grid > t_a) & (grid <= t_b)
        states[inside] = sol.sol(grid[inside]).T
        x = sol.y[:, -1]
    # u on the grid, taken from the segment that ends at or contains each time (right-continuous at cuts)
    u = np.array([plan(t) for t in grid])
    return RendezvousTrack(grid, states, u)


def verify_track(case: Rendezvous, track: RendezvousTrack, settings) -> Verification:
    """Thrust bound :math:`|a u| \\le a` on the dense grid, and the final position and velocity errors."""
    d = case.dim
    accel = case.accel * np.linalg.norm(track.u, axis=1)
    checks = (ConstraintCheck("thrust_accel_mps2", float(accel.max()), case.accel, "max"),)
    err = track.states[-1] - case.xf
    pos_err, vel_err = float(np.linalg.norm(err[:d])), float(np.linalg.norm(err[d:]))
    path_ok = all(c.violation <= settings.thrust_tol * c.bound for c in checks)
    passed = path_ok and pos_err <= settings.final_position_tol_m and vel_err <= settings.final_velocity_tol_mps
    return Verification(
        grid_points=int(track.t.size), checks=checks, final_state_error=float(np.linalg.norm(err)),
        final_errors={"final_position_error_m": pos_err, "final_velocity_error_mps": vel_err}, passed=passed,
        tolerances={"thrust_rel": settings.thrust_tol, "position_m": settings.final_position_tol_m,
                    "velocity_mps": settings.final_velocity_tol_mps})


AXES = ("x", "y", "z")


def state_columns(dim: int, states: np.ndarray, u: np.ndarray, accel: float) -> dict[str, np.ndarray]:
    """CSV columns of states and thrust, units in the headers."""
    cols = {f"{AXES[i]}_m": states[:, i] for i in range(dim)}
    cols.update({f"v{AXES[i]}_mps": states[:, dim + i] for i in range(dim)})
    cols.update({f"u{AXES[i]}": u[:, i] for i in range(dim)})
    cols["thrust_accel_mps2"] = accel * np.linalg.norm(u, axis=1)
    return cols


@dataclass
class RendezvousPlan:
    """What either method hands back before verification."""

    status: str
    message: str
    objective: float
    iterations: int
    size: object
    burns: tuple[BurnArc, ...]
    thrust: ThrustPlan
    nodes: Trajectory
    timing: dict[str, float]
    figures: ArcsPlanFigures | LcvxPlanFigures
    history: list[IterationRecord]
    solver: str = ""
    """The convex backend as it ran (e.g. ``auto -> clarabel (sparse)``); empty: the spec's setting."""
