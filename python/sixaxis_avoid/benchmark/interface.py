"""The Learner interface: what a learner gets for a run and what it gives back.

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

Entry points: :class:`Learner` (subclass it), :class:`RunContext` (one run's task, seed,
budget in env steps, counting envs and curve), :func:`spl` (the score), and the budget
helpers :func:`split_budget` and :func:`whole_iterations`. The built-in learners are in
:mod:`sixaxis_avoid.benchmark.learners` (tabular, BFS, and their registry) and
:mod:`sixaxis_avoid.benchmark.sb3_learners` (Stable-Baselines3).
"""

from __future__ import annotations

import abc
import time
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

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
            blocked = round_world_blocked(scenario)
            if blocked:
                return {"path": None, "total_steps": 0, "reason": blocked}
            fresh = type(self.learner)(self.learner.hyperparams)
            ctx = RunContext(
                self.ctx.task, seed, self.ctx.budget, fresh.hyperparams, [], fresh, scenario
            )
            fresh.learn(ctx)
            path, steps = fresh.greedy_path(scenario), ctx.env_steps
        cells = None if path is None else [tuple(int(v) for v in c) for c in path]
        return {"path": cells, "total_steps": int(steps)}


def round_world_blocked(scenario: Any) -> str | None:
    """Why a re-plan round's world holds no env, or None if it holds one: the points
    Algorithm 2 added as obstacles block the start or the target (a path cell next to it on
    a fine grid, within ``terminal_safe_distance``). Then no learner can learn a path there;
    it returns none with this reason (the ``reason`` of its result), and Algorithm 2 fails
    with it. Any other invalid field raises."""
    import sixaxis_avoid as sa

    try:
        scenario.validate()
    except sa.ScenarioError as e:
        if e.field not in ("start", "target"):
            raise
        return f"the points added so far leave no env to learn in: {e}"
    return None


def same_world(a: Any, b: Any) -> bool:
    """Same start, target and obstacle set (a re-plan round adds obstacles)."""
    return (
        tuple(a.start) == tuple(b.start)
        and tuple(a.target) == tuple(b.target)
        and {tuple(c) for c in a.obstacles} == {tuple(c) for c in b.obstacles}
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
