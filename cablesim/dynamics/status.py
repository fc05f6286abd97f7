"""How a run ended, as data.

Compiled kernels return plain integers (numba cannot return enums); those integers are the
values of :class:`Status`, defined here once. Results carry a ``Status`` member, the time the
run stopped and a message for people; code decides on the member, never on the message.
"""

from __future__ import annotations

from enum import IntEnum


class Status(IntEnum):
    """Outcome of an integration (or of one right-hand-side evaluation)."""

    COMPLETED = 0
    NONFINITE = 1
    SLACK = 2
    INNER_SOLVE = 3
    STEP_UNDERFLOW = 4
    INTERRUPTED = 5
    OUTPUT_NONFINITE = 6
    UNKNOWN = 7
    CHATTER = 8

    @property
    def text(self) -> str:
        """What happened, in words (no time, no advice)."""
        return _TEXT[self]

    @property
    def success(self) -> bool:
        """Whether the run reached its end."""
        return self is Status.COMPLETED


_TEXT = {
    Status.COMPLETED: "completed",
    Status.NONFINITE: "the state became non-finite (NaN or infinity)",
    Status.SLACK: "a segment went slack (its length fell below its natural length)",
    Status.INNER_SOLVE: "the inner equilibrium solve failed",
    Status.STEP_UNDERFLOW: "the adaptive step size fell below its minimum",
    Status.INTERRUPTED: "interrupted",
    Status.OUTPUT_NONFINITE: "derived outputs became non-finite (inner solve failed)",
    Status.UNKNOWN: "stopped early (the stored message says why)",
    Status.CHATTER: "a segment changed mode twice within 1e-6 s (chatter), which periodic orbits do not follow",
}


# The codes the compiled kernels return (plain integers, the values above).
OK = int(Status.COMPLETED)
NONFINITE = int(Status.NONFINITE)
SLACK = int(Status.SLACK)
INNER_SOLVE = int(Status.INNER_SOLVE)
STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)
INTERRUPTED = int(Status.INTERRUPTED)
CHATTER = int(Status.CHATTER)
