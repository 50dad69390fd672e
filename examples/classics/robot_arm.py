"""COPS 3.0 robot arm: the minimum-time move of a telescoping arm turning about two axes (Monma & Gross).

E. D. Dolan, J. J. More, T. S. Munson, Benchmarking Optimization Software with COPS 3.0, ANL/MCS-TM-273,
Argonne National Laboratory, 2004, problem "robot" (after M. Monma, K. Gross, Mathematical Programming Study 1989).
The arm, of length L = 5, sticks out rho from the pivot; theta and phi are its horizontal and vertical angles:

    L rho'' = u_rho,    I_theta theta'' = u_theta,    I_phi phi'' = u_phi,    |u_rho|, |u_theta|, |u_phi| <= 1,
    I_phi = ((L - rho)^3 + rho^3) / 3,    I_theta = I_phi sin(phi)^2,
    0 <= rho <= L,  |theta| <= pi,  0 <= phi <= pi,
    rho = 4.5, theta = 0 -> 2 pi / 3, phi = pi / 4 at t = 0 -> t_f, every rate zero at both ends; minimise t_f.

COPS reports t_f = 9.14101 (nh = 800 trapezoidal intervals). The final time is free above 0.1 from COPS's
starting value 1; the states start on the straight line (COPS's own start has theta = (2 pi / 3) (t / t_f)^2).
Run: python examples/classics/robot_arm.py
"""

import math

import casadi as ca

from convexguid.ocp import Problem

L = 5.0
PUBLISHED = 9.14101
SOURCE = "Dolan, More & Munson, COPS 3.0, ANL/MCS-TM-273 (2004), robot arm"
FIGURE = "minimum final time t_f"


def build(intervals: int = 40) -> Problem:
    p = Problem("cops-robot-arm")
    rho = p.state("rho", bounds=(0.0, L), initial=4.5, final=4.5)
    theta = p.state("theta", bounds=(-math.pi, math.pi), initial=0.0, final=2 * math.pi / 3, unit="rad")
    phi = p.state("phi", bounds=(0.0, math.pi), initial=math.pi / 4, final=math.pi / 4, unit="rad")
    rho_dot = p.state("rho_dot", initial=0.0, final=0.0)
    theta_dot = p.state("theta_dot", initial=0.0, final=0.0, unit="rad/s")
    phi_dot = p.state("phi_dot", initial=0.0, final=0.0, unit="rad/s")
    u_rho = p.control("u_rho", bounds=(-1.0, 1.0))
    u_theta = p.control("u_theta", bounds=(-1.0, 1.0))
    u_phi = p.control("u_phi", bounds=(-1.0, 1.0))
    i_phi = ((L - rho) ** 3 + rho**3) / 3
    i_theta = i_phi * ca.sin(phi) ** 2
    p.dynamics({rho: rho_dot, theta: theta_dot, phi: phi_dot,
                rho_dot: u_rho / L, theta_dot: u_theta / i_theta, phi_dot: u_phi / i_phi})
    p.final_time(bounds=(0.1, None), guess=1.0)  # COPS: t_f >= 0, starting from 1
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
