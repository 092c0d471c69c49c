"""Keyword checks shared by the envs: every bad value raises InvalidArgumentError
(a ValueError) whose message names the keyword and the value, worded like the core's."""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

from sixaxis_avoid._core import InvalidArgumentError

OBS_TYPES = ("vector", "index", "goal")


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


def check_bool(name: str, value: Any) -> bool:
    # numpy bools are fine; ints and strings are not (they are usually a mistake).
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return bool(value)
    raise invalid(name, value, "must be True or False")


def check_optional_bool(name: str, value: Any) -> bool | None:
    if value is None:
        return None
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return bool(value)
    raise invalid(name, value, "must be True, False or None")


def check_nonneg_float(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise invalid(name, value, "must be a finite number >= 0")
    v = float(value)
    if not math.isfinite(v) or v < 0.0:
        raise invalid(name, value, "must be a finite number >= 0")
    return v


def check_positive_int(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or int(value) < 1:
        raise invalid(name, value, "must be a positive integer")
    return int(value)
