"""The Learner interface and the built-in learners.

A learner trains on a task with a seed and an env-step budget, and gives its greedy path::

    from sixaxis_avoid.benchmark import Learner, RunContext

    class MyLearner(Learner):
        family = "deep"                      # re-plan cap and budget of the neural learners

        def learn(self, ctx: RunContext) -> None:
            env = ctx.make_env()             # a Gymnasium env that counts steps for the curve
            ...                              # train for ctx.budget env steps, seeded by ctx.seed

        def greedy_path(self, world) -> list[tuple[int, int, int]] | None:
            ...                              # the policy's path from world.start to world.target

and runs as ``python -m sixaxis_avoid.benchmark run --learners mypkg.mod:MyLearner``.

The harness scores the greedy path at checkpoints of env steps (the learning curve), with the
training time (wall and CPU, evaluation excluded) at each; ``ctx.make_env`` does it while the
learner trains. Learners that do not step a Python env (the native Q-learner, BFS) call
``ctx.checkpoint`` themselves.
"""

from __future__ import annotations

import abc
import importlib
import time
from typing import Any, Callable, ClassVar

import gymnasium as gym
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
    train_freq_as_envs,
    truncation_as_termination,
)

__all__ = [  # the implementation names stay importable from here, where they were first
    "DQN_IMPLEMENTATION",
    "DQN_IMPLEMENTATIONS",
    "IMPLEMENTATIONS",
    "PPO_IMPLEMENTATION",
    "PPO_IMPLEMENTATIONS",
    "LearnerError",
    "check_implementation",
    "expand_implementation",
    "lecun_init",
    "per_network_clipping",
    "train_freq_as_envs",
    "truncation_as_termination",
]

Cell = tuple[int, int, int]


def path_cells(path: Any) -> list[list[int]] | None:
    return None if path is None else [[int(v) for v in c] for c in path]


def spl(path: Any, optimal: int) -> float:
    """Success weighted by path length: optimal / max(length, optimal) if the path reaches
    the target, else 0 (1 = optimal)."""
    if path is None:
        return 0.0
    moves = len(path) - 1
    return float(optimal) / float(max(moves, optimal)) if moves > 0 else 1.0


class Clock:
    """Training time, wall and CPU, with evaluation paused out."""

    def __init__(self) -> None:
        self.wall0, self.cpu0 = time.perf_counter(), time.process_time()
        self.paused_wall = self.paused_cpu = 0.0

    def now(self) -> tuple[float, float]:
        return (
            time.perf_counter() - self.wall0 - self.paused_wall,
            time.process_time() - self.cpu0 - self.paused_cpu,
        )

    def pause(self) -> tuple[float, float]:
        return time.perf_counter(), time.process_time()

    def resume(self, mark: tuple[float, float]) -> None:
        self.paused_wall += time.perf_counter() - mark[0]
        self.paused_cpu += time.process_time() - mark[1]


