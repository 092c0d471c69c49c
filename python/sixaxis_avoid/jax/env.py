"""The JAX twin's functional env: gymnax's interface over the core's env tables."""

from __future__ import annotations

from typing import Any, NamedTuple

from sixaxis_avoid._deps import require

jax = require("jax", "The JAX twin (sixaxis_avoid.jax)")
jnp = jax.numpy


class EnvParams(NamedTuple):
    """The tables of one task (``sixaxis_avoid._core.env_tables``) and the step cap; a
    pytree, so it may be a traced argument (and batched over tasks of equal shapes).

    ``reset_target`` = -1: each reset draws the target index uniformly (one target on a
    fixed-target task, so index 0); ``>= 0``: the next reset takes that index of
    ``target_cells`` (evaluation on chosen targets, and the parity test, which feeds the
    Rust env's draws)."""

    next_state: Any  # (S, 6) int32
    collided: Any  # (S, 6) bool
    next_memory: Any  # (6, 2) int32, by (action, collided)
    reward_case: Any  # (7, 6, 2) int32, by (memory, action, collided)
    rewards: Any  # (T, S, 4) float32, by (target, next state, case)
    terminates: Any  # (T, S, 4) bool
    obs_state: Any  # (S, 13) float32
    obs_target: Any  # (T, 13) float32
    obs_memory: Any  # (7, 13) float32
    cells: Any  # (S, 3) int32
    target_cells: Any  # (T, 3) int32
    start_state: Any  # () int32
    no_memory: Any  # () int32
    max_steps_in_episode: Any  # () int32
    reset_target: Any  # () int32


class EnvState(NamedTuple):
    """One episode: the terminal's state number, eq. 9's memory (the last step's action if
    it collided, else ``no_memory``), the target index and the steps taken."""

    state: Any
    memory: Any
    target: Any
    time: Any


class Discrete(NamedTuple):
    """gymnax's ``Discrete`` space, without gymnax: ``n`` actions ``0..n``."""

    n: int
    shape: tuple[int, ...] = ()
    dtype: Any = None

    def sample(self, key: Any) -> Any:
        return jax.random.randint(key, self.shape, 0, self.n)

    def contains(self, x: Any) -> Any:
        return jnp.logical_and(x >= 0, x < self.n)


class Box(NamedTuple):
    """gymnax's ``Box`` space, without gymnax."""

    low: float
    high: float
    shape: tuple[int, ...]
    dtype: Any = None

    def sample(self, key: Any) -> Any:
        return jax.random.uniform(key, self.shape, minval=self.low, maxval=self.high)

    def contains(self, x: Any) -> Any:
        return jnp.logical_and(jnp.all(x >= self.low), jnp.all(x <= self.high))


def params_of(tables: dict[str, Any]) -> EnvParams:
    """The :class:`EnvParams` of ``_core.env_tables``' arrays (indices as int32)."""
    i32 = jnp.int32
    return EnvParams(
        next_state=jnp.asarray(tables["next_state"], i32),
        collided=jnp.asarray(tables["collided"], bool),
        next_memory=jnp.asarray(tables["next_memory"], i32),
        reward_case=jnp.asarray(tables["reward_case"], i32),
        rewards=jnp.asarray(tables["rewards"], jnp.float32),
        terminates=jnp.asarray(tables["terminates"], bool),
        obs_state=jnp.asarray(tables["obs_state"], jnp.float32),
        obs_target=jnp.asarray(tables["obs_target"], jnp.float32),
        obs_memory=jnp.asarray(tables["obs_memory"], jnp.float32),
        cells=jnp.asarray(tables["cells"], i32),
        target_cells=jnp.asarray(tables["target_cells"], i32),
        start_state=jnp.asarray(tables["start_state"], i32),
        no_memory=jnp.asarray(tables["no_memory"], i32),
        max_steps_in_episode=jnp.asarray(tables["max_episode_steps"], i32),
        reset_target=jnp.asarray(-1, i32),
    )


