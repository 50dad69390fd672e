"""Problem families: each turns a validated spec into a planned, verified :class:`~convexguid.solution.Solution`."""

from __future__ import annotations

from collections.abc import Callable

from convexguid.formulations.flat_attitude import solve_flat_attitude
from convexguid.formulations.quaternion_attitude_solve import solve_quaternion_attitude
from convexguid.formulations.rendezvous import solve_rendezvous

FAMILY_SOLVERS: dict[str, Callable] = {"flat_attitude": solve_flat_attitude, "rendezvous": solve_rendezvous,
                                   "quaternion_attitude": solve_quaternion_attitude}
"""Solve function of each family, by the spec's ``family`` value."""
