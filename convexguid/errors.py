"""Exception hierarchy of convexguid.

Every error a user can provoke derives from :class:`ConvexGuidError` and from the
built-in exception it resembles, so ``except ValueError`` keeps working for
callers that do not know this package.
"""

from __future__ import annotations

import reprlib


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


class OutputError(ConvexGuidError, OSError):
    """An output (file or folder) cannot be written where it was asked for.

    Raised before any work when the target is unusable (a folder where a file is wanted, a missing or
    unwritable folder, a non-empty output folder without permission to replace it); raised after the work
    when the results could not be moved into place, and then the message says where they are.
    """


def value_text(value: object, limit: int = 100) -> str:
    """``value`` as an error message shows it: its repr on one line, cut to ``limit`` characters.

    The repr is bounded before it is built (:mod:`reprlib`: a few levels, a few items each), so a huge value
    (a YAML alias bomb expands to billions of items) costs no more to show than a small one.
    """
    text = " ".join(_BOUNDED_REPR.repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _bounded_repr() -> reprlib.Repr:
    shown = reprlib.Repr()
    shown.maxlevel, shown.maxstring, shown.maxother = 4, 80, 80
    shown.maxlist = shown.maxtuple = shown.maxdict = shown.maxset = 10
    return shown


_BOUNDED_REPR = _bounded_repr()
