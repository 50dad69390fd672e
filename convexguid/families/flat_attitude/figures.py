"""Summary figures of a ``flat_attitude`` solve (the keys after the common ones of the summary JSON)."""

from __future__ import annotations

from dataclasses import dataclass

from convexguid.solution import Figures


@dataclass(frozen=True)
class FlatAttitudeFigures(Figures):
    """Figures of a flat-output attitude plan.

    Attributes
    ----------
    energy : float
        Objective of the plan, the torque energy integral (N^2 m^2 s).
    max_torque_Nm : float
        Largest torque component at the nodes, N m.
    map_alpha : float
        Parameter of the grid's node map.
    max_constraint_violation_nodes : float
        Largest constraint violation at the nodes of the last SCP iterate.
    min_separation_deg : float or None
        Smallest angle to a keep-out cone direction on the dense check, deg (None without cones or check).
    """

    energy: float
    max_torque_Nm: float
    map_alpha: float
    max_constraint_violation_nodes: float
    min_separation_deg: float | None = None
