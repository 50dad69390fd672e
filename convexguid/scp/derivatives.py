"""Complex-step derivatives: exact to machine precision, no subtractive cancellation.

For an analytic map :math:`f`, :math:`\\partial f/\\partial x_j = \\operatorname{Im} f(x + i h e_j) / h`
with :math:`h = 10^{-30}` (Squire & Trapp 1998; Martins, Sturdza & Alonso 2003).
Maps passed here must be written with functions that accept complex input
(``np.sin``, ``np.cos``, products; not ``abs`` or ``np.linalg.norm``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

STEP = 1e-30


def pointwise_jacobian(f: Callable[..., np.ndarray], args: Sequence[np.ndarray], wrt: int) -> np.ndarray:
    """Jacobian of a map applied row by row.

    ``f(*args)`` maps arrays of shape ``(m, q_i)`` to ``(m, p)`` (or ``(m,)``), each row
    depending only on the same row of the inputs. Returns ``(m, p, q)`` (or ``(m, q)``):
    the derivative of row ``k`` of the output with respect to row ``k`` of ``args[wrt]``.
    """
    base = [np.asarray(a, dtype=complex) for a in args]
    width = base[wrt].shape[1]
    columns = []
    for j in range(width):
        shifted = list(base)
        shifted[wrt] = base[wrt].copy()
        shifted[wrt][:, j] += 1j * STEP
        columns.append(np.imag(f(*shifted)) / STEP)
    return np.stack(columns, axis=-1)
