"""Expand a campaign into runs: grid points times Monte Carlo samples, each with its exact ``--set`` overrides.

Run ids count grid point by grid point: ``run_id = grid_point * samples + sample``, grid axes in the file's order,
the last axis fastest. Sample ``s`` takes child ``s`` of ``numpy.random.SeedSequence(seed).spawn(samples)`` and
spawns two from it: the first seeds the generator of its dispersions (drawn in the file's order), the second
gives the integer the ``seed_key`` receives. Every grid point uses the same samples (common random numbers), so
two grid points differ by their grid values only. A run's overrides are the campaign's ``set``, then its varied
values, then its seed: ``convexguid solve PROBLEM --set ...`` with them replays it.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml

if TYPE_CHECKING:
    from convexguid.campaign.definition import Campaign


@dataclass(frozen=True)
class Run:
    """One run of a campaign.

    ``values`` maps each varied key to its value (grid values as the file writes them, drawn values as floats);
    ``seed`` is the value given to the ``seed_key`` (None without one); ``overrides`` are the ``--set`` strings
    that make the problem file this run's problem.
    """

    run_id: int
    sample: int
    values: dict[str, Any]
    seed: int | None
    overrides: tuple[str, ...]


def yaml_text(value: Any) -> str:
    """``value`` as one line of YAML that reads back equal (floats exactly: PyYAML writes their shortest
    round-trip form, with the ``.0`` its own reader needs in ``1.0e-05``)."""
    lines = yaml.safe_dump(value, default_flow_style=True, width=float("inf")).splitlines()
    return " ".join(line for line in lines if line != "...")


def override(key: str, value: Any) -> str:
    """The ``--set`` string giving ``key`` the value ``value``."""
    return f"{key}={yaml_text(value)}"


def plan_runs(campaign: Campaign) -> list[Run]:
    """Every run of ``campaign``, in run id order (see the module docstring)."""
    spec = campaign.spec
    axes = [[dict(zip(axis.names, point, strict=True)) for point in axis.points()] for axis in spec.grid]
    samples = _samples(campaign)
    runs = []
    for point in product(*axes):
        grid_values = {k: v for values in point for k, v in values.items()}
        for sample, (draws, seed) in enumerate(samples):
            values = {**grid_values, **draws}
            seeded = (override(spec.seed_key, seed),) if spec.seed_key is not None else ()
            overrides = (*spec.set, *(override(k, v) for k, v in values.items()), *seeded)
            runs.append(Run(len(runs), sample, values, seed if spec.seed_key is not None else None, overrides))
    return runs


def _samples(campaign: Campaign) -> list[tuple[dict[str, float], int]]:
    """Per sample: the dispersed values and the problem seed (one sample without dispersions or seed key)."""
    spec = campaign.spec
    if not spec.random:
        return [({}, 0)]
    out = []
    for child in np.random.SeedSequence(spec.seed).spawn(spec.samples):
        draw_seq, seed_seq = child.spawn(2)
        rng = np.random.default_rng(draw_seq)
        draws = {d.key: d.draw(rng, campaign.nominal[d.key]) for d in spec.dispersions}
        out.append((draws, int(seed_seq.generate_state(1, np.uint64)[0]) >> 1))
    return out
