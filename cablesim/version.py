"""The version of cablesim (recorded in every result file)."""

__version__ = "0.1.0"
