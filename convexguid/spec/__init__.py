"""Problem specification: the models shared by every family and the YAML reading they are validated from.

:func:`convexguid.problem_files.load_problem` reads a problem file (with optional ``--set`` overrides) and
:func:`convexguid.problem_files.parse_problem` data already in memory, each validated by the model of the family
the file names; both raise :class:`~convexguid.errors.SpecError` with a one-line message on bad input. The keys
shared by every family are in :mod:`convexguid.spec.common`; each family's model is in its package
(``convexguid/families/<name>/spec.py``).
"""

from convexguid.spec.loader import ProblemSpec, apply_overrides, with_overrides, with_values

__all__ = ["ProblemSpec", "apply_overrides", "with_overrides", "with_values"]
