"""Versioned task suites: which scenarios the learners are measured on, with what budgets.

A suite is a JSON file (``suites/<name>.json`` in this package, or any path) with:

- ``name``, ``version``: what the results are labelled with; a result file records both.
- ``seeds``: the learners' seeds of a reported run (``0..N-1``).
- ``budgets``: env steps per run (``deep`` for neural learners; ``native_episodes``, the
  tabular learner's episode cap, the paper's 10000) and ``checkpoints``, the number of greedy
  evaluations on a geometric grid of env steps up to the budget. A suite with a budget axis
  (v2) gives ``axis``, rising env-step budgets that every learner runs, and may mark its tail
  ``best_only``: budgets that only the best learners at the last budget before them run, to
  show their plateau (v2: 10M env steps after 3M).
- ``algorithm2``: the re-plan caps of Algorithm 2 per learner family.
- ``tasks``: the reported tasks; ``tuning``: tasks and seeds for ``benchmark tune``, which
  must be disjoint from the reported ones (checked).

A task is one of

- ``{"id": ..., "kind": "scenario", "scenario": "paper_simple"}`` — a scenario by name;
- ``{"id": ..., "kind": "generated", "seed": 3, "level": "hard", "options": {...}}`` — a
  random cluttered scenario (``sixaxis_avoid.generate_scenario``; options: ``density``,
  ``bounds``, ``min_start_target_distance``), graded by the level's options;
- ``{"id": ..., "kind": "goal", "scenario": ..., "eval_targets": 8, "target_seed": 0}`` —
  goal-conditioned: a new target every episode; scored on a fixed set of evaluation targets
  (reachable free cells drawn with ``target_seed``). Deep learners train one policy on goal
  observations for every target; the tabular learner is re-learned per target and its cost
  (env steps, seconds) is summed.

Any task may carry ``"cell_mm": 50`` (or 25, ...): its scenario is re-gridded to cells of that
size (``Scenario.regrid``, docs/SCENARIOS.md): the same physical world on a finer grid, with
more states and longer paths.

Two reported tasks must not be the same world for a learner (:meth:`Task.learner_world`, a key
of what the grid learner sees): suites of version 2 and later are checked when they are
loaded (:meth:`Suite.check_distinct_worlds`). Suite v1 predates the check: its
``paper_simple`` and ``paper_complex`` differ only in the arm's safe distance and in a
terminal safe distance (0.96 against 0.95 cells) that blocks the same cells.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

SUITES_DIR = Path(__file__).resolve().parent / "suites"
TASK_KINDS = ("scenario", "generated", "goal")


class SuiteError(ValueError):
    """A suite file or a task in it is wrong (names the field and the value)."""


@dataclass(frozen=True)
class Task:
    """One benchmark task; ``scenario`` builds its world (deterministically)."""

    id: str
    kind: str
    spec: dict[str, Any] = field(hash=False, compare=False)

    @property
    def is_goal(self) -> bool:
        return self.kind == "goal"

    @property
    def group(self) -> str:
        """Paper, shipped, generated:LEVEL or goal, with ``@50mm`` for a re-gridded task:
        the rows the report groups by."""
        if self.kind == "generated":
            base = f"generated:{self.spec.get('level', 'default')}"
        elif self.kind == "goal":
            base = "goal"
        else:
            base = "paper" if str(self.spec["scenario"]).startswith("paper_") else "shipped"
        cell_mm = self.spec.get("cell_mm")
        return base if cell_mm is None else f"{base}@{float(cell_mm):g}mm"

    @cached_property
    def scenario(self) -> Any:
        import sixaxis_avoid as sa

        if self.kind == "generated":
            opts = dict(self.spec.get("options", {}))
            if "bounds" in opts:
                opts["bounds"] = tuple(tuple(b) for b in opts["bounds"])
            s = sa.generate_scenario(int(self.spec["seed"]), **opts)
        else:
            s = sa.Scenario(self.spec["scenario"])
        cell_mm = self.spec.get("cell_mm")
        if cell_mm is not None:
            try:
                s = s.regrid(float(cell_mm))
            except (TypeError, ValueError) as e:
                raise SuiteError(f"task {self.id!r}: cell_mm {cell_mm!r}: {e}") from e
        return s

    @cached_property
    def blocked_states(self) -> np.ndarray:
        """The states (the core's numbering) where the terminal collides, as the core's grid
        world computes them, see
        docs/SCENARIOS.md, "The grid world: states, actions, collisions, rewards"."""
        from sixaxis_avoid import _core

        return np.flatnonzero(np.asarray(_core.EnvCore(self.scenario, obs="index").blocked))

    @cached_property
    def learner_world(self) -> str:
        """What a learner of the grid sees, as a key (two tasks with equal keys are the same
        task for every learner of the benchmark): the bounds, the blocked cells (the
        obstacles as the terminal's safe distance makes them, boxes in mm included, as the
        core computes them), the start, the evaluation targets, whether the target changes
        every episode (goal task), the episode's step cap, the reward parameters and the
        learning block but its seed (each run sets its own). The arm, the cell size in mm
        and the planning settings are left out: they reach Algorithms 1 and 2, not the
        learner."""
        s = self.scenario
        doc = json.loads(s.to_json())
        blocked = self.blocked_states
        learning = {k: v for k, v in doc["learning"].items() if k != "seed"}
        key = {
            "bounds": doc["bounds"],
            "blocked_states": blocked.tolist(),
            "start": list(s.start),
            "targets": sorted(list(t) for t in self.eval_targets),
            "goal": self.is_goal,
            "rewards": doc["rewards"],
            "learning": learning,
        }
        return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()

    @cached_property
    def eval_targets(self) -> list[tuple[int, int, int]]:
        """The targets a learner is scored on: the scenario's, or (goal task) a fixed draw of
        reachable free cells other than the start."""
        s = self.scenario
        if not self.is_goal:
            return [tuple(s.target)]
        import sixaxis_avoid as sa

        lo, hi = s.bounds
        blocked = {tuple(c) for c in s.obstacles}
        free = [
            (x, y, z)
            for x in range(lo[0], hi[0] + 1)
            for y in range(lo[1], hi[1] + 1)
            for z in range(lo[2], hi[2] + 1)
            if (x, y, z) not in blocked and (x, y, z) != tuple(s.start)
        ]
        rng = np.random.default_rng(int(self.spec.get("target_seed", 0)))
        want = int(self.spec.get("eval_targets", 8))
        out: list[tuple[int, int, int]] = []
        for i in rng.permutation(len(free)):
            cell = free[int(i)]
            try:
                world = s.replace(target=list(cell))
            except ValueError:  # too close to an obstacle for the terminal's safe distance
                continue
            if sa.shortest_path(world) is not None:
                out.append(cell)
            if len(out) == want:
                break
        if len(out) < want:
            raise SuiteError(f"task {self.id!r}: only {len(out)} reachable targets, want {want}")
        return out

    def world(self, target: tuple[int, int, int]) -> Any:
        """The task's scenario with ``target`` as its target."""
        s = self.scenario
        return s if tuple(s.target) == tuple(target) else s.replace(target=list(target))

    @cached_property
    def optimal_lengths(self) -> list[int]:
        """BFS optimum (moves) per evaluation target."""
        import sixaxis_avoid as sa

        out = []
        for t in self.eval_targets:
            path = sa.shortest_path(self.world(t))
            if path is None:
                raise SuiteError(f"task {self.id!r}: target {t} is not reachable at all")
            out.append(len(path) - 1)
        return out

    def describe(self) -> dict[str, Any]:
        s = self.scenario
        lo, hi = s.bounds
        size = [int(h - low + 1) for low, h in zip(lo, hi)]
        # A re-gridded world holds its obstacles as boxes in mm: count both.
        n_obs = len(s.obstacles) + len(json.loads(s.to_json()).get("obstacle_boxes_mm") or [])
        return {
            "id": self.id,
            "kind": self.kind,
            "group": self.group,
            "spec": self.spec,
            "grid": size,
            "states": int(np.prod(size)),
            "cell_mm": float(s.cell_mm),
            "obstacles": n_obs,
            "blocked": len(self.blocked_states),
            "density": round(n_obs / float(np.prod(size)), 3),
            "start": list(s.start),
            "targets": [list(t) for t in self.eval_targets],
            "optimal_lengths": self.optimal_lengths,
        }


@dataclass
class Suite:
    name: str
    version: str
    seeds: list[int]
    budgets: dict[str, Any]
    algorithm2: dict[str, int]
    tasks: list[Task]
    tuning: dict[str, Any]
    path: Path
    raw: dict[str, Any]

    @property
    def best_only(self) -> list[int]:
        """The budget axis's tail that only the best learners run (``budgets.best_only``, env
        steps; empty without one)."""
        return [int(b) for b in self.budgets.get("best_only", [])]

    def task(self, task_id: str) -> Task:
        for t in self.tasks + self.tuning_tasks:
            if t.id == task_id:
                return t
        raise SuiteError(f"suite {self.name!r}: no task {task_id!r}")

    @cached_property
    def tuning_tasks(self) -> list[Task]:
        return [_task(x, f"tuning.tasks[{i}]") for i, x in enumerate(self.tuning.get("tasks", []))]

    @property
    def major_version(self) -> int:
        """The suite's version as a number (``"2"``, ``"2.1"`` -> 2)."""
        try:
            return int(str(self.version).split(".")[0])
        except ValueError as e:
            raise SuiteError(
                f"suite {self.name!r}: version {self.version!r} is not a number"
            ) from e

    def check_disjoint(self) -> None:
        """Tuning tasks share no world with the reported ones (neither the same scenario nor
        the same learner world, :attr:`Task.learner_world`)."""
        reported = {t.scenario.to_json(): t.id for t in self.tasks}
        worlds = {t.learner_world: t.id for t in self.tasks}
        for t in self.tuning_tasks:
            same = reported.get(t.scenario.to_json()) or worlds.get(t.learner_world)
            if same is not None:
                raise SuiteError(
                    f"suite {self.name!r}: tuning task {t.id!r} is the reported task "
                    f"{same!r}; tuning tasks must be disjoint"
                )

    def check_distinct_worlds(self) -> None:
        """No two reported tasks are the same learner world (:attr:`Task.learner_world`):
        a duplicate would count one task twice in every aggregate."""
        seen: dict[str, str] = {}
        for t in self.tasks:
            other = seen.setdefault(t.learner_world, t.id)
            if other != t.id:
                raise SuiteError(
                    f"suite {self.name!r}: tasks {other!r} and {t.id!r} are the same learner "
                    "world (bounds, blocked cells, start, targets, step cap, rewards and "
                    "learning settings); keep one"
                )

    def checkpoints(self, budget: int) -> list[int]:
        """Env steps of the greedy evaluations: geometric from budget/100 to the budget."""
        n = int(self.budgets.get("checkpoints", 12))
        lo = max(1, budget // 100)
        pts = np.unique(np.geomspace(lo, budget, n).round().astype(np.int64))
        return [int(p) for p in pts]


def available() -> list[str]:
    return sorted(p.stem for p in SUITES_DIR.glob("*.json"))


def _task(x: Any, where: str) -> Task:
    if not isinstance(x, dict):
        raise SuiteError(f"{where}: expected an object, got {x!r}")
    kind = x.get("kind")
    if kind not in TASK_KINDS:
        raise SuiteError(f"{where}.kind: {kind!r} is not one of {', '.join(TASK_KINDS)}")
    if not isinstance(x.get("id"), str) or not x["id"]:
        raise SuiteError(f"{where}.id: {x.get('id')!r} must be a non-empty string")
    need = {"scenario": ("scenario",), "generated": ("seed",), "goal": ("scenario",)}[kind]
    for key in need:
        if key not in x:
            raise SuiteError(f"{where}.{key}: missing (a {kind} task needs it)")
    return Task(id=x["id"], kind=kind, spec={k: v for k, v in x.items() if k not in ("id",)})


def check_budget_axis(budgets: dict[str, Any], where: Path) -> None:
    """A budget axis (``budgets.axis``) rises, and its ``budgets.best_only`` budgets are its
    tail: budgets that only the best learners at the last budget before them run, to show
    their plateau there (docs/BENCHMARKS.md, *Statistics*)."""
    axis = budgets.get("axis")
    if axis is None:
        if "best_only" in budgets:
            raise SuiteError(f"suite {where}: budgets.best_only needs budgets.axis")
        return
    if not axis or any(not isinstance(b, int) or b <= 0 for b in axis) or axis != sorted(set(axis)):
        raise SuiteError(
            f"suite {where}: budgets.axis {axis!r} must be rising positive env-step counts"
        )
    best_only = budgets.get("best_only", [])
    if (
        not isinstance(best_only, list)
        or best_only != axis[len(axis) - len(best_only) :]
        or (best_only and len(best_only) == len(axis))
    ):
        raise SuiteError(
            f"suite {where}: budgets.best_only {best_only!r} must be the tail of "
            f"budgets.axis {axis!r}, after at least one budget every learner runs"
        )


def load_suite(name_or_path: str | Path) -> Suite:
    """A suite by name (``quick``, ``v1``) or JSON path."""
    p = Path(name_or_path)
    if not p.suffix:
        p = SUITES_DIR / f"{name_or_path}.json"
        if not p.exists():
            raise SuiteError(f"suite: {name_or_path!r} unknown; known: {', '.join(available())}")
    try:
        raw = json.loads(p.read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise SuiteError(f"suite: cannot read {p}: {e}") from e
    for key in ("name", "version", "seeds", "budgets", "tasks"):
        if key not in raw:
            raise SuiteError(f"suite {p}: field {key!r} missing")
    seeds = raw["seeds"]
    seeds = list(range(seeds)) if isinstance(seeds, int) else [int(s) for s in seeds]
    tasks = [_task(x, f"tasks[{i}]") for i, x in enumerate(raw["tasks"])]
    ids = [t.id for t in tasks]
    if len(set(ids)) != len(ids):
        raise SuiteError(f"suite {p}: task ids repeat: {ids}")
    suite = Suite(
        name=str(raw["name"]),
        version=str(raw["version"]),
        seeds=seeds,
        budgets=dict(raw["budgets"]),
        algorithm2={"native": 20, "deep": 1, **raw.get("algorithm2", {})},
        tasks=tasks,
        tuning=dict(raw.get("tuning", {})),
        path=p,
        raw=raw,
    )
    check_budget_axis(suite.budgets, p)
    if suite.major_version >= 2:
        suite.check_distinct_worlds()
        suite.check_disjoint()
    return suite
