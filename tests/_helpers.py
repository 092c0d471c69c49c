"""Helpers shared by test modules (not fixtures: those are in conftest.py). Importable as
``from _helpers import ...`` because pytest's default import mode puts tests/ on sys.path
(tests/ has no __init__.py)."""

from __future__ import annotations

import time
from typing import Callable


def wait_for(cond: Callable[[], object], timeout: float = 15.0) -> bool:
    """Whether ``cond()`` holds within ``timeout`` seconds (polled every 50 ms)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.05)
    return bool(cond())


def deep_run_env_steps(spec: dict) -> int:
    """The env steps an SB3 learner's run of ``spec`` uses: the most whole iterations that fit
    in its budget (``learners.whole_iterations``; docs/BENCHMARKS.md, "Statistics"). An
    iteration is a rollout of n_envs x n_steps (PPO, A2C; SB3's n_steps defaults 2048 and 5)
    or one step of the n_envs envs (DQN, QR-DQN)."""
    from sixaxis_avoid.benchmark.learners import whole_iterations

    hp = spec["hyperparams"]
    n_envs = int(hp.get("n_envs", 1))
    on_policy = {"ppo": 2048, "a2c": 5}
    grain = n_envs
    if spec["learner"] in on_policy:
        grain *= int(hp.get("n_steps", on_policy[spec["learner"]]))
    return whole_iterations(spec["budget"], grain)


def assert_same_trials(a: dict, b: dict) -> None:
    """Two jax_tune searches gave the same trials (values, final scores, curves) and best."""
    assert len(a["trials"]) == len(b["trials"])
    for x, y in zip(a["trials"], b["trials"]):
        assert (x["values"], x["final_score"], x["curves"]) == (
            y["values"], y["final_score"], y["curves"],
        )  # fmt: skip
    assert a["best_trial"] == b["best_trial"]
