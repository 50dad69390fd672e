"""Planned body torque as a function of time, with the times where it is not smooth.

A dense check integrates the rigid body under the planned torque
(:func:`convexguid.verification.propagate_attitude`). Planned torques are smooth between known times: the
nodes of a piecewise-linear interpolant (kinks), the phase changes of a bang-coast-bang law (jumps).
An adaptive integrator that steps across such a time shrinks its step until the error estimate
accepts it, many steps per kink; integrated piece by piece between the breakpoints, each piece is
smooth and takes the steps its tolerance needs.

:class:`TorqueCommand` bundles the torque ``u(t)`` (one time, fast: it sits in the integrator's
inner loop), its breakpoints and a vectorised sampler (for the dense grid).
"""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike


class TorqueCommand:
    """Body torque ``u(t)`` in N m, smooth between ``breakpoints`` (s).

    ``command(t)`` is the torque at one time, shape ``(3,)``; ``command.sample(times)`` the torques at
    many, ``(M, 3)`` (``sample`` defaults to one call per time). At a breakpoint the torque may
    have a kink or a jump; an empty ``breakpoints`` means smooth on the whole interval.
    """

    def __init__(self, torque: Callable[[float], np.ndarray], breakpoints: ArrayLike = (),
                 sample: Callable[[np.ndarray], np.ndarray] | None = None) -> None:
        self._torque, self._sample = torque, sample
        self.breakpoints = np.unique(np.asarray(breakpoints, dtype=float))

    def __call__(self, t: float) -> np.ndarray:
        return self._torque(t)

    def sample(self, times: ArrayLike) -> np.ndarray:
        """Torques at ``times``, ``(M, 3)``."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        if self._sample is not None:
            return np.asarray(self._sample(times), dtype=float).reshape(times.size, 3)
        return np.array([self(t) for t in times], dtype=float).reshape(times.size, 3)


class LinearTorque(TorqueCommand):
    """Linear interpolation of node torques ``values`` (N, 3) at increasing ``times`` (N,), held outside.

    The value at one time is computed as :func:`numpy.interp` does (same formula, same result), with
    plain floats; the interior nodes are the breakpoints (kinks).
    """

    def __init__(self, times: ArrayLike, values: ArrayLike) -> None:
        self.times = np.asarray(times, dtype=float)
        self.values = np.asarray(values, dtype=float).reshape(self.times.size, 3)
        super().__init__(self._at, self.times[1:-1])
        self._t = self.times.tolist()
        self._u = [tuple(row) for row in self.values.tolist()]
        # slope of each interval per axis, as numpy.interp forms it
        self._slopes = [tuple((b - a) / (t1 - t0) for a, b in zip(u0, u1, strict=True))
                        for t0, t1, u0, u1 in zip(self._t[:-1], self._t[1:], self._u[:-1], self._u[1:], strict=True)]

    def _at(self, t: float) -> np.ndarray:
        t = float(t)
        knots = self._t
        if t <= knots[0]:
            return np.array(self._u[0])
        if t >= knots[-1]:
            return np.array(self._u[-1])
        j = bisect_right(knots, t) - 1
        tj, uj = knots[j], self._u[j]
        if t == tj:
            return np.array(uj)
        dt = t - tj
        return np.array([s * dt + u for s, u in zip(self._slopes[j], uj, strict=True)])

    def sample(self, times: ArrayLike) -> np.ndarray:
        times = np.atleast_1d(np.asarray(times, dtype=float))
        return np.column_stack([np.interp(times, self.times, self.values[:, i]) for i in range(3)])
