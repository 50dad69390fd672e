"""OpenSCvx's flagship, examples/rocket/6DoF_pdg.py of OpenSCvx 0.5.2 (the PyPI sdist; OpenSCvx adapted it from
Kamath's SCvxGEN), stated in convexguid: a 6-DoF powered descent, free final time, the most mass left.

Nondimensional (g = 1), x up. States: mass m, position r and velocity v (inertial), the quaternion q = (q1, q2, q3,
q4) of the body (scalar last), the body rate w; control: the thrust T in body axes, applied at r_arm. With R(q)
body to inertial and the drag A = -1/2 rho |v| S_a C_A R(q)^T v (body axes), acting at r_cp:
    m' = -|T| / (Isp g0) - beta,  r' = v,  v' = R(q) (T + A) / m - (g, 0, 0),  q' = 1/2 q (x) (w, 0),
    w' = J^-1 (r_arm x T + r_cp x A - w x J w).
Constants, all the file's: g = g0 = 1, Isp = 30 (alpha = 1/30), beta = 0.01 (a constant mass flow),
J = diag(0.00336, 0.168, 0.168), r_arm = (-0.25, 0, 0), r_cp = (0.05, 0, 0), rho = 1, S_a = 0.5,
C_A = diag(0.5, 1, 1). Bounds: m in [m_dry, m_wet] = [1, 2], |r_i| <= 10, |v_i| <= v_max = 3, |q_i| <= 1,
|w_i| <= w_max = 0.3752, |T_i| <= T_max = 6.5. From m = 2, r = (7.5, 4.5, 2.5), v = (-0.5, -2.8, 0),
w = (1e-8, 0, 0), q free, to r = 0, v = (-0.1, 0, 0), q = (0, 0, 0, 1), w = (1e-8, 0, 0), maximizing m(tf); the
final time is free in [2, 10] (time at most 10, time dilation at least 2; guess 10). OpenSCvx flies 5 nodes, a
first-order hold and continuous-time (CTCS) constraints; here a finer grid, checked densely.
Path constraints as 0.5.2 writes them, a weight 0.1 on the first term of five (which loosens them against the
unweighted forms of the same file in OpenSCvx's git history, commit 9399850: glide slope 75 deg -> 88.5 deg,
gimbal 20 deg -> 84.6 deg, minimum thrust 1.5 -> 0.474; the speed and thrust maxima never bind under the boxes):
    glide slope  0.1 |(r2, r3)| <= tan(75 deg) r1        tilt       cos(75 deg) - 1 + 2 (q2^2 + q3^2) <= 0
    speed        0.1 |v|^2 <= v_max^2                    body rate  |w|^2 <= w_max^2
    gimbal       0.1 |T| <= T1 / cos(20 deg)             thrust     0.1 |T|^2 <= T_max^2, 0.1 T_min^2 <= |T|^2
with T_min = 1.5. The quaternion's unit norm is no constraint, in OpenSCvx or here: q' = 1/2 q (x) (w, 0) keeps
|q|, and the final q is a unit quaternion (the initial one is free), so |q| = 1 to the transcription's error
(IPOPT's optimum: within 7e-5 on 20 Hermite-Simpson intervals, 2e-8 on 20 zero-order-hold intervals); R(q) is
the quadratic form the file writes (|q|^2 times a rotation). No published optimum: the reference is IPOPT on the
same transcription (convexguid.ocp.reference.solve_with_ipopt). On the default grid the SCP converges (KKT
conditions met) and is verified after one repair round (the body rate held between nodes): final mass 1.603025,
131 iterations, against IPOPT's 1.603065 on the unrepaired transcription, whose optimum breaks the rate limit
between nodes.
Run: python examples/rocket_6dof_pdg.py
"""

import math

import casadi as ca
import numpy as np

from convexguid.ocp import Problem
from convexguid.ocp.attitude import body_rate_rate, quaternion_rate

GRAVITY, G0, ISP, BETA = 1.0, 1.0, 30.0, 0.01
INERTIA = (0.168 * 2e-2, 0.168, 0.168)
ARM, PRESSURE_CENTRE = (-0.25, 0.0, 0.0), (0.05, 0.0, 0.0)  # body x
RHO, AREA, DRAG = 1.0, 0.5, (0.5, 1.0, 1.0)
DRY_MASS, WET_MASS = 1.0, 2.0
R_MAX, V_MAX, W_MAX, T_MIN, T_MAX = 10.0, 3.0, 0.3752, 1.5, 6.5
GLIDE_SLOPE, TILT_MAX, GIMBAL_MAX = math.radians(75.0), math.radians(75.0), math.radians(20.0)
START_R, START_V, FINAL_V = (7.5, 4.5, 2.5), (-0.5, -2.8, 0.0), (-0.1, 0.0, 0.0)
ROLL_RATE = 1e-8
WEIGHT = 0.1  # 0.5.2's weight on the first term of five of its constraints


