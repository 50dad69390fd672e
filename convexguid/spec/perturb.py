"""Problem data with every physical number moved by a tiny relative amount: the round-off a user's machine adds.

Two machines that differ only in how they round (another CPU, another BLAS kernel) feed the SCP inputs and
intermediate results that differ in their last bits. :func:`perturb_inputs` imitates that on the problem file
itself: each floating-point number of the physical sections (spacecraft, boundary conditions, cones, orbit,
gains, errors, disturbances) is multiplied by :math:`1 + \\epsilon s` with a random sign :math:`s = \\pm 1`.
Settings are left alone (solver, discretization, verification, the paper's reference values, the checks and the
simulation's steps and seeds): they choose the method, not the problem. A whole number is a physical number too
(``roll_pitch_yaw_deg: [60, 45, -60]``) and is moved like the others, except under the keys of
:data:`COUNT_KEYS`, which count things; booleans are kept and a zero stays zero. An algorithm whose answer
holds under such a perturbation gives the same answer on every machine; the property tests and the robustness
benchmark (:mod:`convexguid.robustness`) solve each problem file this way.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import numpy as np

SETTINGS_SECTIONS = frozenset({"name", "family", "method", "objective", "description", "notes", "paper",
                               "solver", "discretization", "verification", "reference", "checks", "simulation",
                               "monte_carlo", "sweep", "timing_nodes", "initial_guess", "certify"})
"""Top-level keys whose numbers are settings of the method, not data of the problem: never perturbed."""
COUNT_KEYS = frozenset({"nodes", "intervals", "burns", "runs", "workers", "seed"})
"""Keys whose whole numbers are counts (in any section): never perturbed."""


def perturb_inputs(data: Mapping[str, Any], relative: float, seed: int) -> tuple[dict[str, Any], int]:
    """A deep copy of the problem ``data`` with each physical float scaled by ``1 +/- relative``.

    Parameters
    ----------
    data : mapping
        A problem file as read (:func:`convexguid.spec.loader.read_yaml_mapping`), overrides applied or not.
    relative : float
        The relative size of each change, e.g. ``1e-12``.
    seed : int
        Seed of the signs; the same seed gives the same perturbed data.

    Returns
    -------
    dict
        The perturbed problem data.
    int
        How many numbers were changed.
    """
    rng = np.random.default_rng(seed)
    perturbed = copy.deepcopy(dict(data))
    changed = 0

    def visit(node: Any) -> Any:
        nonlocal changed
        if isinstance(node, dict):
            return {key: value if key in COUNT_KEYS else visit(value) for key, value in node.items()}
        if isinstance(node, list):
            return [visit(value) for value in node]
        if isinstance(node, (int, float)) and not isinstance(node, bool) and node != 0 and np.isfinite(node):
            changed += 1
            return float(node) * (1.0 + relative * (1.0 if rng.random() < 0.5 else -1.0))
        return node

    for key in sorted(perturbed):
        if key not in SETTINGS_SECTIONS:
            perturbed[key] = visit(perturbed[key])
    return perturbed, changed
