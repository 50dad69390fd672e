"""convexguid: spacecraft guidance problems solved as sequences of convex programs.

Public API: :func:`load_problem`, :func:`solve`, :func:`simulate`, :func:`validate`, :func:`run_campaign`.
They are imported on first use, so ``import convexguid`` stays light (no SCP engine, no matplotlib, no Dask).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from convexguid.api import simulate, solve
    from convexguid.campaign import run_campaign
    from convexguid.problem_files import load_problem
    from convexguid.validation.run import validate

__all__ = ["load_problem", "run_campaign", "simulate", "solve", "validate"]
__version__ = "0.1.0"

_PUBLIC = {"load_problem": "convexguid.problem_files", "simulate": "convexguid.api", "solve": "convexguid.api",
           "validate": "convexguid.validation.run", "run_campaign": "convexguid.campaign"}
"""Module of each public name."""


def __getattr__(name: str) -> Any:
    if name in _PUBLIC:
        value = getattr(importlib.import_module(_PUBLIC[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
