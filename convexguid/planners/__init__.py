"""Heuristic (non-SCP) attitude planners used as paper baselines and as SCP initial guesses."""

from convexguid.planners.path_transfer import (
    PathSegment,
    PathTransferCone,
    PathTransferError,
    PathTransferProblem,
    PathTransferResult,
    eigenaxis_path,
    multicone_scenario,
    plan_path_transfer,
)

__all__ = [
    "PathSegment", "PathTransferCone", "PathTransferError", "PathTransferProblem", "PathTransferResult",
    "eigenaxis_path", "multicone_scenario", "plan_path_transfer",
]
