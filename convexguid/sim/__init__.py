"""Closed-loop attitude simulation."""

from convexguid.sim.reaction_wheel import ManeuverMetrics, SimulationResult, maneuver_metrics, simulate

__all__ = ["ManeuverMetrics", "SimulationResult", "maneuver_metrics", "simulate"]
