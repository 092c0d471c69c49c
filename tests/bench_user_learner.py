"""A user's learner for the benchmark tests, named ``bench_user_learner:ScriptedBFS``: it
walks the breadth-first path in the task's env (so the harness counts real env steps) and
reports that path as its greedy path."""

from __future__ import annotations

from typing import Any

import sixaxis_avoid as sa
from sixaxis_avoid.benchmark import Learner, RunContext

MOVES = {(1, 0, 0): 0, (-1, 0, 0): 1, (0, 1, 0): 2, (0, -1, 0): 3, (0, 0, 1): 4, (0, 0, -1): 5}


class ScriptedBFS(Learner):
    family = "deep"
    title = "test learner: walks the BFS path"

    def learn(self, ctx: RunContext) -> None:
        env = ctx.make_env()
        path = sa.shortest_path(ctx.world)
        actions = [MOVES[tuple(b - a for a, b in zip(p, q))] for p, q in zip(path, path[1:])]
        env.reset(seed=ctx.seed)
        i = 0
        while ctx.env_steps < ctx.budget:
            _, _, terminated, truncated, _ = env.step(actions[i])
            i += 1
            if terminated or truncated:
                env.reset()
                i = 0

    def greedy_path(self, world: Any) -> list[tuple[int, int, int]] | None:
        return sa.shortest_path(world)
