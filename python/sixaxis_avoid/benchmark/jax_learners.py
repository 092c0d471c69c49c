"""rejax learners on the JAX twin (``sixaxis_avoid.jax``), ``jax.vmap``-ed over seeds::

    taskset -c 0 python -m sixaxis_avoid.benchmark.jax_learners --algo ppo --task paper_simple \\
        --seeds 8 --total-timesteps 100000 --out results/jax_ppo_paper_simple.json

One ``jax.jit`` call trains every seed at once (``jax.vmap(algo.train)``); compile time is
measured apart from training (``lower(...).compile()``). The greedy policy is scored on the
task's evaluation targets (``sixaxis_avoid.benchmark.tasks``) every ``--eval-freq`` env
steps, inside the jitted loop: it acts from the start until the episode ends (the target,
or the step cap, which a deterministic policy caught in a loop also reaches); ``success``
is reaching the target, ``spl`` is ``optimal / max(moves, optimal)`` on success (moves
exclude bumps), as ``sixaxis_avoid.benchmark.learners.spl``.

The defaults are suite v1's tuned SB3 values where rejax has the same knob (PPO: learning
rate, gamma, 128x128 net, 8 envs x 64 steps, 4 minibatches of 128, 5 epochs, GAE lambda,
entropy and clip coefficients, max_episode_steps 1000; the env's reward_scale 1e-4 and
assist as ``learners.ENV_DEFAULTS``; SB3's tanh activation and max_grad_norm 0.5). Every knob
is a flag; the JSON output records them all, with env steps/s, wall and compile times and
the evaluations. Needs the ``jax-learners`` extra. (rejax's DQN is not wired here yet: it
fixes its Q-network at 64x64 and updates its target by Polyak averaging, so SB3's tuned DQN
values do not map onto it one to one.)
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid._deps import require


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--algo", choices=("ppo",), default="ppo", help="rejax's PPO")
    p.add_argument("--suite", default="v1", help="suite whose task --task names")
    p.add_argument("--task", default="paper_simple")
    p.add_argument("--seeds", type=int, default=8, help="seeds 0..N-1, vmapped")
    p.add_argument("--seed-offset", type=int, default=0, help="first seed")
    p.add_argument("--total-timesteps", type=int, default=100_000, help="env steps per seed")
    p.add_argument("--eval-freq", type=int, default=10_240, help="env steps between evaluations")
    # Env (sixaxis_avoid.jax.make keywords).
    p.add_argument("--reward-scale", type=float, default=1e-4)
    p.add_argument("--assist", type=int, choices=(0, 1), default=1)
    p.add_argument("--max-episode-steps", type=int, default=1000)
    # Shared.
    p.add_argument("--learning-rate", type=float, default=0.0025083101485988907)
    p.add_argument("--gamma", type=float, default=0.9)
    p.add_argument("--max-grad-norm", type=float, default=0.5)
    p.add_argument("--hidden", default="128,128", help="hidden layer sizes")
    p.add_argument("--activation", default="tanh", help="a flax.linen activation name")
    p.add_argument("--num-envs", type=int, default=8)
    # PPO.
    p.add_argument("--num-steps", type=int, default=64)
    p.add_argument("--num-minibatches", type=int, default=4)
    p.add_argument("--num-epochs", type=int, default=5)
    p.add_argument("--gae-lambda", type=float, default=0.9)
    p.add_argument("--clip-eps", type=float, default=0.1)
    p.add_argument("--ent-coef", type=float, default=0.00011201827711749114)
    p.add_argument("--vf-coef", type=float, default=0.5)
    p.add_argument(
        "--sb3-steps",
        type=int,
        default=0,
        help="also train SB3 PPO with the same values for this many env steps (one seed, one "
        "torch thread, the native SixAxisVecEnv) and record its env steps/s",
    )
    p.add_argument("--out", type=Path, default=None, help="JSON file (also printed)")
    return p.parse_args(argv)


def algo_config(a: argparse.Namespace) -> dict[str, Any]:
    """rejax's keywords for PPO."""
    cfg: dict[str, Any] = {
        "total_timesteps": a.total_timesteps,
        "eval_freq": a.eval_freq,
        "learning_rate": a.learning_rate,
        "gamma": a.gamma,
        "max_grad_norm": a.max_grad_norm,
        "num_envs": a.num_envs,
        "agent_kwargs": {
            "hidden_layer_sizes": tuple(int(h) for h in a.hidden.split(",")),
            "activation": a.activation,
        },
    }
    cfg.update(
        num_steps=a.num_steps,
        num_minibatches=a.num_minibatches,
        num_epochs=a.num_epochs,
        gae_lambda=a.gae_lambda,
        clip_eps=a.clip_eps,
        ent_coef=a.ent_coef,
        vf_coef=a.vf_coef,
    )
    return cfg


