"""The built-in learners and their registry: the core's tabular Q-learners (the paper's and
the budgeted ones), the BFS optimum, and by name the Stable-Baselines3 learners
(:mod:`sixaxis_avoid.benchmark.sb3_learners`) and the JAX ones (:data:`PLUGINS`).

Entry points: :func:`resolve` (a learner class by name or ``module:Class``), :data:`BUILTIN`,
:class:`NativeQ` and its presets :class:`QAssisted`, :class:`QPlain`, :class:`QPaper`, and
:class:`BFS`. The interface a learner implements (:class:`Learner`, :class:`RunContext`) is
:mod:`sixaxis_avoid.benchmark.interface`, re-exported here, where it was first.
"""

from __future__ import annotations

import importlib
import time
from typing import Any, Callable, ClassVar

import numpy as np

from sixaxis_avoid.benchmark.errors import LearnerError
from sixaxis_avoid.benchmark.implementation import (
    DQN_IMPLEMENTATION,
    DQN_IMPLEMENTATIONS,
    IMPLEMENTATIONS,
    PPO_IMPLEMENTATION,
    PPO_IMPLEMENTATIONS,
    check_implementation,
    expand_implementation,
    lecun_init,
    per_network_clipping,
    squared_error_updates,
    train_freq_as_envs,
    truncation_as_termination,
)
from sixaxis_avoid.benchmark.interface import (
    Cell,
    Clock,
    CountingEnv,
    Learner,
    RetrainPerRound,
    RunContext,
    path_cells,
    round_world_blocked,
    same_world,
    spl,
    split_budget,
    whole_iterations,
)
from sixaxis_avoid.benchmark.sb3_learners import (
    A2C,
    A2C_DEFAULTS,
    DQN,
    DQN_DEFAULTS,
    ENV_DEFAULTS,
    ENV_KEYS,
    PPO,
    PPO_DEFAULTS,
    QRDQN,
    QRDQN_DEFAULTS,
    SB3Learner,
    greedy_rollout,
    linear_schedule,
)

__all__ = [  # names first defined here stay importable from here
    "A2C",
    "A2C_DEFAULTS",
    "DQN",
    "DQN_DEFAULTS",
    "DQN_IMPLEMENTATION",
    "DQN_IMPLEMENTATIONS",
    "ENV_DEFAULTS",
    "ENV_KEYS",
    "IMPLEMENTATIONS",
    "PPO",
    "PPO_DEFAULTS",
    "PPO_IMPLEMENTATION",
    "PPO_IMPLEMENTATIONS",
    "QRDQN",
    "QRDQN_DEFAULTS",
    "Cell",
    "Clock",
    "CountingEnv",
    "Learner",
    "LearnerError",
    "RetrainPerRound",
    "RunContext",
    "SB3Learner",
    "check_implementation",
    "expand_implementation",
    "greedy_rollout",
    "lecun_init",
    "linear_schedule",
    "path_cells",
    "per_network_clipping",
    "round_world_blocked",
    "same_world",
    "spl",
    "split_budget",
    "squared_error_updates",
    "train_freq_as_envs",
    "truncation_as_termination",
    "whole_iterations",
]


# ------------------------------------------------------------------------------------------
# Native tabular Q-learning (the paper's) and the BFS optimum


#: Hyperparameters of the tabular learner passed to ``sixaxis_avoid.train`` on a budget in
#: env steps (the tuned ones and the episode step cap).
NATIVE_KEYS = (
    "alpha",
    "gamma",
    "epsilon_start",
    "epsilon_decay_fraction",
    "max_steps_per_episode",
)


