"""Stability under stress (``cablesim stress``): cases, runs and checks, report.

:mod:`~cablesim.stress.cases` builds the cases, :mod:`~cablesim.stress.run` runs and checks them,
:mod:`~cablesim.stress.report` writes the markdown table and the map.
"""

from .cases import AXES, FAILED, OK, STOPPED, StressCase, build_cases
from .report import format_summary, format_table, summary_counts, write_report
from .run import run_one, run_stress

__all__ = [
    "AXES", "FAILED", "OK", "STOPPED", "StressCase", "build_cases", "format_summary", "format_table",
    "summary_counts", "write_report", "run_one", "run_stress",
]
