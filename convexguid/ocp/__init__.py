"""Your own guidance problem in Python: :class:`Problem` (states, controls, final time, dynamics, path constraints,
objective), planned by the same SCP engine as the paper families and checked by the same dense SciPy
re-propagation. A maneuver in phases (burn, coast, burn; stages) is a :class:`Phases` of problems linked at their
ends. See ``examples/`` and the README's "Your own problem"."""

from convexguid.ocp.phases import Phases
from convexguid.ocp.problem import Problem

__all__ = ["Phases", "Problem"]
