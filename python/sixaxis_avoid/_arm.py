"""Arm-aware helpers: which cells a clear arm pose reaches, and a pose to draw.

Both are computed in Rust (``PosePlanner``) once per scenario and cached here, keyed by the
scenario's JSON text.
"""

from __future__ import annotations

import threading

import numpy as np

from sixaxis_avoid import _core
from sixaxis_avoid._checks import invalid

_lock = threading.Lock()
_unreachable: dict[str, list[tuple[int, int, int]]] = {}
_poses: dict[tuple[str, tuple[int, int, int]], np.ndarray | None] = {}


def _require(name: str, keyword: str):
    fn = getattr(_core, name, None)
    if fn is None:
        raise invalid(keyword, True, "this build of sixaxis_avoid has no pose planner")
    return fn


def unreachable_cells(scenario: _core.Scenario) -> list[tuple[int, int, int]]:
    """Free cells inside bounds that no clear arm pose reaches (PosePlanner.cell_reachable),
    start and target excluded; cached per scenario."""
    key = scenario.to_json()
    with _lock:
        hit = _unreachable.get(key)
    if hit is not None:
        return hit
    cells = [tuple(c) for c in _require("unreachable_cells", "arm_aware")(scenario)]
    with _lock:
        _unreachable[key] = cells
    return cells


def clear_pose(scenario: _core.Scenario, cell: tuple[int, int, int]) -> np.ndarray | None:
    """Joint angles (radians) of the first clear IK pose whose terminal is at ``cell``, or
    None; cached per (scenario, cell). The start cell uses beta_0."""
    key = (scenario.to_json(), tuple(int(c) for c in cell))
    with _lock:
        if key in _poses:
            return _poses[key]
    if tuple(cell) == tuple(scenario.start):
        pose = np.radians(np.asarray(scenario.beta0_deg, dtype=np.float64))
    else:
        fn = getattr(_core, "clear_pose_at", None)
        q = fn(scenario, cell) if fn is not None else None
        pose = None if q is None else np.asarray(q, dtype=np.float64)
    with _lock:
        _poses[key] = pose
    return pose
