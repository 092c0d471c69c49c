"""Compare learners on the reach-through-clutter task: reliability, optimality and cost.

One readable file (CleanRL style): every knob is a flag, seeds are fixed, results go to JSON
beside the figures, every file is written atomically. Learners, per scenario and seed:

- ``q_assist``: the native tabular Q-learner with the paper's assisted strategies (eqs. 9, 10);
- ``q_plain``:  the same learner without them (eq. 5 rewards alone);
- ``dqn``:      Stable-Baselines3 DQN on ``SixAxisAvoid-v0`` (vector observation);
- ``bfs``:      the breadth-first shortest path, the optimal reference.

For each learned path the whole arm is checked: Algorithm 1 (``PosePlanner.plan_poses``) on
the first learned path, and Algorithm 2 (re-planning around points no safe pose reaches):
``sixaxis_avoid.plan`` (the core's loop) for every learner: ``learner="bfs"`` for the
breadth-first path, and a Python learner for DQN (which is retrained from scratch per
re-plan, capped by ``--dqn-max-replans``, 0 by default: DQN then gets Algorithm 1's verdict
only).

    python scripts/compare_learners.py                 # the full comparison (~10 min, 2 cores)
    python scripts/compare_learners.py --quick         # a few seconds, for CI

Outputs: ``--out-dir`` (default ``results/compare``): ``compare.json``, ``curves_*.png``,
``summary.png``; and ``--report`` (default ``docs/BENCHMARKS.md``; with ``--quick``,
``OUT_DIR/BENCHMARKS.md``).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import datetime as dt
import io
import json
import math
import multiprocessing as mp
import os
import platform
import re
import shlex
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LEARNERS = ("q_assist", "q_plain", "dqn", "bfs")
LEARNER_TITLES = {
    "q_assist": "Q-learning, assisted (eqs. 5, 9, 10)",
    "q_plain": "Q-learning, plain (eq. 5)",
    "dqn": "SB3 DQN",
    "bfs": "BFS shortest path (optimum)",
}
PAPER_SCENARIOS = "paper_simple,paper_complex,replan_clutter"

# DQN hyperparameters: rl-baselines3-zoo, hyperparams/dqn.yml, entry "MountainCar-v0"
# (marked "Tuned"; a sparse-reward, discrete-action goal-reaching task), commit
# ce95481b041fe5314c1b2f1a53940d169b9253fc. Everything not listed is a Stable-Baselines3 2.x
# default (tau=1.0, exploration_initial_eps=1.0, max_grad_norm=10, Adam). Our changes: the
# budget (--dqn-steps, the zoo trains 1.2e5 steps) and nothing else unless a flag says so.
DQN_SOURCE = (
    "rl-baselines3-zoo hyperparams/dqn.yml, MountainCar-v0 (tuned), commit ce95481b; "
    "other values: Stable-Baselines3 defaults"
)
DQN_DEFAULTS: dict[str, Any] = {
    "learning_rate": 4e-3,
    "batch_size": 128,
    "buffer_size": 10_000,
    "learning_starts": 1_000,
    "gamma": 0.98,
    "target_update_interval": 600,
    "train_freq": 16,
    "gradient_steps": 8,
    "exploration_fraction": 0.2,
    "exploration_final_eps": 0.07,
    "net_arch": [256, 256],
}

# Defaults of the full run and of --quick, for the flags left unset.
FULL = {
    "scenarios": PAPER_SCENARIOS + ",generated:0..9",
    "seeds": "5",
    "episodes": 10_000,
    "dqn_steps": 10_000,
    "dqn_eval_every": 500,
    "dqn_learning_starts": DQN_DEFAULTS["learning_starts"],
    "workers": 2,
}
QUICK = {
    "scenarios": "paper_simple,generated:0",
    "seeds": "2",
    "episodes": 2_000,
    "dqn_steps": 400,
    "dqn_eval_every": 100,
    "dqn_learning_starts": 100,
    "workers": 1,
}


# --------------------------------------------------------------------------------------
# Arguments


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawTextHelpFormatter
    )
    p.add_argument("--quick", action="store_true", help="tiny budget for CI (seconds)")
    p.add_argument(
        "--scenarios",
        help="comma list; generated:A..B expands (default: the paper's three + generated:0..9)",
    )
    p.add_argument("--seeds", help="a count N (seeds 0..N-1) or a comma list (default 5)")
    p.add_argument(
        "--learners",
        default=",".join(LEARNERS),
        help=f"comma list out of {', '.join(LEARNERS)} (default: all)",
    )
    p.add_argument(
        "--episodes", type=int, help="episodes of the Q-learners (default 10000, the paper's)"
    )
    p.add_argument(
        "--max-replans",
        type=int,
        default=None,
        help="re-plan cap of Algorithm 2 (default: the scenario's planning.max_replans)",
    )
    p.add_argument(
        "--timing-repeats",
        type=int,
        default=3,
        help="Q-learners: wall time to first success / convergence is the median of this many"
        " re-runs of the episode prefix",
    )
    g = p.add_argument_group("DQN (Stable-Baselines3)")
    g.add_argument("--dqn-steps", type=int, help="training budget in env steps (default 10000)")
    g.add_argument(
        "--dqn-eval-every",
        type=int,
        help="env steps between greedy-path evaluations (default 500)",
    )
    g.add_argument(
        "--reward-scale",
        type=float,
        default=1e-4,
        help="env reward_scale: the paper's rewards (1e4..2e5) become O(1) (default 1e-4)",
    )
    g.add_argument(
        "--dqn-assist",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="train DQN with the assisted rewards (eqs. 9, 10) on (default: on)",
    )
    g.add_argument(
        "--dqn-max-episode-steps",
        type=int,
        help="step cap of DQN's training episodes (default: the scenario's, 1000)",
    )
    g.add_argument("--dqn-learning-rate", type=float, default=DQN_DEFAULTS["learning_rate"])
    g.add_argument("--dqn-batch-size", type=int, default=DQN_DEFAULTS["batch_size"])
    g.add_argument("--dqn-buffer-size", type=int, default=DQN_DEFAULTS["buffer_size"])
    g.add_argument("--dqn-learning-starts", type=int, help="default 1000 (--quick: 100)")
    g.add_argument("--dqn-gamma", type=float, default=DQN_DEFAULTS["gamma"])
    g.add_argument(
        "--dqn-target-update-interval", type=int, default=DQN_DEFAULTS["target_update_interval"]
    )
    g.add_argument("--dqn-train-freq", type=int, default=DQN_DEFAULTS["train_freq"])
    g.add_argument("--dqn-gradient-steps", type=int, default=DQN_DEFAULTS["gradient_steps"])
    g.add_argument(
        "--dqn-exploration-fraction", type=float, default=DQN_DEFAULTS["exploration_fraction"]
    )
    g.add_argument(
        "--dqn-exploration-final-eps", type=float, default=DQN_DEFAULTS["exploration_final_eps"]
    )
    g.add_argument(
        "--dqn-net-arch",
        default=",".join(map(str, DQN_DEFAULTS["net_arch"])),
        help="hidden layer sizes, comma list (default 256,256)",
    )
    g.add_argument(
        "--dqn-max-replans",
        type=int,
        default=0,
        help="Algorithm 2 for DQN retrains it per re-plan: cap (default 0 = Algorithm 1 only)",
    )
    p.add_argument(
        "--workers",
        type=int,
        help="processes for the DQN runs (torch uses 1 thread each; default 2, --quick: 1)",
    )
    p.add_argument("--out-dir", type=Path, default=ROOT / "results" / "compare")
    p.add_argument(
        "--report",
        type=Path,
        help="Markdown report (default docs/BENCHMARKS.md; --quick: OUT_DIR/BENCHMARKS.md)",
    )
    p.add_argument("--no-report", action="store_true", help="write no Markdown report")
    p.add_argument(
        "--supplement",
        type=Path,
        action="append",
        default=[],
        help="compare.json of another run (e.g. a longer DQN budget) to add to the report as a"
        " supplementary section; repeatable",
    )
    args = p.parse_args(argv)
    defaults = QUICK if args.quick else FULL
    for key, value in defaults.items():
        if getattr(args, key) is None:
            setattr(args, key, value)
    if args.report is None:
        args.report = (
            args.out_dir / "BENCHMARKS.md" if args.quick else ROOT / "docs" / "BENCHMARKS.md"
        )
    args.scenario_names = expand_names(args.scenarios)
    args.seed_list = parse_seeds(args.seeds)
    args.learner_list = [x.strip() for x in args.learners.split(",") if x.strip()]
    bad = [x for x in args.learner_list if x not in LEARNERS]
    if bad or not args.learner_list:
        p.error(f"--learners: unknown {bad}; choose from {', '.join(LEARNERS)}")
    if args.dqn_max_episode_steps is not None and args.dqn_max_episode_steps < 1:
        p.error("--dqn-max-episode-steps must be >= 1")
    for name in ("episodes", "dqn_steps", "dqn_eval_every", "workers", "timing_repeats"):
        if getattr(args, name) < 1:
            p.error(f"--{name.replace('_', '-')} must be >= 1")
    if args.dqn_max_replans < 0 or (args.max_replans is not None and args.max_replans < 0):
        p.error("re-plan caps must be >= 0")
    if not (math.isfinite(args.reward_scale) and args.reward_scale > 0):
        p.error("--reward-scale must be a finite number > 0")
    return args


def expand_names(text: str) -> list[str]:
    """``a,generated:0..3`` -> ``[a, generated:0, ..., generated:3]`` (the core's rule)."""
    import sixaxis_avoid as sa

    try:
        out = sa._core.expand_names(text)
    except sa.InvalidArgumentError as e:
        raise SystemExit(f"--scenarios: {e}") from None
    if not out:
        raise SystemExit("--scenarios: empty list")
    return out


def parse_seeds(text: str) -> list[int]:
    text = str(text).strip()
    seeds = list(range(int(text))) if "," not in text else [int(s) for s in text.split(",")]
    if not seeds or any(s < 0 for s in seeds):
        raise SystemExit(f"--seeds: {text!r}: need at least one seed, all >= 0")
    return seeds


# The keys of dqn_hyperparameters() that go to DQN(...) as they are.
DQN_CONSTRUCTOR_KEYS = (
    "learning_rate",
    "batch_size",
    "buffer_size",
    "learning_starts",
    "gamma",
    "target_update_interval",
    "train_freq",
    "gradient_steps",
    "exploration_fraction",
    "exploration_final_eps",
    "tau",
    "exploration_initial_eps",
    "max_grad_norm",
)


def dqn_hyperparameters(args: argparse.Namespace) -> dict[str, Any]:
    return {
        "policy": "MlpPolicy",
        "learning_rate": args.dqn_learning_rate,
        "batch_size": args.dqn_batch_size,
        "buffer_size": args.dqn_buffer_size,
        "learning_starts": args.dqn_learning_starts,
        "gamma": args.dqn_gamma,
        "target_update_interval": args.dqn_target_update_interval,
        "train_freq": args.dqn_train_freq,
        "gradient_steps": args.dqn_gradient_steps,
        "exploration_fraction": args.dqn_exploration_fraction,
        "exploration_final_eps": args.dqn_exploration_final_eps,
        "net_arch": [int(x) for x in args.dqn_net_arch.split(",") if x.strip()],
        # Stable-Baselines3 defaults, spelled out:
        "tau": 1.0,
        "exploration_initial_eps": 1.0,
        "max_grad_norm": 10.0,
        "optimizer": "Adam",
        # Task settings:
        "total_timesteps": args.dqn_steps,
        "max_episode_steps": args.dqn_max_episode_steps or "the scenario's (1000)",
        "reward_scale": args.reward_scale,
        "assist": args.dqn_assist,
        "observation": "vector (13 floats)",
        "device": "cpu, 1 torch thread",
    }


# --------------------------------------------------------------------------------------
# Small helpers


def atomic_write_text(path: Path, text: str) -> None:
    """The core's atomic write (``io::write_atomic``), after making the directory."""
    from sixaxis_avoid import _core

    path.parent.mkdir(parents=True, exist_ok=True)
    _core.write_atomic(path, text)


def atomic_savefig(fig: Any, path: Path) -> None:
    buf = io.BytesIO()
    fig.savefig(buf, dpi=110, format=path.suffix.lstrip(".") or "png")
    path.parent.mkdir(parents=True, exist_ok=True)
    from sixaxis_avoid import _core

    _core.write_atomic(path, buf.getvalue())


def cells(path: Any) -> list[list[int]] | None:
    return None if path is None else [[int(v) for v in c] for c in path]


def moves(path: list | None) -> int | None:
    return None if path is None else len(path) - 1


def downsample_curve(x: np.ndarray, y: np.ndarray, points: int = 200) -> dict[str, list]:
    """Group consecutive episodes into at most ``points`` bins: x = env steps at the end of
    the bin, y = mean episode length in it."""
    n = len(x)
    if n == 0:
        return {"env_steps": [], "episode_length": []}
    edges = np.unique(np.linspace(0, n, min(points, n) + 1).astype(int))
    xs = [int(x[e - 1]) for e in edges[1:]]
    ys = [float(np.mean(y[a:b])) for a, b in zip(edges[:-1], edges[1:])]
    return {"env_steps": xs, "episode_length": ys}


# --------------------------------------------------------------------------------------
# Native Q-learners and the BFS optimum


def run_native(name: str, seed: int, assist: bool, args: argparse.Namespace) -> dict[str, Any]:
    import sixaxis_avoid as sa

    scenario = sa.Scenario(name)
    r = sa.train(scenario, seed=seed, assist=assist, episodes=args.episodes)
    steps = np.asarray(r.steps_per_episode, dtype=np.int64)
    reached = np.asarray(r.reached_per_episode, dtype=bool)
    cum = np.cumsum(steps)

    def prefix_time(episodes: int) -> float:
        """Wall time of the first ``episodes`` episodes: the learner is re-run for exactly
        that many (epsilon depends on the episode index and M only, so the prefix is the
        same run; checked)."""
        times = []
        for _ in range(args.timing_repeats):
            p = sa.train(scenario, seed=seed, assist=assist, episodes=episodes)
            if not np.array_equal(np.asarray(p.steps_per_episode), steps[:episodes]):
                raise RuntimeError(f"{name} seed {seed}: an episode prefix is not the same run")
            times.append(p.wall_time_s)
        return statistics.median(times)

    first = int(np.argmax(reached)) if reached.any() else None
    conv = r.converged_episode
    path = r.path
    planner = sa.PosePlanner(scenario)
    alg1 = planner.plan_poses(path) if path is not None else None
    plan = sa.plan(
        scenario, seed=seed, episodes=args.episodes, assist=assist, max_replans=args.max_replans
    )
    return {
        "success": path is not None,
        "path": cells(path),
        "path_length": moves(path),
        "greedy_collisions": 0,
        "episodes": int(r.episodes),
        "total_steps": int(r.total_steps),
        "wall_time_s": float(r.wall_time_s),
        "first_success": None
        if first is None
        else {
            "episode": first,
            "env_steps": int(cum[first]),
            "wall_time_s": prefix_time(first + 1),
        },
        "convergence": None
        if conv is None
        else {
            "episode": int(conv),
            "env_steps": int(cum[conv]),
            "wall_time_s": prefix_time(int(conv) + 1),
        },
        "algorithm1": algorithm1_json(alg1),
        "algorithm2": {
            "how": "sixaxis_avoid.plan (core Algorithm 2; each round re-learns from scratch)",
            "success": plan.success,
            "replans": plan.replans,
            "added_obstacles": [list(c) for c in plan.added_obstacles],
            "failure": plan.failure,
            "wall_time_s": plan.wall_time_s,
            "learning_steps": int(sum(rd["total_steps"] for rd in plan.rounds)),
        },
        "curve": downsample_curve(cum, steps),
    }


def algorithm1_json(alg1: dict[str, Any] | None) -> dict[str, Any] | None:
    """Algorithm 1's verdict on a learner's first path, for the JSON (None: no path)."""
    if alg1 is None:
        return None
    blocked = alg1["blocked_cell"]
    return {
        "complete": bool(alg1["complete"]),
        "blocked_cell": None if blocked is None else list(blocked),
    }


def run_bfs(name: str, args: argparse.Namespace) -> dict[str, Any]:
    import sixaxis_avoid as sa

    scenario = sa.Scenario(name)
    t0 = time.perf_counter()
    path = sa.shortest_path(scenario)
    wall = time.perf_counter() - t0
    alg1 = sa.PosePlanner(scenario).plan_poses(path) if path is not None else None
    loop = sa.plan(scenario, learner="bfs", max_replans=args.max_replans)
    return {
        "success": path is not None,
        "path": cells(path),
        "path_length": moves(path),
        "greedy_collisions": 0,
        "episodes": 0,
        "total_steps": 0,
        "wall_time_s": wall,
        "first_success": {"episode": 0, "env_steps": 0, "wall_time_s": wall},
        "convergence": {"episode": 0, "env_steps": 0, "wall_time_s": wall},
        "algorithm1": algorithm1_json(alg1),
        "algorithm2": {
            "how": 'sixaxis_avoid.plan(learner="bfs") (core Algorithm 2)',
            "success": loop.success,
            "replans": loop.replans,
            "added_obstacles": [list(c) for c in loop.added_obstacles],
            "failure": loop.failure,
            "wall_time_s": loop.wall_time_s,
            "learning_steps": 0,
        },
        "curve": {"env_steps": [], "episode_length": []},
    }


def scenario_max_replans(scenario: Any, args: argparse.Namespace) -> int:
    if args.max_replans is not None:
        return args.max_replans
    return int(json.loads(scenario.to_json())["planning"]["max_replans"])


# --------------------------------------------------------------------------------------
# DQN (runs in worker processes)


def greedy_rollout(model: Any, env: Any, cap: int) -> tuple[list | None, int, int]:
    """The greedy policy's path from the start: (cells start..target or None, collisions,
    env steps). The policy is deterministic in the observation, which is a function of
    (cell, last step collided): a repeated pair is a loop, a failure."""
    obs, info = env.reset(seed=0)
    cell = tuple(info["cell"])
    path = [cell]
    seen = {(cell, False)}
    collisions = 0
    for t in range(cap):
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, _, info = env.step(int(action))
        cell, collided = tuple(info["cell"]), bool(info["collided"])
        if collided:
            collisions += 1
        else:
            path.append(cell)
        if terminated:
            return path, collisions, t + 1
        if (cell, collided) in seen:
            return None, collisions, t + 1
        seen.add((cell, collided))
    return None, collisions, cap


def train_dqn(scenario: Any, seed: int, args: argparse.Namespace, track: bool) -> dict[str, Any]:
    import sixaxis_avoid as sa
    import torch
    from stable_baselines3 import DQN
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.logger import Logger

    torch.set_num_threads(1)
    hp = dqn_hyperparameters(args)
    kwargs = {"reward_scale": args.reward_scale, "assist": args.dqn_assist}
    cap = scenario.max_steps_per_episode
    env = sa.make(scenario=scenario, max_episode_steps=args.dqn_max_episode_steps or cap, **kwargs)
    eval_env = sa.make(scenario=scenario, **kwargs)

    class Tracker(BaseCallback):
        def _on_training_start(self) -> None:
            self.t0 = time.perf_counter()
            self.paused = 0.0
            self.episodes: list[tuple[int, int]] = []  # (env steps at the end, length)
            self.ep_len = 0
            self.first: dict[str, Any] | None = None
            self.evals: list[dict[str, Any]] = []

        def train_time(self) -> float:
            return time.perf_counter() - self.t0 - self.paused

        def evaluate(self) -> None:
            t = time.perf_counter()
            path, coll, _ = greedy_rollout(self.model, eval_env, cap)
            self.paused += time.perf_counter() - t
            self.evals.append(
                {
                    "env_steps": int(self.num_timesteps),
                    "train_time_s": self.train_time(),
                    "episodes": len(self.episodes),
                    "success": path is not None,
                    "path_length": moves(path),
                    "collisions": coll,
                    "path": cells(path),
                }
            )

        def _on_step(self) -> bool:
            self.ep_len += 1
            info = self.locals["infos"][0]
            if info.get("is_success") and self.first is None:
                self.first = {
                    "episode": len(self.episodes),
                    "env_steps": int(self.num_timesteps),
                    "wall_time_s": self.train_time(),
                }
            if self.locals["dones"][0]:
                self.episodes.append((int(self.num_timesteps), self.ep_len))
                self.ep_len = 0
            if track and self.num_timesteps % args.dqn_eval_every == 0:
                self.evaluate()
            return True

    model = DQN(
        hp["policy"],
        env,
        **{k: hp[k] for k in DQN_CONSTRUCTOR_KEYS},
        policy_kwargs={"net_arch": hp["net_arch"]},
        seed=seed,
        device="cpu",
        verbose=0,
    )
    model.set_logger(Logger(None, []))  # no log files (SB3 would make a /tmp/SB3-* folder)
    tracker = Tracker()
    model.learn(total_timesteps=args.dqn_steps, callback=tracker)
    if not tracker.evals or tracker.evals[-1]["env_steps"] != tracker.num_timesteps:
        tracker.evaluate()
    wall = tracker.train_time()
    final = tracker.evals[-1]
    env.close()
    eval_env.close()
    return {"tracker": tracker, "final": final, "wall": wall, "steps": int(tracker.num_timesteps)}


def run_dqn(name: str, seed: int, args: argparse.Namespace) -> dict[str, Any]:
    import sixaxis_avoid as sa

    scenario = sa.Scenario(name)
    t_all = time.perf_counter()
    first = train_dqn(scenario, seed, args, track=True)
    tr, final = first["tracker"], first["final"]
    path = final["path"]
    # Convergence: the first evaluation from which the greedy path equals the final one
    # (resolution --dqn-eval-every steps); None if the final greedy path fails.
    conv = None
    if final["success"]:
        k = len(tr.evals) - 1
        while k > 0 and tr.evals[k - 1]["path"] == path:
            k -= 1
        e = tr.evals[k]
        conv = {
            "episode": e["episodes"],
            "env_steps": e["env_steps"],
            "wall_time_s": e["train_time_s"],
        }
    planner = sa.PosePlanner(scenario)
    alg1 = planner.plan_poses(path) if path is not None else None

    rounds_steps = [first["steps"]]

    def learn(world: Any, seed: int) -> list | None:
        """The core loop's path learner: round 0 reuses the first run, later rounds (the
        scenario plus the points added so far) retrain DQN from scratch."""
        if len(world.obstacles) == len(scenario.obstacles):
            return path
        again = train_dqn(world, seed, args, track=False)
        rounds_steps.append(again["steps"])
        return again["final"]["path"]

    cap = min(args.dqn_max_replans, scenario_max_replans(scenario, args))
    loop = sa.plan(scenario, seed=seed, learner=learn, max_replans=cap)
    ends = np.array([e[0] for e in tr.episodes], dtype=np.int64)
    lens = np.array([e[1] for e in tr.episodes], dtype=np.int64)
    return {
        "success": path is not None,
        "path": path,
        "path_length": moves(path),
        "greedy_collisions": final["collisions"],
        "episodes": len(tr.episodes),
        "total_steps": first["steps"],
        "wall_time_s": first["wall"],
        "first_success": tr.first,
        "convergence": conv,
        "algorithm1": algorithm1_json(alg1),
        "algorithm2": {
            "how": f"sixaxis_avoid.plan with DQN retrained from scratch per re-plan, cap {cap}",
            "success": loop.success,
            "replans": loop.replans,
            "added_obstacles": [list(c) for c in loop.added_obstacles],
            "failure": loop.failure,
            "wall_time_s": loop.wall_time_s,
            "learning_steps": int(sum(rounds_steps)),
        },
        "curve": downsample_curve(ends, lens),
        "eval_curve": [
            {k: e[k] for k in ("env_steps", "success", "path_length", "collisions")}
            for e in tr.evals
        ],
        "process_wall_time_s": time.perf_counter() - t_all,
    }


def dqn_task(name: str, seed: int, args: argparse.Namespace) -> tuple[str, int, dict[str, Any]]:
    return name, seed, run_dqn(name, seed, args)


# --------------------------------------------------------------------------------------
# Summaries


def median_or_none(values: list[float]) -> float | None:
    return float(statistics.median(values)) if values else None


def length_convergence(run: dict[str, Any]) -> dict[str, Any] | None:
    """DQN: the first greedy evaluation from which every later one succeeds with the final
    path length (the path itself may still swap between equally long ones); None if the
    final path fails or the run has no evaluations (the Q-learners)."""
    evals = run.get("eval_curve") or []
    if not evals or not evals[-1]["success"]:
        return None
    final = evals[-1]["path_length"]
    k = len(evals) - 1
    while k > 0 and evals[k - 1]["success"] and evals[k - 1]["path_length"] == final:
        k -= 1
    return {"env_steps": evals[k]["env_steps"], "path_length": final}


def summarise(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Aggregate over runs (seeds, and scenarios for the group rows)."""
    n = len(runs)
    stable = [s for s in map(length_convergence, runs) if s is not None]
    ok = [r for r in runs if r["success"]]
    ratios = [r["length_ratio"] for r in ok if r["length_ratio"] is not None]
    firsts = [r["first_success"] for r in runs if r["first_success"] is not None]
    convs = [r["convergence"] for r in runs if r["convergence"] is not None]
    alg1 = [r["algorithm1"]["complete"] for r in ok if r["algorithm1"] is not None]
    alg2 = [r["algorithm2"] for r in runs]
    return {
        "runs": n,
        "success_rate": len(ok) / n if n else None,
        "length_ratio_mean": float(np.mean(ratios)) if ratios else None,
        "length_ratio_max": float(np.max(ratios)) if ratios else None,
        "optimal_path_rate": sum(1 for x in ratios if x == 1.0) / n if n else None,
        "greedy_collisions_mean": float(np.mean([r["greedy_collisions"] for r in ok]))
        if ok
        else None,
        "first_success_rate": len(firsts) / n if n else None,
        "first_success_steps_median": median_or_none([f["env_steps"] for f in firsts]),
        "first_success_time_s_median": median_or_none([f["wall_time_s"] for f in firsts]),
        "convergence_rate": len(convs) / n if n else None,
        "convergence_steps_median": median_or_none([c["env_steps"] for c in convs]),
        "convergence_time_s_median": median_or_none([c["wall_time_s"] for c in convs]),
        "length_convergence_steps_median": median_or_none([s["env_steps"] for s in stable]),
        "total_steps_median": median_or_none([r["total_steps"] for r in runs]),
        "wall_time_s_median": median_or_none([r["wall_time_s"] for r in runs]),
        "algorithm1_pass_rate": sum(alg1) / n if n else None,
        "algorithm2_success_rate": sum(a["success"] for a in alg2) / n if n else None,
        "replans_mean": float(np.mean([a["replans"] for a in alg2])) if alg2 else None,
        "replans_max": int(max(a["replans"] for a in alg2)) if alg2 else None,
    }


def summaries(result: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Per learner: per scenario, the paper group, the generated group, and all runs."""
    out: dict[str, dict[str, Any]] = {}
    for learner in result["config"]["learners"]:
        mine = [r for r in result["runs"] if r["learner"] == learner]
        per = {n: summarise([r for r in mine if r["scenario"] == n]) for n in result["scenarios"]}
        paper = [r for r in mine if not r["scenario"].startswith("generated:")]
        gen = [r for r in mine if r["scenario"].startswith("generated:")]
        if paper:
            per["paper"] = summarise(paper)
        if gen:
            per["generated"] = summarise(gen)
        per["all"] = summarise(mine)
        out[learner] = per
    return out


# --------------------------------------------------------------------------------------
# Figures


def plot_curves(result: dict[str, Any], out_dir: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    colors = {"q_assist": "tab:blue", "q_plain": "tab:orange", "dqn": "tab:green"}
    by = {}
    for r in result["runs"]:
        by.setdefault((r["scenario"], r["learner"]), []).append(r)
    for name, info in result["scenarios"].items():
        fig, ax = plt.subplots(figsize=(7, 4.2))
        for learner in ("q_assist", "q_plain", "dqn"):
            runs = by.get((name, learner), [])
            curves = [r["curve"] for r in runs if r["curve"]["env_steps"]]
            if not curves:
                continue
            hi = max(c["env_steps"][-1] for c in curves)
            grid = np.unique(np.geomspace(1, max(hi, 2), 150).astype(int))
            ys = []
            for c in curves:
                x, y = np.asarray(c["env_steps"]), np.asarray(c["episode_length"])
                yi = np.interp(grid, x, y, left=np.nan, right=np.nan)
                yi[(grid < x[0])] = y[0]
                ys.append(yi)
            arr = np.vstack(ys)
            with np.errstate(all="ignore"):
                import warnings

                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", RuntimeWarning)
                    med = np.nanmedian(arr, axis=0)
                    lo, hi_ = np.nanmin(arr, axis=0), np.nanmax(arr, axis=0)
            ax.plot(grid, med, color=colors[learner], label=f"{LEARNER_TITLES[learner]} (median)")
            ax.fill_between(grid, lo, hi_, color=colors[learner], alpha=0.15, linewidth=0)
        ax.axhline(
            info["optimal_length"],
            color="black",
            linestyle="--",
            linewidth=1,
            label="optimum (BFS)",
        )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("environment steps (cumulative)")
        ax.set_ylabel("episode length (steps)")
        ax.set_title(
            f"{name}: learning curves over {len(result['config']['seeds'])} seeds (band: min-max)"
        )
        ax.legend(fontsize=8, loc="lower left")
        ax.grid(True, which="major", alpha=0.3)
        fig.tight_layout()
        path = out_dir / f"curves_{re.sub(r'[^A-Za-z0-9_]+', '_', name)}.png"
        atomic_savefig(fig, path)
        plt.close(fig)
        written.append(path.name)

    # Summary: success rate and env steps to convergence per learner, per scenario.
    names = list(result["scenarios"])
    learners = [x for x in result["config"]["learners"] if x != "bfs"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    width = 0.8 / max(len(learners), 1)
    for i, learner in enumerate(learners):
        s = result["summary"].get(learner, {})
        rates = [s.get(n, {}).get("success_rate") or 0.0 for n in names]
        conv = [s.get(n, {}).get("convergence_steps_median") or np.nan for n in names]
        xs = np.arange(len(names)) + (i - (len(learners) - 1) / 2) * width
        c = colors.get(learner, None)
        axes[0].bar(xs, rates, width, label=LEARNER_TITLES[learner], color=c)
        axes[1].bar(xs, conv, width, label=LEARNER_TITLES[learner], color=c)
    for ax in axes:
        ax.set_xticks(np.arange(len(names)))
        ax.set_xticklabels(names, rotation=60, ha="right", fontsize=8)
        ax.grid(True, axis="y", alpha=0.3)
    axes[0].set_ylabel("success rate (greedy path reaches the target)")
    axes[0].set_ylim(0, 1.05)
    axes[1].set_ylabel("env steps to convergence (median)")
    if any(
        (result["summary"].get(k, {}).get(n, {}).get("convergence_steps_median") or 0) > 0
        for k in learners
        for n in names
    ):
        axes[1].set_yscale("log")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    atomic_savefig(fig, out_dir / "summary.png")
    plt.close(fig)
    written.append("summary.png")
    return written


# --------------------------------------------------------------------------------------
# Report


def fmt(v: Any, spec: str = ".2f", none: str = "—") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return none
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


def fmt_steps(v: Any) -> str:
    if v is None:
        return "—"
    v = float(v)
    if v >= 1e6:
        return f"{v / 1e6:.2f}M"
    if v >= 1e4:
        return f"{v / 1e3:.0f}k"
    return f"{v:.0f}"


def fmt_time(v: Any) -> str:
    if v is None:
        return "—"
    v = float(v)
    if v < 1e-3:
        return f"{v * 1e6:.0f} µs"
    if v < 1:
        return f"{v * 1e3:.1f} ms"
    return f"{v:.1f} s"


COLUMNS = [
    "scenario",
    "learner",
    "success",
    "length / optimum (mean, max)",
    "env steps to 1st success",
    "time to 1st success",
    "env steps to convergence",
    "time to convergence",
    "DQN: env steps to a stable length",
    "arm: Alg. 1 passes",
    "arm: Alg. 2 success",
    "re-plans (mean, max)",
]


def table(result: dict[str, Any], groups: list[str]) -> list[str]:
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for g in groups:
        for learner in result["config"]["learners"]:
            s = result["summary"].get(learner, {}).get(g)
            if s is None:
                continue
            cells_ = [
                g,
                learner,
                fmt(s["success_rate"]),
                f"{fmt(s['length_ratio_mean'], '.3f')}, {fmt(s['length_ratio_max'], '.2f')}",
                fmt_steps(s["first_success_steps_median"]),
                fmt_time(s["first_success_time_s_median"]),
                fmt_steps(s["convergence_steps_median"]),
                fmt_time(s["convergence_time_s_median"]),
                fmt_steps(s.get("length_convergence_steps_median")),
                fmt(s["algorithm1_pass_rate"]),
                fmt(s["algorithm2_success_rate"]),
                f"{fmt(s['replans_mean'], '.1f')}, {fmt(s['replans_max'])}",
            ]
            lines.append("| " + " | ".join(cells_) + " |")
    return lines


def pct(v: float | None) -> str:
    return "—" if v is None else f"{v * 100:.0f}%"


def headline(result: dict[str, Any]) -> list[str]:
    out = []
    overall = {k: v.get("all") for k, v in result["summary"].items() if v.get("all")}
    learners = [x for x in result["config"]["learners"] if x != "bfs" and x in overall]
    if not learners:
        return out

    def rank(k: str) -> tuple[float, float]:
        s = overall[k]
        return (s["success_rate"] or 0.0, -(s["length_ratio_mean"] or math.inf))

    top = max(rank(k) for k in learners)
    best = " and ".join(f"**{k}**" for k in learners if rank(k) == top)
    if " and " in best:
        best += " (tied on success rate and mean length)"
    for k in learners:
        s = overall[k]
        first = (
            f"{fmt_steps(s['first_success_steps_median'])} env steps / "
            f"{fmt_time(s['first_success_time_s_median'])}"
        )
        conv = (
            f"{fmt_steps(s['convergence_steps_median'])} steps / "
            f"{fmt_time(s['convergence_time_s_median'])}"
        )
        out.append(
            f"- **{k}** ({LEARNER_TITLES[k]}): the greedy path reaches the target in "
            f"{pct(s['success_rate'])} of {s['runs']} runs; successful paths are "
            f"{fmt(s['length_ratio_mean'], '.3f')}x the optimum on average "
            f"({pct(s['optimal_path_rate'])} of all runs exactly optimal); median {first} to "
            f"the first success and {conv} to convergence; the whole arm follows the first "
            f"learned path (Algorithm 1) in {pct(s['algorithm1_pass_rate'])} of runs; "
            f"Algorithm 2 succeeds in {pct(s['algorithm2_success_rate'])} with "
            f"{fmt(s['replans_mean'], '.2f')} re-plans on average."
        )
    out.insert(0, f"Most reliable learner over all scenarios and seeds: {best}.\n")
    return out


def observations(result: dict[str, Any]) -> list[str]:
    """Facts read off the per-scenario summaries (no interpretation beyond counting)."""
    out = []
    summary, names = result["summary"], list(result["scenarios"])
    for learner in result["config"]["learners"]:
        if learner == "bfs":
            continue
        per = summary.get(learner, {})
        never = [n for n in names if per.get(n, {}).get("success_rate") == 0.0]
        always = [n for n in names if per.get(n, {}).get("success_rate") == 1.0]
        out.append(
            f"- {learner}: greedy path reaches the target on every seed in {len(always)} of "
            f"{len(names)} scenarios; on no seed in "
            + (f"{len(never)} ({', '.join(never)})" if never else "0")
            + "."
        )
    bfs = summary.get("bfs", {})
    for learner in ("q_assist", "q_plain"):
        per = summary.get(learner)
        if per is None or not bfs:
            continue
        worse = [
            n
            for n in names
            if per[n]["success_rate"] == 1.0
            and per[n]["algorithm2_success_rate"] < bfs[n]["algorithm2_success_rate"]
        ]
        better = [
            n
            for n in names
            if per[n]["algorithm2_success_rate"] > bfs[n]["algorithm2_success_rate"]
        ]
        if worse or better:
            out.append(
                f"- Algorithm 2 depends on the path it starts from: {learner} succeeds less often "
                f"than with the BFS path on {', '.join(worse) or 'none'}, more often on "
                f"{', '.join(better) or 'none'} (re-plans and failure reasons per run are in the "
                "JSON)."
            )
    blocked = [n for n in names if bfs and bfs[n]["algorithm1_pass_rate"] == 0.0]
    if blocked:
        learned_pass = [
            n
            for n in blocked
            if any(
                (summary[k].get(n, {}).get("algorithm1_pass_rate") or 0) > 0
                for k in summary
                if k != "bfs"
            )
        ]
        out.append(
            "- The whole arm cannot follow the BFS optimal path (Algorithm 1 blocks) on "
            f"{', '.join(blocked)}; on {', '.join(learned_pass) or 'none of them'} some learned "
            "path passes Algorithm 1 without a re-plan."
        )
    return out


def supplement_section(path: Path) -> list[str]:
    sup = json.loads(path.read_text())
    sup["summary"] = summaries(sup)  # with this version's definitions
    cfg, meta = sup["config"], sup["meta"]
    groups = ["all"] + [n for n in sup["scenarios"] if len(sup["scenarios"]) > 1]
    return [
        f"### {', '.join(cfg['learners'])} on {', '.join(sup['scenarios'])}, "
        f"{len(cfg['seeds'])} seeds, DQN budget {fmt_steps(cfg['dqn_steps'])} env steps",
        "",
        "```bash",
        meta["command"],
        "```",
        "",
        f"Run {meta['date']}, total wall time {meta['total_wall_time_s']:.0f} s; other settings "
        "as in the main run unless the command says otherwise.",
        "",
        *table(sup, groups),
        "",
    ]


def write_report(result: dict[str, Any], path: Path, supplements: list[Path] = ()) -> None:
    cfg = result["config"]
    hp = result["dqn_hyperparameters"]
    meta = result["meta"]
    paper = [n for n in result["scenarios"] if not n.startswith("generated:")]
    gen = [n for n in result["scenarios"] if n.startswith("generated:")]
    groups = ["all"] + (["paper"] if paper else []) + (["generated"] if gen else [])
    import sixaxis_avoid as sa

    rw, k = sa.Scenario("paper_simple").rewards, hp["reward_scale"]
    L = [
        "# Learner comparison",
        "",
        "Generated by `scripts/compare_learners.py` (do not edit by hand; re-run the command).",
        "",
        "```bash",
        meta["command"],
        "```",
        "",
        f"Run {meta['date']} on {meta['machine']}; versions: "
        + ", ".join(f"{k} {v}" for k, v in meta["versions"].items())
        + f". Total wall time {meta['total_wall_time_s']:.0f} s "
        f"({cfg['workers']} worker processes for DQN); the machine is shared: load average "
        f"(1, 5, 15 min) {meta['load_average_at_start']} at the start, "
        f"{meta['load_average_at_end']} at the end. Wall times are of this machine under "
        "that load.",
        "",
        f"Scenarios: {', '.join(result['scenarios'])}. Seeds: {', '.join(map(str, cfg['seeds']))} "
        f"(the learner's seed; DQN's SB3 seed). Q-learners: {cfg['episodes']} episodes "
        f"(scenario's alpha, gamma, epsilon schedule). "
        f"DQN: {fmt_steps(cfg['dqn_steps'])} env steps per run.",
        "",
        "## Headline",
        "",
        *headline(result),
        "",
        "## Observations",
        "",
        *observations(result),
        "",
        "## Summary (all runs of a group pooled)",
        "",
        *table(result, groups),
        "",
        "## Per scenario",
        "",
        *table(result, list(result["scenarios"])),
        "",
        "Optimal (BFS) path lengths: "
        + ", ".join(f"{n} {s['optimal_length']}" for n, s in result["scenarios"].items())
        + ".",
        "",
        *(
            ["## Supplementary runs", "", *[x for p in supplements for x in supplement_section(p)]]
            if supplements
            else []
        ),
        "## What the columns mean",
        "",
        "- **success**: fraction of seeds whose final greedy path reaches the target. Q-learners: "
        "the eq. 8 rollout (fails on any collision or revisit). DQN: the deterministic policy "
        "from the start, run until the target, a loop (a repeated (cell, collided) observation) "
        "or the step cap; bumps into obstacles (the terminal stays put) are allowed and counted "
        "(`greedy_collisions` in the JSON) but not moved; the path is the cells visited.",
        "- **length / optimum**: moves of the successful paths over the BFS optimum "
        "(1.0 = optimal).",
        "- **env steps / time to 1st success**: until the end of the first training episode that "
        "reached the target (median over the runs that had one). Q-learners: the time is the "
        "learner re-run for exactly that many episodes (median of "
        f"{cfg['timing_repeats']}; the epsilon schedule depends on the episode index only, so "
        "it is the same run, which the script checks). DQN: training time, evaluation excluded.",
        "- **convergence**: Q-learners: the core's `converged_episode` (first episode after which "
        "the greedy path never changed again). DQN: the first greedy evaluation (every "
        f"{cfg['dqn_eval_every']} env steps) from which the greedy path equals the final one. "
        "Runs whose final path fails have none (the median is over the others).",
        "- **DQN: env steps to a stable length**: the first greedy evaluation from which every "
        "later one reaches the target with the final path's length. DQN's greedy path often "
        "keeps swapping between equally long paths, which the strict definition above counts "
        "as not converged until the last evaluation. (The Q-learners' equivalent is not "
        "exposed to Python; — there.)",
        "- **arm: Alg. 1 passes**: fraction of runs whose first learned path gets a clear "
        "whole-arm pose at every point (`PosePlanner.plan_poses`, Algorithm 1, from beta_0).",
        "- **arm: Alg. 2 success / re-plans**: the paper's Algorithm 2 (a point no pose reaches "
        "becomes an obstacle, the path is learned again). Q-learners: `sixaxis_avoid.plan` with "
        "the same seed, episodes and assistance. BFS: the same loop with the BFS path as "
        "learner. DQN: the same loop retraining DQN from scratch per re-plan, capped at "
        f"{cfg['dqn_max_replans']} re-plans (so with 0, Alg. 2 success = Alg. 1 pass).",
        "",
        "## DQN hyperparameters",
        "",
        f"Source: {DQN_SOURCE}. The zoo trains MountainCar-v0 for 1.2e5 steps; the budget "
        f"here is {cfg['dqn_steps']} steps per run so that the whole comparison stays near "
        "10 minutes on 2 cores.",
        "",
        "| hyperparameter | value |",
        "|---|---|",
        *[f"| `{k}` | {v} |" for k, v in hp.items()],
        "",
        "Rewards: the env's (the paper's eq. 5, plus eqs. 9 and 10 when `assist` is on) times "
        f"`reward_scale` = {hp['reward_scale']}, with Table 1's values: reaching the target "
        f"+{rw['target_reward'] * k:g}, a step -{rw['step_penalty'] * k:g}, a collision "
        f"-{rw['collision_penalty'] * k:g}, a collision right after a collision a further "
        f"-{rw['repeat_collision_penalty'] * k:g}, the opposite action right after a collision "
        f"a further -{rw['reverse_after_collision_penalty'] * k:g}, distance assistance "
        f"+{rw['distance_reward'] * k:g} per cell closer than at the start, per step.",
        "",
        "DQN's learned path is its greedy policy's from the start (see *success* above); its "
        "training episodes end at the target or after the scenario's step cap (1000), as the "
        "env is registered.",
        "",
        "## Figures",
        "",
        "`results/compare/` (git-ignored) holds `compare.json` (every run, with curves), "
        "`summary.png` (success rate and steps to convergence per scenario) and "
        "`curves_<scenario>.png` (episode length against cumulative env steps, median and "
        "min-max band over seeds, BFS optimum dashed).",
        "",
    ]
    atomic_write_text(path, "\n".join(L))


# --------------------------------------------------------------------------------------
# Main


def machine() -> str:
    from sixaxis_avoid import _core

    return _core.machine()


def versions() -> dict[str, str]:
    import gymnasium
    import sixaxis_avoid

    out = {
        "python": platform.python_version(),
        "sixaxis_avoid": sixaxis_avoid.__version__,
        "gymnasium": gymnasium.__version__,
        "numpy": np.__version__,
    }
    try:
        import stable_baselines3
        import torch

        out["stable_baselines3"] = stable_baselines3.__version__
        out["torch"] = torch.__version__
    except ImportError:
        pass
    return out


def main(argv: list[str] | None = None) -> dict[str, Any]:
    os.environ.setdefault("MPLBACKEND", "Agg")
    args = parse_args(argv)
    import sixaxis_avoid as sa

    t_start = time.perf_counter()
    raw_argv = sys.argv[1:] if argv is None else list(argv)
    command = "python scripts/compare_learners.py" + (
        " " + " ".join(shlex.quote(a) for a in raw_argv) if raw_argv else ""
    )
    result: dict[str, Any] = {
        "meta": {
            "command": command,
            "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "machine": machine(),
            "versions": versions(),
            "load_average_at_start": [round(x, 2) for x in os.getloadavg()],
        },
        "config": {
            "scenarios": args.scenario_names,
            "seeds": args.seed_list,
            "learners": args.learner_list,
            "episodes": args.episodes,
            "max_replans": args.max_replans,
            "timing_repeats": args.timing_repeats,
            "dqn_steps": args.dqn_steps,
            "dqn_eval_every": args.dqn_eval_every,
            "dqn_max_replans": args.dqn_max_replans,
            "workers": args.workers,
            "quick": args.quick,
        },
        "dqn_hyperparameters": {**dqn_hyperparameters(args), "source": DQN_SOURCE},
        "scenarios": {},
        "runs": [],
    }
    for name in args.scenario_names:
        s = sa.Scenario(name)
        best = sa.shortest_path(s)
        if best is None:
            raise SystemExit(f"{name}: the target is not reachable at all")
        result["scenarios"][name] = {
            "start": list(s.start),
            "target": list(s.target),
            "obstacles": len(s.obstacles),
            "bounds": [list(b) for b in s.bounds],
            "optimal_length": len(best) - 1,
        }

    def add(learner: str, name: str, seed: int | None, run: dict[str, Any]) -> None:
        opt = result["scenarios"][name]["optimal_length"]
        run["length_ratio"] = None if run["path_length"] is None else run["path_length"] / opt
        result["runs"].append({"learner": learner, "scenario": name, "seed": seed, **run})

    # Native learners and BFS first, in this process, before the DQN workers load the cores.
    for name in args.scenario_names:
        for seed in args.seed_list:
            for learner, assist in (("q_assist", True), ("q_plain", False)):
                if learner in args.learner_list:
                    add(learner, name, seed, run_native(name, seed, assist, args))
        if "bfs" in args.learner_list:
            bfs = run_bfs(name, args)
            for seed in args.seed_list:  # deterministic: one run, reported once per seed
                add("bfs", name, seed, dict(bfs))
        print(f"[native] {name} done ({time.perf_counter() - t_start:.1f} s)", flush=True)

    if "dqn" in args.learner_list:
        tasks = [(n, s) for n in args.scenario_names for s in args.seed_list]
        done: dict[tuple[str, int], dict[str, Any]] = {}
        if args.workers == 1:
            for n, s in tasks:
                done[(n, s)] = run_dqn(n, s, args)
                print(f"[dqn] {n} seed {s}: success={done[(n, s)]['success']}", flush=True)
        else:
            ctx = mp.get_context("spawn")
            with cf.ProcessPoolExecutor(max_workers=args.workers, mp_context=ctx) as pool:
                futures = [pool.submit(dqn_task, n, s, args) for n, s in tasks]
                for f in cf.as_completed(futures):
                    n, s, run = f.result()
                    done[(n, s)] = run
                    print(
                        f"[dqn] {n} seed {s}: success={run['success']} "
                        f"({len(done)}/{len(tasks)}, {time.perf_counter() - t_start:.0f} s)",
                        flush=True,
                    )
        for n, s in tasks:
            add("dqn", n, s, done[(n, s)])

    result["summary"] = summaries(result)

    args.out_dir.mkdir(parents=True, exist_ok=True)
    result["figures"] = plot_curves(result, args.out_dir)
    result["meta"]["total_wall_time_s"] = time.perf_counter() - t_start
    result["meta"]["load_average_at_end"] = [round(x, 2) for x in os.getloadavg()]
    atomic_write_text(args.out_dir / "compare.json", json.dumps(result, indent=1) + "\n")
    if not args.no_report:
        write_report(result, args.report, args.supplement)
    print(
        f"wrote {args.out_dir / 'compare.json'}" + ("" if args.no_report else f" and {args.report}")
    )
    print(f"total wall time {result['meta']['total_wall_time_s']:.1f} s")
    return result


if __name__ == "__main__":
    main()