def greedy_action_fn(algo: Any):
    """``act(ts, obs) -> action`` of PPO's greedy policy (the most likely action)."""
    jnp = require("jax.numpy", "rejax learners")

    def act(ts, obs):
        dist = algo.actor.apply(ts.actor_ts.params, obs[None], method="_action_dist")
        return jnp.argmax(dist.logits[0])

    return act


def make_eval(twin: Any, params: Any, targets: list[int], optimal: list[int]):
    """The eval callback: greedy success and SPL per evaluation target."""
    jax = require("jax", "rejax learners")
    jnp = jax.numpy
    targets_a = jnp.asarray(targets, jnp.int32)
    optimal_a = jnp.asarray(optimal, jnp.float32)
    cap = int(params.max_steps_in_episode)

    def callback(algo, ts, rng):
        act = greedy_action_fn(algo)

        def one(t):
            p = params._replace(reset_target=t)
            obs, st = twin.reset_env(rng, p)

            def body(c):
                obs, st, _, _, moves, n = c
                a = act(ts, obs)
                obs, st, _, d, info = twin.step_env(rng, st, a, p)
                moves = moves + jnp.logical_not(info["collided"]).astype(jnp.int32)
                return obs, st, d, info["terminated"], moves, n + 1

            init = (obs, st, jnp.bool_(False), jnp.bool_(False), jnp.int32(0), jnp.int32(0))
            c = jax.lax.while_loop(lambda c: jnp.logical_and(~c[2], c[5] < cap), body, init)
            return c[3], c[4]

        reached, moves = jax.vmap(one)(targets_a)
        spl = jnp.where(reached, optimal_a / jnp.maximum(moves, optimal_a), 0.0)
        return {"success": reached.astype(jnp.float32).mean(), "spl": spl.mean()}

    return callback


