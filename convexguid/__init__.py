"""convexguid: spacecraft guidance problems solved as sequences of convex programs.

Public API: :func:`load_problem`, :func:`solve`, :func:`simulate`, :func:`validate`.
"""

from convexguid.api import simulate, solve
from convexguid.report.validation import validate
from convexguid.spec import load_problem

__all__ = ["load_problem", "simulate", "solve", "validate"]
__version__ = "0.1.0"
