"""The native vector envs: N copies of ``SixAxisAvoid-v0`` (or ``SixAxisAvoidGoal-v0``)
stepped in one Rust call."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from sixaxis_avoid import _arm, _core
from sixaxis_avoid._checks import (
    invalid,
)
from sixaxis_avoid._goal import GoalRewards, goal_dict, goal_to_cell
from sixaxis_avoid.env import (
    as_scenario,
    check_keywords,
    check_obs_type,
    check_random_target,
    observation_space_of,
)


# The vector envs' argument checks, shared with the remote vector env
# (sixaxis_avoid.remote.vector): the same errors in the same words in process and over a server.
def reset_mask_of(options: dict[str, Any] | None, num_envs: int) -> np.ndarray | None:
    """``options["reset_mask"]`` of ``reset(options=...)`` checked: a bool array of shape
    ``(num_envs,)``, or None when not given."""
    if not options or "reset_mask" not in options:
        return None
    mask = np.asarray(options["reset_mask"])
    if mask.dtype != np.bool_ or mask.shape != (num_envs,):
        raise invalid(
            "options['reset_mask']",
            options["reset_mask"],
            f"must be a bool array of shape ({num_envs},)",
        )
    return mask


def seed_list_of(seed: Any, num_envs: int) -> list[Any]:
    """A ``reset(seed=[...])`` list checked: one seed (or None) per env."""
    seeds = list(seed)
    if len(seeds) != num_envs:
        raise invalid("seed", seed, f"a list of seeds must have one per env ({num_envs})")
    return seeds


def discrete_actions_of(actions: Any, num_envs: int) -> np.ndarray:
    """The discrete actions of a step checked: integers, one per env, as an array of shape
    ``(num_envs,)`` of their own integer dtype (the range 0..6 is the core's check)."""
    a = np.asarray(actions)
    if a.dtype.kind not in "iu":
        raise invalid("actions", actions, "must be integers in 0..6")
    if a.shape != (num_envs,):
        a = a.reshape(-1) if a.size == num_envs else a
        if a.shape != (num_envs,):
            raise invalid("actions", actions, f"must have shape ({num_envs},)")
    return a


class NativeVectorEnv(VectorEnv):
    """What the package's native vector envs share: a Rust batch (``self._core``) that steps
    all envs in one call into NumPy buffers it owns, Gymnasium 1.x next-step autoreset, the
    ``copy`` rule and ``reset(options={"reset_mask": mask})``. A subclass sets ``self._core``,
    the buffers ``self._obs``, ``self._rewards``, ``self._terminated``, ``self._truncated``
    and ``self.copy``, and gives :meth:`_info`, :meth:`actions_array`, :meth:`_seed` and
    (goal-conditioned, ``_GOAL``) :meth:`_goal_dict`."""

    metadata: ClassVar[dict[str, Any]] = {
        "autoreset_mode": AutoresetMode.NEXT_STEP,
        "render_modes": [],
    }
    #: Goal-conditioned: ``Dict`` observations.
    _GOAL: ClassVar[bool] = False

    @staticmethod
    def _refuse_render_mode(render_mode: Any) -> None:
        if render_mode is not None:
            raise invalid(
                "render_mode",
                render_mode,
                'the native vector env does not render; use vectorization_mode="sync" to render',
            )

    def _seed(self, seed: int | list[int | None] | None) -> None:
        """Seed the envs' generators (none by default)."""

    def _goal_dict(self, obs: np.ndarray) -> dict[str, np.ndarray]:
        raise NotImplementedError

    def _info(self) -> dict[str, Any]:
        raise NotImplementedError

    def actions_array(self, actions) -> np.ndarray:
        """``actions`` as the array the core steps with."""
        raise NotImplementedError

    def _result(self, arr: np.ndarray) -> np.ndarray:
        return arr.copy() if self.copy else arr

    def _observations(self):
        obs = self._result(self._obs)
        return self._goal_dict(obs) if self._GOAL else obs

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ):
        super().reset(seed=seed if isinstance(seed, (int, np.integer)) else None)
        self._seed(seed)
        self._core.reset(reset_mask_of(options, self.num_envs))
        return self._observations(), self._info()

    def step(self, actions):
        self._core.step(self.actions_array(actions))
        return (
            self._observations(),
            self._result(self._rewards),
            self._result(self._terminated),
            self._result(self._truncated),
            self._info(),
        )

    def render(self):
        return None

    def close_extras(self, **kwargs: Any) -> None:
        pass


