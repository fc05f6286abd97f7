"""User-facing errors.

Every problem a user can fix (bad input, a cable that cannot carry its loads, a solver that does
not converge) is raised as a :class:`CablesimError`. The command line prints its message as one
paragraph and exits with status 2; it never shows a traceback for these.
"""

from __future__ import annotations


class CablesimError(Exception):
    """A problem the user can act on.

    Parameters
    ----------
    message : str
        One paragraph: what is wrong, naming the field or segment, and what to do.
    field : str, optional
        Dotted name of the case-file field at fault (``"cable.S"``), if any.
    """

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.field = field


class SlackSegmentError(CablesimError):
    """A segment would carry no tension (it would go slack) under the given loads."""

    def __init__(self, message: str, segment: int):
        super().__init__(message, field="loads")
        self.segment = segment


class ConvergenceError(CablesimError):
    """An iterative solver did not converge."""
