"""convexguid: spacecraft guidance problems solved as sequences of convex programs.

Public API: :func:`load_problem`, :func:`solve`, :func:`validate`.
"""

from convexguid.api import solve
from convexguid.report.validation import validate
from convexguid.spec import load_problem

__all__ = ["load_problem", "solve", "validate"]
__version__ = "0.1.0"
