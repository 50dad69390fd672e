"""Exception hierarchy of convexguid.

Every error a user can provoke derives from :class:`ConvexGuidError` and from the
built-in exception it resembles, so ``except ValueError`` keeps working for
callers that do not know this package.
"""

from __future__ import annotations


class ConvexGuidError(Exception):
    """Base class of every error raised on purpose by convexguid."""


class SpecError(ConvexGuidError, ValueError):
    """A problem file or keyword argument is invalid.

    The message is a single line naming the file, the dotted key path and the
    offending value, and says what would be valid.
    """


class BackendError(ConvexGuidError, KeyError):
    """An unknown or unusable convex solver backend was requested."""

    def __str__(self) -> str:  # KeyError would otherwise quote the message
        return str(self.args[0]) if self.args else ""


class SolverError(ConvexGuidError, RuntimeError):
    """A convex subproblem could not be solved (numerical failure of the backend)."""