def run(a: argparse.Namespace) -> dict[str, Any]:
    jax = require("jax", "rejax learners")
    rejax = require("rejax", "rejax learners (sixaxis_avoid.benchmark.jax_learners)")
    from sixaxis_avoid.benchmark.tasks import load_suite
    from sixaxis_avoid.jax import make
    from sixaxis_avoid.jax.gymnax_compat import as_gymnax

    task = load_suite(a.suite).task(a.task)
    twin, params = make(
        task.scenario,
        reward_scale=a.reward_scale,
        assist=bool(a.assist),
        max_episode_steps=a.max_episode_steps,
        random_target=task.is_goal,
    )
    index = {tuple(int(v) for v in c): i for i, c in enumerate(np.asarray(params.target_cells))}
    targets = [index[tuple(t)] for t in task.eval_targets]
    cfg = algo_config(a)
    algo = rejax.PPO.create(env=as_gymnax(twin, params), env_params=params, **cfg)
    algo = algo.replace(eval_callback=make_eval(twin, params, targets, task.optimal_lengths))
    seeds = list(range(a.seed_offset, a.seed_offset + a.seeds))
    keys = jax.vmap(jax.random.PRNGKey)(jax.numpy.asarray(seeds))
    train = jax.jit(jax.vmap(algo.train))
    t0 = time.perf_counter()
    compiled = train.lower(keys).compile()
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    _, evaluation = compiled(keys)
    evaluation = jax.tree_util.tree_map(np.asarray, jax.block_until_ready(evaluation))
    wall = time.perf_counter() - t0
    success, spl = evaluation["success"], evaluation["spl"]  # (seeds, evaluations)
    n_evals = success.shape[1]
    env_steps = [min(i * a.eval_freq, a.total_timesteps) for i in range(n_evals)]
    steps_done = len(seeds) * a.total_timesteps
    return {
        "algo": a.algo,
        "rejax_version": importlib.metadata.version("rejax"),
        "jax_version": jax.__version__,
        "task": a.task,
        "suite": a.suite,
        "seeds": seeds,
        "flags": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(a).items()},
        "rejax_config": {k: v for k, v in cfg.items() if k != "agent_kwargs"}
        | {
            "agent_kwargs": {
                k: list(v) if isinstance(v, tuple) else v for k, v in cfg["agent_kwargs"].items()
            }
        },
        "compile_s": compile_s,
        "train_wall_s": wall,
        "env_steps_per_s": steps_done / wall,
        "eval_env_steps": env_steps,
        "success": success.tolist(),
        "spl": spl.tolist(),
        "final_success_mean": float(success[:, -1].mean()),
        "final_spl_mean": float(spl[:, -1].mean()),
        "seeds_reaching_target": int((success[:, -1] > 0).sum()),
        "seeds_reaching_target_any_eval": int((success.max(axis=1) > 0).sum()),
    }


def sb3_speed(a: argparse.Namespace) -> dict[str, Any]:
    """SB3 PPO with the same values (SB3's names), timed: env steps/s."""
    torch = require("torch", "the SB3 comparison")
    sb3 = require("stable_baselines3", "the SB3 comparison")
    from sixaxis_avoid.benchmark.tasks import load_suite
    from sixaxis_avoid.sb3 import SixAxisVecEnv

    task = load_suite(a.suite).task(a.task)
    torch.set_num_threads(1)
    kw = {"reward_scale": a.reward_scale, "assist": bool(a.assist)}
    if task.is_goal:
        kw["random_target"] = True
    venv = SixAxisVecEnv(
        a.num_envs, seed=a.seed_offset, scenario=task.scenario,
        max_episode_steps=a.max_episode_steps, **kw,
    )  # fmt: skip
    activation = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[a.activation]
    model = sb3.PPO(
        "MlpPolicy", venv, learning_rate=a.learning_rate, gamma=a.gamma, n_steps=a.num_steps,
        batch_size=a.num_envs * a.num_steps // a.num_minibatches, n_epochs=a.num_epochs,
        gae_lambda=a.gae_lambda, clip_range=a.clip_eps, ent_coef=a.ent_coef, vf_coef=a.vf_coef,
        max_grad_norm=a.max_grad_norm, seed=a.seed_offset, device="cpu", verbose=0,
        policy_kwargs={"net_arch": [int(h) for h in a.hidden.split(",")],
                       "activation_fn": activation},
    )  # fmt: skip
    t0 = time.perf_counter()
    model.learn(a.sb3_steps)
    wall = time.perf_counter() - t0
    return {"env_steps": a.sb3_steps, "wall_s": wall, "env_steps_per_s": a.sb3_steps / wall}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    a = parse_args(argv)
    out = run(a)
    if a.sb3_steps > 0:
        out["sb3_ppo"] = sb3_speed(a)
        out["speedup_vs_sb3"] = out["env_steps_per_s"] / out["sb3_ppo"]["env_steps_per_s"]
    text = json.dumps(out, indent=1)
    if a.out is not None:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(text + "\n")
    print(text)
    return out


if __name__ == "__main__":
    main()
