"""Attitude control of a space station with momentum management: the control moment gyros unloaded in 30 minutes.

J. T. Betts, Practical Methods for Optimal Control and Estimation Using Nonlinear Programming, 2nd ed. (SIAM, 2010),
Sec. 6.11 (also an example of GPOPS-II, which reports 3.5867511). The station's body rate w (rad/s), its attitude as
Rodrigues (Gibbs) parameters r relative to the local orbital frame, and the gyros' momentum h (ft lbf s), driven by
the gyro torque u (ft lbf) over 1800 s:

    w' = J^-1 (tau_gg(r) - w x (J w + h) - u),   r' = 1/2 (r r^T + I + [r x]) (w - w_o(r)),   h' = u,
    C(r) = I + 2 / (1 + r.r) ([r x]^2 - [r x]),   w_o(r) = -n C(r) e2,   tau_gg(r) = 3 n^2 c3 x (J c3), c3 = C(r) e3,

with n the orbital rate, from Betts' initial state to h(tf) = 0 and torque equilibrium at tf (w' = 0 and r' = 0
there with u = 0: six nonlinear final conditions), |w_i| <= 2e-3, |r_i| <= 1, |h_i| <= 15000, |u_i| <= 150 and the
momentum h.h <= 1e8 along the path (stated as Betts writes it, in (ft lbf s)^2); minimise 1e-6 times the integral
of u.u (Betts' scaling). Published: 3.58675.
Run: python examples/classics/space_station.py
"""

import math

import casadi as ca
import numpy as np

from convexguid.ocp import Problem

PUBLISHED = 3.58675
SOURCE = "Betts, Practical Methods for Optimal Control..., 2nd ed. (2010), Sec. 6.11; GPOPS-II: 3.5867511"
FIGURE = "1e-6 integral of u.u"

INERTIA = np.array([[2.80701911616e7, 4.822509936e5, -1.71675094448e7],
                    [4.822509936e5, 9.5144639344e7, 6.02604448e4],
                    [-1.71675094448e7, 6.02604448e4, 7.6594401336e7]])
"""slug ft^2."""
ORBITAL_RATE = math.radians(0.06511)
MOMENTUM_LIMIT = 1e4
RATE_START = (-9.5380685844896e-6, -1.1363312657036e-3, 5.3472801108427e-6)
ATTITUDE_START = (2.9963689649816e-3, 1.5334477761054e-1, 3.8359805613992e-3)
MOMENTUM_START = (5000.0, 5000.0, 5000.0)


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["cost"]


def rates(w: ca.SX, r: ca.SX, h: ca.SX, u: ca.SX) -> tuple[ca.SX, ca.SX]:
    """The body rate's and the attitude's derivatives."""
    inertia, rx = ca.DM(INERTIA), ca.skew(r)
    attitude = ca.DM.eye(3) + 2 / (1 + ca.dot(r, r)) * (rx @ rx - rx)
    c3 = attitude[:, 2]
    gravity_gradient = 3 * ORBITAL_RATE**2 * ca.cross(c3, inertia @ c3)
    w_dot = ca.solve(inertia, gravity_gradient - ca.cross(w, inertia @ w + h) - u)
    r_dot = 0.5 * (r @ r.T + ca.DM.eye(3) + rx) @ (w + ORBITAL_RATE * attitude[:, 1])
    return w_dot, r_dot


def build(intervals: int = 50) -> Problem:
    p = Problem("space-station-attitude")
    w = [p.state(f"w{i + 1}", bounds=(-2e-3, 2e-3), initial=RATE_START[i], unit="rad/s") for i in range(3)]
    r = [p.state(f"r{i + 1}", bounds=(-1.0, 1.0), initial=ATTITUDE_START[i]) for i in range(3)]
    h = [p.state(f"h{i + 1}", bounds=(-15000.0, 15000.0), initial=MOMENTUM_START[i], final=0.0, unit="ft lbf s")
         for i in range(3)]
    u = [p.control(f"u{i + 1}", bounds=(-150.0, 150.0), unit="ft lbf") for i in range(3)]
    W, R, H, U = ca.vertcat(*w), ca.vertcat(*r), ca.vertcat(*h), ca.vertcat(*u)
    w_dot, r_dot = rates(W, R, H, U)
    p.dynamics({**dict(zip(w, ca.vertsplit(w_dot), strict=True)), **dict(zip(r, ca.vertsplit(r_dot), strict=True)),
                **dict(zip(h, u, strict=True))})
    p.path_constraint("momentum", ca.dot(H, H) - MOMENTUM_LIMIT**2, unit="(ft lbf s)^2")
    w_rest, r_rest = rates(W, R, H, ca.DM.zeros(3))
    p.boundary_constraint("torque_equilibrium", ca.vertsplit(ca.vertcat(w_rest, r_rest)), at="final")
    p.final_time(fixed=1800.0)
    p.minimize_integral(1e-6 * ca.dot(U, U))
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
