"""Linear pseudospectral model predictive control (LPMPC): the terminal-error map and the energy-optimal correction.

About a nominal :math:`(\\tilde x, \\tilde u)` on :math:`[t_0, t_f]` the deviations
:math:`\\delta x = x - \\tilde x`, :math:`\\delta u = u - \\tilde u` obey
:math:`\\delta\\dot x = A(t)\\delta x + B(t)\\delta u` (eq. 11). On the :math:`N` LGR points
:math:`\\tau_0 = -1, \\dots, \\tau_{N-1}` with the state also carried at :math:`\\tau_N = 1`
(:mod:`convexguid.transcription.lgr`) and :math:`p = (t_f - t_0)/2`, collocation at every LGR point reads
(eqs. 29-37)

.. math::

    \\sum_{l=0}^{N} D_{kl}\\,\\delta x_l = p\\,(A_k \\delta x_k + B_k \\delta u_k), \\qquad k = 0, \\dots, N-1,

with :math:`\\delta x_0` known and :math:`\\delta u_0 = 0` (the command stays continuous at :math:`t_0`).
Solved for the unknown states, its last block is the terminal deviation, equivalently the Radau
quadrature :math:`\\delta x_f = \\delta x_0 + p \\sum_k w_k (A_k\\delta x_k + B_k\\delta u_k)` (eqs. 38-41), so
(eqs. 42-44)

.. math:: \\delta x_f = K_x\\,\\delta x_0 + K_u\\,\\delta\\hat U, \\qquad
          \\delta\\hat U = [\\delta u_1, \\dots, \\delta u_{N-1}].

The correction (eqs. 45-56): after re-nominalizing from the current state (:math:`\\delta x_0 = 0`) the
nominal misses the target by :math:`e = \\tilde x(t_f) - x_f`; choose :math:`\\delta\\hat U` with
:math:`K_u\\,\\delta\\hat U = -e` minimizing the energy of the *corrected* control,
:math:`\\sum_k p\\,w_k\\,|\\tilde u_k + \\delta u_k|^2` (eq. 50), whose KKT solution is

.. math::

    \\tilde U + \\delta\\hat U = \\Omega^{-1} K_u^T P^{-1} (K_u \\tilde U - e), \\qquad
    \\Omega = \\mathrm{diag}(p\\,w_k) \\otimes I_3, \\quad P = K_u \\Omega^{-1} K_u^T.

For an energy-optimal nominal this correction is small only if :math:`K_u / (p w_k)` is the adjoint
sensitivity :math:`\\Phi(t_f, t_k) B_k`, which the Radau layout above gives to about 1e-5 on the Feng
scenario. Reading the paper's count literally (states interpolated on :math:`N + 1` LGR points only,
collocation off :math:`\\tau_0`, :math:`K_u \\in R^{6 \\times 3N}`) gave per-node sensitivities 20-40% off,
and a correction of 3.9 N m for a zero miss; here :math:`N` counts the LGR points and
:math:`K_u \\in R^{6 \\times 3(N-1)}`. Signs follow :math:`\\delta x = x - \\tilde x`; the paper writes
:math:`u = \\tilde u - \\delta u`, the same correction. :func:`box_constrained_correction` adds
:math:`|\\tilde u_k + \\delta u_k| \\le U_{max}` at the nodes, the paper's listed defect, as a small QP
through the project's backends.

References
----------
Feng Y., Chen W., Yang L., "Fuel-optimal attitude maneuver using linear pseudo-spectral model predictive
control method", J. Beijing Univ. Aeronautics and Astronautics 44(10), 2018, Sec. 2.
Garg D. et al., Automatica 46(11), 2010 (the Radau layout and its costate mapping).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from convexguid.backends import Cones, ConicProgram, make_backend
from convexguid.transcription.lgr import RadauGrid


@dataclass(frozen=True)
class TerminalMap:
    """:math:`\\delta x_f = K_x \\delta x_0 + K_u \\delta\\hat U` on one Radau grid (eq. 42)."""

    grid: RadauGrid
    Kx: np.ndarray
    Ku: np.ndarray

    @property
    def energy_weights(self) -> np.ndarray:
        """:math:`p\\,w_k`, k = 1..N-1: the quadrature of :math:`\\int |u|^2 dt` at the free nodes (eq. 50)."""
        return self.grid.p * self.grid.weights[1:]

    def predict(self, dx0: np.ndarray, du: np.ndarray | None = None) -> np.ndarray:
        """The predicted terminal deviation for an initial deviation ``dx0`` and node corrections ``du`` (N-1, 3)."""
        out = self.Kx @ dx0
        return out if du is None else out + self.Ku @ np.ravel(du)


def terminal_map(grid: RadauGrid, A: np.ndarray, B: np.ndarray) -> TerminalMap:
    """:math:`K_x, K_u` (eqs. 43-44) from the error matrices at the :math:`N` LGR points (``A`` (N, n, n),
    ``B`` (N, n, m))."""
    N, n, m = grid.n, A.shape[-1], B.shape[-1]
    p, D = grid.p, grid.differentiation
    M = np.kron(D[:, 1:], np.eye(n))
    rhs_x = -np.kron(D[:, :1], np.eye(n))
    rhs_x[:n] += p * A[0]
    rhs_u = np.zeros((N * n, (N - 1) * m))
    for k in range(1, N):
        M[k * n:(k + 1) * n, (k - 1) * n:k * n] -= p * A[k]
        rhs_u[k * n:(k + 1) * n, (k - 1) * m:k * m] = p * B[k]
    X = np.linalg.solve(M, np.hstack([rhs_x, rhs_u]))[-n:]  # the last block is the state at tau = 1
    return TerminalMap(grid, X[:, :n], X[:, n:])


def energy_optimal_correction(tmap: TerminalMap, u_nodes: np.ndarray, miss: np.ndarray) -> np.ndarray:
    """Node corrections :math:`\\delta u_k` (N-1, m), k = 1..N-1, cancelling the linear terminal miss ``miss`` with the
    least energy of the corrected control (eqs. 45-56, closed form)."""
    omega_inv = 1.0 / np.repeat(tmap.energy_weights, u_nodes.shape[1])
    Ku, U = tmap.Ku, np.ravel(u_nodes)
    P = (Ku * omega_inv) @ Ku.T
    lam = np.linalg.solve(P, Ku @ U - miss)
    return (omega_inv * (Ku.T @ lam) - U).reshape(u_nodes.shape)


def least_change_correction(tmap: TerminalMap, miss: np.ndarray, m: int = 3) -> np.ndarray:
    """Node corrections cancelling the linear miss with the least energy of the *correction*,
    :math:`\\delta\\hat U = -\\Omega^{-1} K_u^T P^{-1} e`.

    The paper rejects this objective (Sec. 2.2) because it does not keep the corrected control
    energy-optimal. It is the right one for a nominal whose path constraints are active (a keep-out zone, a
    forbidden attitude): the energy-optimal correction moves the control towards the unconstrained optimum,
    which ignores them, even for a zero miss; this one leaves the nominal alone when nothing is missed.
    """
    omega_inv = 1.0 / np.repeat(tmap.energy_weights, m)
    P = (tmap.Ku * omega_inv) @ tmap.Ku.T
    return (-omega_inv * (tmap.Ku.T @ np.linalg.solve(P, miss))).reshape(-1, m)


def box_constrained_correction(tmap: TerminalMap, u_nodes: np.ndarray, miss: np.ndarray, u_max: np.ndarray,
                               backend: str = "clarabel") -> np.ndarray | None:
    """As :func:`energy_optimal_correction`, with :math:`|\\tilde u_k + \\delta u_k|_i \\le U_{max,i}` at the nodes.

    A QP in the corrected node controls :math:`v = \\tilde U + \\delta\\hat U`:
    :math:`\\min v^T \\Omega v` s.t. :math:`K_u v = K_u \\tilde U - e`, :math:`-U_{max} \\le v \\le U_{max}`.
    Returns ``None`` when the box leaves no correction that cancels the miss.
    """
    N, m = u_nodes.shape
    omega = np.repeat(tmap.energy_weights, m)
    U = np.ravel(u_nodes)
    bound = np.tile(np.asarray(u_max, dtype=float), N)
    A = sp.vstack([sp.csc_matrix(tmap.Ku), sp.identity(N * m), -sp.identity(N * m)], format="csc")
    b = np.concatenate([tmap.Ku @ U - miss, bound, bound])
    qp = ConicProgram(sp.diags(2 * omega, format="csc"), np.zeros(N * m), A, b, Cones(zero=tmap.Ku.shape[0],
                                                                                      nonneg=2 * N * m))
    result = make_backend(backend, qp, 1e-9).solve()
    if not result.usable:
        return None
    return (result.x - U).reshape(N, m)