class RunContext:
    """What a learner gets for one run: the task, seed, budget and hyperparameters, envs that
    count steps, and the learning curve being recorded."""

    def __init__(
        self,
        task: Any,
        seed: int,
        budget: int,
        hyperparams: dict[str, Any],
        checkpoints: list[int],
        learner: Learner,
        world: Any = None,
    ) -> None:
        self.task = task
        self.seed = int(seed)
        self.budget = int(budget)
        self.hyperparams = dict(hyperparams)
        self.checkpoints = sorted(int(c) for c in checkpoints)
        self.learner = learner
        #: The world trained on (the task's scenario; a re-plan round's world in Algorithm 2).
        self.world = task.scenario if world is None else world
        self.env_steps = 0
        self.episodes = 0
        self.points: list[dict[str, Any]] = []
        self.first_success: dict[str, Any] | None = None
        self.clock = Clock()
        self._next = 0

    # -- for learners that step Python envs ------------------------------------------------
    def make_env(self, **kwargs: Any) -> gym.Env:
        """The task's training env (``sixaxis_avoid.make``), counting steps, episodes and
        the first success, and scoring the greedy path when a checkpoint is passed. Goal tasks
        get the goal-conditioned id ``SixAxisAvoidGoal-v0`` and ``random_target=True`` unless
        given."""
        import sixaxis_avoid as sa

        env_id, kwargs = self._env_id(kwargs)
        return CountingEnv(sa.make(env_id, scenario=self.world, **kwargs), self)

    def make_vec_env(self, n_envs: int, **kwargs: Any) -> Any:
        """``n_envs`` of :meth:`make_env`'s envs (same id and keywords) as one
        Stable-Baselines3 ``VecEnv``: the native ``sixaxis_avoid.sb3.SixAxisVecEnv`` (one
        Rust call per batched step), counting steps as ``make_env``'s envs do, env 0 first
        (:mod:`sixaxis_avoid.benchmark.vec_env`). Step for step the same as ``DummyVecEnv``
        over ``make_env`` envs; needs the ``sb3`` extra. SB3 seeds it (env ``i`` with
        ``seed + i``) when the algorithm is built."""
        from sixaxis_avoid.benchmark.vec_env import CountingVecEnv
        from sixaxis_avoid.sb3 import SixAxisVecEnv

        env_id, kwargs = self._env_id(kwargs)
        # sixaxis_avoid.make's default step cap, the scenario's (SixAxisVecEnv's is the same).
        kwargs.setdefault("max_episode_steps", self.world.max_steps_per_episode)
        venv = SixAxisVecEnv(int(n_envs), env_id=env_id, scenario=self.world, **kwargs)
        return CountingVecEnv(venv, self)

    def _env_id(self, kwargs: dict[str, Any]) -> tuple[str, dict[str, Any]]:
        """The env id of the task and the keywords (goal tasks: random targets unless given)."""
        import sixaxis_avoid as sa

        kwargs = dict(kwargs)
        if self.task.is_goal:
            kwargs.setdefault("random_target", True)
            return sa.GOAL_ENV_ID, kwargs
        return sa.ENV_ID, kwargs

    def on_step(self, reached: bool, done: bool) -> None:
        self.env_steps += 1
        if reached and self.first_success is None:
            wall, cpu = self.clock.now()
            self.first_success = {
                "env_steps": self.env_steps,
                "episode": self.episodes,
                "wall_time_s": wall,
                "cpu_time_s": cpu,
            }
        if done:
            self.episodes += 1
        while self._next < len(self.checkpoints) and self.env_steps >= self.checkpoints[self._next]:
            self._next += 1
            self.checkpoint(self.env_steps)

    # -- for every learner -----------------------------------------------------------------
    def checkpoint(
        self,
        env_steps: int,
        paths: list[Any] | None = None,
        wall_time_s: float | None = None,
        cpu_time_s: float | None = None,
    ) -> None:
        """Record a curve point: the greedy path per evaluation target (``paths``; default:
        ask the learner) after ``env_steps`` env steps of training, which took
        ``wall_time_s``/``cpu_time_s`` (default: the clock's training time)."""
        wall, cpu = self.clock.now()
        wall = wall if wall_time_s is None else wall_time_s
        cpu = cpu if cpu_time_s is None else cpu_time_s
        mark = self.clock.pause()
        if paths is None:
            paths = [self.learner.greedy_path(self.task.world(t)) for t in self.targets()]
        self.clock.resume(mark)
        opt = self.task.optimal_lengths if self.world is self.task.scenario else None
        scores = (
            [spl(p, o) for p, o in zip(paths, opt)]
            if opt
            else [float(p is not None) for p in paths]
        )
        self.points.append(
            {
                "env_steps": int(env_steps),
                "score": float(np.mean(scores)),
                "success": float(np.mean([p is not None for p in paths])),
                "wall_time_s": float(wall),
                "cpu_time_s": float(cpu),
                "paths": [path_cells(p) for p in paths],
            }
        )

    def targets(self) -> list[Cell]:
        if self.world is self.task.scenario:
            return self.task.eval_targets
        return [tuple(self.world.target)]

    def finish(self) -> None:
        """After training: a final point at the last env step, unless one is there."""
        if not self.points or self.points[-1]["env_steps"] != self.env_steps:
            self.checkpoint(self.env_steps)