class SixAxisAvoidVectorEnv(NativeVectorEnv):
    """``num_envs`` copies of :class:`~sixaxis_avoid.env.SixAxisAvoidEnv` in one Rust object.

    Made by ``gym.make_vec("SixAxisAvoid-v0", num_envs=N,
    vectorization_mode="vector_entry_point")`` (the default mode for our ids). Each
    :meth:`step` is one Rust call that moves all N envs with the GIL released and writes
    into NumPy arrays allocated once; with ``copy=True`` (default, as Gymnasium's
    ``SyncVectorEnv``) the returned arrays are copies of them, with ``copy=False`` they are
    the reused buffers themselves (overwritten by the next call).

    Same keywords and trajectories as N single envs made with ``gym.make`` (the single env's
    ``TimeLimit`` is done here in Rust, at ``max_episode_steps``), with Gymnasium 1.x
    next-step autoreset: the step after an episode ends resets that env, ignores its action,
    and returns reward 0, not terminated, not truncated. ``reset(seed=s)`` seeds env ``i``
    with ``s + i``, as ``SyncVectorEnv`` does. ``reset(options={"reset_mask": mask})`` resets
    only the envs where ``mask`` is true.

    ``info`` holds arrays ``collided``, ``distance_to_target``, ``cell`` (``(N, 3)`` int32),
    ``is_success`` and ``detour_penalty``, each with its ``_key`` mask (all true). Observation
    types ``"vector"`` and ``"index"`` (goals: :class:`SixAxisAvoidGoalVectorEnv`); no
    rendering.

    Besides Gymnasium's API, the configuration (``scenario``, ``obs_type``, ``reward_scale``,
    ``random_target``, ``arm_aware``, ``max_episode_steps``, ``num_states``,
    ``blocked_cells``, ``extra_obstacles``), each env's state (``cells``,
    ``current_targets``, ``elapsed_steps``) and the single env's stateless methods
    (``cell_of``, ``state_of``, ``goal_to_cell``) are public.
    """

    #: The per-env info keys (the SB3 VecEnv's info dicts).
    INFO_KEYS: ClassVar[tuple[str, ...]] = (
        "collided",
        "distance_to_target",
        "cell",
        "is_success",
        "detour_penalty",
    )

    def __init__(
        self,
        num_envs: int = 1,
        scenario: Any = None,
        obs_type: str = "vector",
        assist: bool | None = None,
        reward_scale: float = 1.0,
        random_target: bool = False,
        arm_aware: bool = False,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        copy: bool = True,
    ):
        check_obs_type(obs_type, self._GOAL)
        kw = check_keywords(
            num_envs=num_envs,
            assist=assist,
            reward_scale=reward_scale,
            random_target=random_target,
            arm_aware=arm_aware,
            max_episode_steps=max_episode_steps,
            copy=copy,
        )
        num_envs, assist, reward_scale = kw["num_envs"], kw["assist"], kw["reward_scale"]
        random_target, arm_aware, self.copy = kw["random_target"], kw["arm_aware"], kw["copy"]
        self._refuse_render_mode(render_mode)
        check_random_target(obs_type, random_target)
        self.scenario = as_scenario(scenario)
        if max_episode_steps is None:
            max_episode_steps = self.scenario.max_steps_per_episode
        max_episode_steps = check_keywords(max_episode_steps=max_episode_steps)["max_episode_steps"]

        self.num_envs = num_envs
        self.obs_type = obs_type
        self.render_mode = None
        self.max_episode_steps = max_episode_steps
        self.arm_aware = arm_aware
        extra = _arm.unreachable_cells(self.scenario) if arm_aware else None
        self._core = _core.VecEnvCore(
            self.scenario,
            num_envs=num_envs,
            max_episode_steps=max_episode_steps,
            obs="index" if obs_type == "index" else "vector",
            assist=assist,
            reward_scale=reward_scale,
            random_target=random_target,
            extra_obstacles=extra,
        )
        self.single_observation_space = observation_space_of(obs_type, self._core.num_states)
        self.single_action_space = spaces.Discrete(6)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)

        self._obs = self._core.observations
        self._rewards = self._core.rewards
        self._terminated = self._core.terminated
        self._truncated = self._core.truncated
        self._collided = self._core.collided
        self._distance = self._core.distance_to_target
        self._cells = self._core.cells
        self._detour = self._core.detour_penalty
        self._mask = np.ones(num_envs, dtype=bool)
        self._seeded = False

    def _seed(self, seed: int | list[int | None] | None) -> None:
        n = self.num_envs
        if seed is None:
            if self._seeded:
                return
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = seed_list_of(seed, n)
        # Env i's generator is seeded exactly as a single env's reset(seed=seeds[i]) does.
        self._core.seed([int(seeding.np_random(s)[0].integers(0, 2**63)) for s in seeds])
        self._seeded = True

    def _goal_dict(self, obs: np.ndarray) -> dict[str, np.ndarray]:
        return goal_dict(obs)

    def _info(self) -> dict[str, Any]:
        m = self._mask
        return {
            "collided": self._result(self._collided),
            "_collided": m,
            "distance_to_target": self._result(self._distance),
            "_distance_to_target": m,
            "cell": self._result(self._cells),
            "_cell": m,
            "is_success": self._terminated.copy(),
            "_is_success": m,
            "detour_penalty": self._result(self._detour),
            "_detour_penalty": m,
        }

    def actions_array(self, actions) -> np.ndarray:
        """``actions`` as the int64 array of shape ``(num_envs,)`` the core steps with."""
        return discrete_actions_of(actions, self.num_envs).astype(np.int64, copy=False)

    # Configuration ----------------------------------------------------------------------
    @property
    def reward_scale(self) -> float:
        return self._core.reward_scale

    @property
    def random_target(self) -> bool:
        return self._core.random_target

    @property
    def num_states(self) -> int:
        return self._core.num_states

    @property
    def blocked_cells(self) -> list[tuple[int, int, int]]:
        """Obstacles, then (arm-aware) the cells no clear arm pose reaches."""
        return self._core.obstacles

    @property
    def extra_obstacles(self) -> list[tuple[int, int, int]]:
        """The arm-aware blocked cells (empty unless ``arm_aware``)."""
        return self._core.extra_obstacles

    # Each env's state -------------------------------------------------------------------
    @property
    def cells(self) -> np.ndarray:
        """Each env's terminal cell, ``(N, 3)`` int32 (a copy)."""
        return self._cells.copy()

    @property
    def current_targets(self) -> np.ndarray:
        """Each env's current target cell, ``(N, 3)`` int32."""
        return self._core.current_targets

    @property
    def elapsed_steps(self) -> np.ndarray:
        """Steps since each env's reset, ``(N,)``."""
        return self._core.steps

    # The single env's stateless methods ------------------------------------------------
    def cell_of(self, state: int) -> tuple[int, int, int]:
        """The cell of an ``"index"`` observation."""
        return self._core.cell_of(int(state))

    def state_of(self, cell) -> int | None:
        """The ``"index"`` observation of a cell (None outside bounds)."""
        return self._core.state_of(cell)

    def goal_to_cell(self, goal: np.ndarray) -> np.ndarray:
        """Normalised cell(s) ``(..., 3)`` -> integer cells ``(..., 3)``."""
        return goal_to_cell(self._core, goal)


