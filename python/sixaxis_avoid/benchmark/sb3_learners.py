"""The Stable-Baselines3 and sb3-contrib learners of the benchmark: DQN, QR-DQN, PPO and
A2C on the native ``SixAxisVecEnv``, with their defaults until tuned and their implementation
variants (:mod:`sixaxis_avoid.benchmark.implementation`).

Entry points: :class:`SB3Learner` (the shared training loop: env keywords, learning-rate
schedule, hindsight replay on goal tasks, the greedy rollout) and its four subclasses
:class:`DQN`, :class:`QRDQN`, :class:`PPO`, :class:`A2C`; :data:`ENV_DEFAULTS` and each
algorithm's ``*_DEFAULTS``.
"""

from __future__ import annotations

import importlib
from typing import Any, Callable, ClassVar

import gymnasium as gym

from sixaxis_avoid.benchmark.errors import LearnerError
from sixaxis_avoid.benchmark.implementation import (
    DQN_IMPLEMENTATION,
    IMPLEMENTATIONS,
    check_implementation,
    expand_implementation,
    lecun_init,
    per_network_clipping,
    squared_error_updates,
    train_freq_as_envs,
    truncation_as_termination,
)
from sixaxis_avoid.benchmark.interface import Cell, Learner, RunContext, whole_iterations

#: Hyperparameters that configure the env rather than the algorithm.
ENV_KEYS = ("reward_scale", "assist", "max_episode_steps", "n_envs")

#: Env settings of every deep learner's defaults: the paper's assisted rewards scaled to
#: O(1) (the paper's are tens of thousands), episodes capped at 200 steps.
ENV_DEFAULTS: dict[str, Any] = {"reward_scale": 1e-4, "assist": True, "max_episode_steps": 200}

#: DQN defaults (until tuned): rl-baselines3-zoo hyperparams/dqn.yml, MountainCar-v0 (a
#: sparse-reward, discrete-action goal-reaching task; commit ce95481b), SB3 defaults otherwise.
DQN_DEFAULTS: dict[str, Any] = {
    **ENV_DEFAULTS,
    "learning_rate": 4e-3,
    "batch_size": 128,
    "buffer_size": 10_000,
    "learning_starts": 1_000,
    "gamma": 0.98,
    "target_update_interval": 600,
    "train_freq": 16,
    "gradient_steps": 8,
    "exploration_fraction": 0.2,
    "exploration_final_eps": 0.07,
    "net_arch": [256, 256],
}
#: QR-DQN defaults (until tuned): DQN's, with 50 quantiles.
QRDQN_DEFAULTS: dict[str, Any] = {**DQN_DEFAULTS, "n_quantiles": 50}
#: PPO defaults (until tuned): SB3's, with 8 envs, n_steps 256 and ent_coef 0.01.
PPO_DEFAULTS: dict[str, Any] = {**ENV_DEFAULTS, "n_envs": 8, "n_steps": 256, "ent_coef": 0.01}
#: A2C defaults (until tuned): SB3's, with 8 envs and ent_coef 0.01.
A2C_DEFAULTS: dict[str, Any] = {**ENV_DEFAULTS, "n_envs": 8, "ent_coef": 0.01}


def greedy_rollout(model: Any, env: gym.Env, cap: int) -> list[Cell] | None:
    """The deterministic policy's path from the start: the cells visited until the target
    (bumps into obstacles leave the terminal in place and are not moves); None on a loop (a
    repeated (cell, collided) pair: the observation repeats, so does the action) or at the
    step cap."""
    obs, info = env.reset(seed=0)
    cell = tuple(info["cell"])
    path, seen = [cell], {(cell, False)}
    for _ in range(cap):
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, _, info = env.step(int(action))
        cell, collided = tuple(info["cell"]), bool(info["collided"])
        if not collided:
            path.append(cell)
        if terminated:
            return path
        if (cell, collided) in seen:
            return None
        seen.add((cell, collided))
    return None


def linear_schedule(initial: float) -> Callable[[float], float]:
    """A learning rate falling linearly from ``initial`` to 0 over training (SB3 calls it
    with the fraction of the budget remaining, 1 to 0)."""

    def rate(progress_remaining: float) -> float:
        return initial * progress_remaining

    return rate


