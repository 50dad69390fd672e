"""The Delta III launch to a geosynchronous transfer orbit: four burn phases, stages dropped between them, the most
mass delivered.

The multiphase ascent of Benson's thesis (MIT, 2004) as the GPOPS and PSOPT examples state it (PSOPT applications
document, Sec. 16, and its source examples/launch/launch.cxx, whose constants are used here): PSOPT reaches a final
mass of 7529.661 kg at t_f = 924.1413 s.

Earth-centred inertial position r and velocity v (SI units), mass m, and the thrust direction u (a unit vector):

    r' = v,  v' = -mu r / |r|^3 + (T / m) u + D / m,  m' = -T / (g0 Isp),
    D = -1/2 C_D A rho |v_rel| v_rel,  v_rel = v - omega x r,  rho = rho_0 exp(-(|r| - R_e) / h_0).

Phase ``stage1`` (0 to 75.2 s): six solid boosters and the first stage; ``stage2`` (to 150.4 s): the other three
boosters and the first stage, the six spent cases dropped; ``stage3`` (to 261 s): the first stage alone, three more
cases dropped; ``stage4`` (at most 700 s more): the second stage, the first dropped. Position and velocity are
continuous across the junctions and the mass falls by each dropped structure. The final orbit: semi-major axis
24361.14 km, eccentricity 0.7308, inclination 28.5 deg, node 269.8 deg, argument of perigee 130.5 deg (five
nonlinear equalities of the final state, the quadrants of the node and perigee as point constraints).

Statement choices a user makes here, and why (each measured on 20 intervals a phase):
- |v_rel| is smoothed by 1 mm/s: the rocket starts at rest relative to the air, where the norm has no derivative.
- Position and velocity are scaled per phase by about how far they move in it (100 km and 2 km/s in the first
  phase, up to 1000 km and 6 km/s in the third), not by their size (an Earth radius): the trust region is a box
  in scaled units, and at the size's scale one step of the first phase could span two density scale heights. With
  the scales the bounds give, the run crawled to ``max_iterations``.
- The semi-major axis row is stated relative, a / a_f - 1, as the other rows are of order one.
- The guess climbs continuously from the pad to the target orbit's perigee (position turned and stretched, velocity
  linear, mass linear in each phase), the last phase guessed at 700 s.
Measured (python -m convexguid.classics, 20 intervals a phase): converged and verified at 7529.715 kg (+7.2e-6 of
PSOPT's figure) in 85 SCP iterations, about 40 s; IPOPT on the same transcription from the same guess reaches the
same mass in 1526 iterations. With the constants moved by 1e-12 the plan ends at the same mass to the gram.
Run: python examples/phases/delta_iii_launch.py
"""

import math

import casadi as ca
import numpy as np

from convexguid.ocp import Phases, Problem

PUBLISHED = 7529.661
SOURCE = "Benson 2004; PSOPT applications document, Sec. 16 (examples/launch), Delta III launch: m(tf) = 7529.661 kg"
FIGURE = "final mass m(tf) [kg]"

MU, OMEGA, R_E, G0 = 3.986012e14, 7.29211585e-5, 6378145.0, 9.80665
C_D, AREA, RHO_0, H_0 = 0.5, 4 * math.pi, 1.225, 7200.0
LATITUDE = math.radians(28.5)
SPEED_SMOOTHING = 1e-3  # m/s

# (total mass, propellant mass, thrust, burn time) of a solid booster, the first stage and the second stage
BOOSTER, FIRST, SECOND = (19290.0, 17010.0, 628500.0, 75.2), (104380.0, 95550.0, 1083100.0, 261.0), \
    (19300.0, 16820.0, 110094.0, 700.0)
PAYLOAD = 4164.0
ENDS = (75.2, 150.4, 261.0, 961.0)  # s: the phases' ends (the last one's at most)
ORBIT = (24361140.0, 0.7308, math.radians(28.5), math.radians(269.8), math.radians(130.5))  # a, e, i, node, perigee
SCALES = ((1e5, 2e3), (3e5, 3e3), (1e6, 6e3), (None, None))  # (position m, velocity m/s) per phase
LAST_PHASE_GUESS = 700.0  # s


def burn(stage: tuple[float, float, float, float]) -> tuple[float, float]:
    """A stage's thrust and its propellant's flow (it burns at a constant rate for its burn time)."""
    _, propellant, thrust, burn_time = stage
    return thrust, propellant / burn_time


