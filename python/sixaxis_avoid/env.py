"""The Gymnasium environments ``SixAxisAvoid-v0`` (and ``SixAxisAvoidArm-v0``) and the
goal-conditioned ``SixAxisAvoidGoal-v0``."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sixaxis_avoid import _arm, _core
from sixaxis_avoid._checks import (
    invalid,
)
from sixaxis_avoid._deps import require
from sixaxis_avoid._goal import (
    GoalRewards,
    goal_dict,
    goal_to_cell,
    refuse_goal_obs_type,
)

VECTOR_OBS_DIM = _core.VECTOR_OBS_DIM


def as_scenario(scenario: Any) -> _core.Scenario:
    """A Scenario from a Scenario, built-in name, JSON path, dict, or None (the default)."""
    return scenario if isinstance(scenario, _core.Scenario) else _core.Scenario(scenario)


def vector_observation_space() -> spaces.Box:
    low = np.array([-1.0] * 6 + [0.0] * 7, dtype=np.float32)
    high = np.ones(VECTOR_OBS_DIM, dtype=np.float32)
    return spaces.Box(low, high, dtype=np.float32)


def goal_observation_space() -> spaces.Dict:
    goal = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
    return spaces.Dict(
        {"observation": vector_observation_space(), "achieved_goal": goal, "desired_goal": goal}
    )


def check_obs_type(obs_type: Any, goal: bool) -> str:
    """``"vector"`` / ``"index"`` on the plain envs (``"goal"`` names the goal id), ``"goal"``
    on the goal envs."""
    if goal:
        if obs_type != "goal":
            raise invalid("obs_type", obs_type, 'must be "goal" on the goal envs')
        return obs_type
    refuse_goal_obs_type(obs_type)
    return check_keywords(obs_type=obs_type)["obs_type"]


def check_keywords(**keywords: Any) -> dict[str, Any]:
    """Env keywords checked against the core's one table (ENV_OPTIONS, rust/core/src/env/mod.rs)
    and returned as plain values: a bad value raises InvalidArgumentError naming the keyword
    and the value."""
    return _core.check_options("env", **keywords)


def check_render_size(render_size: Any) -> int:
    return check_keywords(render_size=render_size)["render_size"]


def check_random_target(obs_type: str, random_target: bool) -> None:
    """A per-episode target needs an observation that shows the target."""
    if random_target and obs_type == "index":
        raise invalid(
            "random_target",
            random_target,
            'needs obs_type "vector" or "goal" (the "index" observation does not show the target)',
        )


def observation_space_of(obs_type: str, num_states: int) -> spaces.Space:
    """The (single-env) observation space of an obs_type."""
    if obs_type == "vector":
        return vector_observation_space()
    if obs_type == "index":
        return spaces.Discrete(num_states)
    return goal_observation_space()


class SixAxisAvoidEnv(gym.Env):
    """The terminal (end effector) of a six-axis arm moves on a 3D grid of 100 mm cells and
    must reach a target through clutter, after *Path Planning with Autonomous Obstacle
    Avoidance Using Reinforcement Learning for Six-axis Arms* (section III.B).

    ## Description

    The grid is the scenario's box of cells; obstacles are unit cubes centred on cells. Each
    step moves the terminal one cell along an axis. A move that leaves the box or comes
    within ``terminal_safe_distance`` of an obstacle centre collides and the terminal stays
    where it was (the paper: "moves back"). The default scenario is the paper's simple case
    (Table 1): start ``(0, -2, 4)``, target ``(0, 3, 0)``, 19 obstacles. With
    ``arm_aware=True`` (id ``SixAxisAvoidArm-v0``), a move into a cell that no clear pose of
    the whole arm reaches (the core's ``PosePlanner.cell_reachable``, eq. 11) also collides.
    Those cells are computed in Rust once per scenario and cached; the start and target
    cells are never among them.
    The grid world's dynamics and rewards run in Rust.

    ## Action Space

    ``Discrete(6)``: ``0: +x, 1: -x, 2: +y, 3: -y, 4: +z, 5: -z`` (eq. 3).

    ## Observation Space

    By keyword ``obs_type``:

    - ``"vector"`` (default): ``Box(13,)`` float32 — the terminal's cell normalised to the
      bounds (``2 (c - min) / (max - min) - 1`` per axis, in [-1, 1]); the target's cell
      normalised the same way; six flags, 1 if the move of that action would collide; 1 if
      the last step collided.
    - ``"index"``: ``Discrete(num_states)`` — the number of the terminal's cell (row-major
      over x, y, z with z fastest; ``env.unwrapped.cell_of(i)`` converts).

    The goal-conditioned variant (``Dict`` observations with achieved and desired goals and
    a vectorised ``compute_reward`` for hindsight experience replay) is its own id,
    ``SixAxisAvoidGoal-v0`` (:class:`SixAxisAvoidGoalEnv`); ``obs_type="goal"`` here raises
    an ``InvalidArgumentError`` that names it.

    ## Rewards

    The paper's reward, computed in Rust, times ``reward_scale``:

    - eq. 5: ``+target_reward`` (20000) on reaching the target, ``-collision_penalty``
      (8000) on a collision, ``-step_penalty`` (15000) otherwise;
    - eq. 9 (``assist``): after a colliding step with action *a*, an extra
      ``-repeat_collision_penalty`` (230000) if the next step collides again, else
      ``-reverse_after_collision_penalty`` (10000) if it takes the opposite of *a*;
    - eq. 10 (``assist``): ``+distance_reward * (d_o - d_t)`` (40 per cell) on every step,
      ``d_o = |target - start|``, ``d_t = |target - terminal|`` (cells).

    The magnitudes are the paper's (tens of thousands): for neural-network agents pass e.g.
    ``reward_scale=1e-4``.

    ## Starting State

    The terminal starts at the scenario's start cell. The target is the scenario's, or with
    ``random_target=True`` drawn uniformly at each reset from the free cells other than the
    start (seeded through ``np_random``).

    ## Episode End

    - Termination: the terminal reaches the target.
    - Truncation: after ``max_episode_steps`` steps, by Gymnasium's ``TimeLimit`` (the
      registration uses 1000, the shipped scenarios' ``learning.max_steps_per_episode``; for
      another cap pass ``max_episode_steps=`` to ``gym.make`` or use
      :func:`sixaxis_avoid.make`, which takes it from the scenario).

    ``info`` holds ``collided`` (bool), ``distance_to_target`` (cells), ``cell`` (the
    terminal's cell, a tuple), ``is_success`` (reached the target on this step) and
    ``detour_penalty`` (eq. 9's part of the reward before scaling, used by the goal env's
    ``compute_reward``).

    ## Arguments

    ```python
    import gymnasium as gym
    import sixaxis_avoid  # registers the ids

    env = gym.make(
        "SixAxisAvoid-v0",
        scenario="paper_simple",  # built-in name, JSON path, dict, Scenario, or None
        obs_type="vector",  # "vector" | "index" (goals: the id "SixAxisAvoidGoal-v0")
        assist=None,  # None: the scenario's learning.assist_* (both on in every built-in);
        # True: eqs. 9 and 10 on; False: eq. 5 alone
        reward_scale=1.0,  # finite, >= 0
        random_target=False,  # draw the target per episode (needs "vector" or "goal")
        arm_aware=False,  # cells no clear arm pose reaches count as collisions
        render_mode=None,  # None | "rgb_array" | "human"
        render_arm=False,  # draw the arm in a clear IK pose at the terminal's cell
    )
    ```

    Every bad value raises ``InvalidArgumentError`` / ``ScenarioError`` (``ValueError``
    subclasses) naming the keyword or field and the value.

    ## Version History

    - v0: initial version. The goal-conditioned variant, once ``obs_type="goal"`` of this
      id, is ``SixAxisAvoidGoal-v0``; ``obs_type="goal"`` raises an error naming it.
      ``assist`` defaults to ``None`` (the scenario's flags, as ``train`` and ``plan``); every
      built-in scenario has both on, so the built-in worlds behave as before (``True``).
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array"], "render_fps": 8}
    #: Goal-conditioned (``SixAxisAvoidGoalEnv``): Dict observations and compute_reward.
    _GOAL: ClassVar[bool] = False

    def __init__(
        self,
        scenario: Any = None,
        obs_type: str = "vector",
        assist: bool | None = None,
        reward_scale: float = 1.0,
        random_target: bool = False,
        arm_aware: bool = False,
        render_mode: str | None = None,
        render_arm: bool = False,
        render_size: int = 512,
    ):
        check_obs_type(obs_type, self._GOAL)
        kw = check_keywords(
            assist=assist,
            reward_scale=reward_scale,
            random_target=random_target,
            arm_aware=arm_aware,
            render_mode=render_mode,
            render_arm=render_arm,
            render_size=render_size,
        )
        assist, reward_scale, random_target = kw["assist"], kw["reward_scale"], kw["random_target"]
        arm_aware, render_arm = kw["arm_aware"], kw["render_arm"]
        check_random_target(obs_type, random_target)
        if render_mode == "human":
            # Fail at construction, not at the first frame, if Matplotlib is missing.
            require("matplotlib", 'render_mode="human"')

        self.scenario: _core.Scenario = as_scenario(scenario)
        self.obs_type = obs_type
        self.reward_scale = reward_scale
        self.random_target = random_target
        self.arm_aware = arm_aware
        self.render_mode = render_mode
        self.render_arm = render_arm
        self._render_size = render_size

        extra = _arm.unreachable_cells(self.scenario) if arm_aware else None
        self._core = _core.EnvCore(
            self.scenario,
            obs="index" if obs_type == "index" else "vector",
            assist=assist,
            reward_scale=reward_scale,
            random_target=random_target,
            extra_obstacles=extra,
            track_path=render_mode is not None,
        )
        self._seeded = False

        self.action_space = spaces.Discrete(6)
        self.observation_space = observation_space_of(obs_type, self._core.num_states)

        self._renderer = None
        self._window = None

    # Gymnasium API ----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is not None or not self._seeded:
            # The Rust generator of random targets is seeded from np_random.
            self._core.seed(int(self.np_random.integers(0, 2**63)))
            self._seeded = True
        obs, info = self._core.reset()
        if self._GOAL:
            obs = goal_dict(obs)
        if self.render_mode == "human":
            self._render_human()
        return obs, info

    def step(self, action):
        obs, reward, terminated, info = self._core.step(action)
        if self._GOAL:
            obs = goal_dict(obs)
        if self.render_mode == "human":
            self._render_human()
        return obs, reward, terminated, False, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn(
                "Calling render() without a render_mode; "
                "pass render_mode='rgb_array' or 'human' to gym.make."
            )
            return None
        if self.render_mode == "rgb_array":
            return self._frame()
        self._render_human()
        return None

    def close(self):
        if self._window is not None:
            self._window.close()
            self._window = None

    def goal_to_cell(self, goal: np.ndarray) -> np.ndarray:
        """Normalised cell(s) ``(..., 3)`` (as in the vector observation and the goals) ->
        integer cells ``(..., 3)``."""
        return goal_to_cell(self._core, goal)

    # Introspection ----------------------------------------------------------------------
    @property
    def num_states(self) -> int:
        return self._core.num_states

    @property
    def cell(self) -> tuple[int, int, int]:
        """The terminal's cell."""
        return self._core.cell

    @property
    def target_cell(self) -> tuple[int, int, int]:
        """This episode's target cell."""
        return self._core.target_cell

    def cell_of(self, state: int) -> tuple[int, int, int]:
        """The cell of an ``"index"`` observation."""
        return self._core.cell_of(int(state))

    def state_of(self, cell) -> int | None:
        """The ``"index"`` observation of a cell (None outside bounds)."""
        return self._core.state_of(cell)

    @property
    def blocked_cells(self) -> list[tuple[int, int, int]]:
        """Obstacles, then (arm-aware) the cells no clear arm pose reaches."""
        return self._core.obstacles

    @property
    def path(self) -> list[tuple[int, int, int]]:
        """Cells visited in this episode (tracked when a render_mode is set)."""
        return self._core.path

    # Rendering --------------------------------------------------------------------------
    def _frame(self) -> np.ndarray:
        from sixaxis_avoid.render import SceneRenderer

        if self._renderer is None:
            self._renderer = SceneRenderer(
                self.scenario,
                self._core.extra_obstacles,
                size=self._render_size,
                render_arm=self.render_arm,
            )
        return self._renderer.frame(self._core.path, self._core.cell, self._core.target_cell)

    def _render_human(self) -> None:
        from sixaxis_avoid.render import HumanWindow

        if self._window is None:
            self._window = HumanWindow(
                f"SixAxisAvoid: {self.scenario.name}", self.metadata["render_fps"]
            )
        caption = (
            f"step {self._core.steps}  cell {self._core.cell}  target {self._core.target_cell}"
        )
        self._window.show(self._frame(), caption)


class SixAxisAvoidGoalEnv(SixAxisAvoidEnv):
    """The goal-conditioned variant of :class:`SixAxisAvoidEnv` (id ``SixAxisAvoidGoal-v0``):
    the same grid world, dynamics and rewards, with ``Dict`` observations and a vectorised
    :meth:`compute_reward` for hindsight experience replay (SB3's ``HerReplayBuffer``).

    ## Observation Space

    ``Dict(observation=Box(13,), achieved_goal=Box(3,), desired_goal=Box(3,))``:
    ``observation`` is ``SixAxisAvoid-v0``'s vector observation, ``achieved_goal`` the
    terminal's normalised cell and ``desired_goal`` the target's (both float32 in [-1, 1],
    the observation's elements 0-2 and 3-5); :meth:`goal_to_cell` converts a goal to its
    cell. Pass ``random_target=True`` for a target drawn per episode.

    ## Rewards

    As ``SixAxisAvoid-v0``. :meth:`compute_reward` gives the same rewards for relabelled
    goals, computed in Rust by the step's own code (the core's ``EnvModel::goal_rewards``).

    ## Arguments

    ```python
    import gymnasium as gym
    import sixaxis_avoid  # registers the ids

    env = gym.make(
        "SixAxisAvoidGoal-v0",
        scenario="paper_simple",
        random_target=True,
        arm_aware=False,  # True: the arm-aware world of SixAxisAvoidArm-v0
        # assist, reward_scale, render_mode, render_arm, render_size: as SixAxisAvoid-v0
    )
    ```

    There is no ``obs_type`` keyword: the observation is always the ``Dict``.

    ## Version History

    - v0: initial version (before it had its own id: ``SixAxisAvoid-v0`` with
      ``obs_type="goal"``).
    """

    _GOAL: ClassVar[bool] = True

    def __init__(
        self,
        scenario: Any = None,
        assist: bool | None = None,
        reward_scale: float = 1.0,
        random_target: bool = False,
        arm_aware: bool = False,
        render_mode: str | None = None,
        render_arm: bool = False,
        render_size: int = 512,
    ):
        super().__init__(
            scenario,
            obs_type="goal",
            assist=assist,
            reward_scale=reward_scale,
            random_target=random_target,
            arm_aware=arm_aware,
            render_mode=render_mode,
            render_arm=render_arm,
            render_size=render_size,
        )
        self._goal_rewards = GoalRewards(self._core)

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray | float:
        """The step reward for (achieved, desired) goal pairs, vectorised over leading axes
        (``(3,)`` gives a float, ``(..., 3)`` an array of shape ``...``).

        Equals, to the bit, the reward ``step`` returned when ``achieved_goal`` is the goal
        reached by that step; with another ``desired_goal`` it is the reward the same move
        would have earned for that target (HER relabelling). Computed in Rust by the step's
        own eqs. 5, 9 and 10. ``info`` is the step's info dict (for every pair) or a sequence
        of them, one per pair (its ``collided`` and ``detour_penalty`` are used).

        SB3's ``HerReplayBuffer`` passes empty info dicts unless made with
        ``replay_buffer_kwargs={"copy_info_dict": True}``; without them the reward is
        computed as if the step had not collided and had no eq. 9 term (a warning says so
        once), which is exact for every transition but collisions and detours.

        Bad shapes raise ``InvalidArgumentError`` naming ``achieved_goal``, ``desired_goal``
        or ``info``.
        """
        return self._goal_rewards(achieved_goal, desired_goal, info)
