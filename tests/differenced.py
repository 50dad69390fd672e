"""The Lagrangian's Hessian by central differences of its gradient, column by column: what the programs' exact
Hessians (the end game's only kind) are tested against."""

import numpy as np

from convexguid.scp.lagrangian import lagrangian_gradient


def differenced_hessian(program, x: np.ndarray, weights, scale: np.ndarray) -> np.ndarray:
    """Symmetrized central differences with steps of 1e-6 in scaled units."""
    columns = np.zeros((x.size, x.size))
    for j in range(x.size):
        step = np.zeros(x.size)
        step[j] = 1e-6 * scale[j]
        columns[:, j] = (lagrangian_gradient(program.evaluate(x + step), weights)
                         - lagrangian_gradient(program.evaluate(x - step), weights)) / (2 * step[j])
    return 0.5 * (columns + columns.T)
