"""The hang glider of COPS 3.0: the longest glide through a thermal updraft, with a free final time.

E. D. Dolan, J. J. More, T. S. Munson, "Benchmarking optimization software with COPS 3.0", Argonne National
Laboratory, ANL/MCS-TM-273, 2004, problem "Hang glider" (after R. Bulirsch, E. Nerz, H. J. Pesch, O. von Stryk,
"Combining direct and indirect methods in optimal control: range maximization of a hang glider", 1993).

States: position x, y [m] and velocity vx, vy [m/s]; control: the lift coefficient cL in [0, 1.4]. With the
updraft u_a(x) = u_c (1 - X) exp(-X), X = (x / r_0 - 2.5)^2, the air-relative sink V_y = vy - u_a(x), the airspeed
v_r = sqrt(vx^2 + V_y^2), drag D = 1/2 (c_0 + c_1 cL^2) rho S v_r^2 and lift L = 1/2 cL rho S v_r^2:

    x' = vx,  y' = vy,  vx' = (-L V_y / v_r - D vx / v_r) / m,  vy' = (L vx / v_r - D V_y / v_r) / m - g,

from x(0) = 0, y(0) = 1000 m, (vx, vy)(0) = (13.23, -1.288) m/s to y(tf) = 900 m and the same velocity, with
x >= 0 and vx >= 0; maximize x(tf). Constants (COPS): u_c = 2.5 m/s, r_0 = 100 m, m = 100 kg, g = 9.81 m/s^2,
c_0 = 0.034, c_1 = 0.069662, S = 14 m^2, rho = 1.13 kg/m^3. Published: x(tf) = 1248.03 m, tf near 98.4 s (Betts,
Practical Methods..., 2nd ed., SIAM 2010: 1248.031026 m, tf = 98.43694 s). That figure is the continuous optimum
with Bulirsch et al.'s g = 9.80665 m/s^2 (and boundary speeds 13.2275675, -1.28750052 m/s); with COPS's g = 9.81
the converged range is 1247.99 m (IPOPT on 50 to 400 intervals), 3.4e-5 below it.

The control is linear between node values (``control="linear"``), as COPS holds it at the nodes: with Hermite-
Simpson's quadratic control the NLP has spurious optima on coarse grids where cL chatters from node to node
(50 intervals: x(tf) = 1443.6 m, cL alternating between about 1.3 and 0; 100 intervals: 1248.81 m with a kink
at the first node); the linear control gives 1247.997 m on 50 intervals.
Run: python examples/classics/hang_glider.py
"""

import casadi as ca

from convexguid.ocp import Problem

PUBLISHED = 1248.03
SOURCE = "Dolan, More & Munson, COPS 3.0 (ANL/MCS-TM-273, 2004), hang glider"
FIGURE = "final range x(tf) [m]"

U_C, R_0 = 2.5, 100.0  # updraft strength [m/s] and radius [m]
MASS, G = 100.0, 9.81  # kg, m/s^2
C_0, C_1, AREA, RHO = 0.034, 0.069662, 14.0, 1.13  # drag polar, m^2, kg/m^3
Y_0, Y_F, VX_0, VY_0 = 1000.0, 900.0, 13.23, -1.288  # m, m, m/s, m/s (the same velocity at both ends)
CL_MAX = 1.4


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["x"]


def build(intervals: int = 50, control: str = "linear") -> Problem:
    p = Problem("cops-hang-glider")
    x = p.state("x", bounds=(0.0, None), initial=0.0, scale=1000.0, unit="m")
    y = p.state("y", initial=Y_0, final=Y_F, unit="m")
    vx = p.state("vx", bounds=(0.0, None), initial=VX_0, final=VX_0, unit="m/s")
    vy = p.state("vy", initial=VY_0, final=VY_0, unit="m/s")
    cl = p.control("cL", bounds=(0.0, CL_MAX))
    X = (x / R_0 - 2.5) ** 2
    sink = vy - U_C * (1 - X) * ca.exp(-X)  # air-relative vertical speed
    airspeed = ca.sqrt(vx**2 + sink**2)
    drag = 0.5 * (C_0 + C_1 * cl**2) * RHO * AREA * airspeed**2
    lift = 0.5 * cl * RHO * AREA * airspeed**2
    p.dynamics({x: vx, y: vy,
                vx: (-lift * sink / airspeed - drag * vx / airspeed) / MASS,
                vy: (lift * vx / airspeed - drag * sink / airspeed) / MASS - G})
    p.final_time(bounds=(10.0, 200.0), guess=(Y_0 - Y_F) / -VY_0)  # guess: 100 m at the initial sink rate
    p.minimize_terminal(-x)
    p.transcription(intervals, control=control)  # Hermite-Simpson
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
