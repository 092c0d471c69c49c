"""The benchmark's learner errors, below every module that raises them."""

from __future__ import annotations


class LearnerError(ValueError):
    """A learner name that is neither built in nor an importable ``module:Class``, or a
    learner setting that is not one of its choices (names the field and the value)."""