class SB3Learner(Learner):
    """A Stable-Baselines3-style algorithm on ``SixAxisAvoid-v0`` (vector observations; goal
    observations on goal tasks, with hindsight experience replay for off-policy ones),
    trained on ``n_envs`` envs of the native ``SixAxisVecEnv`` (:meth:`RunContext.make_vec_env`;
    its class name is the run file's ``result.vec_env``)."""

    family = "deep"
    off_policy: ClassVar[bool] = False
    #: ``module:Class`` of the algorithm.
    algorithm_path: ClassVar[str] = ""

    def algorithm(self) -> Any:
        module, _, name = self.algorithm_path.partition(":")
        return getattr(importlib.import_module(module), name)

    def learn(self, ctx: RunContext) -> None:
        import torch
        from stable_baselines3.common.logger import Logger

        torch.set_num_threads(1)
        hp = self.expand_hyperparams(dict(self.hyperparams))
        env_kw = {k: hp.pop(k) for k in ENV_KEYS if k in hp}
        n_envs = int(env_kw.pop("n_envs", 1))
        self._env_kw = {k: env_kw[k] for k in ("reward_scale", "assist") if k in env_kw}
        self._goal = ctx.task.is_goal
        # The native SB3 VecEnv over the Rust batch, for every kind of task (fixed and random
        # targets, goal observations, re-gridded and re-plan worlds): step for step the same
        # as DummyVecEnv over ctx.make_env() envs (docs/BENCHMARKS.md, "Tasks").
        vec = ctx.make_vec_env(n_envs, **env_kw)
        self.vec_env = type(vec.unwrapped).__name__
        policy_kwargs = {k: hp.pop(k) for k in ("net_arch", "n_quantiles") if k in hp}
        impl = {k: hp.pop(k) for k in self.implementation_keys if k in hp}
        vec, policy_kwargs = self.before_model(impl, vec, policy_kwargs)
        schedule = hp.pop("lr_schedule", "constant")
        if schedule == "linear":
            # rl-baselines3-zoo's "lin_": from the value down to 0 at the end of the budget.
            hp["learning_rate"] = linear_schedule(float(hp.get("learning_rate", 3e-4)))
        elif schedule != "constant":
            raise LearnerError(
                f"lr_schedule: {schedule!r} is not a schedule (use 'constant' or 'linear')"
            )
        if self._goal and self.off_policy and impl.get("her", True):
            from stable_baselines3 import HerReplayBuffer

            # HER cannot sample before an episode has ended: learning starts after one.
            cap = int(env_kw.get("max_episode_steps", ctx.world.max_steps_per_episode))
            hp["learning_starts"] = max(int(hp.get("learning_starts", 100)), cap)
            hp["replay_buffer_class"] = HerReplayBuffer
            hp["replay_buffer_kwargs"] = {
                "n_sampled_goal": int(hp.pop("her_n_sampled_goal", 4)),
                "goal_selection_strategy": "future",
                "copy_info_dict": True,
            }
        else:
            hp.pop("her_n_sampled_goal", None)
        policy = "MultiInputPolicy" if self._goal else "MlpPolicy"
        self.model = self.algorithm()(
            policy,
            vec,
            policy_kwargs=policy_kwargs or None,
            seed=ctx.seed,
            device="cpu",
            verbose=0,
            **hp,
        )
        self.after_model(impl, self.model)
        self.model.set_logger(Logger(None, []))  # no log files
        self._eval_envs: dict[Cell, gym.Env] = {}
        # Whole rollouts (on-policy) or vector steps (off-policy) at or under the budget:
        # SB3 ends learn() on the first whole one past total_timesteps.
        n_steps = int(getattr(self.model, "n_steps", 1))
        self.model.learn(total_timesteps=whole_iterations(ctx.budget, n_steps * self.model.n_envs))
        vec.close()

    #: The algorithm's implementation variants (:data:`IMPLEMENTATIONS` key: "ppo", "dqn"),
    #: hyperparameters that choose between them rather than set SB3 arguments.
    implementation: ClassVar[str | None] = None

    @property
    def implementation_keys(self) -> tuple[str, ...]:
        return () if self.implementation is None else tuple(IMPLEMENTATIONS[self.implementation][0])

    def expand_hyperparams(self, hp: dict[str, Any]) -> dict[str, Any]:
        """``hp`` with any preset it names replaced by the preset's values."""
        if self.implementation is None:
            return hp
        return expand_implementation(self.implementation, hp)

    def before_model(
        self, impl: dict[str, Any], vec: Any, policy_kwargs: dict[str, Any]
    ) -> tuple[Any, dict[str, Any]]:
        """The VecEnv and policy keywords for the implementation variant ``impl``: every
        algorithm's ``bootstrap_truncated: False`` (rejax's) takes the truncation flags out."""
        if self.implementation is not None:
            if not check_implementation(self.implementation, impl)["bootstrap_truncated"]:
                vec = truncation_as_termination(vec)
        return vec, policy_kwargs

    def after_model(self, impl: dict[str, Any], model: Any) -> None:
        """Changes to the built model for the implementation variant ``impl``."""

    def greedy_path(self, world: Any) -> list[Cell] | None:
        import sixaxis_avoid as sa

        key = (tuple(world.target), len(world.obstacles))
        env = self._eval_envs.get(key)
        if env is None:
            env_id = sa.GOAL_ENV_ID if self._goal else sa.ENV_ID
            env = sa.make(env_id, scenario=world, **self._env_kw).unwrapped
            self._eval_envs[key] = env
        return greedy_rollout(self.model, env, world.max_steps_per_episode)


