"""The names users write: analyses, integrators, sweep directions.

Each tuple is the single source from which the case-file schema (pydantic ``Literal``), the
command-line choices and the registries are built; ``tests/test_architecture.py`` checks that
they agree.
"""

from __future__ import annotations

#: Static models a time history can use (``analysis:`` in a case file, ``--analysis``).
ANALYSES = ("exact", "approximate")
#: Time-integration schemes (``integrator.name``, ``--integrator``).
INTEGRATORS = ("rk4", "dopri5", "newmark", "generalized-alpha")
#: What the exact analysis does when a segment goes slack (``slack:`` in a case file, ``--slack``):
#: continue through it (tension-only segments) or stop there.
SLACK_POLICIES = ("continue", "stop")
#: Sweep directions (``sweep.direction``).
DIRECTIONS = ("independent", "up", "down", "both")
#: Continuation parameters (``continuation.parameter``).
CONTINUATION_PARAMETERS = ("omega", "gamma")
