"""Algorithm 2 (re-planning around path points no arm pose reaches) for any learner.

Every learner goes through the core's one generic loop, ``sixaxis_avoid.plan(scenario,
seed=..., learner=...)``: ``"qlearning"`` (the native learner), ``"bfs"``, or an object whose
``learn_path(scenario, seed)`` learns a round's path. :func:`algorithm2` is the only call
site; this package never loops over re-plans itself.
"""

from __future__ import annotations

import time
from typing import Any


def algorithm2(scenario: Any, *, seed: int, learner: Any, **kwargs: Any) -> Any:
    """``sixaxis_avoid.plan(scenario, seed=seed, learner=learner, **kwargs)``: the core's loop."""
    import sixaxis_avoid as sa

    return sa.plan(scenario, seed=seed, learner=learner, **kwargs)


def algorithm2_record(
    scenario: Any, seed: int, learner: Any, max_replans: int, **kwargs: Any
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Run Algorithm 2; return (result, timing) for the run's record."""
    t0 = time.perf_counter()
    r = algorithm2(scenario, seed=seed, learner=learner, max_replans=max_replans, **kwargs)
    result = {
        "success": bool(r.success),
        "replans": int(r.replans),
        "max_replans": int(max_replans),
        "added_obstacles": [list(c) for c in r.added_obstacles],
        "failure": r.failure,
        "path": [list(c) for c in r.path] if r.success else None,
        "learning_steps": int(sum(int(rd.get("total_steps") or 0) for rd in r.rounds)),
    }
    return result, {"wall_time_s": time.perf_counter() - t0}


def algorithm1_record(scenario: Any, path: Any) -> dict[str, Any] | None:
    """Algorithm 1 (pose planning) on a learned path, as a run file records it: whether every
    point got a pose, and the first point that got none; None without a path."""
    import sixaxis_avoid as sa

    if path is None:
        return None
    alg1 = sa.PosePlanner(scenario).plan_poses(path)
    blocked = alg1["blocked_cell"]
    return {
        "complete": bool(alg1["complete"]),
        "blocked_cell": None if blocked is None else list(blocked),
    }
