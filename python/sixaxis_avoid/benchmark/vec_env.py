"""The Stable-Baselines3 learners' training env: the native ``SixAxisVecEnv`` counting steps.

:meth:`RunContext.make_vec_env <sixaxis_avoid.benchmark.learners.RunContext.make_vec_env>`
builds ``CountingVecEnv(SixAxisVecEnv(...), ctx)``: all ``n_envs`` envs step in one Rust
call, and after each batched step this wrapper tells the run's context about every env's
step in env order (env 0 first), as ``DummyVecEnv`` over ``ctx.make_env()`` envs does one
env after the other. The counts, the first success and the checkpoints (the policy does not
change within a batched step) are therefore the same as on ``DummyVecEnv``, and so is the
training: ``SixAxisVecEnv`` is step for step the same as that ``DummyVecEnv`` seeded alike
(tests/test_sb3_vecenv.py; docs/BENCHMARKS.md, *Tasks*).

Needs the ``sb3`` extra.
"""

from __future__ import annotations

from typing import Any

from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper


class CountingVecEnv(VecEnvWrapper):
    """``venv`` (an SB3 ``VecEnv`` whose infos hold ``is_success``), calling
    ``ctx.on_step(reached, done)`` for each env of every step, env 0 first."""

    def __init__(self, venv: VecEnv, ctx: Any) -> None:
        super().__init__(venv)
        self._ctx = ctx

    def reset(self):
        return self.venv.reset()

    def step_wait(self):
        obs, rewards, dones, infos = self.venv.step_wait()
        for info, done in zip(infos, dones.tolist()):
            self._ctx.on_step(bool(info.get("is_success", False)), bool(done))
        return obs, rewards, dones, infos
