"""The README's PPO example ("PPO reaches the target in a few lines") over several seeds: how
often do its settings reach the target, and on the shortest path?

    python scripts/readme_ppo_seeds.py --seeds 0,1,2,3,4 --out docs/results/readme-ppo-seeds.json

Each seed runs the example exactly (``tests/test_readme_ppo.py``'s code, with ``seed=k`` for
the vector env and PPO, torch's default threads unless --torch-threads), one after the other, and
records whether the greedy rollout reached the target and in how many moves, with the
package versions.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import time
from pathlib import Path

from sixaxis_avoid.benchmark._io import atomic_write_text


def example(seed: int, steps: int) -> dict:
    """The README example with ``seed`` in place of 0."""
    import sixaxis_avoid
    from sixaxis_avoid.sb3 import SixAxisVecEnv
    from stable_baselines3 import PPO

    t0 = time.perf_counter()
    venv = SixAxisVecEnv(8, seed=seed, reward_scale=1e-4, max_episode_steps=200)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=256,
        ent_coef=0.01,
        learning_rate=lambda progress: 3e-4 * progress,  # linear decay to 0
        seed=seed,
        device="cpu",
    )
    model.learn(steps)
    env = sixaxis_avoid.make(reward_scale=1e-4, max_episode_steps=200)
    obs, info = env.reset(seed=0)
    done, moves = False, 0
    while not done:
        obs, _, terminated, truncated, info = env.step(model.predict(obs, deterministic=True)[0])
        done, moves = terminated or truncated, moves + 1
    return {
        "seed": seed,
        "target_reached": bool(info["is_success"]),
        "moves": moves,
        "train_wall_s": round(time.perf_counter() - t0, 1),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", default="0,1,2,3,4", help="comma list")
    p.add_argument("--steps", type=int, default=200_000, help="PPO's total_timesteps")
    p.add_argument(
        "--torch-threads", type=int, default=None, help="torch.set_num_threads (default: torch's)"
    )
    p.add_argument("--out", type=Path, required=True)
    a = p.parse_args(argv)
    if a.torch_threads is not None:
        import torch

        torch.set_num_threads(a.torch_threads)
    runs: list[dict] = []
    for s in (int(x) for x in a.seeds.split(",")):
        runs.append(example(s, a.steps))
        print(json.dumps(runs[-1]), flush=True)
        write(a, runs)  # after every seed: a stopped study keeps the seeds it finished
    out = write(a, runs)
    print(f"reached {out['reached']}/{len(runs)}, on the 9-move path {out['shortest']}")
    return 0


def write(a: argparse.Namespace, runs: list[dict]) -> dict:
    out = {
        "example": "README.md, 'PPO reaches the target in a few lines' (seed=k for venv and PPO)",
        "command": f"python scripts/readme_ppo_seeds.py --seeds {a.seeds} --steps {a.steps} "
        + ("" if a.torch_threads is None else f"--torch-threads {a.torch_threads} ")
        + f"--out {a.out}",
        "torch_threads": a.torch_threads,
        "steps": a.steps,
        "runs": runs,
        "reached": sum(r["target_reached"] for r in runs),
        "shortest": sum(r["target_reached"] and r["moves"] == 9 for r in runs),
        "versions": {
            k: importlib.metadata.version(k)
            for k in ("stable-baselines3", "torch", "gymnasium", "numpy")
        },
    }
    a.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(a.out, json.dumps(out, indent=1) + "\n")
    return out


if __name__ == "__main__":
    raise SystemExit(main())
