"""Size limits: what a problem is estimated to need before its run starts, and the refusal above a family's limit.

A family estimates the peak memory of a run from its spec alone (``Family.estimate_size``: a few arithmetic
operations on the discretisation, the step count, the number of runs) and declares the most it accepts
(``Family.memory_limit_bytes``, see :class:`~convexguid.families.base.Family`). :func:`check_size` refuses a
larger problem with one line that names the key that sets the size, the estimate and what it counts, so a problem
that would run out of memory (or abort inside a solver) an hour in is exit 2 at once.
"""

from __future__ import annotations

from dataclasses import dataclass

from convexguid.errors import SpecError, value_text

MIB = 2**20
GIB = 2**30

DEFAULT_MEMORY_LIMIT_BYTES = 2 * GIB
"""Limit of a family that declares none: well inside a laptop, and the runs it admits finish in minutes to hours."""

PROCESS_BYTES = 100 * MIB
"""What the Python process with NumPy, SciPy and the solvers loaded takes before any problem (measured ~105 MB)."""


@dataclass(frozen=True)
class SizeEstimate:
    """The estimated peak memory of one run of a problem.

    Attributes
    ----------
    memory_bytes : float
        Estimated peak memory of the process, bytes (:data:`PROCESS_BYTES` included).
    key : str
        Dotted key path of the setting that drives the size (named in the error), e.g. ``discretization.nodes``.
    value : object
        Its value.
    basis : str
        What the estimate counts, in a few words (e.g. ``3003 variables x 21007 path-constraint rows``).
    fix : str
        What to do instead; default ``give a smaller <key>``.
    """

    memory_bytes: float
    key: str
    value: object
    basis: str
    fix: str = ""


def memory_text(size_bytes: float) -> str:
    """``340 MiB``, ``5.1 GiB``, ``45.8 TiB``."""
    for unit, scale in (("TiB", 2**40), ("GiB", GIB)):
        if size_bytes >= scale:
            return f"{size_bytes / scale:.3g} {unit}"
    return f"{size_bytes / MIB:.3g} MiB"


def check_size(source: str, family: str, estimate: SizeEstimate, limit_bytes: float) -> None:
    """Raise a one-line :class:`~convexguid.errors.SpecError` if ``estimate`` is above ``limit_bytes``.

    ``source`` is the problem's file, ``family`` the family's name (both for the message).
    """
    if estimate.memory_bytes > limit_bytes:
        raise SpecError(f"{source}: {estimate.key}: problem too large: a run needs about "
                        f"{memory_text(estimate.memory_bytes)} of memory ({estimate.basis}), above the {family} "
                        f"family's limit of {memory_text(limit_bytes)} (got {value_text(estimate.value)}); "
                        f"{estimate.fix or 'give a smaller ' + estimate.key}")
