"""The mapped Chebyshev pseudospectral transcription (the grid of Cai, Zhu & Zeng 2018, Sec. 2.3, eqs. 17-26).

States and controls are their values at the :math:`N + 1` mapped Chebyshev-Gauss-Lobatto nodes :math:`\\lambda_k`
(:class:`~convexguid.transcription.mapped_chebyshev.MappedChebyshev`: the Kosloff-Tal-Ezer map spreads the CGL
points towards a uniform grid and keeps the differentiation matrix well conditioned), :math:`t_k = (\\lambda_k + 1)
t_f / 2`; between nodes both are the barycentric interpolant through all of them (eq. 21). The dynamics are
collocated at every node with the differentiation matrix :math:`D` (eq. 22):

.. math::

    \\tfrac{2}{N}\\Big(\\sum_j D_{kj} x_j - \\tfrac{t_f}{2} f(x_k, u_k, t_k)\\Big) = 0,\\qquad k = 0..N,

divided by the states' scales (the factor :math:`2/N`, about one node spacing in :math:`\\lambda`, puts the defect
in the state's own units, as a Hermite-Simpson defect is). Path constraints and bounds hold at the nodes; the
objectives use the map's Clenshaw-Curtis weights (eq. 26). For smooth problems the error falls faster than any power
of :math:`1/N`; for a bang-bang control (a switch inside the grid) prefer a hold or Hermite-Simpson. A point
constraint must fall on a node (``at`` 0 or 1, or a node's share of the final time).
"""

from __future__ import annotations

from functools import cached_property

import casadi as ca
import numpy as np

from convexguid.ocp.mesh import require_point_constraints_on_nodes
from convexguid.ocp.transcription import Symbols, Transcription
from convexguid.transcription.mapped_chebyshev import MappedChebyshev

MAP_EPSILON = 1e-6
"""The rounding error the Kosloff-Tal-Ezer map admits (eq. 20; the paper's value)."""


class MappedChebyshevProgram(Transcription):
    method = "chebyshev"

    def __init__(self, problem, margins=None, intervals=None) -> None:
        self.grid = MappedChebyshev(intervals if intervals is not None else problem.intervals, MAP_EPSILON)
        require_point_constraints_on_nodes(problem, self.node_shares(),
                                           f"{self.grid.n}-interval mapped Chebyshev grid")
        super().__init__(problem, margins, intervals)

    def node_shares(self) -> np.ndarray:
        return 0.5 * (self.grid.nodes + 1.0)

    def control_values_per_axis(self) -> int:
        return self.N + 1

    def per_step_weights(self) -> np.ndarray:
        # the quadrature over [-1, 1] in lambda is t_f / 2 times one over [0, t_f]; per step of t_f / N
        return self.grid.quadrature_weights * self.N / 2

    def intervals(self, s: Symbols, imposed) -> list:
        N, f = self.N, self.rate
        derivative = ca.mtimes(s.X, ca.DM(np.asarray(self.grid.d1).T))  # column k: sum_j D_kj x_j
        defects = []
        for k, share in enumerate(self.node_shares()):
            time = float(share) * s.tf
            rate = f(s.X[:, k], s.V[:, k], time)
            defects.append((2.0 / N) * (derivative[:, k] - s.tf / 2 * rate) / self.state_scale)
            imposed("node", k, float(share), s.X[:, k], s.V[:, k], time)
        return defects

    def control_value_shares(self) -> np.ndarray:
        return self.node_shares()

    def node_controls(self, z: np.ndarray) -> np.ndarray:
        return self.control_values(z)

    def values_from_nodes(self, controls: np.ndarray) -> np.ndarray:
        return controls

    @cached_property
    def _barycentric(self) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(self.grid.nodes), np.asarray(self.grid.barycentric_weights)

    def control_function(self, z: np.ndarray):
        values, tf = self.control_values(z), self.final_time(z)
        nodes, weights = self._barycentric

        def u(t: float) -> np.ndarray:
            lam = 2.0 * t / tf - 1.0
            gap = lam - nodes
            hit = np.flatnonzero(np.abs(gap) < 1e-14)
            if hit.size:
                return values[hit[0]]
            terms = weights / gap
            return terms @ values / terms.sum()

        return u

    def refined(self, z: np.ndarray) -> tuple[MappedChebyshevProgram, np.ndarray]:
        """The same problem on a grid of twice the order, the states and controls interpolated onto it."""
        fine = MappedChebyshevProgram(self.problem, intervals=2 * self.N)
        onto = self.grid.interpolation_matrix(np.asarray(fine.grid.nodes))
        return fine, fine.assemble(onto @ self.states(z), onto @ self.control_values(z), self.final_time(z))
