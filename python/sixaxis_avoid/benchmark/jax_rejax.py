"""rejax 0.1.3's PPO and DQN adjusted to SB3's semantics (:func:`rejax_classes`), and the
JAX twin wrapped to count what the learners' records need (:func:`counting_env`): the layer
under :mod:`sixaxis_avoid.benchmark.jax_learners`, which re-exports both. What maps exactly
and what differs is in the "JAX learners" section of docs/PERFORMANCE.md.
"""

from __future__ import annotations

import functools
from typing import Any

from sixaxis_avoid._deps import require


def rejax_classes() -> dict[str, Any]:
    """:func:`_rejax_classes`, after checking that rejax imports (names the extra if not)."""
    require("rejax", "rejax learners (sixaxis_avoid.benchmark.jax_learners)")
    return _rejax_classes()


@functools.cache
def _rejax_classes() -> dict[str, Any]:
    """rejax's PPO and DQN with SB3's optimiser semantics and every knob that need not fix a
    shape as a traced field:

    - the learning rate is an optax schedule of traced values: constant, or linear to 0 over
      the budget, stepped once per training iteration as SB3 steps it once per rollout
      (``lr x (1 - lr_decay x done_fraction)``, the fraction of the budget after this
      iteration's env steps);
    - gradients are clipped by their global norm (SB3's ``max_grad_norm``; rejax 0.1.3 clips
      each element, ``optax.clip``); PPO's Adam has SB3's eps 1e-5;
    - DQN: any hidden layers (rejax 0.1.3 fixes 64x64), a traced exploration fraction,
      learning start and target-update interval (static fields in rejax); replay minibatches
      drawn as rejax draws them or, with ``replay_sample = "with_replacement"``, uniformly
      with replacement from the stored transitions as SB3 draws them (rejax's draw weighs
      the whole buffer, so its cost grows with ``buffer_size``, not with the batch).
    """
    rejax = require("rejax", "rejax learners (sixaxis_avoid.benchmark.jax_learners)")
    optax = require("optax", "rejax learners")
    jax = require("jax", "rejax learners")
    jnp = jax.numpy
    from flax import linen as nn
    from flax import struct
    from flax.training.train_state import TrainState
    from rejax.algos.algorithm import register_init
    from rejax.buffers import ReplayBuffer
    from rejax.networks import DiscreteQNetwork, EpsilonGreedyPolicy

    def schedule(algo: Any, updates_per_iteration: int, first_iteration: Any = 0) -> Any:
        """``count`` (updates so far) -> rate; ``first_iteration``: the iteration of the
        first update (DQN's first after ``learning_starts``)."""
        lr, decay = algo.learning_rate, algo.lr_decay
        iters = max(int(algo.lr_iterations), 1)

        def rate(count: Any) -> Any:
            it = first_iteration + count // updates_per_iteration
            return lr * (1.0 - decay * jnp.minimum((it + 1) / iters, 1.0))

        return rate

    class PPO(rejax.PPO):
        lr_decay: Any = struct.field(pytree_node=True, default=0.0)
        lr_iterations: int = struct.field(pytree_node=False, default=1)

        @register_init
        def initialize_network_params(self, rng: Any) -> dict[str, Any]:
            rng, rng_actor, rng_critic = jax.random.split(rng, 3)
            obs = jnp.empty([1, *self.env.observation_space(self.env_params).shape])
            actor_params = self.actor.init(rng_actor, obs, rng_actor)
            critic_params = self.critic.init(rng_critic, obs)
            tx = optax.chain(
                optax.clip_by_global_norm(self.max_grad_norm),
                optax.adam(
                    learning_rate=schedule(self, self.num_epochs * self.num_minibatches),
                    eps=1e-5,
                ),
            )
            return {
                "actor_ts": TrainState.create(apply_fn=(), params=actor_params, tx=tx),
                "critic_ts": TrainState.create(apply_fn=(), params=critic_params, tx=tx),
            }

    class UniformReplayBuffer(ReplayBuffer):
        """rejax's buffer drawing ``num`` stored transitions uniformly with replacement
        (SB3's ``ReplayBuffer.sample``): O(num), where rejax's draw without replacement
        builds weights over the whole buffer."""

        def sample(self, num: int, rng: Any) -> Any:
            idx = jax.random.randint(rng, (num,), 0, jnp.maximum(self.num_entries, 1))
            return jax.tree_util.tree_map(lambda arr: arr[idx], self.data)

    class DQN(rejax.DQN):
        replay_with_replacement: bool = struct.field(pytree_node=False, default=False)
        lr_decay: Any = struct.field(pytree_node=True, default=0.0)
        lr_iterations: int = struct.field(pytree_node=False, default=1)
        exploration_fraction: Any = struct.field(pytree_node=True, default=0.1)
        fill_buffer: Any = struct.field(pytree_node=True, default=1000)
        target_update_freq: Any = struct.field(pytree_node=True, default=500)

        @classmethod
        def create_agent(cls, config: dict[str, Any], env: Any, env_params: Any) -> Any:
            kw = dict(config.pop("agent_kwargs", {}))
            net = EpsilonGreedyPolicy(DiscreteQNetwork)(
                hidden_layer_sizes=tuple(kw.pop("hidden_layer_sizes", (64, 64))),
                activation=getattr(nn, kw.pop("activation", "relu")),
                action_dim=env.action_space(env_params).n,
            )
            return {"agent": net}

        @property
        def epsilon_schedule(self) -> Any:
            steps = jnp.maximum(self.exploration_fraction * self.total_timesteps, 1.0)

            def eps(step: Any) -> Any:
                f = jnp.clip(step / steps, 0.0, 1.0)
                return self.eps_start + (self.eps_end - self.eps_start) * f

            return eps

        @register_init
        def initialize_replay_buffer(self, rng: Any) -> dict[str, Any]:
            buffer = UniformReplayBuffer if self.replay_with_replacement else ReplayBuffer
            return {
                "replay_buffer": buffer.empty(self.buffer_size, self.obs_space, self.action_space)
            }

        @register_init
        def initialize_network_params(self, rng: Any) -> dict[str, Any]:
            obs = jnp.empty([1, *self.env.observation_space(self.env_params).shape])
            q_params = self.agent.init(rng, obs)
            tx = optax.chain(
                optax.clip_by_global_norm(self.max_grad_norm),
                # rejax updates from the first iteration whose env steps before it exceed
                # learning_starts; the schedule counts the iterations before it too.
                optax.adam(
                    learning_rate=schedule(
                        self, self.num_epochs, jnp.floor(self.fill_buffer / self.num_envs) + 1
                    )
                ),
            )
            q_ts = TrainState.create(apply_fn=(), params=q_params, tx=tx)
            return {"q_ts": q_ts, "q_target_params": q_params}

    return {"ppo": PPO, "dqn": DQN}


