"""Problem specification: YAML problem files -> validated, frozen models in SI units.

Use :func:`load_problem` for a file (with optional ``--set`` overrides) and
:func:`parse_problem` for data already in memory; both raise
:class:`~convexguid.errors.SpecError` with a one-line message on bad input.
The keys shared by every family are in :mod:`convexguid.spec.common`; each family's
model is in its package (``convexguid/families/<name>/spec.py``).
"""

from convexguid.spec.loader import ProblemSpec, apply_overrides, load_problem, parse_problem

__all__ = ["ProblemSpec", "apply_overrides", "load_problem", "parse_problem"]
