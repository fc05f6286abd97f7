"""Analyses: each takes a validated case and returns a result object (no I/O, no plotting)."""
