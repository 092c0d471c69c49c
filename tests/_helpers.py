"""Helpers shared by test modules (not fixtures: those are in conftest.py). Importable as
``from _helpers import ...`` because pytest's default import mode puts tests/ on sys.path
(tests/ has no __init__.py)."""

from __future__ import annotations

import time
from typing import Callable


def wait_for(cond: Callable[[], object], timeout: float = 15.0) -> bool:
    """Whether ``cond()`` holds within ``timeout`` seconds (polled every 50 ms)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.05)
    return bool(cond())
