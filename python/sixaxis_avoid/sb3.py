"""A Stable-Baselines3 ``VecEnv`` over the native Rust batch.

SB3 takes its own ``VecEnv`` type, not Gymnasium's vector API, so without this module it
trains on ``DummyVecEnv`` (one Python ``step`` per env). :class:`SixAxisVecEnv` steps all
N envs in one Rust call and gives SB3 its own semantics::

    from stable_baselines3 import PPO
    from sixaxis_avoid.sb3 import SixAxisVecEnv

    venv = SixAxisVecEnv(8, seed=0, reward_scale=1e-4, max_episode_steps=200)
    model = PPO("MlpPolicy", venv, n_steps=256, seed=0).learn(50_000)

For hindsight experience replay pass ``env_id="SixAxisAvoidGoal-v0"``: ``env_method`` then
runs the goal env's ``compute_reward``.

It drives the native vector env (:class:`~sixaxis_avoid.vector.SixAxisAvoidVectorEnv`)
through its public API only: ``reset``/``step`` (with ``copy=False``, so its buffers are
read without copies), ``reset(options={"reset_mask": ...})`` for the envs whose episode
ended, and its documented configuration and per-env state.

Needs the ``sb3`` extra (``pip install "sixaxis-avoid[sb3]"``).
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from sixaxis_avoid._checks import check_choice, invalid
from sixaxis_avoid._deps import require
from sixaxis_avoid._ids import ARM_ENV_ID, ENV_ID, GOAL_ENV_ID, JOINT_ENV_ID, JOINT_GOAL_ENV_ID
from sixaxis_avoid.env import ENV_DEFAULTS, check_keywords, check_render_size
from sixaxis_avoid.vector import NativeVectorEnv

_vec_env = require("stable_baselines3.common.vec_env", "sixaxis_avoid.sb3")
VecEnv = _vec_env.VecEnv

#: Keywords of the single env that configure every env of the batch alike (read-only here).
_SHARED_ATTRS = (
    "scenario",
    "obs_type",
    "reward_scale",
    "random_target",
    "arm_aware",
    "max_episode_steps",
    "render_mode",
    "render_arm",
    "num_states",
    "blocked_cells",
)
#: Per-env state, read-only.
_STATE_ATTRS = ("cell", "target_cell", "elapsed_steps", "path")
#: Methods of the single env that depend on the configuration only, not on an env's state.
_STATELESS_METHODS = ("compute_reward", "cell_of", "state_of", "goal_to_cell")


def _vector_env_class(env_id: Any) -> tuple[type[NativeVectorEnv], dict[str, Any]]:
    """The native vector env class and default keywords of one of our Gymnasium ids."""
    ours = (ENV_ID, ARM_ENV_ID, GOAL_ENV_ID, JOINT_ENV_ID, JOINT_GOAL_ENV_ID)
    if env_id not in ours:
        raise invalid("env_id", env_id, "must be one of " + ", ".join(repr(i) for i in ours))
    spec = gym.spec(env_id)
    module, name = str(spec.vector_entry_point).split(":")
    cls = getattr(importlib.import_module(module), name)
    return cls, dict(spec.kwargs)


class SixAxisVecEnv(VecEnv):
    """``n_envs`` copies of ``SixAxisAvoid-v0`` (or another of our ids, ``env_id``) as one
    Stable-Baselines3 ``VecEnv``.

    ``env_id`` is ``"SixAxisAvoid-v0"`` (default), ``"SixAxisAvoidArm-v0"`` or
    ``"SixAxisAvoidGoal-v0"``; ``env_kwargs`` are the keywords of ``gym.make(env_id, ...)``
    (``scenario``, ``obs_type`` (not for the goal id), ``assist``, ``reward_scale``,
    ``random_target``, ``arm_aware``, ``render_mode`` (``None`` or ``"rgb_array"``),
    ``render_arm``, ``render_size``) plus ``max_episode_steps`` (default: the scenario's
    ``learning.max_steps_per_episode``).

    Step for step the same as ``DummyVecEnv([lambda: gym.make(env_id, **kw)] * n_envs)``
    seeded alike: an env whose episode ends is reset at once and its returned
    observation is the new episode's first; ``infos[i]`` holds the single env's info
    (``collided``, ``distance_to_target``, ``cell``, ``is_success``, ``detour_penalty``),
    ``"TimeLimit.truncated"`` (the step cap ended the episode, not the target) and, when the
    episode ended, ``"terminal_observation"``. Rewards are float32 as in ``DummyVecEnv``.

    ``seed`` seeds env ``i`` with ``seed + i`` at the next :meth:`reset` (SB3's rule; the
    constructor's ``seed`` does the same as calling :meth:`seed`). The generators only matter
    with ``random_target=True``; otherwise every episode is deterministic.

    ``get_attr`` reads the configuration (``scenario``, ``obs_type``, ``reward_scale``,
    ``max_episode_steps``, ...), each env's state (``cell``, ``target_cell``,
    ``elapsed_steps``, ``path`` when rendering) and attributes stored by ``set_attr``;
    ``set_attr`` stores per-env attributes of your own but refuses the configuration, which
    all envs share in one Rust object (make a new ``SixAxisVecEnv`` instead).
    ``env_method`` runs ``reset`` and ``render`` for the chosen envs, and the single env's
    stateless methods (``compute_reward`` for HER on the goal id, ``cell_of``, ``state_of``,
    ``goal_to_cell``), which the native vector env provides for all its envs.
    ``env_is_wrapped`` is ``False``: no Gymnasium wrapper is involved.

    The joint-space ids (``"SixAxisAvoidJoint-v0"``, ``"SixAxisAvoidJointGoal-v0"``) take
    their own keywords (docs/JOINT.md), do not render, and read their configuration through
    the vector env's ``SHARED_ATTRS``; their infos are the keys of its ``INFO_KEYS``.
    """

    def __init__(
        self,
        n_envs: int,
        seed: int | None = None,
        env_id: str = ENV_ID,
        **env_kwargs: Any,
    ):
        cls, defaults = _vector_env_class(env_id)
        render_mode = env_kwargs.pop("render_mode", ENV_DEFAULTS["render_mode"])
        renders = getattr(cls, "RENDERS", True)
        check_choice("render_mode", render_mode, (None, "rgb_array") if renders else (None,))
        self.render_arm = ENV_DEFAULTS["render_arm"]
        self._render_size = ENV_DEFAULTS["render_size"]
        if renders:
            self.render_arm = check_keywords(
                render_arm=env_kwargs.pop("render_arm", ENV_DEFAULTS["render_arm"])
            )["render_arm"]
            # Checked now, as the single env does, though only rendering uses it.
            self._render_size = check_render_size(
                env_kwargs.pop("render_size", ENV_DEFAULTS["render_size"])
            )
        self.env_id = env_id
        self.venv = cls(num_envs=n_envs, copy=False, **{**defaults, **env_kwargs})
        v = self.venv
        self.render_mode = render_mode
        self._user_attrs: list[dict[str, Any]] = [{} for _ in range(v.num_envs)]
        self._renderers: dict[int, Any] = {}
        self._paths: list[list[tuple[int, int, int]]] | None = None
        super().__init__(v.num_envs, v.single_observation_space, v.single_action_space)
        self.metadata = {"render_modes": ["rgb_array"] if render_mode else [], "render_fps": 8}
        self._index = getattr(v, "obs_type", None) == "index"
        self._actions: np.ndarray | None = None
        if seed is not None:
            self.seed(seed)

    # Configuration ----------------------------------------------------------------------
    @property
    def scenario(self):
        return self.venv.scenario

    @property
    def obs_type(self) -> str:
        return self.venv.obs_type

    @property
    def max_episode_steps(self) -> int:
        return self.venv.max_episode_steps

    # Observations and infos -------------------------------------------------------------
    # The native vector env's observations are an array or (goal id) a dict of arrays.
    @staticmethod
    def _copy(obs):
        if isinstance(obs, dict):
            return {k: v.copy() for k, v in obs.items()}
        return obs.copy()

    @staticmethod
    def _set_rows(dst, src, idx: np.ndarray) -> None:
        if isinstance(dst, dict):
            for k in dst:
                dst[k][idx] = src[k][idx]
        else:
            dst[idx] = src[idx]

    def _obs_row(self, obs, i: int):
        if isinstance(obs, dict):
            return {k: v[i].copy() for k, v in obs.items()}
        if self._index:
            return int(obs[i])
        return obs[i].copy()

    def _infos(
        self, info: dict[str, Any], idx: Sequence[int] | None = None
    ) -> list[dict[str, Any]]:
        """The single env's info dicts of envs ``idx`` (all if None), from the vector env's
        info (a dict of arrays, the keys of its ``INFO_KEYS``; rows of 2-D arrays become
        tuples, as the single env's ``cell``)."""
        idx = slice(None) if idx is None else list(idx)
        columns = {}
        for key in self.venv.INFO_KEYS:
            values = info[key][idx]
            columns[key] = (
                [tuple(r) for r in values.tolist()] if values.ndim == 2 else values.tolist()
            )
        n = len(next(iter(columns.values())))
        return [{key: col[k] for key, col in columns.items()} for k in range(n)]

    # VecEnv API -------------------------------------------------------------------------
    def _reset_envs(self, mask: np.ndarray):
        """Reset the envs where ``mask`` is true: their observations (the vector env's
        buffers) and info."""
        return self.venv.reset(options={"reset_mask": mask})

    def reset(self):
        seeds = self._seeds
        # Env i's generator is seeded exactly as a single env's reset(seed=seeds[i]); without
        # seeds the vector env draws random ones on the first reset, else keeps its generators.
        seed = list(seeds) if any(s is not None for s in seeds) else None
        obs, info = self.venv.reset(seed=seed)
        self.reset_infos = self._infos(info)
        self._reset_seeds()
        self._reset_options()
        if self.render_mode is not None:
            self._paths = [[i["cell"]] for i in self.reset_infos]
        return self._copy(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = self.venv.actions_array(actions)

    def step_wait(self):
        if self._actions is None:
            raise invalid("actions", None, "step_wait() needs a step_async(actions) first")
        step_obs, step_rewards, step_terminated, step_truncated, step_info = self.venv.step(
            self._actions
        )
        self._actions = None
        obs = self._copy(step_obs)
        rewards = step_rewards.astype(np.float32)
        terminated = step_terminated.copy()
        truncated = step_truncated.copy()
        dones = terminated | truncated
        infos = self._infos(step_info)
        time_limit = (truncated & ~terminated).tolist()
        for i, info in enumerate(infos):
            info["TimeLimit.truncated"] = time_limit[i]
        if self._paths is not None:
            self._track_paths(infos)
        if dones.any():
            done = np.flatnonzero(dones)
            for i in done:
                infos[i]["terminal_observation"] = self._obs_row(obs, int(i))
            new_obs, new_info = self._reset_envs(dones)
            self._set_rows(obs, new_obs, done)
            for i, info in zip(done, self._infos(new_info, done)):
                self.reset_infos[i] = info
                if self._paths is not None:
                    self._paths[i] = [info["cell"]]
        return obs, rewards, dones, infos

    def _track_paths(self, infos: Sequence[dict[str, Any]]) -> None:
        for path, info in zip(self._paths, infos):
            if not info["collided"]:
                path.append(info["cell"])

    def close(self) -> None:
        self.venv.close()

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seeds env ``i`` with ``seed + i`` at the next :meth:`reset` (a random ``seed`` if
        None), as every SB3 ``VecEnv`` does."""
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))):
            raise invalid("seed", seed, "must be an integer or None")
        return super().seed(None if seed is None else int(seed))

    # Attributes and methods -------------------------------------------------------------
    def _env_attr(self, name: str, i: int) -> Any:
        if name in self._user_attrs[i]:
            return self._user_attrs[i][name]
        if name in ("observation_space", "action_space"):
            return getattr(self.venv, "single_" + name)
        if name in ("scenario", "obs_type", "max_episode_steps"):
            return getattr(self.venv, name)
        if name == "render_mode":
            return self.render_mode
        if name == "render_arm":
            return self.render_arm
        if name in ("reward_scale", "random_target", "arm_aware", "num_states", "blocked_cells"):
            return getattr(self.venv, name)
        if name == "cell":
            return tuple(self.venv.cells[i].tolist())
        if name == "target_cell":
            return tuple(self.venv.current_targets[i].tolist())
        if name == "elapsed_steps":
            return int(self.venv.elapsed_steps[i])
        if name == "path" and self._paths is not None:
            return list(self._paths[i])
        if name in getattr(self.venv, "SHARED_ATTRS", ()):
            return getattr(self.venv, name)
        if name == "metadata":
            return self.metadata
        if name == "spec":
            return None
        raise AttributeError(
            f"SixAxisVecEnv envs have no attribute {name!r} (they have: "
            + ", ".join((*_SHARED_ATTRS, *_STATE_ATTRS, "observation_space", "action_space"))
            + ", and those stored by set_attr)"
        )

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [self._env_attr(attr_name, i) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        shared = getattr(self.venv, "SHARED_ATTRS", ())
        if attr_name in (
            *_SHARED_ATTRS,
            *shared,
            *_STATE_ATTRS,
            "observation_space",
            "action_space",
        ):
            raise invalid(
                attr_name,
                value,
                "all envs of a SixAxisVecEnv share it in one Rust object (or it is an env's "
                "state); make a new SixAxisVecEnv with the keyword instead",
            )
        for i in self._get_indices(indices):
            self._user_attrs[i][attr_name] = value

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs):
        idx = list(self._get_indices(indices))
        if method_name == "render":
            return [self._frame(i) for i in idx]
        if method_name == "reset":
            mask = np.zeros(self.num_envs, dtype=bool)
            mask[idx] = True
            obs, info = self._reset_envs(mask)
            infos = self._infos(info, idx)
            for i, info in zip(idx, infos):
                self.reset_infos[i] = info
                if self._paths is not None:
                    self._paths[i] = [info["cell"]]
            return [(self._obs_row(obs, i), info) for i, info in zip(idx, infos)]
        if method_name == "get_wrapper_attr":
            return [self._env_attr(method_args[0], i) for i in idx]
        if method_name in _STATELESS_METHODS and hasattr(self.venv, method_name):
            fn = getattr(self.venv, method_name)
            return [fn(*method_args, **method_kwargs) for _ in idx]
        raise AttributeError(
            f"SixAxisVecEnv envs have no method {method_name!r} (they have: render, reset, "
            "get_wrapper_attr, " + ", ".join(_STATELESS_METHODS) + ")"
        )

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    # Rendering --------------------------------------------------------------------------
    def _frame(self, i: int) -> np.ndarray | None:
        if self.render_mode is None:
            return None
        r = self._renderers.get(i)
        if r is None:
            from sixaxis_avoid.render import SceneRenderer

            r = SceneRenderer(
                self.scenario,
                self.venv.extra_obstacles,
                size=self._render_size,
                render_arm=self.render_arm,
            )
            self._renderers[i] = r
        cell = tuple(self.venv.cells[i].tolist())
        path = self._paths[i] if self._paths is not None else [cell]
        return r.frame(path, cell, tuple(self.venv.current_targets[i].tolist()))

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [self._frame(i) for i in range(self.num_envs)]
