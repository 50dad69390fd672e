"""The trials of the robustness benchmark: problem files perturbed by round-off, and random instances per family.

Every random instance is drawn from a seeded generator around one of the committed problem files, so the same
command gives the same instances on every machine. What is drawn, and from which distributions, is stated in
each generator's docstring and repeated in the report.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from convexguid.robustness.trial import Trial
from convexguid.spec.loader import apply_overrides, read_yaml_mapping
from convexguid.spec.perturb import perturb_inputs

ROUNDOFF = 1e-12
"""Relative size of the round-off perturbations."""

SMALLER_RUNS = {"feng2018_lpmpc_montecarlo.yaml": ["monte_carlo.runs=20", "monte_carlo.workers=1"]}
"""Files whose round-off trials run a smaller Monte Carlo than the file's (the 200 runs take minutes each), in the
worker's own process (a Dask worker may not start a process pool of its own)."""


def _read(path: Path, overrides: list[str] = ()) -> dict[str, Any]:
    return apply_overrides(read_yaml_mapping(path, "a problem file"), list(overrides), str(path))


def roundoff_trials(problem_files: list[Path], perturbations: int, links: dict[str, list[str]]) -> Iterator[Trial]:
    """Each file as written (label ``nominal``) and ``perturbations`` times moved by :data:`ROUNDOFF`.

    ``links`` gives the overrides that resolve a file's input links (``boundary.tf_from``: another case's
    result), by file name; :mod:`convexguid.robustness.bench` takes them from the nominal runs of the linked cases.
    """
    for path in problem_files:
        data = _read(path, SMALLER_RUNS.get(path.name, []) + links.get(path.name, []))
        yield Trial(0, "round-off", path.name, "nominal", data, str(path))
        for seed in range(1, perturbations + 1):
            moved, _ = perturb_inputs(data, ROUNDOFF, seed)
            yield Trial(0, "round-off", path.name, f"perturbed {seed}", moved, str(path))


def _unit(rng: np.random.Generator) -> list[float]:
    v = rng.standard_normal(3)
    return [float(x) for x in v / np.linalg.norm(v)]


def random_rendezvous(problems: Path, samples: int, seed: int) -> Iterator[Trial]:
    """3-D finite-thrust rendezvous around ``wang2003_rendezvous_3d.yaml``, burns from LCvx (``burns: auto``).

    Initial position x ~ U(6, 16) km, y ~ U(-1.5, 1.5) km, z ~ U(-1, 1) km; velocity x ~ U(-100, -40) m/s,
    y ~ U(-15, 15) m/s, z ~ U(-8, 8) m/s; the target, the 600 s and the 0.5 m/s^2 thrust as in the file.
    Judged against the LCvx optimum on the file's grid.
    """
    path = problems / "wang2003_rendezvous_3d.yaml"
    rng = np.random.default_rng(seed)
    for i in range(samples):
        r = [rng.uniform(6000, 16000), rng.uniform(-1500, 1500), rng.uniform(-1000, 1000)]
        v = [rng.uniform(-100, -40), rng.uniform(-15, 15), rng.uniform(-8, 8)]
        data = _read(path, [f"boundary.initial.position_m={[round(x, 3) for x in r]}",
                            f"boundary.initial.velocity_mps={[round(x, 4) for x in v]}",
                            "discretization.burns=auto"])
        yield Trial(0, "random rendezvous", "rendezvous", f"#{i}", data, str(path), reference_starts=1)


def random_flat_attitude(problems: Path, samples: int, seed: int) -> Iterator[Trial]:
    """Cai, Zhu, Zeng's slew with the sun cone active (``cai2018_flat_attitude_sun_active.yaml``), each of the six
    boundary 3-2-1 Euler angles moved by N(0, (5 deg)^2). Judged against IPOPT on the same NLP from 4 starts."""
    path = problems / "cai2018_flat_attitude_sun_active.yaml"
    base = _read(path)
    rng = np.random.default_rng(seed)
    for i in range(samples):
        overrides = []
        for end in ("initial", "final"):
            angles = base["boundary"][end]["roll_pitch_yaw_deg"]
            moved = [round(float(a) + 5.0 * rng.standard_normal(), 4) for a in angles]
            overrides.append(f"boundary.{end}.roll_pitch_yaw_deg={moved}")
        yield Trial(0, "random flat attitude", "flat attitude", f"#{i}", _read(path, overrides), str(path),
                    reference_starts=4)


def random_minimum_time_slews(problems: Path, samples: int, seed: int, rate_max_degps: float | None = 1000.0
                              ) -> Iterator[Trial]:
    """Unconstrained minimum-time rest-to-rest slews on ``wang_multicone_time.yaml``'s grid (50 intervals, no
    cones): principal inertias ~ U(1, 10) kg m^2 about a random frame (products of inertia included), a random
    axis, angle ~ U(30, 180) deg, per-axis torque box ~ U(0.5, 2) N m, rate bound ``rate_max_degps`` (1000 deg/s:
    never reached). Judged against IPOPT on the same NLP from 4 starts."""
    path = problems / "wang_multicone_time.yaml"
    rng = np.random.default_rng(seed)
    for i in range(samples):
        q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
        inertia = q @ np.diag(rng.uniform(1.0, 10.0, 3)) @ q.T
        matrix = [[round(float(x), 6) for x in row] for row in (inertia + inertia.T) / 2]
        overrides = ["keep_out=[]", f"spacecraft.inertia_kgm2={matrix}",
                     f"spacecraft.torque_max_Nm={[round(float(x), 4) for x in rng.uniform(0.5, 2.0, 3)]}",
                     f"spacecraft.rate_max_degps={rate_max_degps!r}".replace("None", "null"),
                     f"boundary.final.axis={[round(x, 6) for x in _unit(rng)]}",
                     f"boundary.final.angle_deg={round(float(rng.uniform(30, 180)), 3)}"]
        yield Trial(0, "random minimum-time slew", "minimum-time slew", f"#{i}", _read(path, overrides), str(path),
                    reference_starts=4)


def random_multicone_energy(problems: Path, samples: int, seed: int) -> Iterator[Trial]:
    """The multi-cone minimum-energy slew (``wang_multicone_energy.yaml``) with the final attitude's axis moved by
    N(0, (5 deg)^2) per component and its angle by U(-10, 10) deg. Judged against IPOPT from 4 starts."""
    path = problems / "wang_multicone_energy.yaml"
    base = _read(path)
    rng = np.random.default_rng(seed)
    final = base["boundary"]["final"]
    for i in range(samples):
        axis = np.asarray(final["axis"], float)
        axis = axis / np.linalg.norm(axis) + np.radians(5.0) * rng.standard_normal(3)
        angle = float(final["angle_deg"]) + rng.uniform(-10, 10)
        overrides = [f"boundary.final.axis={[round(float(x), 6) for x in axis / np.linalg.norm(axis)]}",
                     f"boundary.final.angle_deg={round(angle, 3)}"]
        yield Trial(0, "random multi-cone energy", "multi-cone energy", f"#{i}", _read(path, overrides), str(path),
                    reference_starts=4)


GENERATORS: dict[str, Callable[[Path, int, int], Iterator[Trial]]] = {
    "rendezvous": random_rendezvous,
    "flat": random_flat_attitude,
    "slew": random_minimum_time_slews,
    "multicone": random_multicone_energy,
}
"""Random-instance sections by the name ``--families`` takes."""

DEFAULT_SAMPLES = {"rendezvous": 100, "flat": 12, "slew": 12, "multicone": 6}
"""Instances per section when ``--samples`` is not given."""
