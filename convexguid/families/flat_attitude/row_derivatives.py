"""Exact derivatives of a row-wise numpy map, by CasADi, evaluated on many rows at once.

The flat program's maps (the torque of eq. 12 at each node, a cone's cosine at each path point) act row by row:
row ``k`` of the output depends on row ``k`` of the inputs alone. :class:`RowDerivative` states such a map once in
CasADi by evaluating the program's own numpy map on one row of symbols (numpy's functions act on object arrays
element by element, so the map differentiated is the program's, not a second statement of it), takes its Jacobian
or the Hessian of a weighted sum of its outputs by algorithmic differentiation, and maps that over the rows.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from convexguid.ocp.parts import DERIVATIVES

KINDS = ("jacobian", "hessian")


class RowDerivative:
    """Jacobians of :math:`f(\\text{row } k)` (``kind="jacobian"``) or Hessians of :math:`w_k \\cdot f(\\text{row }
    k)` (``kind="hessian"``) for a row-wise map ``f`` of arguments ``widths`` wide with ``outputs`` values, over
    ``rows`` rows at once.

    Called with the arguments stacked ``(rows, q)``, ``q = sum(widths)`` (and, for Hessians, the weights
    ``(rows, outputs)``), it returns ``(rows, outputs, q)`` Jacobians or ``(rows, q, q)`` Hessians. The mapped
    function is evaluated through buffers on numpy memory (``Function.buffer``, made per call, so one instance may
    serve two threads): the same numbers as a call with numpy arrays, without its conversions to and from CasADi
    matrices (two thirds of that call's time).
    """

    def __init__(self, f: Callable[..., np.ndarray], widths: tuple[int, ...], outputs: int, rows: int,
                 kind: str = "hessian") -> None:
        if kind not in KINDS:
            raise ValueError(f"RowDerivative: kind must be one of {KINDS}, not {kind!r}")
        args = [ca.SX.sym(f"a{i}", width) for i, width in enumerate(widths)]
        values = ca.vertcat(*np.ravel(f(*(np.array([[a[j] for j in range(a.shape[0])]], dtype=object)
                                         for a in args))))
        stacked = ca.vertcat(*args)
        self._size = stacked.shape[0]
        hessian = kind == "hessian"
        self._rows_out = self._size if hessian else outputs  # rows of one row's derivative
        self._shapes = [(rows, self._size)] + ([(rows, outputs)] if hessian else [])

        def mapped() -> ca.Function:
            if not hessian:
                return ca.Function("row_jacobian", [stacked], [ca.densify(ca.jacobian(values, stacked))]).map(rows)
            weights = ca.SX.sym("w", outputs)
            second = ca.hessian(ca.dot(weights, values), stacked)[0]
            return ca.Function("row_hessian", [stacked, weights], [ca.densify(second)]).map(rows)

        # a slew solved again (a campaign's runs) differentiates nothing again: the process keeps the functions
        self._mapped = DERIVATIVES.get(f"row_{kind}_{rows}", [stacked], [values], mapped)

    def __call__(self, *arrays: np.ndarray) -> np.ndarray:
        # CasADi stores column-major: row k of a C-ordered (rows, width) array is column k of its (width, rows) input
        args = [np.ascontiguousarray(a, dtype=float) for a in arrays]
        if [a.shape for a in args] != self._shapes:  # the buffers are raw memory: no size is checked past here
            raise ValueError(f"RowDerivative: arguments of shapes {[a.shape for a in args]}, expected {self._shapes}")
        out = np.empty((args[0].shape[0], self._size, self._rows_out))  # column j of row k's derivative at out[k, j]
        buffer, evaluate = self._mapped.buffer()
        for i, arg in enumerate(args):
            buffer.set_arg(i, memoryview(arg))
        buffer.set_res(0, memoryview(out))
        evaluate()
        return out.transpose(0, 2, 1)
