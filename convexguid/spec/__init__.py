"""Problem specification: YAML problem files -> validated, frozen models in SI units.

Use :func:`load_problem` for a file (with optional ``--set`` overrides) and
:func:`parse_problem` for data already in memory; both raise
:class:`~convexguid.errors.SpecError` with a one-line message on bad input.
"""

from convexguid.spec.loader import FAMILY_MODELS, ProblemSpec, apply_overrides, load_problem, parse_problem

__all__ = ["FAMILY_MODELS", "ProblemSpec", "apply_overrides", "load_problem", "parse_problem"]
