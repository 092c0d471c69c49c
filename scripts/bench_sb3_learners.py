"""The benchmark's SB3 learners: training speed on the native VecEnv against DummyVecEnv.

Trains one learner of ``sixaxis_avoid.benchmark`` (``ppo``, ``dqn``, ``qrdqn``, ``a2c``)
with its defaults (``learners.PPO_DEFAULTS`` ...) on one task for ``--steps`` env steps,
once on the native ``SixAxisVecEnv`` (what the learners train on, ``RunContext.make_vec_env``)
and once on ``DummyVecEnv`` over ``RunContext.make_env`` envs (what they trained on before),
with the same seed and no greedy evaluations, so only training is timed. One torch thread,
as in a benchmark run. Prints env steps per second of wall time and of the process's CPU
time, and the CPU time spent in the VecEnv's steps and resets (``env_cpu_s``: the env
side, the step counting included), one JSON line per VecEnv (``--vec-env native dummy``
runs them in that order). Pin it to one core for a per-core figure::

    taskset -c 0 python scripts/bench_sb3_learners.py --learner ppo --steps 20000
"""

from __future__ import annotations

import argparse
import json
import os
import time
from typing import Any

from sixaxis_avoid.benchmark import load_suite, resolve
from sixaxis_avoid.benchmark.learners import RunContext
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnvWrapper


class TimedVecEnv(VecEnvWrapper):
    """Adds up the CPU time of the wrapped VecEnv's steps and resets (the env side, with
    the run context's counting, apart from the algorithm's networks)."""

    def __init__(self, venv: Any) -> None:
        super().__init__(venv)
        self.cpu_s = 0.0

    def reset(self):
        t = time.process_time()
        obs = self.venv.reset()
        self.cpu_s += time.process_time() - t
        return obs

    def step_wait(self):
        t = time.process_time()
        out = self.venv.step_wait()
        self.cpu_s += time.process_time() - t
        return out


class NativeContext(RunContext):
    """The learners' run context (native ``SixAxisVecEnv``), its VecEnv timed."""

    def make_vec_env(self, n_envs: int, **kwargs: Any) -> Any:
        self.timed = TimedVecEnv(super().make_vec_env(n_envs, **kwargs))
        return self.timed


class DummyContext(RunContext):
    """A run context whose SB3 VecEnv is ``DummyVecEnv`` over :meth:`make_env` envs, timed."""

    def make_vec_env(self, n_envs: int, **kwargs: Any) -> Any:
        venv = DummyVecEnv([lambda: self.make_env(**kwargs)] * int(n_envs))
        self.timed = TimedVecEnv(venv)
        return self.timed


def measure(learner: str, suite: str, task_id: str, steps: int, seed: int, kind: str) -> dict:
    task = load_suite(suite).task(task_id)
    model = resolve(learner)()
    cls = NativeContext if kind == "native" else DummyContext
    ctx = cls(task, seed, steps, model.hyperparams, [], model)
    wall, cpu = time.perf_counter(), time.process_time()
    model.learn(ctx)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return {
        "learner": learner,
        "task": task_id,
        "vec_env": type(ctx.timed.unwrapped).__name__,
        "env_steps": ctx.env_steps,
        "wall_s": round(wall, 2),
        "cpu_s": round(cpu, 2),
        "steps_per_wall_s": round(ctx.env_steps / wall),
        "steps_per_cpu_s": round(ctx.env_steps / cpu),
        "env_cpu_s": round(ctx.timed.cpu_s, 3),
        "env_steps_per_env_cpu_s": round(ctx.env_steps / ctx.timed.cpu_s),
        "load_average": round(os.getloadavg()[0], 2),
    }


def main() -> None:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--learner", default="ppo", help="ppo, dqn, qrdqn or a2c")
    p.add_argument("--suite", default="v2")
    p.add_argument("--task", default="paper_simple")
    p.add_argument("--steps", type=int, default=20_000, help="env steps of each training")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--vec-env", nargs="+", default=["dummy", "native"], choices=["dummy", "native"])
    args = p.parse_args()
    # Imports (SB3's algorithm module, torch's first use) outside the timed runs: they would
    # be charged to whichever VecEnv runs first.
    warm = resolve(args.learner)()
    measure_ctx = RunContext(load_suite(args.suite).task(args.task), args.seed, 0, {}, [], warm)
    warm.learn(measure_ctx)
    for kind in args.vec_env:
        print(json.dumps(measure(args.learner, args.suite, args.task, args.steps, args.seed, kind)))


if __name__ == "__main__":
    main()
