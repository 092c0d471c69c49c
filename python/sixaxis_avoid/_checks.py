"""The error of a bad Python keyword, worded like the core's, and the checks of keywords the
core does not declare (the animation's). The envs' keywords are checked by the core's one
table (``_core.check_options("env", ...)``, ENV_OPTIONS in rust/core/src/env/mod.rs)."""

from __future__ import annotations

import numbers
from collections.abc import Iterable
from typing import Any

from sixaxis_avoid._core import InvalidArgumentError


def invalid(name: str, value: Any, reason: str) -> InvalidArgumentError:
    """The exception the core raises for a bad argument (same message format)."""
    err = InvalidArgumentError(f"invalid argument `{name}` = {value!r}: {reason}")
    err.name = name
    err.value = repr(value)
    err.reason = reason
    return err


def check_choice(name: str, value: Any, choices: Iterable[Any]) -> Any:
    choices = tuple(choices)
    if value not in choices:
        raise invalid(name, value, "must be one of " + ", ".join(repr(c) for c in choices))
    return value


def check_positive_int(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or int(value) < 1:
        raise invalid(name, value, "must be a positive integer")
    return int(value)
