"""Verification of a planned trajectory by dense re-propagation.

A solver's "optimal" says nothing about what happens between the nodes. Here the
planned control is fed to the equations of motion, integrated with SciPy at tight
tolerance, and every path constraint is evaluated on a dense grid; the final state
is compared with the target. The result fills the ``verification`` object of the
summary JSON (docs/cli.md).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from convexguid.dynamics.rigid_body import rigid_body_rhs_fast
from convexguid.errors import SolverError
from convexguid.geometry import PointingCone
from convexguid.rotations import quat_angle_between


@dataclass(frozen=True)
class ConstraintCheck:
    """Worst value of one path constraint on the dense grid, in the constraint's own unit.

    ``sense`` is ``"max"`` for an upper bound (``worst <= bound``) and ``"min"`` for a
    lower bound (``worst >= bound``).
    """

    name: str
    worst: float
    bound: float
    sense: str
    held: bool | None = None
    """Whether it held as its checker judged it, within a tolerance and perhaps net of the flight's final miss (None:
    the checker does not say, and any violation counts)."""

    @property
    def failed(self) -> bool:
        """It broke its bound as judged (where the checker does not judge: by more than round-off)."""
        if self.held is not None:
            return not self.held
        return self.violation > 1e-9 * max(1.0, abs(self.bound))

    @property
    def violation(self) -> float:
        excess = self.worst - self.bound if self.sense == "max" else self.bound - self.worst
        return max(0.0, float(excess))


@dataclass(frozen=True)
class Verification:
    """Outcome of the dense check; ``passed`` when every tolerance holds."""

    grid_points: int
    checks: tuple[ConstraintCheck, ...]
    final_state_error: float
    final_errors: dict[str, float]
    passed: bool
    tolerances: dict[str, float] = field(default_factory=dict)
    remarks: tuple[str, ...] = ()
    """What the checker saw that may explain a failure (e.g. a control that jumps between nodes); in messages
    only, not in the summary."""

    @property
    def max_violation(self) -> float:
        return max((c.violation for c in self.checks), default=0.0)

    def to_dict(self) -> dict:
        return {
            "grid_points": self.grid_points,
            "constraints": {c.name: {"worst": c.worst, "bound": c.bound} for c in self.checks},
            "max_violation": self.max_violation,
            "final_state_error": self.final_state_error,
            **self.final_errors,
            "passed": self.passed,
        }


@dataclass(frozen=True)
class AttitudeTrack:
    """Dense attitude history from propagation: times, quaternions (scalar-last), body rates, torques."""

    t: np.ndarray
    q: np.ndarray
    omega: np.ndarray
    torque: np.ndarray


def propagate_attitude(inertia: np.ndarray, torque: Callable[[float], np.ndarray], q0: np.ndarray,
                       omega0: np.ndarray, t_grid: np.ndarray, rtol: float, atol: float,
                       max_step: float = np.inf) -> AttitudeTrack:
    """Integrate the rigid body under ``torque(t)`` (DOP853) and sample it on ``t_grid``.

    A torque with ``breakpoints`` (a :class:`~convexguid.dynamics.torque.TorqueCommand`) is integrated
    piece by piece between the breakpoints inside the grid's span, the state carried across each;
    on every piece the torque is smooth and the step is set by ``rtol``/``atol`` alone. Inside a piece
    the torque is read strictly between its ends (:data:`BREAKPOINT_NUDGE`), so that a torque that
    jumps at a breakpoint is integrated with the piece's own side of the jump. A torque without
    breakpoints is integrated in one piece; ``max_step`` (default none) then keeps the integrator
    from stepping over short torque features it does not know about. The grid is sampled from each
    piece's dense output; the track's torque is ``torque.sample(t_grid)`` when the torque has it.
    """
    t_grid = np.asarray(t_grid, dtype=float)
    edges = piece_edges(getattr(torque, "breakpoints", ()), t_grid[0], t_grid[-1])
    y = np.concatenate([q0, omega0]).astype(float)
    states = np.empty((t_grid.size, y.size))
    first = 0
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        rhs = rigid_body_rhs_fast(inertia, torque if len(edges) == 2 else _inside(torque, a, b))
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=rtol, atol=atol, max_step=max_step,
                        dense_output=True)
        if not sol.success:
            raise SolverError(f"dense propagation failed on [{a:.6g}, {b:.6g}] s: {sol.message}")
        last = t_grid.size if k == len(edges) - 2 else int(np.searchsorted(t_grid, b, side="right"))
        if last > first:
            states[first:last] = sol.sol(t_grid[first:last]).T
        first, y = last, sol.y[:, -1]
    q = states[:, :4] / np.linalg.norm(states[:, :4], axis=1, keepdims=True)
    sample = getattr(torque, "sample", None)
    torques = sample(t_grid) if sample is not None else np.array([torque(t) for t in t_grid])
    return AttitudeTrack(t_grid, q, states[:, 4:], torques)


BREAKPOINT_NUDGE = 64
"""Inside a piece the torque is read at least this many ulps (of the piece's end times) from its ends.

The piece's last integration step ends on the breakpoint, where a right-continuous torque already
gives the next piece's value; and a breakpoint formed as ``start + fraction * duration`` may sit an
ulp or two either side of where the torque's own comparisons switch. 64 ulps (1.4e-14 relative)
is well clear of both and moves the torque by a negligible amount.
"""

MIN_PIECE = 1e-9
"""Breakpoints closer than this fraction of the span to the ends or to one another are merged."""


def piece_edges(breakpoints, t0: float, tf: float) -> np.ndarray:
    """``t0``, the breakpoints inside ``(t0, tf)`` (at least :data:`MIN_PIECE` of the span apart), ``tf``."""
    gap = MIN_PIECE * (tf - t0)
    edges = [t0]
    for b in np.unique(np.asarray(breakpoints, dtype=float)):
        if b - edges[-1] > gap and tf - b > gap:
            edges.append(float(b))
    edges.append(tf)
    return np.array(edges)


def _inside(torque: Callable[[float], np.ndarray], a: float, b: float) -> Callable[[float], np.ndarray]:
    """``torque`` on the piece ``[a, b]``, read strictly inside it (see :data:`BREAKPOINT_NUDGE`)."""
    nudge = BREAKPOINT_NUDGE * float(np.spacing(max(abs(a), abs(b))))
    lo, hi = a + nudge, b - nudge

    def on_piece(t: float) -> np.ndarray:
        return torque(lo if t < lo else hi if t > hi else t)

    return on_piece


TORQUE_AXIS_CHECKS = ("torque_x_Nm", "torque_y_Nm", "torque_z_Nm")
"""Names of the per-axis torque checks, emitted when the three axis bounds differ."""


def torque_box_checks(torque: np.ndarray, torque_max: float | Sequence[float] | np.ndarray
                      ) -> tuple[ConstraintCheck, ...]:
    """Checks of the torque box :math:`|u_i| \\le u_{max,i}` on rows of body torque ``torque`` (N m).

    One check ``torque_Nm`` (the largest component against the bound) when ``torque_max`` is one number or
    three equal ones; otherwise one check per axis, :data:`TORQUE_AXIS_CHECKS`, each against its own bound.
    """
    bounds = np.broadcast_to(np.asarray(torque_max, dtype=float), (3,))
    if np.all(bounds == bounds[0]):
        return (ConstraintCheck("torque_Nm", float(np.max(np.abs(torque))), float(bounds[0]), "max"),)
    worst = np.max(np.abs(torque), axis=0)
    return tuple(ConstraintCheck(name, float(w), float(b), "max")
                 for name, w, b in zip(TORQUE_AXIS_CHECKS, worst, bounds, strict=True))


def torque_checks(checks: Sequence[ConstraintCheck]) -> tuple[ConstraintCheck, ...]:
    """The torque-box checks among ``checks``: ``torque_Nm``, or the per-axis ``torque_[xyz]_Nm``."""
    return tuple(c for c in checks if c.name == "torque_Nm" or c.name in TORQUE_AXIS_CHECKS)


def verify_attitude_track(track: AttitudeTrack, torque_max: float | np.ndarray,
                          cones: Sequence[PointingCone],
                          q_target: np.ndarray, omega_target: np.ndarray, constraint_tol: float,
                          attitude_tol_rad: float, rate_tol_radps: float,
                          rate_max: float | None = None) -> Verification:
    """Check torque box, keep-out cones (:class:`~convexguid.geometry.PointingCone`),
    optional rate box, and the final attitude and rate against the target.

    ``torque_max`` is one bound for every body axis or three (x, y, z); see :func:`torque_box_checks`
    for the check names.

    Path constraints pass when their violation is at most ``constraint_tol`` times
    the bound's magnitude. ``final_state_error`` is the Euclidean distance of
    (Euler-axis attitude error in rad, rate error in rad/s) from zero.
    """
    checks = list(torque_box_checks(track.torque, torque_max))
    if rate_max is not None:
        checks.append(ConstraintCheck("rate_degps", float(np.degrees(np.max(np.abs(track.omega)))),
                                      float(np.degrees(rate_max)), "max"))
    for cone in cones:
        angles = cone.angles_deg(track.q)
        checks.append(ConstraintCheck(f"keep_out_{cone.name}_deg", float(angles.min()), cone.half_angle_deg, "min"))
    attitude_error = float(quat_angle_between(track.q[-1], q_target))
    rate_error = float(np.linalg.norm(track.omega[-1] - omega_target))
    path_ok = all(c.violation <= constraint_tol * max(1.0, abs(c.bound)) for c in checks)
    passed = path_ok and attitude_error <= attitude_tol_rad and rate_error <= rate_tol_radps
    return Verification(
        grid_points=int(track.t.size), checks=tuple(checks),
        final_state_error=float(np.hypot(attitude_error, rate_error)),
        final_errors={"final_attitude_error_rad": attitude_error, "final_rate_error_radps": rate_error},
        passed=passed,
        tolerances={"constraint_rel": constraint_tol, "attitude_rad": attitude_tol_rad, "rate_radps": rate_tol_radps},
    )