class DQN(SB3Learner):
    title = "Stable-Baselines3 DQN (HER on goal tasks)"
    algorithm_path = "stable_baselines3:DQN"
    off_policy = True
    defaults = DQN_DEFAULTS
    implementation = "dqn"

    def expand_hyperparams(self, hp: dict[str, Any]) -> dict[str, Any]:
        hp = super().expand_hyperparams(hp)
        if check_implementation("dqn", {k: hp[k] for k in DQN_IMPLEMENTATION if k in hp})[
            "train_freq_as_envs"
        ]:
            hp = train_freq_as_envs(hp)
        return hp

    def after_model(self, impl: dict[str, Any], model: Any) -> None:
        impl = check_implementation("dqn", impl)
        if impl["init"] == "lecun":
            lecun_init(model.policy.q_net)
            model.policy.q_net_target.load_state_dict(model.policy.q_net.state_dict())
        if impl["loss"] == "squared":
            squared_error_updates(model)


class QRDQN(SB3Learner):
    title = "sb3-contrib QR-DQN (HER on goal tasks)"
    algorithm_path = "sb3_contrib:QRDQN"
    off_policy = True
    # DQN's values, and 50 quantiles (sb3-contrib's 200 make the pairwise quantile loss,
    # batch x 200 x 200, cost most of a run's CPU time).
    defaults = QRDQN_DEFAULTS


class PPO(SB3Learner):
    title = "Stable-Baselines3 PPO"
    algorithm_path = "stable_baselines3:PPO"
    defaults = PPO_DEFAULTS
    implementation = "ppo"

    def before_model(
        self, impl: dict[str, Any], vec: Any, policy_kwargs: dict[str, Any]
    ) -> tuple[Any, dict[str, Any]]:
        vec, policy_kwargs = super().before_model(impl, vec, policy_kwargs)
        if check_implementation("ppo", impl)["init"] != "orthogonal":
            policy_kwargs = {**policy_kwargs, "ortho_init": False}  # lecun: re-initialised below
        return vec, policy_kwargs

    def after_model(self, impl: dict[str, Any], model: Any) -> None:
        impl = check_implementation("ppo", impl)
        if impl["init"] == "lecun":
            lecun_init(model.policy)
        if impl["grad_clip"] == "per_network":
            per_network_clipping(model)


class A2C(SB3Learner):
    title = "Stable-Baselines3 A2C"
    algorithm_path = "stable_baselines3:A2C"
    defaults = A2C_DEFAULTS
