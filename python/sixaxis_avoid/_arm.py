"""Arm-aware helpers: which cells a clear arm pose reaches, and a pose to draw.

Both are computed in Rust (``PosePlanner``) once per scenario and cached here, keyed by the
scenario's JSON text.
"""

from __future__ import annotations

import threading

import numpy as np

from sixaxis_avoid import _core

_lock = threading.Lock()
_unreachable: dict[str, list[tuple[int, int, int]]] = {}
_poses: dict[tuple[str, tuple[int, int, int]], np.ndarray | None] = {}


def unreachable_cells(scenario: _core.Scenario) -> list[tuple[int, int, int]]:
    """Free cells inside bounds that no clear arm pose reaches (PosePlanner.cell_reachable),
    start and target excluded; cached per scenario."""
    key = scenario.to_json()
    with _lock:
        hit = _unreachable.get(key)
    if hit is not None:
        return hit
    cells = [tuple(c) for c in _core.unreachable_cells(scenario)]
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
        q = _core.clear_pose_at(scenario, cell)
        pose = None if q is None else np.asarray(q, dtype=np.float64)
    with _lock:
        _poses[key] = pose
    return pose
