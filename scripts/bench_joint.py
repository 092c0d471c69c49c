"""Step rates of the joint-space env (docs/PERFORMANCE.md, "Joint-space env"), with the
anchors FetchReach-v4 (Gymnasium-Robotics, MuJoCo) and PandaReach-v3 (panda-gym, PyBullet)
when they are installed; and (``baseline``) SB3 SAC / TD3, optionally with HER on the goal
id, with success rates over seeds and the terminal's path length against Algorithm 2's plan
(docs/JOINT.md, "Baselines"). Short runs; every knob a flag; JSON out.

    taskset -c 0 python scripts/bench_joint.py --json bench_joint.json
    python scripts/bench_joint.py baseline --algo sac --timesteps 20000 --seeds 0,1 --json sac.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

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


def path_length_mm(points: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))


def baseline(argv: list[str]) -> int:
    """Train SB3 SAC / TD3 (``--her``: on SixAxisAvoidJointGoal-v0 with HerReplayBuffer) for
    each seed, then evaluate the deterministic policy: success rate, mean return, terminal
    path length (mm) of the successful episodes, and Algorithm 2's terminal path (mm)."""
    p = argparse.ArgumentParser(prog="bench_joint.py baseline", description=baseline.__doc__)
    p.add_argument("--algo", choices=("sac", "td3"), default="sac")
    p.add_argument("--her", action="store_true", help="HER on the goal-conditioned id")
    p.add_argument("--scenario", default="paper_simple")
    p.add_argument("--timesteps", type=int, default=20_000)
    p.add_argument("--seeds", default="0,1,2,3,4")
    p.add_argument("--max-episode-steps", type=int, default=200)
    p.add_argument("--eval-episodes", type=int, default=1)
    p.add_argument("--learning-rate", type=float, default=3e-4)
    p.add_argument("--batch-size", type=int, default=256)
    p.add_argument("--gamma", type=float, default=0.98)
    p.add_argument("--learning-starts", type=int, default=1000)
    p.add_argument("--net", default="256,256", help="hidden layer sizes")
    p.add_argument(
        "--n-envs",
        type=int,
        default=1,
        help="envs of the native SB3 VecEnv (sixaxis_avoid.sb3.SixAxisVecEnv) trained on; "
        "SB3 takes one vector step (n-envs env steps) per train-freq",
    )
    p.add_argument("--train-freq", type=int, default=1, help="vector steps between updates")
    p.add_argument("--gradient-steps", type=int, default=1, help="updates per train-freq")
    p.add_argument("--torch-threads", type=int, default=1)
    p.add_argument("--json", default=None)
    a = p.parse_args(argv)
    import torch
    from stable_baselines3 import SAC, TD3, HerReplayBuffer

    torch.set_num_threads(a.torch_threads)
    scenario = (
        sixaxis_avoid.generate_scenario(int(a.scenario.split(":")[1]))
        if a.scenario.startswith("generated:")
        else _core.Scenario(a.scenario)
    )
    env_id = sixaxis_avoid.JOINT_GOAL_ENV_ID if a.her else sixaxis_avoid.JOINT_ENV_ID
    plan = sixaxis_avoid.plan(scenario, seed=0)
    alg2_mm = (
        path_length_mm(np.array(plan.path, dtype=float) * scenario.cell_mm)
        if plan.success
        else None
    )
    algo = {"sac": SAC, "td3": TD3}[a.algo]
    runs = []
    for seed in [int(v) for v in a.seeds.split(",")]:
        env = gym.make(env_id, scenario=scenario, max_episode_steps=a.max_episode_steps)
        train_env: Any = env
        if a.n_envs > 1:
            from sixaxis_avoid.sb3 import SixAxisVecEnv

            train_env = SixAxisVecEnv(
                a.n_envs,
                seed=seed,
                env_id=env_id,
                scenario=scenario,
                max_episode_steps=a.max_episode_steps,
            )
        kwargs: dict = {
            "train_freq": a.train_freq,
            "gradient_steps": a.gradient_steps,
            "learning_rate": a.learning_rate,
            "batch_size": a.batch_size,
            "gamma": a.gamma,
            "learning_starts": a.learning_starts,
            "policy_kwargs": {"net_arch": [int(v) for v in a.net.split(",")]},
            "seed": seed,
            "verbose": 0,
            "device": "cpu",
        }
        if a.her:
            kwargs["replay_buffer_class"] = HerReplayBuffer
            kwargs["replay_buffer_kwargs"] = {"copy_info_dict": True}
        policy = "MultiInputPolicy" if a.her else "MlpPolicy"
        t0 = time.perf_counter()
        model = algo(policy, train_env, **kwargs).learn(a.timesteps)
        train_s = time.perf_counter() - t0
        successes, returns, lengths, final_mm, closest_mm = 0, [], [], [], []
        for k in range(a.eval_episodes):
            obs, _ = env.reset(seed=10_000 + k)
            u = env.unwrapped
            points, total, done = [u.terminal_mm], 0.0, False
            info: dict = {}
            closest = float(np.linalg.norm(u.terminal_mm - u.target_mm))
            while not done:
                action, _ = model.predict(obs, deterministic=True)
                obs, r, te, tr, info = env.step(action)
                total += float(r)
                points.append(u.terminal_mm)
                closest = min(closest, float(info["distance_to_target"]))
                done = te or tr
            returns.append(total)
            final_mm.append(float(info["distance_to_target"]))
            closest_mm.append(closest)
            if info.get("is_success"):
                successes += 1
                lengths.append(path_length_mm(np.array(points)))
        runs.append(
            {
                "seed": seed,
                "success_rate": successes / a.eval_episodes,
                "mean_return": float(np.mean(returns)),
                "terminal_path_mm": lengths,
                "final_distance_mm": final_mm,
                "closest_distance_mm": closest_mm,
                "train_seconds": train_s,
                "env_steps": int(model.num_timesteps),
                "updates": int(model._n_updates),
            }
        )
        print(json.dumps(runs[-1]), flush=True)
    rates = np.array([r["success_rate"] for r in runs])
    # The Wilson interval of the success rate over every evaluated episode of every seed
    # (the benchmark's one implementation).
    from sixaxis_avoid.benchmark.stats import wilson

    ci = wilson(round(rates.sum() * a.eval_episodes), len(rates) * a.eval_episodes)
    out = {
        "machine": _core.machine(),
        "args": vars(a),
        "env_id": env_id,
        "runs": runs,
        "success_rate": float(rates.mean()),
        "success_rate_95ci": [ci["lo"], ci["hi"]],
        "algorithm2_terminal_path_mm": alg2_mm,
    }
    text = json.dumps(out, indent=2)
    print(text)
    if a.json:
        _core.write_atomic(a.json, text + "\n")
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["baseline"]:
        return baseline(argv[1:])
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
