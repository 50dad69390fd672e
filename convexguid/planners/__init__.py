"""Heuristic (non-SCP) attitude planners used as paper baselines and as SCP initial guesses."""

from convexguid.planners.path_transfer import (
    PathSegment,
    PathTransferError,
    PathTransferProblem,
    PathTransferResult,
    multicone_scenario,
    plan_path_transfer,
)

__all__ = [
    "PathSegment", "PathTransferError", "PathTransferProblem", "PathTransferResult",
    "multicone_scenario", "plan_path_transfer",
]
