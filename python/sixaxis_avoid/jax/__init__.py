"""The JAX twin of ``SixAxisAvoid-v0``: the same env, compiled by the Rust core into arrays
and stepped by look-ups in JAX, so that learners written in JAX (``jax.vmap`` over seeds,
``jax.lax.scan`` over steps, all under ``jax.jit``) train without leaving the device.

::

    import jax
    from sixaxis_avoid.jax import make

    env, params = make("paper_simple")          # or random_target=True: the goal task
    obs, state = env.reset(jax.random.key(0), params)
    obs, state, reward, done, info = env.step(jax.random.key(1), state, 5, params)

The interface is gymnax's (``reset``/``step`` with same-step autoreset, ``reset_env``/
``step_env`` without it, ``action_space(params)``, ``observation_space(params)``,
``params.max_steps_in_episode``). No equation is written here: ``make`` asks the core for
the env's tables (``sixaxis_avoid._core.env_tables``, layout in ``rust/core/src/tables.rs``
and docs/BENCHMARKS.md, "JAX twin"), and a step is a handful of indexed reads of them:
next state, collision flag, eq. 9's case, reward (eqs. 5, 9, 10, times ``reward_scale``, as
the Rust env computes them, rounded to float32), termination, observation rows. The parity
test (tests/test_jax_parity.py) steps it against the native vector env on every suite task.

Differences from the Gymnasium env, all of the interface: rewards are float32; autoreset
is gymnax's same-step one (the native vector env resets at the next step); truncation at
``max_episode_steps`` is ``info["truncated"]``, and ``done`` covers both; each reset draws
its target with the JAX key, not the Rust generator (``EnvParams.reset_target`` chooses one).

Needs the ``jax`` extra (``pip install "sixaxis-avoid[jax]"``; CPU is enough).
"""

from __future__ import annotations

from sixaxis_avoid.jax.env import Box, Discrete, EnvParams, EnvState, SixAxisAvoidJax, make

__all__ = ["Box", "Discrete", "EnvParams", "EnvState", "SixAxisAvoidJax", "make"]