def rotation(q) -> ca.SX:
    """Body to inertial, the quadratic form of the quaternion (scalar last)."""
    q1, q2, q3, q4 = q
    return ca.vertcat(
        ca.horzcat(q4**2 + q1**2 - q2**2 - q3**2, 2 * (q1 * q2 - q4 * q3), 2 * (q4 * q2 + q1 * q3)),
        ca.horzcat(2 * (q4 * q3 + q1 * q2), q4**2 - q1**2 + q2**2 - q3**2, 2 * (q2 * q3 - q4 * q1)),
        ca.horzcat(2 * (q1 * q3 - q4 * q2), 2 * (q4 * q1 + q2 * q3), q4**2 - q1**2 - q2**2 + q3**2))


def build(intervals: int = 20, method: str = "zoh") -> Problem:
    """The descent on ``intervals`` intervals of ``method``. A zero-order hold by default: on the minimum-thrust arc
    the optimal thrust direction turns from node to node, and a first-order hold or Hermite-Simpson's quadratic
    interpolates it through |T| < T_min between nodes (OpenSCvx holds it first-order and judges the constraints
    over each interval, CTCS)."""
    p = Problem("openscvx-6dof-pdg")
    m = p.state("m", bounds=(DRY_MASS, WET_MASS), initial=WET_MASS)
    r = [p.state(f"r{i + 1}", bounds=(-R_MAX, R_MAX), initial=START_R[i], final=0.0) for i in range(3)]
    v = [p.state(f"v{i + 1}", bounds=(-V_MAX, V_MAX), initial=START_V[i], final=FINAL_V[i]) for i in range(3)]
    q = [p.state(f"q{i + 1}", bounds=(-1.0, 1.0), final=(0.0, 0.0, 0.0, 1.0)[i]) for i in range(4)]
    # the roll rate cannot change (J2 = J3, and neither the engine nor the drag torques about body x): its final
    # value would repeat the initial one, a redundant equality (dependent constraint rows: IPOPT then runs out
    # its 3000 iterations on 20 intervals, zero-order hold or Hermite-Simpson), so it is left free
    w = [p.state(f"w{i + 1}", bounds=(-W_MAX, W_MAX), initial=(ROLL_RATE, 0.0, 0.0)[i],
                 final=(None, 0.0, 0.0)[i]) for i in range(3)]
    # the file's thrust guess goes from m_wet g to m_dry g along body x; a constant guess here, its mean
    thrust = [p.control(f"T{i + 1}", bounds=(-T_MAX, T_MAX), guess=(1.5 * GRAVITY, 0.0, 0.0)[i]) for i in range(3)]
    T, V, R = ca.vertcat(*thrust), ca.vertcat(*v), rotation(q)
    aero = -0.5 * RHO * AREA * ca.norm_2(V) * ca.diag(ca.DM(DRAG)) @ R.T @ V  # body axes
    torque = ca.cross(ca.DM(ARM), T) + ca.cross(ca.DM(PRESSURE_CENTRE), aero)
    rates = ca.vertcat(-ca.norm_2(T) / (ISP * G0) - BETA, V, R @ (T + aero) / m - ca.DM([GRAVITY, 0.0, 0.0]),
                       quaternion_rate(q, w), body_rate_rate(w, ca.vertsplit(torque), np.diag(INERTIA)))
    p.dynamics(dict(zip([m, *r, *v, *q, *w], ca.vertsplit(rates), strict=True)))
    p.cone_constraint("glide_slope", [WEIGHT * r[1], WEIGHT * r[2]], math.tan(GLIDE_SLOPE) * r[0])
    p.cone_constraint("speed", v, V_MAX / math.sqrt(WEIGHT))
    p.path_constraint("tilt", math.cos(TILT_MAX) - 1 + 2 * (q[1] ** 2 + q[2] ** 2))
    p.cone_constraint("body_rate", w, W_MAX)
    p.cone_constraint("gimbal", [WEIGHT * t for t in thrust], thrust[0] / math.cos(GIMBAL_MAX))
    p.cone_constraint("thrust_max", thrust, T_MAX / math.sqrt(WEIGHT))
    p.path_constraint("thrust_min", WEIGHT * T_MIN**2 - ca.sumsqr(T))
    # (m >= m_dry, a constraint of the file, is the mass's lower bound)
    p.final_time(bounds=(2.0, 10.0), guess=10.0)
    p.minimize_terminal(-m)
    p.transcription(intervals, method)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations)
    print(f"final mass {-solution.objective:.6f}, final time {solution.figures.final_time_s:.4f}, "
          f"wall {solution.wall_time_s:.3f} s")
    if solution.verification is not None:
        broken = [f"{c.name} by {c.violation:.2g}" for c in solution.verification.checks if c.violation > 1e-6]
        print("dense check:", "passed" if solution.verification.passed else ", ".join(broken) or "final state")
