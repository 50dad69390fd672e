"""Disturbance torque models shared by the closed-loop simulations (the potential-function controller's
reaction-wheel plant and the LPMPC/LQR flights).

Guo Yanning, Li Chuanjiang, Ma Guangfu, "Spacecraft autonomous attitude maneuver control by potential function
method", Acta Aeronautica et Astronautica Sinica 32(3), 457-464, 2011 (Sec. 4).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray


def guo2011_disturbance(t: float) -> NDArray:
    r"""Disturbance torque of Guo, Li, Ma, Sec. 4 (N m, body axes).

    .. math:: u_d = 10^{-3}\,[\sin(0.01t) - 0.5,\; \sin(0.01t) + 0.5,\; \cos(0.01t)]^T
    """
    s, c = math.sin(0.01 * t), math.cos(0.01 * t)
    return np.array([1e-3 * (s - 0.5), 1e-3 * (s + 0.5), 1e-3 * c])


def no_disturbance(t: float) -> NDArray:
    """Zero disturbance torque."""
    return np.zeros(3)
