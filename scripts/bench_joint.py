"""Step rates of the joint-space env (docs/PERFORMANCE.md, "Joint-space env"), with the
anchors FetchReach-v4 (Gymnasium-Robotics, MuJoCo) and PandaReach-v3 (panda-gym, PyBullet)
when they are installed. Short runs; every knob a flag; JSON out.

    taskset -c 0 python scripts/bench_joint.py --json docs/results/bench_joint.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import gymnasium as gym
import numpy as np
import sixaxis_avoid
from sixaxis_avoid import _core


def rate_single(env_id: str, steps: int, seed: int, **kwargs) -> float:
    """``gym.make(env_id)`` steps per second with random actions (resets included)."""
    env = gym.make(env_id, **kwargs)
    env.reset(seed=seed)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(steps)]
    t0 = time.perf_counter()
    for a in actions:
        _, _, te, tr, _ = env.step(a)
        if te or tr:
            env.reset()
    return steps / (time.perf_counter() - t0)


def rate_vector(scenario, num_envs: int, steps: int, seed: int) -> float:
    """Native vector env steps per second (env steps, all lanes) with random actions."""
    venv = gym.make_vec(
        sixaxis_avoid.JOINT_ENV_ID, num_envs=num_envs, scenario=scenario, copy=False
    )
    venv.reset(seed=seed)
    rng = np.random.default_rng(seed)
    acts = rng.uniform(-1, 1, (8, num_envs, 6))
    venv.step(acts[0])
    t0 = time.perf_counter()
    for k in range(steps):
        venv.step(acts[k % 8])
    return steps * num_envs / (time.perf_counter() - t0)


def world_with_obstacles(count: int, seed: int) -> _core.Scenario:
    """paper_simple's arm and target with ``count`` random obstacle cells in x, y, z
    -8..8, none within 2 cells of beta_0's polyline (sampled every 10 mm) nor of the
    target, so that beta_0 stays clear."""
    s = _core.Scenario("paper_simple")
    arm = _core.Arm.from_scenario(s)
    pts = np.asarray(arm.points_mm(np.radians(s.beta0_deg)))
    line = np.concatenate(
        [
            a + (b - a) * t[:, None]
            for a, b in zip(pts[:-1], pts[1:])
            for t in [np.linspace(0, 1, 60)]
        ]
    )
    keep_out = np.vstack([line, np.array(s.target, dtype=float) * s.cell_mm])
    rng = np.random.default_rng(seed)
    cells: set[tuple[int, int, int]] = set()
    while len(cells) < count:
        c = tuple(int(v) for v in rng.integers(-8, 9, 3))
        if np.min(np.linalg.norm(keep_out - np.array(c) * s.cell_mm, axis=1)) > 2 * s.cell_mm:
            cells.add(c)
    return s.replace(obstacles=sorted(cells), bounds={"min": [-8, -8, -8], "max": [8, 8, 8]})


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--single-steps", type=int, default=20_000)
    p.add_argument("--num-envs", type=int, default=1024)
    p.add_argument("--vector-steps", type=int, default=30, help="batch steps of the vector env")
    p.add_argument(
        "--obstacles", default="0,19,50,100,200", help="obstacle counts of the cost sweep"
    )
    p.add_argument("--sweep-envs", type=int, default=256)
    p.add_argument("--sweep-steps", type=int, default=20)
    p.add_argument("--anchor-steps", type=int, default=5_000)
    p.add_argument("--no-anchors", action="store_true")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None, help="write the results here")
    a = p.parse_args(argv)

    out: dict = {"machine": _core.machine(), "args": vars(a)}
    out["joint_make_steps_per_s"] = rate_single(sixaxis_avoid.JOINT_ENV_ID, a.single_steps, a.seed)
    out["joint_vector_steps_per_s"] = rate_vector(
        "paper_simple", a.num_envs, a.vector_steps, a.seed
    )
    sweep = []
    for k in [int(v) for v in a.obstacles.split(",")]:
        s = world_with_obstacles(k, a.seed) if k != 19 else _core.Scenario("paper_simple")
        r = rate_vector(s, a.sweep_envs, a.sweep_steps, a.seed)
        sweep.append({"obstacles": k, "steps_per_s": r, "us_per_step": 1e6 / r})
    out["obstacle_sweep"] = sweep
    anchors = {}
    if not a.no_anchors:
        for name, module, env_id in (
            ("FetchReach-v4", "gymnasium_robotics", "FetchReach-v4"),
            ("PandaReach-v3", "panda_gym", "PandaReach-v3"),
        ):
            try:
                mod = __import__(module)
                if hasattr(gym, "register_envs"):
                    gym.register_envs(mod)
                anchors[name] = rate_single(env_id, a.anchor_steps, a.seed)
            except Exception as e:
                anchors[name] = f"not run: {type(e).__name__}: {e}"
    out["anchors_make_steps_per_s"] = anchors
    text = json.dumps(out, indent=2)
    print(text)
    if a.json:
        _core.write_atomic(a.json, text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