def dropped_mass(k: int) -> float:
    """The structure dropped where phase ``k`` ends."""
    return (6 * (BOOSTER[0] - BOOSTER[1]), 3 * (BOOSTER[0] - BOOSTER[1]), FIRST[0] - FIRST[1])[k]


def phases_table() -> list[tuple[float, float, float, float]]:
    """Per phase: thrust [N], mass flow [kg/s], mass at its start and at its end [kg], all engines at full burn."""
    boosters, first, second = burn(BOOSTER), burn(FIRST), burn(SECOND)
    engines = [((6, boosters), (1, first)), ((3, boosters), (1, first)), ((1, first),), ((1, second),)]
    mass = PAYLOAD + SECOND[0] + FIRST[0] + 9 * BOOSTER[0]
    table, start = [], 0.0
    for k, running in enumerate(engines):
        thrust = sum(n * t for n, (t, _) in running)
        flow = sum(n * f for n, (_, f) in running)
        mass -= dropped_mass(k - 1) if k else 0.0
        end = mass - flow * (ENDS[k] - start) if k < 3 else PAYLOAD
        table.append((thrust, flow, mass, end))
        mass, start = end, ENDS[k]
    return table


PHASES = phases_table()


def about_z(angle: float) -> np.ndarray:
    """The active rotation by ``angle`` about z (convexguid.rotations gives the same as the transpose of a DCM built
    from quaternions, equal to 1e-16; those last bits moved this run's path from 85 to 100 iterations)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def about_x(angle: float) -> np.ndarray:
    """The active rotation by ``angle`` about x."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def orbit_state(true_anomaly: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity on the target orbit at ``true_anomaly``."""
    a, e, inclination, node, perigee = ORBIT
    p = a * (1 - e * e)
    radius = p / (1 + e * math.cos(true_anomaly))
    in_plane_r = radius * np.array([math.cos(true_anomaly), math.sin(true_anomaly), 0.0])
    in_plane_v = math.sqrt(MU / p) * np.array([-math.sin(true_anomaly), e + math.cos(true_anomaly), 0.0])
    rotation = about_z(node) @ about_x(inclination) @ about_z(perigee)  # perifocal to inertial, 3-1-3
    return rotation @ in_plane_r, rotation @ in_plane_v


