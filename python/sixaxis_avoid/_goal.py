"""Goal-conditioned pieces shared by ``SixAxisAvoidGoal-v0`` and its vector envs.

The one module that knows where the goals sit in the vector observation (the core's
``VECTOR_OBS_TERMINAL`` / ``VECTOR_OBS_TARGET``) and how info dicts feed the core's
relabelled rewards (``EnvCore.compute_reward``: the step's own eqs. 5, 9 and 10, computed in
Rust). The single env, the native vector env and the SB3 ``VecEnv`` all call it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from sixaxis_avoid import _core
from sixaxis_avoid._checks import invalid
from sixaxis_avoid._ids import GOAL_ENV_ID

#: The achieved goal (the terminal's normalised cell) in a vector observation.
ACHIEVED = slice(*_core.VECTOR_OBS_TERMINAL)
#: The desired goal (the target's normalised cell) in a vector observation.
DESIRED = slice(*_core.VECTOR_OBS_TARGET)


def goal_dict(obs: np.ndarray) -> dict[str, np.ndarray]:
    """The ``Dict`` observation of vector observation(s) ``obs`` (``(13,)`` or ``(n, 13)``):
    ``observation`` is ``obs`` itself, the goals are copies of its slices."""
    return {
        "observation": obs,
        "achieved_goal": obs[..., ACHIEVED].copy(),
        "desired_goal": obs[..., DESIRED].copy(),
    }


def refuse_goal_obs_type(obs_type: Any) -> None:
    """``obs_type="goal"`` on the plain ids: the goal env is its own id."""
    if isinstance(obs_type, str) and obs_type == "goal":
        raise invalid(
            "obs_type",
            obs_type,
            f'the goal-conditioned env is its own id: gym.make("{GOAL_ENV_ID}") (or '
            f'gym.make_vec("{GOAL_ENV_ID}", ...); arm-aware: arm_aware=True)',
        )


def _goals(name: str, goal: Any) -> np.ndarray:
    try:
        g = np.asarray(goal, dtype=np.float64)
    except (TypeError, ValueError):
        raise invalid(name, goal, "must be an array of normalised cells, shape (..., 3)") from None
    if g.ndim == 0 or g.shape[-1] != 3:
        raise invalid(name, f"array of shape {g.shape}", "must have shape (3,) or (..., 3)")
    return g


def goal_to_cell(core: Any, goal: Any) -> np.ndarray:
    """Normalised goal(s) ``(..., 3)`` -> integer cells ``(..., 3)`` (the core's inverse of
    the observation's normalisation)."""
    g = _goals("goal", goal)
    return core.goal_to_cell(g.reshape(-1, 3)).reshape(g.shape)


def info_dicts(info: Any, shape: tuple[int, ...], n: int, item: str) -> list[Mapping]:
    """The info dicts handed to a ``compute_reward`` for ``n`` items of ``shape``: one dict
    (for every item) or one per item, as a list; anything else is an
    :class:`~sixaxis_avoid.InvalidArgumentError` naming ``info``."""
    if isinstance(info, Mapping):
        infos: list[Any] = [info]
    else:
        infos = list(np.asarray(info, dtype=object).ravel())
    if len(infos) not in (1, n) or not all(isinstance(i, Mapping) for i in infos):
        raise invalid(
            "info", f"{len(infos)} items", f"expected an info dict or one per {item} {shape}"
        )
    return infos


def goal_pair(achieved_goal: Any, desired_goal: Any) -> tuple[np.ndarray, np.ndarray, tuple, int]:
    """The (achieved, desired) goals of a ``compute_reward`` call, checked to be float arrays
    of one shape ``(..., 3)``, with that leading shape and its number of goal pairs."""
    a = _goals("achieved_goal", achieved_goal)
    d = _goals("desired_goal", desired_goal)
    if d.shape != a.shape:
        raise invalid(
            "desired_goal",
            f"array of shape {d.shape}",
            f"must have the shape of achieved_goal {a.shape}",
        )
    shape = a.shape[:-1]
    return a, d, shape, int(np.prod(shape, dtype=np.int64))


class GoalRewards:
    """``compute_reward`` of a goal env over its core (``EnvCore`` or ``VecEnvCore``)."""

    def __init__(self, core: Any):
        self._core = core
        self._warned = False

    def __call__(self, achieved_goal: Any, desired_goal: Any, info: Any) -> np.ndarray | float:
        a, d, shape, n = goal_pair(achieved_goal, desired_goal)
        collided, detour = self._info_arrays(info, shape, n)
        r = self._core.compute_reward(a.reshape(-1, 3), d.reshape(-1, 3), collided, detour)
        return float(r[0]) if shape == () else r.reshape(shape)

    def _info_arrays(self, info: Any, shape: tuple[int, ...], n: int):
        """Each pair's ``collided`` and ``detour_penalty`` from one info dict (for every pair)
        or one per pair."""
        infos = info_dicts(info, shape, n, "goal pair")
        if all("collided" in i for i in infos):
            collided = np.array([bool(i["collided"]) for i in infos], dtype=bool)
            detour = np.array([float(i.get("detour_penalty", 0.0)) for i in infos])
        else:
            if not self._warned:
                self._warned = True
                gym.logger.warn(
                    "compute_reward got info dicts without 'collided': computing the reward "
                    "as if no step collided. For the exact reward with SB3's HerReplayBuffer "
                    'pass replay_buffer_kwargs={"copy_info_dict": True}.'
                )
            collided = np.zeros(len(infos), dtype=bool)
            detour = np.zeros(len(infos))
        if len(infos) == 1 and n != 1:
            collided, detour = np.repeat(collided, n), np.repeat(detour, n)
        return collided, detour