class NativeQ(Learner):
    """The core's tabular Q-learner (``sixaxis_avoid.train``), the paper's eqs. 5-8.

    On a budget in env steps (``epsilon_schedule="env_steps"`` in its hyperparameters, set by
    ``runner.budget_of`` for a suite with a budget axis) a run stops at ``max_env_steps`` = B
    with epsilon falling over ``epsilon_decay_fraction`` x B env steps; a goal task gives
    each evaluation target its own run of B / n_targets env steps, one after the other, so
    the total is B. The curve's greedy paths come from the core's checkpoints during that one
    run. Otherwise (suite v1) the paper's episode count, with the curve from episode
    prefixes."""

    family = "native"
    assist: ClassVar[bool] = True

    def learn(self, ctx: RunContext) -> None:
        if self.hyperparams.get("epsilon_schedule") == "env_steps":
            self._learn_env_steps(ctx)
            return
        cap = int(self.hyperparams.get("episodes") or ctx.world.learning["episodes"])
        step_cap = self.hyperparams.get("max_env_steps")
        targets = ctx.targets()
        runs = [
            _NativeRun(self._world(ctx, t), ctx.seed, self.assist, cap, step_cap) for t in targets
        ]
        self._paths = {t: r.full.path for t, r in zip(targets, runs)}
        self.converged_episode = runs[0].full.converged_episode
        self.episodes_run = runs[0].episodes
        # Goal tasks: one run per target, one after the other, cost summed.
        offsets = np.concatenate([[0], np.cumsum([int(r.cum[-1]) for r in runs])])
        first = next((i for i, r in enumerate(runs) if r.reached.any()), None)
        if first is not None:
            r = runs[first]
            e = int(np.argmax(r.reached))
            res, cpu = r.prefix(e + 1)
            ctx.first_success = {
                "env_steps": int(offsets[first] + r.cum[e]),
                "episode": sum(x.episodes for x in runs[:first]) + e,
                "wall_time_s": sum(x.full.wall_time_s for x in runs[:first]) + res.wall_time_s,
                "cpu_time_s": sum(x.cpu for x in runs[:first]) + cpu,
            }
        total = int(offsets[-1])
        # The suite's checkpoints are sized for the deep learners' budget; add as many on a
        # geometric grid up to this run's own length.
        own = np.geomspace(max(1, total // 100), total, max(len(ctx.checkpoints), 2))
        grid = sorted({*ctx.checkpoints, *own.round().astype(np.int64).tolist()})
        done_at: set[int] = set()
        for c in [*[c for c in grid if c < total], total]:
            i = min(int(np.searchsorted(offsets, c, side="right")) - 1, len(runs) - 1)
            r = runs[i]
            k = int(np.searchsorted(r.cum, c - offsets[i], side="right"))
            steps_at = int(offsets[i] + (r.cum[k - 1] if k else 0))
            if steps_at in done_at:
                continue
            done_at.add(steps_at)
            res, cpu = r.prefix(k) if k else (None, 0.0)
            paths = [x.full.path for x in runs[:i]] + [None if res is None else res.path]
            paths += [None] * (len(runs) - len(paths))
            ctx.checkpoint(
                steps_at,
                paths,
                wall_time_s=sum(x.full.wall_time_s for x in runs[:i])
                + (0.0 if res is None else res.wall_time_s),
                cpu_time_s=sum(x.cpu for x in runs[:i]) + cpu,
            )
        ctx.env_steps = total
        ctx.episodes = sum(r.episodes for r in runs)

    def _train_options(self) -> dict[str, Any]:
        hp = self.hyperparams
        return {k: hp[k] for k in NATIVE_KEYS if hp.get(k) is not None}

    def _learn_env_steps(self, ctx: RunContext) -> None:
        import sixaxis_avoid as sa

        budget = int(self.hyperparams.get("max_env_steps") or ctx.budget)
        targets = ctx.targets()
        shares = split_budget(budget, len(targets))
        if min(shares) < 1:
            raise LearnerError(f"budget {budget}: fewer env steps than targets ({len(targets)})")
        offsets = np.concatenate([[0], np.cumsum(shares)]).astype(np.int64)
        grid = sorted({int(c) for c in ctx.checkpoints if 0 < c <= budget} | {budget})
        opts = self._train_options()
        self._paths = {}
        self._per_target = {"max_env_steps": shares[0], "episodes": shares[0], **opts}
        # Per target run: its result, CPU seconds, and its checkpoints by global env step.
        done: list[tuple[Any, float]] = []
        points: list[tuple[int, int, dict[str, Any]]] = []  # (global step, run, checkpoint)
        for i, (t, share) in enumerate(zip(targets, shares)):
            local = [c - int(offsets[i]) for c in grid if offsets[i] < c <= offsets[i + 1]]
            c0 = time.process_time()
            r = sa.train(
                self._world(ctx, t),
                seed=ctx.seed,
                assist=self.assist,
                episodes=min(share, 2**32 - 1),
                max_env_steps=share,
                epsilon_schedule="env_steps",
                checkpoints=local,
                **opts,
            )
            cpu = time.process_time() - c0
            if r.total_steps != share:  # the episode cap is never the binding one
                raise RuntimeError(f"target {t}: {r.total_steps} env steps, budget {share}")
            self._paths[t] = r.path
            done.append((r, cpu))
            points += [(int(offsets[i]) + cp["env_steps"], i, cp) for cp in r.checkpoints]
        before_wall = np.concatenate([[0.0], np.cumsum([r.wall_time_s for r, _ in done])])
        before_cpu = np.concatenate([[0.0], np.cumsum([c for _, c in done])])
        for step, i, cp in points:
            paths: list[Any] = [done[j][0].path for j in range(i)] + [cp["path"]]
            paths += [None] * (len(targets) - len(paths))
            cpu = cp["cpu_time_s"] if cp["cpu_time_s"] is not None else cp["wall_time_s"]
            ctx.checkpoint(
                step,
                paths,
                wall_time_s=float(before_wall[i] + cp["wall_time_s"]),
                cpu_time_s=float(before_cpu[i] + cpu),
            )
        # First success: the end of the first episode that reached its target. Its time is
        # interpolated (linear in env steps) between the recorded points around it.
        for i, (r, _) in enumerate(done):
            reached = np.asarray(r.reached_per_episode, dtype=bool)
            if reached.any():
                e = int(np.argmax(reached))
                step = int(offsets[i] + np.sum(np.asarray(r.steps_per_episode)[: e + 1]))
                xs = [0] + [p["env_steps"] for p in ctx.points]
                ctx.first_success = {
                    "env_steps": step,
                    "episode": sum(len(x.steps_per_episode) for x, _ in done[:i]) + e,
                    "wall_time_s": float(
                        np.interp(step, xs, [0.0] + [p["wall_time_s"] for p in ctx.points])
                    ),
                    "cpu_time_s": float(
                        np.interp(step, xs, [0.0] + [p["cpu_time_s"] for p in ctx.points])
                    ),
                }
                break
        self.converged_episode = done[0][0].converged_episode
        self.episodes_run = len(done[0][0].steps_per_episode)
        ctx.env_steps = budget
        ctx.episodes = sum(len(r.steps_per_episode) for r, _ in done)

    @staticmethod
    def _world(ctx: RunContext, target: Cell) -> Any:
        return ctx.task.world(target) if ctx.world is ctx.task.scenario else ctx.world

    def greedy_path(self, world: Any) -> list[Cell] | None:
        return self._paths.get(tuple(world.target))

    def algorithm2_learner(self, ctx: RunContext) -> str:
        return "qlearning"

    def algorithm2_kwargs(self) -> dict[str, Any]:
        if self.hyperparams.get("epsilon_schedule") == "env_steps":
            # Every re-plan round learns on the run's budget (per target) and schedule.
            return {**self._per_target, "epsilon_schedule": "env_steps", "assist": self.assist}
        return {"episodes": self.episodes_run, "assist": self.assist}


class _NativeRun:
    """One ``sixaxis_avoid.train`` run and its episode prefixes. The epsilon schedule depends
    on the episode index only, so training for fewer episodes is the same run's prefix
    (checked): the greedy path after k episodes is that of a k-episode run."""

    def __init__(
        self, world: Any, seed: int, assist: bool, episodes: int, step_cap: int | None
    ) -> None:
        self.world, self.seed, self.assist = world, seed, assist
        self._prefixes: dict[int, tuple[Any, float]] = {}
        full, cpu = self._train(episodes)
        self.steps = np.asarray(full.steps_per_episode, dtype=np.int64)
        cum = np.cumsum(self.steps)
        if step_cap is not None and cum[-1] > int(step_cap):
            episodes = max(1, int(np.searchsorted(cum, int(step_cap), side="right")))
            full, cpu = self.prefix(episodes)
        self.episodes = episodes
        self.cum = cum[:episodes]
        self.reached = np.asarray(full.reached_per_episode, dtype=bool)[:episodes]
        self.full, self.cpu = full, cpu
        self._prefixes[episodes] = (full, cpu)

    def _train(self, episodes: int) -> tuple[Any, float]:
        import sixaxis_avoid as sa

        c0 = time.process_time()
        r = sa.train(self.world, seed=self.seed, assist=self.assist, episodes=episodes)
        return r, time.process_time() - c0

    def prefix(self, k: int) -> tuple[Any, float]:
        if k not in self._prefixes:
            r, cpu = self._train(k)
            if not np.array_equal(np.asarray(r.steps_per_episode), self.steps[:k]):
                raise RuntimeError(f"{k} episodes of sixaxis_avoid.train are not a prefix")
            self._prefixes[k] = (r, cpu)
        return self._prefixes[k]


class QAssisted(NativeQ):
    title = "tabular Q-learning, assisted (the paper's eqs. 5, 9, 10)"
    assist = True


class QPlain(NativeQ):
    title = "tabular Q-learning, plain (eq. 5 alone)"
    assist = False


class QPaper(NativeQ):
    """The paper's learner as published: assisted, 10,000 episodes, epsilon over episodes,
    whatever the suite's env-step budget (the reproduction row, outside the ranking)."""

    title = "tabular Q-learning, assisted, the paper's 10,000 episodes (reproduction row)"
    family = "paper"
    assist = True


class BFS(Learner):
    """The breadth-first shortest path: the optimum, no learning (0 env steps)."""

    family = "reference"
    title = "breadth-first shortest path (the optimum; no learning)"

    def learn(self, ctx: RunContext) -> None:
        ctx.checkpoint(0)

    def greedy_path(self, world: Any) -> list[Cell] | None:
        import sixaxis_avoid as sa

        return sa.shortest_path(world)

    def algorithm2_learner(self, ctx: RunContext) -> str:
        return "bfs"


BUILTIN: dict[str, type[Learner]] = {
    "q_assist": QAssisted,
    "q_plain": QPlain,
    "q_paper": QPaper,
    "bfs": BFS,
    "dqn": DQN,
    "qrdqn": QRDQN,
    "ppo": PPO,
    "a2c": A2C,
}


#: Learners found by name but not in BUILTIN (the default study and its tests run BUILTIN),
#: as ``module:Class`` paths resolved on use: the JAX learners (family "jax") live above this
#: module (they build on it) and import JAX only when they run.
PLUGINS: dict[str, str] = {
    "jax_ppo": "sixaxis_avoid.benchmark.jax_runs:JaxPPO",
    "jax_dqn": "sixaxis_avoid.benchmark.jax_runs:JaxDQN",
}


def resolve(name: str) -> type[Learner]:
    """A built-in learner by name, or a user's as ``module:Class``."""
    if name in BUILTIN:
        return BUILTIN[name]
    if name in PLUGINS:
        return resolve(PLUGINS[name])
    if ":" not in name:
        raise LearnerError(
            f"learner {name!r}: not built in ({', '.join(BUILTIN)}) and not module:Class"
        )
    module, _, cls = name.partition(":")
    try:
        obj = getattr(importlib.import_module(module), cls)
    except (ImportError, AttributeError) as e:
        raise LearnerError(
            f"learner {name!r}: cannot import {cls} from {module} ({e}); it must be importable "
            "on every Ray node (install it or put it on PYTHONPATH)"
        ) from e
    if not (isinstance(obj, type) and callable(getattr(obj, "learn", None))):
        raise LearnerError(f"learner {name!r}: {obj!r} is not a class with learn/greedy_path")
    for attr in ("learn", "greedy_path"):
        if not callable(getattr(obj, attr, None)):
            raise LearnerError(f"learner {name!r}: {cls} has no method {attr}()")
    return obj


def family_of(cls: type[Any]) -> str:
    return str(getattr(cls, "family", "deep"))


Factory = Callable[[dict[str, Any]], Learner]