class SixAxisAvoidJax:
    """``SixAxisAvoid-v0`` (vector observations) as a functional JAX env with gymnax's
    interface: ``reset(key, params) -> (obs, state)``, ``step(key, state, action, params)
    -> (obs, state, reward, done, info)`` with gymnax's same-step autoreset (when ``done``,
    the returned ``obs`` and ``state`` are those of a new episode), plus ``reset_env`` and
    ``step_env`` without it. Every value is a look-up in the core's tables (``params``);
    nothing is computed here but indices.

    ``done`` is ``terminated | truncated``; ``info`` holds ``terminated`` (the target was
    reached), ``truncated`` (the step cap ``max_steps_in_episode`` ended the episode),
    ``collided``, ``cell`` (the terminal's cell after the move, before any reset) and
    ``discount`` (0 when terminated, else 1, as gymnax's envs give it).

    Actions are integers in ``0..6`` (``0:+x 1:-x 2:+y 3:-y 4:+z 5:-z``). They are not
    checked: inside ``jax.jit`` nothing can raise, and JAX clamps an out-of-range index to
    the nearest valid one, so check actions before they reach a jitted step.
    """

    def __init__(self, num_targets: int, random_target: bool):
        self.num_targets = int(num_targets)
        self.random_target = bool(random_target)

    @property
    def name(self) -> str:
        return "SixAxisAvoidGoal-jax" if self.random_target else "SixAxisAvoid-jax"

    @property
    def num_actions(self) -> int:
        return 6

    def action_space(self, params: EnvParams | None = None) -> Discrete:
        return Discrete(6, (), jnp.int32)

    def observation_space(self, params: EnvParams | None = None) -> Box:
        return Box(-1.0, 1.0, (13,), jnp.float32)

    def get_obs(self, state: EnvState, params: EnvParams) -> Any:
        """The vector observation: the state's, the target's and the memory's rows, each
        zero outside its own part (so the sum is exact)."""
        return (
            params.obs_state[state.state]
            + params.obs_target[state.target]
            + params.obs_memory[state.memory]
        )

    def reset_env(self, key: Any, params: EnvParams) -> tuple[Any, EnvState]:
        drawn = jax.random.randint(key, (), 0, self.num_targets, dtype=jnp.int32)
        target = jnp.where(params.reset_target >= 0, params.reset_target, drawn)
        state = EnvState(
            state=params.start_state,
            memory=params.no_memory,
            target=target.astype(jnp.int32),
            time=jnp.asarray(0, jnp.int32),
        )
        return self.get_obs(state, params), state

    def step_env(
        self, key: Any, state: EnvState, action: Any, params: EnvParams
    ) -> tuple[Any, EnvState, Any, Any, dict[str, Any]]:
        a = jnp.asarray(action, jnp.int32)
        s = state.state
        collided = params.collided[s, a]
        c = collided.astype(jnp.int32)
        nxt = params.next_state[s, a]
        case = params.reward_case[state.memory, a, c]
        reward = params.rewards[state.target, nxt, case]
        terminated = params.terminates[state.target, nxt, case]
        time = state.time + 1
        truncated = jnp.logical_and(
            jnp.logical_not(terminated), time >= params.max_steps_in_episode
        )
        new = EnvState(state=nxt, memory=params.next_memory[a, c], target=state.target, time=time)
        info = {
            "terminated": terminated,
            "truncated": truncated,
            "collided": collided,
            "cell": params.cells[nxt],
            "discount": 1.0 - terminated.astype(jnp.float32),
        }
        done = jnp.logical_or(terminated, truncated)
        return self.get_obs(new, params), new, reward, done, info

    def reset(self, key: Any, params: EnvParams | None = None) -> tuple[Any, EnvState]:
        if params is None:
            raise TypeError("reset needs the task's params (sixaxis_avoid.jax.make)")
        return self.reset_env(key, params)

    def step(
        self, key: Any, state: EnvState, action: Any, params: EnvParams | None = None
    ) -> tuple[Any, EnvState, Any, Any, dict[str, Any]]:
        """``step_env``, then (as gymnax) a new episode where ``done``."""
        if params is None:
            raise TypeError("step needs the task's params (sixaxis_avoid.jax.make)")
        key, key_reset = jax.random.split(key)
        obs_st, state_st, reward, done, info = self.step_env(key, state, action, params)
        obs_re, state_re = self.reset_env(key_reset, params)
        state = jax.tree_util.tree_map(lambda x, y: jax.lax.select(done, x, y), state_re, state_st)
        obs = jax.lax.select(done, obs_re, obs_st)
        return obs, state, reward, done, info


def make(scenario: Any = None, **env_options: Any) -> tuple[SixAxisAvoidJax, EnvParams]:
    """The JAX twin of ``SixAxisAvoid-v0`` on ``scenario`` (a name, a path, a
    ``Scenario``; default ``paper_simple``) and its params: ``(env, params)``, as
    ``gymnax.make``. Keywords: the Gymnasium env's ``assist``, ``reward_scale``,
    ``random_target`` (the goal task), ``arm_aware`` and ``max_episode_steps``, checked by
    the core's env option table."""
    from sixaxis_avoid import _core

    tables = _core.env_tables(scenario, **env_options)
    env = SixAxisAvoidJax(tables["target_cells"].shape[0], bool(tables["random_target"]))
    return env, params_of(tables)
