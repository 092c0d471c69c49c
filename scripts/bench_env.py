"""Throughput of SixAxisAvoid-v0 (CleanRL-style: flags, fixed seeds, JSON out).

Measures, in one run:

1. single env through ``gym.make`` (all default wrappers) vs Gymnasium's ``CliffWalking-v1``
   through ``gym.make``, same random actions, reset on episode end;
2. the native vector env (``gym.make_vec(..., vectorization_mode="vector_entry_point")``)
   vs ``gymnasium.vector.SyncVectorEnv`` over our env, for each ``--num-envs``.

Usage::

    python scripts/bench_env.py --single-steps 200000 --num-envs 16 256 1024 --out bench.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import gymnasium as gym
import numpy as np
import sixaxis_avoid


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--seed", type=int, default=1, help="seed of the actions and the envs")
    p.add_argument(
        "--single-steps", type=int, default=200_000, help="steps per single-env measurement"
    )
    p.add_argument("--num-envs", type=int, nargs="+", default=[16, 256, 1024], help="vector sizes")
    p.add_argument(
        "--vector-steps", type=int, default=20_000_000, help="env steps per native measurement"
    )
    p.add_argument(
        "--sync-steps", type=int, default=200_000, help="env steps per SyncVectorEnv measurement"
    )
    p.add_argument("--obs-type", default="vector", choices=["vector", "index"])
    p.add_argument("--repeats", type=int, default=3, help="best of this many runs per measurement")
    p.add_argument("--out", default=None, help="write the JSON here too")
    p.add_argument("--quick", action="store_true", help="short runs (smoke test, noisy figures)")
    args = p.parse_args()
    if args.quick:
        args.single_steps = min(args.single_steps, 20_000)
        args.vector_steps = min(args.vector_steps, 2_000_000)
        args.sync_steps = min(args.sync_steps, 20_000)
        args.repeats = 1
    return args


def bench_single(env_id: str, steps: int, seed: int, repeats: int, **kwargs) -> float:
    env = gym.make(env_id, **kwargs)
    actions = np.random.default_rng(seed).integers(0, env.action_space.n, size=steps).tolist()
    best = 0.0
    for _ in range(repeats):
        env.reset(seed=seed)
        step = env.step
        t = time.perf_counter()
        for a in actions:
            _, _, term, trunc, _ = step(a)
            if term or trunc:
                env.reset()
        best = max(best, steps / (time.perf_counter() - t))
    env.close()
    return best


def bench_vector(envs: gym.vector.VectorEnv, steps: int, seed: int, repeats: int) -> float:
    n = envs.num_envs
    iters = max(1, steps // n)
    actions = np.random.default_rng(seed).integers(0, 6, size=(min(iters, 256), n), dtype=np.int64)
    best = 0.0
    for _ in range(repeats):
        envs.reset(seed=seed)
        step = envs.step
        t = time.perf_counter()
        for i in range(iters):
            step(actions[i % len(actions)])
        best = max(best, iters * n / (time.perf_counter() - t))
    envs.close()
    return best


def main() -> None:
    args = parse_args()
    out: dict = {
        "config": vars(args),
        "system": system_info(gymnasium=gym.__version__),
    }
    ours = bench_single(
        "SixAxisAvoid-v0", args.single_steps, args.seed, args.repeats, obs_type=args.obs_type
    )
    cliff = bench_single("CliffWalking-v1", args.single_steps, args.seed, args.repeats)
    out["single"] = {
        "sixaxis_steps_per_s": round(ours),
        "cliffwalking_steps_per_s": round(cliff),
        "speedup_vs_cliffwalking": round(ours / cliff, 2),
    }
    print(json.dumps({"single": out["single"]}), file=sys.stderr)
    vec = []
    for n in args.num_envs:
        row = {"num_envs": n}
        for copy in (True, False):
            envs = gym.make_vec(
                "SixAxisAvoid-v0",
                num_envs=n,
                vectorization_mode="vector_entry_point",
                obs_type=args.obs_type,
                copy=copy,
            )
            key = "native_steps_per_s" if copy else "native_nocopy_steps_per_s"
            row[key] = round(bench_vector(envs, args.vector_steps, args.seed, args.repeats))
        sync = gym.make_vec(
            "SixAxisAvoid-v0", num_envs=n, vectorization_mode="sync", obs_type=args.obs_type
        )
        row["sync_steps_per_s"] = round(bench_vector(sync, args.sync_steps, args.seed, 1))
        row["speedup_vs_sync"] = round(row["native_steps_per_s"] / row["sync_steps_per_s"], 1)
        print(json.dumps(row), file=sys.stderr)
        vec.append(row)
    out["vector"] = vec
    emit_json(out, args.out)


def system_info(**versions: str) -> dict:
    """Machine (the core's description), Python, platform, CPUs, load average and package
    versions of a benchmark run."""
    return {
        "machine": sixaxis_avoid._core.machine(),
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "load_average_at_start": os.getloadavg()[0],
        "sixaxis_avoid": sixaxis_avoid.__version__,
        **versions,
    }


def emit_json(out: dict, path: str | None) -> None:
    """Print the results as JSON, and write them to ``path`` too when given."""
    text = json.dumps(out, indent=2)
    print(text)
    if path:
        with open(path, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
