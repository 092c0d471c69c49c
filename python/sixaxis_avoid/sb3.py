"""A Stable-Baselines3 ``VecEnv`` over the native Rust batch.

SB3 takes its own ``VecEnv`` type, not Gymnasium's vector API, so without this module it
trains on ``DummyVecEnv`` (one Python ``step`` per env). :class:`SixAxisVecEnv` steps all
N envs in one Rust call and gives SB3 its own semantics::

    from stable_baselines3 import PPO
    from sixaxis_avoid.sb3 import SixAxisVecEnv

    venv = SixAxisVecEnv(8, seed=0, reward_scale=1e-4, max_episode_steps=200)
    model = PPO("MlpPolicy", venv, n_steps=256, seed=0).learn(50_000)

Needs the ``sb3`` extra (``pip install "sixaxis-avoid[sb3]"``).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from sixaxis_avoid._checks import check_bool, check_choice, invalid
from sixaxis_avoid._deps import require
from sixaxis_avoid.vector import SixAxisAvoidVectorEnv

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


class SixAxisVecEnv(VecEnv):
    """``n_envs`` copies of ``SixAxisAvoid-v0`` as one Stable-Baselines3 ``VecEnv``.

    ``env_kwargs`` are the keywords of ``gym.make("SixAxisAvoid-v0", ...)`` (``scenario``,
    ``obs_type``, ``assist``, ``reward_scale``, ``random_target``, ``arm_aware``,
    ``render_mode`` (``None`` or ``"rgb_array"``), ``render_arm``, ``render_size``) plus
    ``max_episode_steps`` (default: the scenario's ``learning.max_steps_per_episode``).

    Step for step the same as ``DummyVecEnv([lambda: gym.make("SixAxisAvoid-v0", **kw)] *
    n_envs)`` seeded alike: an env whose episode ends is reset at once and its returned
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
    stateless methods (``compute_reward`` for HER, ``cell_of``, ``state_of``,
    ``goal_to_cell``). ``env_is_wrapped`` is ``False``: no Gymnasium wrapper is involved.
    """

    def __init__(self, n_envs: int, seed: int | None = None, **env_kwargs: Any):
        render_mode = env_kwargs.pop("render_mode", None)
        check_choice("render_mode", render_mode, (None, "rgb_array"))
        self.render_arm = check_bool("render_arm", env_kwargs.pop("render_arm", False))
        self._render_size = env_kwargs.pop("render_size", 512)
        self._env_kwargs = dict(env_kwargs)
        self.venv = SixAxisAvoidVectorEnv(num_envs=n_envs, copy=False, **env_kwargs)
        v = self.venv
        self._core = v._core
        self.render_mode = render_mode
        self._user_attrs: list[dict[str, Any]] = [{} for _ in range(v.num_envs)]
        self._single = None
        self._renderers: dict[int, Any] = {}
        self._paths: list[list[tuple[int, int, int]]] | None = None
        if render_mode is not None:
            # Validate render_size now, as the single env does.
            self._single_env()
        super().__init__(v.num_envs, v.single_observation_space, v.single_action_space)
        self.metadata = {"render_modes": ["rgb_array"] if render_mode else [], "render_fps": 8}
        self._goal = v.obs_type == "goal"
        self._index = v.obs_type == "index"
        self._actions: np.ndarray | None = None
        self._obs_buf = self._core.observations
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

    def _single_env(self):
        """A single env of the same configuration (for its stateless methods)."""
        if self._single is None:
            from sixaxis_avoid.env import SixAxisAvoidEnv

            kw = {k: v for k, v in self._env_kwargs.items() if k != "max_episode_steps"}
            self._single = SixAxisAvoidEnv(
                **kw,
                render_mode=None,
                render_arm=self.render_arm,
                render_size=self._render_size,
            )
        return self._single

    # Observations and infos -------------------------------------------------------------
    def _obs(self, obs: np.ndarray):
        if self._goal:
            return {
                "observation": obs,
                "achieved_goal": obs[:, 0:3].copy(),
                "desired_goal": obs[:, 3:6].copy(),
            }
        return obs

    def _obs_row(self, obs: np.ndarray, i: int):
        if self._index:
            return int(obs[i])
        row = obs[i].copy()
        if self._goal:
            return {
                "observation": row,
                "achieved_goal": row[0:3].copy(),
                "desired_goal": row[3:6].copy(),
            }
        return row

    def _infos(self, idx: Iterable[int] | None = None) -> list[dict[str, Any]]:
        """The single env's info dicts of envs ``idx`` (all if None), from the core's buffers."""
        c = self._core
        idx = range(self.num_envs) if idx is None else list(idx)
        collided = c.collided[idx].tolist()
        distance = c.distance_to_target[idx].tolist()
        cells = c.cells[idx].tolist()
        success = c.terminated[idx].tolist()
        detour = c.detour_penalty[idx].tolist()
        return [
            {
                "collided": collided[k],
                "distance_to_target": distance[k],
                "cell": tuple(cells[k]),
                "is_success": success[k],
                "detour_penalty": detour[k],
            }
            for k in range(len(collided))
        ]

    # VecEnv API -------------------------------------------------------------------------
    def reset(self):
        seeds = self._seeds
        if any(s is not None for s in seeds):
            # Env i's generator is seeded exactly as a single env's reset(seed=seeds[i]).
            self.venv._seed(list(seeds))
        else:
            self.venv._seed(None)  # random seeds on the first reset, else keep the generators
        self._core.reset(None)
        self.reset_infos = self._infos()
        self._reset_seeds()
        self._reset_options()
        if self.render_mode is not None:
            self._paths = [[tuple(cell)] for cell in self._core.cells.tolist()]
        return self._obs(self._obs_buf.copy())

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = self.venv.actions_array(actions)

    def step_wait(self):
        if self._actions is None:
            raise invalid("actions", None, "step_wait() needs a step_async(actions) first")
        c = self._core
        c.step(self._actions)
        self._actions = None
        obs = self._obs_buf.copy()
        rewards = c.rewards.astype(np.float32)
        terminated = c.terminated.copy()
        truncated = c.truncated.copy()
        dones = terminated | truncated
        infos = self._infos()
        time_limit = (truncated & ~terminated).tolist()
        for i, info in enumerate(infos):
            info["TimeLimit.truncated"] = time_limit[i]
        if self._paths is not None:
            self._track_paths(infos)
        if dones.any():
            done = np.flatnonzero(dones)
            for i in done:
                infos[i]["terminal_observation"] = self._obs_row(obs, int(i))
            c.reset(dones)
            obs[done] = self._obs_buf[done]
            for i, info in zip(done, self._infos(done)):
                self.reset_infos[i] = info
                if self._paths is not None:
                    self._paths[i] = [info["cell"]]
        return self._obs(obs), rewards, dones, infos

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
            return getattr(self._single_env(), name)
        if name == "cell":
            return tuple(self._core.cells[i].tolist())
        if name == "target_cell":
            return tuple(self._core.target_cells[i].tolist())
        if name == "elapsed_steps":
            return int(self._core.steps[i])
        if name == "path" and self._paths is not None:
            return list(self._paths[i])
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
        if attr_name in (*_SHARED_ATTRS, *_STATE_ATTRS, "observation_space", "action_space"):
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
            self._core.reset(mask)
            infos = self._infos(idx)
            obs = self._obs_buf
            for i, info in zip(idx, infos):
                self.reset_infos[i] = info
                if self._paths is not None:
                    self._paths[i] = [info["cell"]]
            return [(self._obs_row(obs, i), info) for i, info in zip(idx, infos)]
        if method_name == "get_wrapper_attr":
            return [self._env_attr(method_args[0], i) for i in idx]
        if method_name in _STATELESS_METHODS:
            fn = getattr(self._single_env(), method_name)
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
                self._core_extra(),
                size=self._render_size,
                render_arm=self.render_arm,
            )
            self._renderers[i] = r
        cell = tuple(self._core.cells[i].tolist())
        path = self._paths[i] if self._paths is not None else [cell]
        return r.frame(path, cell, tuple(self._core.target_cells[i].tolist()))

    def _core_extra(self) -> list[tuple[int, int, int]]:
        return self._single_env()._core.extra_obstacles

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [self._frame(i) for i in range(self.num_envs)]
