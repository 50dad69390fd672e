"""Clohessy-Wiltshire (Hill) relative motion about a circular target orbit.

Frame (Wang & Tang 2003, Fig. 1): origin at the target, x opposite to the target's
orbital velocity, y away from the Earth (radial), z completing the right-handed
triad (orbit normal). With mean motion :math:`n` and thrust acceleration
:math:`a\\,u` (eq. 1):

.. math::

    \\ddot x - 2n\\dot y = a u_x,\\qquad
    \\ddot y + 2n\\dot x - 3n^2 y = a u_y,\\qquad
    \\ddot z + n^2 z = a u_z .

The 3-D state is ``[x, y, z, vx, vy, vz]``; the coplanar (2-D) state is the in-plane
part ``[x, y, vx, vy]``. Every function takes ``dim`` = 2 or 3.

References
----------
Wang H., Tang G., "Optimal finite thrust rendezvous using nonlinear programming",
J. National Univ. of Defense Technology 25(5), 2003, eqs. (1)-(3).
"""

from __future__ import annotations

import numpy as np

IN_PLANE = np.array([0, 1, 3, 4])
"""Rows/columns of the 3-D state that form the coplanar state ``[x, y, vx, vy]``."""


def _check_dim(dim: int) -> None:
    if dim not in (2, 3):
        raise ValueError(f"Clohessy-Wiltshire dimension must be 2 or 3, got {dim}")


def _reduce(matrix_3d: np.ndarray, dim: int, columns: np.ndarray | None = None) -> np.ndarray:
    """The in-plane block of a 3-D matrix (``columns`` defaults to the state's in-plane part)."""
    if dim == 3:
        return matrix_3d
    cols = IN_PLANE if columns is None else columns
    return matrix_3d[np.ix_(IN_PLANE, cols)]


def cw_matrices(mean_motion: float, accel: float, dim: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """State and input matrices of eq. (2), :math:`\\dot X = A X + B u` with ``B = a [0; I]``."""
    _check_dim(dim)
    n = mean_motion
    A = np.zeros((6, 6))
    A[:3, 3:] = np.eye(3)
    A[3, 4] = 2 * n
    A[4, 1] = 3 * n**2
    A[4, 3] = -2 * n
    A[5, 2] = -(n**2)
    B = np.vstack([np.zeros((3, 3)), accel * np.eye(3)])
    return _reduce(A, dim), _reduce(B, dim, np.arange(2))


def _stm_rows(n: float, tau, s, c, zero, one) -> list[list]:
    """The rows of the 3-D :math:`\\Phi(\\Delta t)` of eq. (3) from :math:`\\tau = n\\Delta t`, :math:`\\sin\\tau` and
    :math:`\\cos\\tau` (numpy arrays, or CasADi expressions)."""
    return [
        [one, 6 * (tau - s), zero, (4 * s - 3 * tau) / n, 2 * (1 - c) / n, zero],
        [zero, 4 - 3 * c, zero, 2 * (c - 1) / n, s / n, zero],
        [zero, zero, c, zero, zero, s / n],
        [zero, 6 * n * (1 - c), zero, 4 * c - 3, 2 * s, zero],
        [zero, 3 * n * s, zero, -2 * s, c, zero],
        [zero, zero, -n * s, zero, zero, c],
    ]


def cw_stm(mean_motion: float, dt: float | np.ndarray, dim: int = 3) -> np.ndarray:
    """Closed-form state transition matrix :math:`\\Phi(\\Delta t)` of eq. (3), :math:`\\tau = n\\Delta t`.

    ``dt`` may be an array (the result then has a leading batch axis) and complex
    (complex-step differentiation).
    """
    _check_dim(dim)
    tau = mean_motion * np.asarray(dt)
    rows = _stm_rows(mean_motion, tau, np.sin(tau), np.cos(tau), np.zeros_like(tau), np.ones_like(tau))
    phi = np.moveaxis(np.array(rows), (0, 1), (-2, -1))
    return phi if dim == 3 else phi[..., IN_PLANE[:, None], IN_PLANE]


def cw_stm_casadi(mean_motion: float, dt, dim: int = 3):
    """:math:`\\Phi(\\Delta t)` of eq. (3) as a CasADi matrix of the expression ``dt`` (a coast of unknown
    duration: a closed-form flow, :meth:`convexguid.ocp.Problem.flow`)."""
    import casadi as ca  # the symbolic statement needs it; the numpy functions here do not

    _check_dim(dim)
    tau = mean_motion * dt
    rows = _stm_rows(mean_motion, tau, ca.sin(tau), ca.cos(tau), 0, 1)
    keep = range(6) if dim == 3 else IN_PLANE
    return ca.vertcat(*(ca.horzcat(*(ca.SX(rows[i][j]) for j in keep)) for i in keep))


def cw_hold_input_casadi(mean_motion: float, accel: float, dt, dim: int = 3):
    """:math:`\\Gamma(\\Delta t) = \\int_0^{\\Delta t} \\Phi(s) B\\,ds`, the input matrix of a zero-order hold over a
    step ``dt`` (a CasADi expression), in closed form: the velocity columns of eq. (3) integrated term by term,
    with :math:`\\theta = n\\Delta t`. The flow of a held thrust is then
    :math:`X(\\Delta t) = \\Phi(\\Delta t) X_0 + \\Gamma(\\Delta t) u` (:meth:`convexguid.ocp.Problem.flow`)."""
    import casadi as ca  # the symbolic statement needs it; the numpy functions here do not

    _check_dim(dim)
    n, t = mean_motion, dt
    s, versine = ca.sin(n * t), 2 * ca.sin(n * t / 2) ** 2  # 1 - cos, without its cancellation for short steps
    rows = [
        [4 * versine / n**2 - 1.5 * t**2, 2 * (t - s / n) / n, 0],
        [2 * (s / n - t) / n, versine / n**2, 0],
        [0, 0, versine / n**2],
        [4 * s / n - 3 * t, 2 * versine / n, 0],
        [-2 * versine / n, s / n, 0],
        [0, 0, s / n],
    ]
    keep, columns = (range(6), range(3)) if dim == 3 else (IN_PLANE, range(2))
    return accel * ca.vertcat(*(ca.horzcat(*(ca.SX(rows[i][j]) for j in columns)) for i in keep))


def cw_zoh(mean_motion: float, accel: float, dt: float, dim: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretization :math:`X_{k+1} = \\Phi X_k + \\Gamma u_k` over a step ``dt``.

    .. math:: \\Gamma = \\int_0^{\\Delta t} \\Phi(s)\\,B\\,ds,

    computed from the matrix exponential of the augmented matrix
    :math:`\\begin{bmatrix} A & B \\\\ 0 & 0\\end{bmatrix}\\Delta t` (Van Loan 1978), so it holds for any
    ``dt`` without series truncation.
    """
    from scipy.linalg import expm  # only the exact-ZOH path needs it

    A, B = cw_matrices(mean_motion, accel, dim)
    nx, nu = B.shape
    aug = np.zeros((nx + nu, nx + nu))
    aug[:nx, :nx], aug[:nx, nx:] = A, B
    e = expm(aug * dt)
    return e[:nx, :nx], e[:nx, nx:]