class SixAxisAvoidGoalVectorEnv(SixAxisAvoidVectorEnv):
    """``num_envs`` copies of :class:`~sixaxis_avoid.env.SixAxisAvoidGoalEnv`
    (``gym.make_vec("SixAxisAvoidGoal-v0", num_envs=N)``): :class:`SixAxisAvoidVectorEnv`
    with batched ``Dict`` observations (``observation`` ``(N, 13)``, ``achieved_goal`` and
    ``desired_goal`` ``(N, 3)``) and the single env's :meth:`compute_reward`. Same keywords
    as :class:`SixAxisAvoidVectorEnv` without ``obs_type``."""

    _GOAL: ClassVar[bool] = True

    def __init__(
        self,
        num_envs: int = 1,
        scenario: Any = None,
        assist: bool | None = None,
        reward_scale: float = 1.0,
        random_target: bool = False,
        arm_aware: bool = False,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        copy: bool = True,
    ):
        super().__init__(
            num_envs,
            scenario,
            obs_type="goal",
            assist=assist,
            reward_scale=reward_scale,
            random_target=random_target,
            arm_aware=arm_aware,
            max_episode_steps=max_episode_steps,
            render_mode=render_mode,
            copy=copy,
        )
        self._goal_rewards = GoalRewards(self._core)

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray | float:
        """As :meth:`SixAxisAvoidGoalEnv.compute_reward
        <sixaxis_avoid.env.SixAxisAvoidGoalEnv.compute_reward>` (every env shares the model)."""
        return self._goal_rewards(achieved_goal, desired_goal, info)
