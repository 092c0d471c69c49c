"""SB3 VecEnvs on SixAxisAvoid-v0: env steps/s and PPO training time (CleanRL-style: flags,
fixed seeds, JSON out).

Compares ``sixaxis_avoid.sb3.SixAxisVecEnv`` (the native Rust batch) with SB3's own
``DummyVecEnv`` and ``SubprocVecEnv`` over single envs made by ``gym.make``:

1. env steps/s with random actions, for each ``--num-envs`` (SB3 semantics: immediate
   reset, info dicts per env);
2. PPO's total wall time for ``--ppo-steps`` timesteps with each VecEnv at ``--ppo-envs``
   envs (same hyperparameters and seed; the network update time is the same for all, so the
   difference is the env side).

Usage::

    python scripts/bench_sb3.py --num-envs 8 64 --out docs/figures/bench_sb3.json
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import gymnasium as gym
import numpy as np
import sixaxis_avoid
import stable_baselines3
from bench_env import emit_json, system_info  # scripts/ is on sys.path when this script runs
from sixaxis_avoid.sb3 import SixAxisVecEnv
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

KINDS = ("native", "dummy", "subproc")


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the envs, actions and PPO")
    p.add_argument("--num-envs", type=int, nargs="+", default=[8, 64], help="VecEnv sizes")
    p.add_argument("--steps", type=int, default=200_000, help="env steps per measurement")
    p.add_argument("--repeats", type=int, default=3, help="best of this many runs")
    p.add_argument("--ppo-envs", type=int, default=8, help="envs of the PPO runs")
    p.add_argument("--ppo-steps", type=int, default=50_000, help="PPO timesteps per run")
    p.add_argument("--max-episode-steps", type=int, default=200, help="step cap per episode")
    p.add_argument(
        "--torch-threads", type=int, default=1, help="torch threads of PPO (fixed for fair timing)"
    )
    p.add_argument("--out", default=None, help="write the JSON here too")
    p.add_argument("--quick", action="store_true", help="short runs (smoke test, noisy figures)")
    args = p.parse_args()
    if args.quick:
        args.steps = min(args.steps, 20_000)
        args.ppo_steps = min(args.ppo_steps, 4096)
        args.repeats = 1
    return args


ENV_KW = {"reward_scale": 1e-4}


def make_vec(kind: str, n: int, seed: int, max_episode_steps: int):
    kw = {**ENV_KW, "max_episode_steps": max_episode_steps}
    if kind == "native":
        return SixAxisVecEnv(n, seed=seed, **kw)

    def make():
        return gym.make(sixaxis_avoid.ENV_ID, **kw)

    venv = DummyVecEnv([make] * n) if kind == "dummy" else SubprocVecEnv([make] * n)
    venv.seed(seed)
    return venv


def steps_per_s(venv, steps: int, seed: int, repeats: int) -> float:
    n = venv.num_envs
    iters = max(1, steps // n)
    actions = np.random.default_rng(seed).integers(0, 6, size=(min(iters, 256), n))
    best = 0.0
    for _ in range(repeats):
        venv.reset()
        t = time.perf_counter()
        for i in range(iters):
            venv.step(actions[i % len(actions)])
        best = max(best, iters * n / (time.perf_counter() - t))
    return best


def ppo_seconds(kind: str, args: argparse.Namespace) -> dict:
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(args.torch_threads)

    venv = make_vec(kind, args.ppo_envs, args.seed, args.max_episode_steps)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=256,
        batch_size=256,
        ent_coef=0.01,
        seed=args.seed,
        device="cpu",
    )
    load = os.getloadavg()[0]
    t = time.perf_counter()
    model.learn(total_timesteps=args.ppo_steps)
    seconds = time.perf_counter() - t
    venv.close()
    return {
        "seconds": round(seconds, 2),
        "timesteps": int(model.num_timesteps),
        "load_average_at_start": round(load, 2),
    }


def main() -> None:
    args = parse_args()
    out: dict = {
        "config": vars(args),
        "system": system_info(stable_baselines3=stable_baselines3.__version__),
    }
    rows = []
    for n in args.num_envs:
        row: dict = {"num_envs": n}
        for kind in KINDS:
            venv = make_vec(kind, n, args.seed, args.max_episode_steps)
            # SubprocVecEnv pays a pipe round trip per step: fewer steps keep the run short.
            steps = args.steps if kind == "native" else max(n, args.steps // 10)
            row[f"{kind}_steps_per_s"] = round(steps_per_s(venv, steps, args.seed, args.repeats))
            venv.close()
        row["speedup_vs_dummy"] = round(row["native_steps_per_s"] / row["dummy_steps_per_s"], 1)
        row["speedup_vs_subproc"] = round(row["native_steps_per_s"] / row["subproc_steps_per_s"], 1)
        print(json.dumps(row), file=sys.stderr)
        rows.append(row)
    out["steps_per_s"] = rows
    ppo = {kind: ppo_seconds(kind, args) for kind in KINDS}
    print(json.dumps({"ppo": ppo}), file=sys.stderr)
    out["ppo"] = {"num_envs": args.ppo_envs, **ppo}
    out["system"]["load_average_at_end"] = os.getloadavg()[0]
    emit_json(out, args.out)


if __name__ == "__main__":
    main()
