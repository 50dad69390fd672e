"""The time-optimal rest-to-rest reorientation of a rigid spacecraft by 180 degrees about an axis of symmetry.

K. D. Bilimoria, B. Wie, "Time-optimal three-axis reorientation of a rigid spacecraft", Journal of Guidance,
Control, and Dynamics 16(3), 1993. A sphere-like body (unit inertia on every axis), each axis' torque bounded by 1,
the attitude a quaternion (vector part q1..q3, scalar q4) and the body rate w:

    q' = 1/2 Omega(w) q,  w' = u,  |u_i| <= 1,
    from q = (0, 0, 0, 1) at rest to q = (0, 0, 1, 0) at rest (180 deg about z);  minimise tf.

The eigenaxis slew, a bang-bang torque about z alone, takes 2 sqrt(pi) = 3.5449; the time-optimal one uses all three
axes and is not an eigenaxis rotation. Published: tf = 3.2431.
Run: python examples/classics/time_optimal_slew.py
"""

from convexguid.ocp import Problem

PUBLISHED = 3.2431
SOURCE = "Bilimoria & Wie, J. Guidance, Control, and Dynamics 16(3), 1993: 180 deg, unit inertia and torque"
FIGURE = "final time tf [s]"


def build(intervals: int = 50) -> Problem:
    p = Problem("bilimoria-wie-slew")
    q1, q2 = p.state("q1", initial=0.0, final=0.0), p.state("q2", initial=0.0, final=0.0)
    q3, q4 = p.state("q3", initial=0.0, final=1.0), p.state("q4", initial=1.0, final=0.0)
    w1, w2, w3 = (p.state(f"w{i}", initial=0.0, final=0.0, unit="rad/s") for i in (1, 2, 3))
    u1, u2, u3 = (p.control(f"u{i}", bounds=(-1.0, 1.0)) for i in (1, 2, 3))
    p.dynamics({q1: 0.5 * (w1 * q4 - w2 * q3 + w3 * q2), q2: 0.5 * (w1 * q3 + w2 * q4 - w3 * q1),
                q3: 0.5 * (-w1 * q2 + w2 * q1 + w3 * q4), q4: -0.5 * (w1 * q1 + w2 * q2 + w3 * q3),
                w1: u1, w2: u2, w3: u3})
    p.final_time(bounds=(1.0, 10.0), guess=4.0)
    p.minimize_time()
    p.transcription(intervals)
    return p


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations, solution.objective)
