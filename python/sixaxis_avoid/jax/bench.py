"""Env steps per second of the JAX twin against the native vector env, under a uniform
random policy::

    taskset -c 0 python -m sixaxis_avoid.jax.bench --num-envs 1024 --steps 2000

The JAX twin steps ``num_envs`` envs with ``jax.vmap`` inside one ``jax.lax.scan`` over
``steps`` under ``jax.jit`` (actions drawn by ``jax.random`` in the loop; compile time is
measured apart, on a first call). The native vector env (``SixAxisAvoidVectorEnv``,
``copy=False``) steps the same number of envs, one Rust call per step, with actions drawn
by NumPy ahead of the timing (as scripts/bench_env.py does). Prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import time
from functools import partial
from typing import Any

import numpy as np

from sixaxis_avoid.jax.env import jax, make


def jax_steps_per_s(scenario: str, num_envs: int, steps: int, repeats: int, **kw: Any) -> dict:
    env, params = make(scenario, **kw)

    @partial(jax.jit, static_argnums=(1,))
    def run(key, n):
        k0, k1 = jax.random.split(key)
        _, states = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(k0, n), params)

        def body(carry, k):
            st, total = carry
            ka, ks = jax.random.split(k)
            actions = jax.random.randint(ka, (n,), 0, 6)
            _, st, r, _, _ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
                jax.random.split(ks, n), st, actions, params
            )
            return (st, total + r.sum()), None

        (_, total), _ = jax.lax.scan(body, (states, 0.0), jax.random.split(k1, steps))
        return total

    t0 = time.perf_counter()
    run(jax.random.key(0), num_envs).block_until_ready()
    compile_s = time.perf_counter() - t0
    best = float("inf")
    for r in range(repeats):
        t0 = time.perf_counter()
        run(jax.random.key(r + 1), num_envs).block_until_ready()
        best = min(best, time.perf_counter() - t0)
    return {
        "steps_per_s": num_envs * steps / best,
        "seconds": best,
        "compile_and_first_run_s": compile_s,
    }


def native_steps_per_s(scenario: str, num_envs: int, steps: int, repeats: int, **kw: Any) -> dict:
    from sixaxis_avoid.vector import SixAxisAvoidVectorEnv

    env = SixAxisAvoidVectorEnv(num_envs=num_envs, scenario=scenario, copy=False, **kw)
    env.reset(seed=0)
    # As scripts/bench_env.py: actions drawn ahead, 256 rows cycled.
    actions = np.random.default_rng(0).integers(0, 6, size=(min(steps, 256), num_envs))
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for i in range(steps):
            env.step(actions[i % len(actions)])
        best = min(best, time.perf_counter() - t0)
    return {"steps_per_s": num_envs * steps / best, "seconds": best}


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenario", default="paper_simple")
    p.add_argument("--num-envs", type=int, default=1024)
    p.add_argument("--steps", type=int, default=2000, help="steps of each env per timed run")
    p.add_argument("--repeats", type=int, default=3, help="timed runs; the best is reported")
    p.add_argument("--random-target", action="store_true", help="the goal task")
    p.add_argument("--max-episode-steps", type=int, default=200)
    p.add_argument("--reward-scale", type=float, default=1e-4)
    a = p.parse_args(argv)
    kw = {
        "random_target": a.random_target,
        "max_episode_steps": a.max_episode_steps,
        "reward_scale": a.reward_scale,
    }
    out = {
        "scenario": a.scenario,
        "num_envs": a.num_envs,
        "steps": a.steps,
        **kw,
        "jax": jax_steps_per_s(a.scenario, a.num_envs, a.steps, a.repeats, **kw),
        "native": native_steps_per_s(a.scenario, a.num_envs, a.steps, a.repeats, **kw),
        "jax_version": jax.__version__,
        "jax_devices": [str(d) for d in jax.devices()],
    }
    out["ratio"] = out["jax"]["steps_per_s"] / out["native"]["steps_per_s"]
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