def pad_state() -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity at lift-off: at 28.5 deg latitude on the meridian of the x axis, turning with the
    Earth."""
    r = np.array([R_E * math.cos(LATITUDE), 0.0, R_E * math.sin(LATITUDE)])
    return r, np.cross([0.0, 0.0, OMEGA], r)


def orbit_rows(r, v) -> tuple[list, ca.SX, ca.SX]:
    """The five final-orbit equalities of ``(r, v)`` and the two quadrant signs (node's y, eccentricity's z)."""
    a_f, e_f, inclination, node, perigee = ORBIT
    h = ca.cross(r, v)
    n = ca.vertcat(-h[1], h[0], 0)  # the node line, z x h
    radius, speed2 = ca.norm_2(r), ca.dot(v, v)
    e_vector = ((speed2 - MU / radius) * r - ca.dot(r, v) * v) / MU
    e = ca.norm_2(e_vector)
    a = 1 / (2 / radius - speed2 / MU)
    rows = [a / a_f - 1, e - e_f, h[2] / ca.norm_2(h) - math.cos(inclination),
            n[0] / ca.norm_2(n) - math.cos(node), ca.dot(n, e_vector) / (ca.norm_2(n) * e) - math.cos(perigee)]
    return rows, n[1], e_vector[2]


def stage(k: int, intervals: int, scales: tuple[float | None, float | None]) -> tuple[Problem, ca.SX, ca.SX, ca.SX]:
    thrust, flow, mass_start, mass_end = PHASES[k]
    position_scale, velocity_scale = scales
    p = Problem(f"stage{k + 1}")
    at_pad = np.concatenate(pad_state())
    r = ca.vertcat(*(p.state(name, bounds=(-2 * R_E, 2 * R_E), initial=at_pad[j] if k == 0 else None,
                             scale=position_scale, unit="m") for j, name in enumerate("xyz")))
    v = ca.vertcat(*(p.state(name, bounds=(-1e4, 1e4), initial=at_pad[3 + j] if k == 0 else None,
                             scale=velocity_scale, unit="m/s") for j, name in enumerate(("vx", "vy", "vz"))))
    m = p.state("m", bounds=(mass_end, mass_start), initial=mass_start if k == 0 else None, unit="kg")
    u = ca.vertcat(*(p.control(name, bounds=(-1.0, 1.0)) for name in ("u1", "u2", "u3")))
    v_rel = v - ca.cross(ca.DM([0.0, 0.0, OMEGA]), r)
    density = RHO_0 * ca.exp(-(ca.norm_2(r) - R_E) / H_0)
    drag = -0.5 * C_D * AREA * density * ca.sqrt(ca.dot(v_rel, v_rel) + SPEED_SMOOTHING**2) * v_rel
    acceleration = -MU * r / ca.norm_2(r) ** 3 + thrust / m * u + drag / m
    p.dynamics({**{r[j]: v[j] for j in range(3)}, **{v[j]: acceleration[j] for j in range(3)}, m: -flow})
    p.path_equality("unit_thrust_direction", ca.dot(u, u) - 1)
    if k < 3:
        p.final_time(fixed=ENDS[k] - (ENDS[k - 1] if k else 0.0))
    else:
        p.final_time(bounds=(1.0, ENDS[3] - ENDS[2]), guess=LAST_PHASE_GUESS)
    p.transcription(intervals)
    return p, r, v, m


def climbing_guess(problems: list[Problem], intervals: int) -> None:
    """From the pad to the target orbit's perigee over the whole ascent: the position's direction turned at a steady
    rate while its length grows linearly, the velocity linear, the mass linear within each phase, thrust along the
    velocity."""
    start_r, start_v = pad_state()
    end_r, end_v = orbit_state(0.0)
    starts, total = (0.0, *ENDS[:3]), ENDS[2] + LAST_PHASE_GUESS
    angle = math.acos(float(np.clip(start_r @ end_r / (np.linalg.norm(start_r) * np.linalg.norm(end_r)), -1, 1)))
    share = np.linspace(0.0, 1.0, intervals + 1)
    for k, p in enumerate(problems):
        duration = (ENDS[k] - starts[k]) if k < 3 else LAST_PHASE_GUESS
        s = ((starts[k] + share * duration) / total)[:, None]
        direction = (np.sin((1 - s) * angle) * start_r / np.linalg.norm(start_r)
                     + np.sin(s * angle) * end_r / np.linalg.norm(end_r)) / math.sin(angle)
        r = direction * (np.linalg.norm(start_r) + s * (np.linalg.norm(end_r) - np.linalg.norm(start_r)))
        v = start_v + s * (end_v - start_v)
        _, _, mass_start, mass_end = PHASES[k]
        m = mass_start + share[:, None] * (mass_end - mass_start)
        p.initial_guess(np.hstack([r, v, m]), v / np.linalg.norm(v, axis=1)[:, None])


def build(intervals: int = 20, scales=SCALES, guessed: bool = True) -> Phases:
    """``intervals`` Hermite-Simpson intervals a phase; ``scales`` (position, velocity) per phase (None: the bounds
    give them); ``guessed``: the climbing guess, else the engine's straight lines."""
    made = [stage(k, intervals, scales[k]) for k in range(4)]
    problems = [p for p, *_ in made]
    last, r, v, m = made[3]
    rows, node_y, perigee_z = orbit_rows(r, v)
    last.boundary_constraint("target_orbit", rows, at="final")
    last.point_constraint("node_quadrant", node_y, at=1.0)  # the node at 269.8 deg: its line's y below zero
    last.point_constraint("perigee_quadrant", -perigee_z, at=1.0)  # perigee at 130.5 deg: above the equator
    last.minimize_terminal(-m)
    if guessed:
        climbing_guess(problems, intervals)
    ascent = Phases("delta-iii", problems)
    for k in range(3):
        ascent.connect(problems[k], problems[k + 1], ["x", "y", "z", "vx", "vy", "vz"])
        ascent.link(f"stage_drop_{k + 1}", problems[k].end(made[k][3]) - problems[k + 1].start(made[k + 1][3])
                    - dropped_mass(k))
    return ascent


def figure(final_state: dict[str, float], final_time: float) -> float:
    return final_state["m"]


if __name__ == "__main__":
    solution = build().solve()
    print(solution.status, solution.message, solution.iterations,
          f"final mass {solution.nodes.columns['m'][-1]:.3f} kg at {solution.figures.final_time_s:.4f} s")