class CountingEnv(gym.Wrapper):
    """Counts env steps for the :class:`RunContext` (its curve, first success, budget)."""

    def __init__(self, env: gym.Env, ctx: RunContext) -> None:
        super().__init__(env)
        self._ctx = ctx

    def step(self, action: Any):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._ctx.on_step(bool(info.get("is_success", False)), terminated or truncated)
        return obs, reward, terminated, truncated, info

    def compute_reward(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        return self.env.unwrapped.compute_reward(achieved_goal, desired_goal, info)


class Learner(abc.ABC):
    """One learner; a fresh instance per run, built with the run's hyperparameters."""

    #: "native" (tabular), "paper" (the paper's 10,000-episode learner), "deep" (neural) or
    #: "reference" (BFS): which budget
    #: and Algorithm 2 re-plan cap of the suite apply.
    family: ClassVar[str] = "deep"
    #: Hyperparameters used when the hyperparameter file has none for this learner.
    defaults: ClassVar[dict[str, Any]] = {}
    #: One line for the report.
    title: ClassVar[str] = ""

    def __init__(self, hyperparams: dict[str, Any] | None = None) -> None:
        self.hyperparams = {**self.defaults, **(hyperparams or {})}

    @abc.abstractmethod
    def learn(self, ctx: RunContext) -> None:
        """Train on ``ctx.world`` with ``ctx.seed`` for about ``ctx.budget`` env steps."""

    @abc.abstractmethod
    def greedy_path(self, world: Any) -> list[Cell] | None:
        """The greedy path from ``world.start`` to ``world.target`` (None: not reached)."""

    def algorithm2_learner(self, ctx: RunContext) -> Any:
        """What Algorithm 2 (``sixaxis_avoid.plan(learner=...)``) learns each round's path
        with. Default: round 0 reuses this run's path; a re-plan trains a fresh learner of this
        class on the round's world with the same seed, budget and hyperparameters."""
        return RetrainPerRound(self, ctx)

    def algorithm2_kwargs(self) -> dict[str, Any]:
        """Further keywords of ``sixaxis_avoid.plan`` for this learner."""
        return {}


class RetrainPerRound:
    """``learn_path(scenario, seed)`` for the core's Algorithm 2 loop (see
    :meth:`Learner.algorithm2_learner`)."""

    def __init__(self, learner: Learner, ctx: RunContext) -> None:
        self.learner, self.ctx = learner, ctx

    def learn_path(self, scenario: Any, seed: int) -> dict[str, Any]:
        base = self.ctx.task.scenario
        if same_world(scenario, base):  # round 0: this run's own path
            path = self.ctx.points[-1]["paths"][0]
            steps = self.ctx.env_steps
        else:
            import sixaxis_avoid as sa

            try:
                scenario.validate()
            except sa.ScenarioError as e:
                if e.field != "target":
                    raise
                # The round's new obstacles block the target (a path cell next to it on a
                # fine grid, within terminal_safe_distance): no env can be built, so there is
                # no path in this world, and Algorithm 2 fails.
                return {"path": None, "total_steps": 0}
            fresh = type(self.learner)(self.learner.hyperparams)
            ctx = RunContext(
                self.ctx.task, seed, self.ctx.budget, fresh.hyperparams, [], fresh, scenario
            )
            fresh.learn(ctx)
            path, steps = fresh.greedy_path(scenario), ctx.env_steps
        cells = None if path is None else [tuple(int(v) for v in c) for c in path]
        return {"path": cells, "total_steps": int(steps)}


def same_world(a: Any, b: Any) -> bool:
    """Same start, target and obstacle set (a re-plan round adds obstacles)."""
    return (
        tuple(a.start) == tuple(b.start)
        and tuple(a.target) == tuple(b.target)
        and {tuple(c) for c in a.obstacles} == {tuple(c) for c in b.obstacles}
    )


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


def split_budget(budget: int, parts: int) -> list[int]:
    """``budget`` env steps in ``parts`` near-equal shares that sum to it (the first ones get
    the remainder)."""
    q, r = divmod(int(budget), int(parts))
    return [q + (i < r) for i in range(parts)]


def whole_iterations(budget: int, grain: int) -> int:
    """The env steps a learner that trains in iterations of ``grain`` env steps (PPO: a
    rollout of ``n_envs x n_steps``; DQN: one step of its ``n_envs`` envs) may use on a
    budget of ``budget`` env steps: the most whole iterations that fit, at least one. A
    budget is a cap: a run never ends past it unless one iteration alone is larger
    (docs/BENCHMARKS.md, "Statistics")."""
    grain = max(int(grain), 1)
    return max(int(budget) // grain, 1) * grain


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


# ------------------------------------------------------------------------------------------
# Stable-Baselines3 and sb3-contrib

#: Hyperparameters that configure the env rather than the algorithm.
ENV_KEYS = ("reward_scale", "assist", "max_episode_steps", "n_envs")

#: Env settings of every deep learner's defaults: the paper's assisted rewards scaled to
#: O(1) (the paper's are tens of thousands), episodes capped at 200 steps.
ENV_DEFAULTS: dict[str, Any] = {"reward_scale": 1e-4, "assist": True, "max_episode_steps": 200}

#: DQN defaults (until tuned): rl-baselines3-zoo hyperparams/dqn.yml, MountainCar-v0 (a
#: sparse-reward, discrete-action goal-reaching task; commit ce95481b), SB3 defaults otherwise.
DQN_DEFAULTS: dict[str, Any] = {
    **ENV_DEFAULTS,
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
#: QR-DQN defaults (until tuned): DQN's, with 50 quantiles.
QRDQN_DEFAULTS: dict[str, Any] = {**DQN_DEFAULTS, "n_quantiles": 50}
#: PPO defaults (until tuned): SB3's, with 8 envs, n_steps 256 and ent_coef 0.01.
PPO_DEFAULTS: dict[str, Any] = {**ENV_DEFAULTS, "n_envs": 8, "n_steps": 256, "ent_coef": 0.01}
#: A2C defaults (until tuned): SB3's, with 8 envs and ent_coef 0.01.
A2C_DEFAULTS: dict[str, Any] = {**ENV_DEFAULTS, "n_envs": 8, "ent_coef": 0.01}


def greedy_rollout(model: Any, env: gym.Env, cap: int) -> list[Cell] | None:
    """The deterministic policy's path from the start: the cells visited until the target
    (bumps into obstacles leave the terminal in place and are not moves); None on a loop (a
    repeated (cell, collided) pair: the observation repeats, so does the action) or at the
    step cap."""
    obs, info = env.reset(seed=0)
    cell = tuple(info["cell"])
    path, seen = [cell], {(cell, False)}
    for _ in range(cap):
        action, _ = model.predict(obs, deterministic=True)
        obs, _, terminated, _, info = env.step(int(action))
        cell, collided = tuple(info["cell"]), bool(info["collided"])
        if not collided:
            path.append(cell)
        if terminated:
            return path
        if (cell, collided) in seen:
            return None
        seen.add((cell, collided))
    return None


def linear_schedule(initial: float) -> Callable[[float], float]:
    """A learning rate falling linearly from ``initial`` to 0 over training (SB3 calls it
    with the fraction of the budget remaining, 1 to 0)."""

    def rate(progress_remaining: float) -> float:
        return initial * progress_remaining

    return rate


class SB3Learner(Learner):
    """A Stable-Baselines3-style algorithm on ``SixAxisAvoid-v0`` (vector observations; goal
    observations on goal tasks, with hindsight experience replay for off-policy ones),
    trained on ``n_envs`` envs of the native ``SixAxisVecEnv`` (:meth:`RunContext.make_vec_env`;
    its class name is the run file's ``result.vec_env``)."""

    family = "deep"
    off_policy: ClassVar[bool] = False
    #: ``module:Class`` of the algorithm.
    algorithm_path: ClassVar[str] = ""

    def algorithm(self) -> Any:
        module, _, name = self.algorithm_path.partition(":")
        return getattr(importlib.import_module(module), name)

    def learn(self, ctx: RunContext) -> None:
        import torch
        from stable_baselines3.common.logger import Logger

        torch.set_num_threads(1)
        hp = self.expand_hyperparams(dict(self.hyperparams))
        env_kw = {k: hp.pop(k) for k in ENV_KEYS if k in hp}
        n_envs = int(env_kw.pop("n_envs", 1))
        self._env_kw = {k: env_kw[k] for k in ("reward_scale", "assist") if k in env_kw}
        self._goal = ctx.task.is_goal
        # The native SB3 VecEnv over the Rust batch, for every kind of task (fixed and random
        # targets, goal observations, re-gridded and re-plan worlds): step for step the same
        # as DummyVecEnv over ctx.make_env() envs (docs/BENCHMARKS.md, "Tasks").
        vec = ctx.make_vec_env(n_envs, **env_kw)
        self.vec_env = type(vec.unwrapped).__name__
        policy_kwargs = {k: hp.pop(k) for k in ("net_arch", "n_quantiles") if k in hp}
        impl = {k: hp.pop(k) for k in self.implementation_keys if k in hp}
        vec, policy_kwargs = self.before_model(impl, vec, policy_kwargs)
        schedule = hp.pop("lr_schedule", "constant")
        if schedule == "linear":
            # rl-baselines3-zoo's "lin_": from the value down to 0 at the end of the budget.
            hp["learning_rate"] = linear_schedule(float(hp.get("learning_rate", 3e-4)))
        elif schedule != "constant":
            raise LearnerError(
                f"lr_schedule: {schedule!r} is not a schedule (use 'constant' or 'linear')"
            )
        if self._goal and self.off_policy and impl.get("her", True):
            from stable_baselines3 import HerReplayBuffer

            # HER cannot sample before an episode has ended: learning starts after one.
            cap = int(env_kw.get("max_episode_steps", ctx.world.max_steps_per_episode))
            hp["learning_starts"] = max(int(hp.get("learning_starts", 100)), cap)
            hp["replay_buffer_class"] = HerReplayBuffer
            hp["replay_buffer_kwargs"] = {
                "n_sampled_goal": int(hp.pop("her_n_sampled_goal", 4)),
                "goal_selection_strategy": "future",
                "copy_info_dict": True,
            }
        else:
            hp.pop("her_n_sampled_goal", None)
        policy = "MultiInputPolicy" if self._goal else "MlpPolicy"
        self.model = self.algorithm()(
            policy,
            vec,
            policy_kwargs=policy_kwargs or None,
            seed=ctx.seed,
            device="cpu",
            verbose=0,
            **hp,
        )
        self.after_model(impl, self.model)
        self.model.set_logger(Logger(None, []))  # no log files
        self._eval_envs: dict[Cell, gym.Env] = {}
        # Whole rollouts (on-policy) or vector steps (off-policy) at or under the budget:
        # SB3 ends learn() on the first whole one past total_timesteps.
        n_steps = int(getattr(self.model, "n_steps", 1))
        self.model.learn(total_timesteps=whole_iterations(ctx.budget, n_steps * self.model.n_envs))
        vec.close()

    #: The algorithm's implementation variants (:data:`IMPLEMENTATIONS` key: "ppo", "dqn"),
    #: hyperparameters that choose between them rather than set SB3 arguments.
    implementation: ClassVar[str | None] = None

    @property
    def implementation_keys(self) -> tuple[str, ...]:
        return () if self.implementation is None else tuple(IMPLEMENTATIONS[self.implementation][0])

    def expand_hyperparams(self, hp: dict[str, Any]) -> dict[str, Any]:
        """``hp`` with any preset it names replaced by the preset's values."""
        if self.implementation is None:
            return hp
        return expand_implementation(self.implementation, hp)

    def before_model(
        self, impl: dict[str, Any], vec: Any, policy_kwargs: dict[str, Any]
    ) -> tuple[Any, dict[str, Any]]:
        """The VecEnv and policy keywords for the implementation variant ``impl``."""
        return vec, policy_kwargs

    def after_model(self, impl: dict[str, Any], model: Any) -> None:
        """Changes to the built model for the implementation variant ``impl``."""

    def greedy_path(self, world: Any) -> list[Cell] | None:
        import sixaxis_avoid as sa

        key = (tuple(world.target), len(world.obstacles))
        env = self._eval_envs.get(key)
        if env is None:
            env_id = sa.GOAL_ENV_ID if self._goal else sa.ENV_ID
            env = sa.make(env_id, scenario=world, **self._env_kw).unwrapped
            self._eval_envs[key] = env
        return greedy_rollout(self.model, env, world.max_steps_per_episode)


class DQN(SB3Learner):
    title = "Stable-Baselines3 DQN (HER on goal tasks)"
    algorithm_path = "stable_baselines3:DQN"
    off_policy = True
    defaults = DQN_DEFAULTS
    implementation = "dqn"

    def expand_hyperparams(self, hp: dict[str, Any]) -> dict[str, Any]:
        hp = super().expand_hyperparams(hp)
        if check_implementation("dqn", {k: hp[k] for k in DQN_IMPLEMENTATION if k in hp})[
            "train_freq_as_envs"
        ]:
            hp = train_freq_as_envs(hp)
        return hp

    def before_model(
        self, impl: dict[str, Any], vec: Any, policy_kwargs: dict[str, Any]
    ) -> tuple[Any, dict[str, Any]]:
        if not check_implementation("dqn", impl)["bootstrap_truncated"]:
            vec = truncation_as_termination(vec)
        return vec, policy_kwargs

    def after_model(self, impl: dict[str, Any], model: Any) -> None:
        if check_implementation("dqn", impl)["init"] == "lecun":
            lecun_init(model.policy.q_net)
            model.policy.q_net_target.load_state_dict(model.policy.q_net.state_dict())


class QRDQN(SB3Learner):
    title = "sb3-contrib QR-DQN (HER on goal tasks)"
    algorithm_path = "sb3_contrib:QRDQN"
    off_policy = True
    # DQN's values, and 50 quantiles (sb3-contrib's 200 make the pairwise quantile loss,
    # batch x 200 x 200, cost most of a run's CPU time).
    defaults = QRDQN_DEFAULTS


class PPO(SB3Learner):
    title = "Stable-Baselines3 PPO"
    algorithm_path = "stable_baselines3:PPO"
    defaults = PPO_DEFAULTS
    implementation = "ppo"

    def before_model(
        self, impl: dict[str, Any], vec: Any, policy_kwargs: dict[str, Any]
    ) -> tuple[Any, dict[str, Any]]:
        impl = check_implementation("ppo", impl)
        if impl["init"] != "orthogonal":
            policy_kwargs = {**policy_kwargs, "ortho_init": False}  # lecun: re-initialised below
        if not impl["bootstrap_truncated"]:
            vec = truncation_as_termination(vec)
        return vec, policy_kwargs

    def after_model(self, impl: dict[str, Any], model: Any) -> None:
        impl = check_implementation("ppo", impl)
        if impl["init"] == "lecun":
            lecun_init(model.policy)
        if impl["grad_clip"] == "per_network":
            per_network_clipping(model)


class A2C(SB3Learner):
    title = "Stable-Baselines3 A2C"
    algorithm_path = "stable_baselines3:A2C"
    defaults = A2C_DEFAULTS


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
