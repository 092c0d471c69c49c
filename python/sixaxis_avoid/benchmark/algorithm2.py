"""Algorithm 2 (re-planning around path points no arm pose reaches) for any learner.

Every learner goes through the core's one generic loop, ``sixaxis_avoid.plan(scenario,
seed=..., learner=...)``: ``"qlearning"`` (the native learner), ``"bfs"``, or an object whose
``learn_path(scenario, seed)`` learns a round's path. :func:`algorithm2` is the only call
site; this package never loops over re-plans itself.
"""

from __future__ import annotations

import functools
import inspect
import time
from typing import Any


class Algorithm2Unavailable(RuntimeError):
    """The installed core's ``plan`` takes no ``learner`` (it predates the generic loop)."""


@functools.lru_cache(maxsize=1)
def plan_takes_learner() -> bool:
    """Whether ``sixaxis_avoid.plan`` accepts ``learner=`` (the generic Algorithm 2 loop)."""
    import sixaxis_avoid as sa

    try:
        return "learner" in inspect.signature(sa.plan).parameters
    except (TypeError, ValueError):  # no signature exposed: ask the function itself
        try:
            sa.plan("no-such-scenario", learner="bfs")
        except TypeError:
            return False
        except ValueError:
            return True
        return True


def algorithm2(scenario: Any, *, seed: int, learner: Any, **kwargs: Any) -> Any:
    """``sixaxis_avoid.plan(scenario, seed=seed, learner=learner, **kwargs)``.

    Without the generic loop in the installed core, the native learner (``"qlearning"``, the
    core's default) still runs through ``plan``; any other raises
    :class:`Algorithm2Unavailable`.
    """
    import sixaxis_avoid as sa

    if plan_takes_learner():
        return sa.plan(scenario, seed=seed, learner=learner, **kwargs)
    if learner == "qlearning":
        return sa.plan(scenario, seed=seed, **kwargs)
    raise Algorithm2Unavailable(
        "sixaxis_avoid.plan(learner=...) is not in this build: Algorithm 2 for "
        f"{learner if isinstance(learner, str) else type(learner).__name__} needs it"
    )


def algorithm2_record(
    scenario: Any, seed: int, learner: Any, max_replans: int, **kwargs: Any
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Run Algorithm 2; return (result, timing) for the run's record."""
    t0 = time.perf_counter()
    try:
        r = algorithm2(scenario, seed=seed, learner=learner, max_replans=max_replans, **kwargs)
    except Algorithm2Unavailable as e:
        return {"available": False, "reason": str(e)}, {}
    result = {
        "available": True,
        "success": bool(r.success),
        "replans": int(r.replans),
        "max_replans": int(max_replans),
        "added_obstacles": [list(c) for c in r.added_obstacles],
        "failure": r.failure,
        "path": [list(c) for c in r.path] if r.success else None,
        "learning_steps": int(sum(int(rd.get("total_steps") or 0) for rd in r.rounds)),
    }
    return result, {"wall_time_s": time.perf_counter() - t0}
