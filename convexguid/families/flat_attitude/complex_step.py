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


def pointwise_jacobians(f: Callable[..., np.ndarray], args: Sequence[np.ndarray]) -> list[np.ndarray]:
    """Jacobians of a map applied row by row, with respect to each of its arguments, in one call of ``f``.

    ``f(*args)`` maps arrays of shape ``(m, q_i)`` to ``(m, p)`` (or ``(m,)``), each row
    depending only on the same row of the inputs. Returns, for each argument ``i``, an array
    ``(m, p, q_i)`` (or ``(m, q_i)``): the derivative of row ``k`` of the output with respect
    to row ``k`` of ``args[i]``. Every perturbed copy of the inputs is stacked row-wise and
    evaluated at once, so the cost is one vectorized call rather than one per input column.
    """
    base = [np.asarray(a, dtype=complex) for a in args]
    m = base[0].shape[0]
    widths = [a.shape[1] for a in base]
    copies = sum(widths)
    stacked = [np.tile(a, (copies, 1)) for a in base]
    block = 0
    for i, width in enumerate(widths):
        for j in range(width):
            stacked[i][block * m:(block + 1) * m, j] += 1j * STEP
            block += 1
    out = np.imag(f(*stacked)) / STEP
    out = out.reshape(copies, m, *out.shape[1:])
    jacobians, first = [], 0
    for width in widths:
        jacobians.append(np.moveaxis(out[first:first + width], 0, -1))
        first += width
    return jacobians


def pointwise_jacobian(f: Callable[..., np.ndarray], args: Sequence[np.ndarray], wrt: int) -> np.ndarray:
    """Jacobian of a row-wise map with respect to ``args[wrt]`` alone (see :func:`pointwise_jacobians`)."""
    others = [np.asarray(a) for a in args]

    def of_one(arg: np.ndarray) -> np.ndarray:
        return f(*others[:wrt], arg, *others[wrt + 1:])

    return pointwise_jacobians(of_one, [others[wrt]])[0]
