"""Errors of the training package, importable without torch (the CLI lists them)."""

from __future__ import annotations


class PolicyError(ValueError):
    """A policy file that cannot drive this model; one sentence saying what to do."""
