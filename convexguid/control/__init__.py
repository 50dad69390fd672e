"""Feedback attitude control laws."""

from convexguid.control.potential_function import (
    ControlInfo,
    PotentialFunctionController,
    PotentialFunctionGains,
    guo2011_adaptive_gains,
    guo2011_fixed_gains,
)

__all__ = [
    "ControlInfo", "PotentialFunctionController", "PotentialFunctionGains", "guo2011_adaptive_gains",
    "guo2011_fixed_gains",
]
