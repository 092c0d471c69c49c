"""The joint-space Gymnasium environments ``SixAxisAvoidJoint-v0`` and the goal-conditioned
``SixAxisAvoidJointGoal-v0``, their native vector envs, and :func:`rollout_plan` (a rollout
as a plan that ``verify`` and ``animate`` accept). The dynamics, the clearance and the
rewards run in Rust (``sixaxis_core::joint_env``); docs/JOINT.md documents every choice."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

from sixaxis_avoid import _core
from sixaxis_avoid._checks import invalid
from sixaxis_avoid._goal import goal_pair, info_dicts
from sixaxis_avoid._ids import JOINT_ENV_ID, JOINT_GOAL_ENV_ID
from sixaxis_avoid.env import as_scenario
from sixaxis_avoid.vector import NativeVectorEnv

#: Each joint-env keyword's default, from the core's one table (``_core.options("joint")``,
#: JOINT_ENV_OPTIONS; None where the scenario's value or Gymnasium's applies).
JOINT_DEFAULTS: dict[str, Any] = {o["key"]: o["default"] for o in _core.options("joint")}

#: Step cap of the registrations (the core's default ``max_episode_steps``).
JOINT_MAX_EPISODE_STEPS: int = JOINT_DEFAULTS["max_episode_steps"]

#: Keywords of the Python envs that the model does not take.
_ENV_ONLY = ("num_envs", "copy", "render_mode")


def check_joint_keywords(**keywords: Any) -> dict[str, Any]:
    """Joint-env keywords checked against the core's one table (JOINT_ENV_OPTIONS,
    rust/core/src/joint_env/options.rs) and returned as plain values: a bad value raises
    InvalidArgumentError naming the keyword and the value; an unknown keyword a TypeError."""
    return _core.check_options("joint", **keywords)


def _model_options(keywords: Mapping[str, Any]) -> dict[str, Any]:
    """The checked keywords the core's model takes (``None``: the scenario's or the
    default)."""
    return {k: v for k, v in keywords.items() if k not in _ENV_ONLY and v is not None}


def joint_observation_space(core: Any) -> spaces.Box:
    """The observation's Box: sin/cos, goals and direction in [-1, 1], clearances and the
    refused flag in [0, 1] (the layout is the core's ``obs_layout``)."""
    lay = core.obs_layout
    low = -np.ones(core.obs_dim, dtype=np.float32)
    high = np.ones(core.obs_dim, dtype=np.float32)
    low[slice(*lay["clearance"])] = 0.0
    low[lay["refused"]] = 0.0
    return spaces.Box(low, high, dtype=np.float32)


def joint_goal_space(core: Any) -> spaces.Dict:
    goal = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
    return spaces.Dict(
        {
            "observation": joint_observation_space(core),
            "achieved_goal": goal,
            "desired_goal": goal,
        }
    )


def joint_goal_dict(core: Any, obs: np.ndarray) -> dict[str, np.ndarray]:
    """The ``Dict`` observation of observation(s) ``obs``: the goals are copies of its
    terminal and target slices."""
    lay = core.obs_layout
    return {
        "observation": obs,
        "achieved_goal": obs[..., slice(*lay["terminal"])].copy(),
        "desired_goal": obs[..., slice(*lay["target"])].copy(),
    }


class JointGoalRewards:
    """``compute_reward`` of a joint goal env over its core (``JointEnvCore`` or
    ``JointVecEnvCore``): the core's ``goal_rewards``, vectorised over leading axes."""

    def __init__(self, core: Any):
        self._core = core
        self._warned = False

    def __call__(self, achieved_goal: Any, desired_goal: Any, info: Any) -> np.ndarray | float:
        a, d, shape, n = goal_pair(achieved_goal, desired_goal)
        a32 = a.reshape(-1, 3).astype(np.float32)
        previous, refused, detour = self._info_arrays(info, shape, n, a32)
        r = self._core.compute_reward(
            previous, a32, d.reshape(-1, 3).astype(np.float32), refused, detour
        )
        return float(r[0]) if shape == () else r.reshape(shape)

    def _info_arrays(self, info: Any, shape: tuple[int, ...], n: int, achieved: np.ndarray):
        """Each transition's previous achieved goal, ``refused`` and ``detour_penalty`` from
        one info dict (for every transition) or one per transition."""
        infos = info_dicts(info, shape, n, "transition")
        keys = ("previous_achieved_goal", "refused", "detour_penalty")
        if all(all(k in i for k in keys) for i in infos):
            previous = np.array(
                [np.asarray(i["previous_achieved_goal"], dtype=np.float32) for i in infos]
            ).reshape(-1, 3)
            refused = np.array([bool(i["refused"]) for i in infos], dtype=bool)
            detour = np.array([float(i["detour_penalty"]) for i in infos])
            if len(infos) == 1 and n != 1:
                previous = np.repeat(previous, n, axis=0)
                refused, detour = np.repeat(refused, n), np.repeat(detour, n)
            return previous, refused, detour
        if not self._warned:
            self._warned = True
            gym.logger.warn(
                "compute_reward got info dicts without 'previous_achieved_goal', 'refused' "
                "and 'detour_penalty': computing the reward without progress, refusal or "
                "eq. 9 terms. For the exact reward with SB3's HerReplayBuffer pass "
                'replay_buffer_kwargs={"copy_info_dict": True}.'
            )
        return achieved, np.zeros(n, dtype=bool), np.zeros(n)


class SixAxisAvoidJointEnv(gym.Env):
    """The whole six-axis arm moves in joint space and must bring its terminal to a target
        through clutter; every step is checked by the exact capsule-to-box clearance
        (docs/JOINT.md). After *Path Planning with Autonomous Obstacle Avoidance Using
        Reinforcement Learning for Six-axis Arms*, whose grid reward shaping it carries over.

        ## Description

        The scenario gives the arm (D-H table, beta_0, optional joint limits), the obstacles (the
        cells' cubes of ``cell_mm`` and the boxes of ``obstacle_boxes_mm``, in mm) and the target
        (the target cell's centre, mm). Each link is a capsule (``link_radius_mm``) around a
        segment of the arm's polyline. A step moves the joints linearly by the scaled action; it
        is refused, and the arm stays where it was (the paper's "move back"), when the new
        angles leave the joint limits or when any of the interpolated poses brings a capsule
        within ``safe_distance_mm`` of a box. The sub-steps are enough that no arm point moves
        more than ``substep_fraction`` times the safe distance between two checked poses, so
        no link can pass through a box. Dynamics, clearance and rewards run in Rust.

        ## Action Space

        ``Box(-1, 1, (6,), float32)``: joint ``i`` moves by ``action[i] * max_joint_step_deg``
        degrees (default {max_joint_step_deg}).

        ## Observation Space

        ``Box(22 + L,)`` float32 (L = number of links of non-zero length, 5 for the paper's
        arm; the layout is ``env.unwrapped.obs_layout``): sin of the six joints (6), cos of the
        six joints (6), the terminal position divided by the arm's reach (3), the target divided
        by the reach (3) (the reach is the polyline's length, so both lie in [-1, 1]), per link
        the exact gap ``g`` (mm) to the nearest obstacle as ``g / (g + safe_distance_mm)`` (L;
        1 without obstacles), the unit vector from the terminal to the nearest point of the
        nearest obstacle box (3; zeros without obstacles), 1 if the last step was refused (1).

        ## Rewards

        The paper's shaping, per step, times ``reward_scale`` (default {reward_scale}; the
        defaults give O(1) per step):

        - eq. 5: ``+target_reward`` ({target_reward}) for the step that ends within
          ``target_tolerance_mm``, ``-collision_penalty`` ({collision_penalty}) for a refused
          step, else ``-step_penalty`` ({step_penalty});
        - eq. 10 (``assist``, default {assist}): ``+progress_reward * (d_before - d_after)``
          ({progress_reward} per mm), d the terminal-target distance in mm;
        - eq. 9 (``assist``), after a refused step: ``-repeat_collision_penalty``
          ({repeat_collision_penalty}) if this step is refused too, else
          ``-reverse_after_collision_penalty * max(0, -cos)`` ({reverse_after_collision_penalty})
          of the angle between this action and the refused one.

        ## Starting State

        The scenario's beta_0 (``arm.beta0_deg``), which must be clear and within the limits.

        ## Episode End

        - Termination: the terminal is within ``target_tolerance_mm`` ({target_tolerance_mm} mm)
          of the target.
        - Truncation: after ``max_episode_steps`` steps by Gymnasium's ``TimeLimit``
          ({max_episode_steps} in the registration; the native vector env truncates in Rust).

        ``info`` holds ``is_success`` (terminated on this step), ``clearance`` (the smallest
        link gap, mm), ``refused``, ``distance_to_target`` (mm), ``detour_penalty`` (eq. 9's
        part of the reward before scaling) and ``previous_achieved_goal`` (the terminal / reach
        before the step, for ``compute_reward``).

        ## Arguments

        ```python
        import gymnasium as gym
        import sixaxis_avoid  # registers the ids

        env = gym.make("SixAxisAvoidJoint-v0", scenario="paper_simple", max_joint_step_deg=1.0)
        ```

        ``scenario``: a built-in name, a JSON path, a dict, a ``Scenario``, or None (the paper's
        simple case). The keywords, with their units and defaults, from the core's one table
        (``sixaxis_avoid.options("joint")``; docs/JOINT.md's keyword table is the same):

    {arguments}

        Every bad value raises ``InvalidArgumentError`` / ``ScenarioError`` (``ValueError``
        subclasses) naming the keyword or field and the value.

        ## Version History

        - v0: initial version.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": []}
    _GOAL: ClassVar[bool] = False

    def __init__(self, scenario: Any = None, render_mode: str | None = None, **keywords: Any):
        NativeVectorEnv._refuse_render_mode(render_mode)
        kw = check_joint_keywords(**keywords)
        for k in _ENV_ONLY:
            if k in kw:
                raise TypeError(
                    f"got an unexpected keyword argument '{k}' (a keyword of the vector envs)"
                )
        self.scenario: _core.Scenario = as_scenario(scenario)
        self.render_mode = None
        self._core = _core.JointEnvCore(self.scenario, options=_model_options(kw))
        self.action_space = spaces.Box(-1.0, 1.0, shape=(6,), dtype=np.float32)
        self.observation_space = (
            joint_goal_space(self._core) if self._GOAL else joint_observation_space(self._core)
        )

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        # The episode is deterministic (beta_0, the scenario's target): the seed only seeds
        # np_random, as Gymnasium asks.
        super().reset(seed=seed)
        obs, info = self._core.reset()
        return (joint_goal_dict(self._core, obs) if self._GOAL else obs), info

    def step(self, action):
        obs, reward, terminated, info = self._core.step(np.asarray(action, dtype=np.float64))
        if self._GOAL:
            obs = joint_goal_dict(self._core, obs)
        return obs, reward, terminated, False, info

    # Introspection ----------------------------------------------------------------------
    @property
    def obs_layout(self) -> dict[str, Any]:
        """Where each field sits in the observation (``(start, end)`` per field)."""
        return self._core.obs_layout

    @property
    def joints(self) -> np.ndarray:
        """The joint angles, radians."""
        return np.array(self._core.joints)

    @property
    def terminal_mm(self) -> np.ndarray:
        """The terminal's position, mm."""
        return np.array(self._core.terminal_mm)

    @property
    def target_mm(self) -> np.ndarray:
        """The target, mm."""
        return np.array(self._core.target_mm)

    @property
    def reach_mm(self) -> float:
        return self._core.reach_mm

    @property
    def safe_distance_mm(self) -> float:
        return self._core.safe_distance_mm

    @property
    def link_radius_mm(self) -> float:
        return self._core.link_radius_mm


def _default_text(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return repr(value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def documented(doc: str) -> str:
    """``doc`` with each ``{keyword}`` replaced by that keyword's default and ``{arguments}``
    by one line per model keyword (unit, default, doc line), all from the core's one table
    (JOINT_ENV_OPTIONS), so the docstring cannot state a default the env does not have."""
    rows = [o for o in _core.options("joint") if o["key"] not in _ENV_ONLY]
    lines = []
    for o in rows:
        unit = f"{o['unit']}, " if o["unit"] else ""
        lines.append(
            f"    - ``{o['key']}`` ({unit}default {_default_text(o['default'])}): {o['doc']}"
        )
    out = doc.replace("{arguments}", "\n".join(lines))
    for o in rows:
        out = out.replace("{" + o["key"] + "}", _default_text(o["default"]))
    left = re.findall(r"\{[a-z_]+\}", out)
    if left:  # a placeholder naming no keyword: a typo in the docstring
        raise RuntimeError(f"docstring placeholders without a keyword: {left}")
    return out


SixAxisAvoidJointEnv.__doc__ = documented(SixAxisAvoidJointEnv.__doc__ or "")


class SixAxisAvoidJointGoalEnv(SixAxisAvoidJointEnv):
    """The goal-conditioned variant of :class:`SixAxisAvoidJointEnv` (id
    ``SixAxisAvoidJointGoal-v0``), for hindsight experience replay.

    ## Observation Space

    ``Dict(observation=Box(22 + L,), achieved_goal=Box(3,), desired_goal=Box(3,))``:
    ``observation`` is ``SixAxisAvoidJoint-v0``'s, ``achieved_goal`` the terminal / reach and
    ``desired_goal`` the target / reach (float32 in [-1, 1]).

    ## Rewards

    As ``SixAxisAvoidJoint-v0``. :meth:`compute_reward` gives the reward of relabelled goals,
    computed in Rust by the step's own arithmetic (``JointModel::goal_rewards``): a step's own
    goals give its reward to the bit.

    ## Arguments

    As ``SixAxisAvoidJoint-v0``.

    ## Version History

    - v0: initial version.
    """

    _GOAL: ClassVar[bool] = True

    def __init__(self, scenario: Any = None, render_mode: str | None = None, **keywords: Any):
        super().__init__(scenario, render_mode=render_mode, **keywords)
        self._goal_rewards = JointGoalRewards(self._core)

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray | float:
        """The step reward of (achieved, desired) goal pairs, vectorised over leading axes
        (``(3,)`` gives a float, ``(..., 3)`` an array of shape ``...``). ``info`` is the
        step's info dict (for every pair) or one per pair; its ``previous_achieved_goal``,
        ``refused`` and ``detour_penalty`` are used. Without them (SB3's HerReplayBuffer
        without ``copy_info_dict=True``) the progress, refusal and eq. 9 terms are left out
        (a warning says so once)."""
        return self._goal_rewards(achieved_goal, desired_goal, info)


#: The vector env's per-env info keys, in order.
JOINT_INFO_KEYS = (
    "is_success",
    "clearance",
    "refused",
    "distance_to_target",
    "detour_penalty",
    "previous_achieved_goal",
)


class SixAxisAvoidJointVectorEnv(NativeVectorEnv):
    """``num_envs`` copies of :class:`SixAxisAvoidJointEnv` in one Rust object
    (``gym.make_vec("SixAxisAvoidJoint-v0", num_envs=N)``): each :meth:`step` is one Rust
    call with the GIL released, into NumPy buffers allocated once (``copy=False`` returns the
    buffers themselves). Same trajectories as N single envs, with Gymnasium 1.x next-step
    autoreset and truncation at ``max_episode_steps`` in Rust. ``info`` holds the single
    env's keys as arrays, each with its ``_key`` mask; ``joints`` (``(N, 6)``, rad) and
    ``terminal_mm`` (``(N, 3)``) give each env's state."""

    SHARED_ATTRS: ClassVar[tuple[str, ...]] = (
        "scenario",
        "obs_type",
        "max_episode_steps",
        "reach_mm",
        "safe_distance_mm",
        "link_radius_mm",
        "obs_layout",
    )
    INFO_KEYS: ClassVar[tuple[str, ...]] = JOINT_INFO_KEYS
    #: No rendering (the SB3 VecEnv refuses render keywords).
    RENDERS: ClassVar[bool] = False

    def __init__(
        self,
        num_envs: int = 1,
        scenario: Any = None,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        copy: bool = True,
        **keywords: Any,
    ):
        self._refuse_render_mode(render_mode)
        if max_episode_steps is None:
            max_episode_steps = JOINT_MAX_EPISODE_STEPS
        kw = check_joint_keywords(
            num_envs=num_envs, max_episode_steps=max_episode_steps, copy=copy, **keywords
        )
        self.num_envs, self.copy = kw["num_envs"], kw["copy"]
        self.max_episode_steps = kw["max_episode_steps"]
        self.scenario = as_scenario(scenario)
        self.render_mode = None
        self.obs_type = "goal" if self._GOAL else "vector"
        self._core = _core.JointVecEnvCore(
            self.scenario, num_envs=self.num_envs, options=_model_options(kw)
        )
        self.single_observation_space = (
            joint_goal_space(self._core) if self._GOAL else joint_observation_space(self._core)
        )
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(6,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        c = self._core
        self._obs, self._rewards = c.observations, c.rewards
        self._terminated, self._truncated = c.terminated, c.truncated
        self._buffers = {
            "clearance": c.clearance,
            "refused": c.refused,
            "distance_to_target": c.distance_to_target,
            "detour_penalty": c.detour_penalty,
            "previous_achieved_goal": c.previous_achieved_goal,
        }
        self._joints, self._terminal = c.joints, c.terminal_mm
        self._mask = np.ones(self.num_envs, dtype=bool)

    def _goal_dict(self, obs: np.ndarray) -> dict[str, np.ndarray]:
        return joint_goal_dict(self._core, obs)

    def _info(self) -> dict[str, Any]:
        m = self._mask
        info: dict[str, Any] = {"is_success": self._terminated.copy(), "_is_success": m}
        for k, buf in self._buffers.items():
            info[k] = self._result(buf)
            info["_" + k] = m
        return info

    def actions_array(self, actions) -> np.ndarray:
        """``actions`` as the float64 ``(num_envs, 6)`` array the core steps with."""
        try:
            a = np.asarray(actions, dtype=np.float64)
        except (TypeError, ValueError):
            raise invalid("actions", actions, "must be numbers in [-1, 1]") from None
        if a.shape != (self.num_envs, 6):
            if a.size != 6 * self.num_envs:
                raise invalid("actions", actions, f"must have shape ({self.num_envs}, 6)")
            a = a.reshape(self.num_envs, 6)
        return np.ascontiguousarray(a)

    # Configuration and state ------------------------------------------------------------
    @property
    def obs_layout(self) -> dict[str, Any]:
        return self._core.obs_layout

    @property
    def reach_mm(self) -> float:
        return self._core.reach_mm

    @property
    def safe_distance_mm(self) -> float:
        return self._core.safe_distance_mm

    @property
    def link_radius_mm(self) -> float:
        return self._core.link_radius_mm

    @property
    def joints(self) -> np.ndarray:
        """Each env's joint angles, rad, ``(N, 6)`` (a copy)."""
        return self._joints.copy()

    @property
    def terminal_mm(self) -> np.ndarray:
        """Each env's terminal position, mm, ``(N, 3)`` (a copy)."""
        return self._terminal.copy()

    @property
    def elapsed_steps(self) -> np.ndarray:
        return self._core.steps


class SixAxisAvoidJointGoalVectorEnv(SixAxisAvoidJointVectorEnv):
    """``num_envs`` copies of :class:`SixAxisAvoidJointGoalEnv`
    (``gym.make_vec("SixAxisAvoidJointGoal-v0", num_envs=N)``): batched ``Dict``
    observations and the single env's :meth:`compute_reward`."""

    _GOAL: ClassVar[bool] = True

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self._goal_rewards = JointGoalRewards(self._core)

    def compute_reward(self, achieved_goal, desired_goal, info) -> np.ndarray | float:
        """As :meth:`SixAxisAvoidJointGoalEnv.compute_reward`."""
        return self._goal_rewards(achieved_goal, desired_goal, info)


def rollout_plan(
    env: gym.Env,
    policy: Callable[[Any], Any],
    *,
    max_steps: int | None = None,
    seed: int | None = None,
) -> dict[str, Any]:
    """Run ``policy`` (observation -> action) for one episode of a joint env (``gym.make``'d
    or not) and return the motion as a plan: the dict of ``sixaxis_avoid.plan(...).to_dict()``
    that :func:`sixaxis_avoid.verify.verify_plan` and :mod:`sixaxis_avoid.animate` read.

    ``poses_rad`` holds beta_0 and the pose after every accepted step (a refused step does
    not move the arm); ``path`` the terminal's nearest cell at each pose;
    ``interpolation_steps`` the most sub-steps any step was checked at; ``success`` whether
    the episode terminated at the target; ``failure`` ``None`` or why not; plus the
    scenario's ``obstacles``, ``obstacle_boxes_mm``, ``cell_mm``, ``start``, ``target``,
    the env's capsules model, the return and the step counts. ``max_steps`` caps the
    episode (default: the env's ``TimeLimit``, else its ``max_episode_steps``)."""
    base = env.unwrapped
    if not isinstance(base, SixAxisAvoidJointEnv):
        raise invalid("env", env, f"must be a {JOINT_ENV_ID} or {JOINT_GOAL_ENV_ID} env")
    if max_steps is None:
        spec = getattr(env, "spec", None)
        max_steps = (spec.max_episode_steps if spec else None) or base._core.max_episode_steps
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise invalid("max_steps", max_steps, "must be a positive integer")
    core = base._core
    s = base.scenario
    cell_mm = float(s.cell_mm)
    obs, _ = env.reset(seed=seed)
    poses = [list(core.joints)]
    substeps = 1
    total, steps, refused = 0.0, 0, 0
    terminated = truncated = False
    while steps < max_steps and not (terminated or truncated):
        action = np.asarray(policy(obs), dtype=np.float64)
        before = list(core.joints)
        obs, reward, terminated, truncated, info = env.step(action)
        steps += 1
        total += float(reward)
        if info["refused"]:
            refused += 1
        else:
            substeps = max(substeps, core.substeps(before, core.joints))
            poses.append(list(core.joints))
    arm = _core.Arm.from_scenario(s)
    path = [tuple(round(float(v) / cell_mm) for v in arm.fk(np.asarray(q))[0]) for q in poses]
    failure = None
    if not terminated:
        failure = f"the target was not reached in {steps} steps"
    d = s.to_dict()
    return {
        "success": bool(terminated),
        "failure": failure,
        "poses_rad": poses,
        "path": [list(c) for c in path],
        "interpolation_steps": int(substeps),
        "obstacles": [list(c) for c in d["obstacles"]],
        "obstacle_boxes_mm": list(d.get("obstacle_boxes_mm", [])),
        "cell_mm": cell_mm,
        "start": list(d["start"]),
        "target": list(d["target"]),
        "clearance_model": {
            "kind": "capsules",
            "link_radius_mm": core.link_radius_mm,
            "margin_mm": core.safe_distance_mm,
        },
        "source": JOINT_ENV_ID,
        "steps": steps,
        "refused_steps": refused,
        "return": total,
    }
