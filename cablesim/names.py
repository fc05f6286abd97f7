"""The names users write: analyses, integrators, sweep directions.

Each tuple is the single source from which the case-file schema (pydantic ``Literal``), the
command-line choices and the registries are built; ``tests/test_architecture.py`` checks that
they agree.
"""

from __future__ import annotations

#: Static models a time history can use (``analysis:`` in a case file, ``--analysis``).
ANALYSES = ("exact", "approximate")
#: Time-integration schemes (``integrator.name``, ``--integrator``) and the settings each takes
#: (keys of the case file's ``integrator:`` section). Their defaults, and the rule that picks a
#: scheme when a case names none, are in :mod:`cablesim.dynamics.integrators.settings`.
INTEGRATOR_SETTINGS = {
    "rk4": ("dt",),
    "dopri5": ("rtol", "atol"),
    "newmark": ("dt", "rtol", "atol"),
    "generalized-alpha": ("dt", "rtol", "atol", "rho_inf"),
}
INTEGRATORS = tuple(INTEGRATOR_SETTINGS)
#: Every setting some scheme takes.
INTEGRATOR_KEYS = tuple(sorted({k for keys in INTEGRATOR_SETTINGS.values() for k in keys}))
#: What the exact analysis does when a segment goes slack (``slack:`` in a case file, ``--slack``):
#: continue through it (tension-only segments) or stop there.
SLACK_POLICIES = ("continue", "stop")
#: Sweep directions (``sweep.direction``).
DIRECTIONS = ("independent", "up", "down", "both")
#: Continuation parameters (``continuation.parameter``): the forcing frequency, the multiplier of
#: FL and of the supports' motion, and the multiplier of the supports' motion alone.
CONTINUATION_PARAMETERS = ("omega", "gamma", "support")
