"""Benchmarks: scripts that print figures, each beside its issue's target; never installed."""