def counting_env(twin: Any, params: Any) -> Any:
    """The twin as a gymnax env whose state also counts, per env, its steps and episodes and
    the step and episode of its first reach of the target (gymnax's same-step autoreset,
    keeping the counters): the run's first success, read after training."""
    jax = require("jax", "rejax learners")
    jnp = jax.numpy
    from flax import struct

    from sixaxis_avoid.jax.gymnax_compat import GymnaxEnv

    class Counted(struct.PyTreeNode):
        inner: Any
        steps: Any
        episodes: Any
        first_step: Any
        first_episode: Any

    class CountingEnv(GymnaxEnv):
        def reset_env(self, key: Any, p: Any) -> Any:
            obs, s = self.twin.reset_env(key, p)
            z = jnp.asarray(0, jnp.int32)
            return obs, Counted(s, z, z, z - 1, z - 1)

        def step_env(self, key: Any, state: Any, action: Any, p: Any) -> Any:
            obs, s, r, d, info = self.twin.step_env(key, state.inner, action, p)
            return obs, state.replace(inner=s), r, d, info

        def step(self, key: Any, state: Any, action: Any, params: Any = None) -> Any:
            p = self._params if params is None else params
            k_step, k_reset = jax.random.split(key)
            obs, s, r, d, info = self.twin.step_env(k_step, state.inner, action, p)
            obs_re, s_re = self.twin.reset_env(k_reset, p)
            inner = jax.tree_util.tree_map(lambda a, b: jax.lax.select(d, a, b), s_re, s)
            steps = state.steps + 1
            new_first = jnp.logical_and(state.first_step < 0, info["terminated"])
            counted = Counted(
                inner,
                steps,
                state.episodes + d.astype(jnp.int32),
                jnp.where(new_first, steps, state.first_step),
                jnp.where(new_first, state.episodes, state.first_episode),
            )
            return jax.lax.select(d, obs_re, obs), counted, r, d, info

        def get_obs(self, state: Any, params: Any = None, key: Any = None) -> Any:
            return self.twin.get_obs(state.inner, params if params is not None else self._params)

    return CountingEnv(twin, params)
