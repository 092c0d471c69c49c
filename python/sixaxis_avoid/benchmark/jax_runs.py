"""Run files of the JAX learners (``jax_ppo``, ``jax_dqn``): all seeds of one (task, budget,
values) in one vmapped call, one record per seed in :func:`runner.execute_run`'s schema.

The runner plans JAX runs like any other (``learners.resolve("jax_ppo")``, family
``"jax"``); :func:`run_group` takes specs that differ only in seed and returns their
records, which ``runner.write_run`` writes. Per-seed times are the group's time divided by
its seeds (``timing.shared_by_seeds``), and the time of a curve point or first success is
that share pro rata to its env steps: the seeds train together, so no seed has a time of
its own. ``first_success.episode`` is estimated as the reaching env's own episode index
times the number of parallel envs (the envs step in lockstep).
"""

from __future__ import annotations

import json
import time
from typing import Any, ClassVar

from sixaxis_avoid.benchmark.jax_values import DQN_DEFAULTS, PPO_DEFAULTS
from sixaxis_avoid.benchmark.learners import Learner, RunContext, round_world_blocked, same_world

SEED_FREE = ("seed",)


class JaxLearner(Learner):
    """A rejax learner on the JAX twin; its runs go through :func:`run_group`."""

    family = "jax"
    algo: ClassVar[str] = ""

    def learn(self, ctx: RunContext) -> None:
        raise RuntimeError(
            f"{type(self).__name__} trains all seeds of a task at once: use "
            "sixaxis_avoid.benchmark.jax_runs.run_group (runner.execute_run and "
            "runner.run_study call it for family 'jax')"
        )

    def greedy_path(self, world: Any) -> Any:
        raise RuntimeError(f"{type(self).__name__}: paths come from jax_runs.run_group")

    # How the runner trains this family (it dispatches through the class, so it needs no
    # import of this module, which is layered above it).
    @staticmethod
    def groups(specs: list[dict[str, Any]]) -> list[list[dict[str, Any]]]:
        """:func:`groups`: the specs that train together."""
        return groups(specs)

    @staticmethod
    def run_group(specs: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """:func:`run_group`: one vmapped call, one record per spec."""
        return run_group(specs)


class JaxPPO(JaxLearner):
    title = "rejax PPO on the JAX twin (seeds vmapped)"
    algo = "ppo"
    defaults = PPO_DEFAULTS


class JaxDQN(JaxLearner):
    title = "rejax DQN on the JAX twin (seeds vmapped)"
    algo = "dqn"
    defaults = DQN_DEFAULTS


LEARNERS: dict[str, type[JaxLearner]] = {"jax_ppo": JaxPPO, "jax_dqn": JaxDQN}


def group_key(spec: dict[str, Any]) -> str:
    """Specs with the same key differ only in seed (and so in their result file)."""
    return json.dumps({k: v for k, v in spec.items() if k not in SEED_FREE}, sort_keys=True)


def groups(specs: list[dict[str, Any]]) -> list[list[dict[str, Any]]]:
    """The specs split into :func:`run_group`'s groups, in order of first appearance."""
    out: dict[str, list[dict[str, Any]]] = {}
    for s in specs:
        out.setdefault(group_key(s), []).append(s)
    return list(out.values())


class _Replan:
    """``learn_path(scenario, seed)`` for Algorithm 2: round 0 is the run's own path; a
    re-plan round trains one seed of the same values on the round's world."""

    def __init__(self, algo: str, task: Any, values: dict[str, Any], budget: int, path: Any):
        self.algo, self.task, self.values, self.budget, self.path = algo, task, values, budget, path
        self.steps = 0

    def learn_path(self, scenario: Any, seed: int) -> dict[str, Any]:
        from sixaxis_avoid.benchmark import jax_learners as jl
        from sixaxis_avoid.benchmark.tasks import Task

        if same_world(scenario, self.task.scenario):
            return {"path": self.path, "total_steps": int(self.steps)}
        blocked = round_world_blocked(scenario)
        if blocked:
            return {"path": None, "total_steps": 0, "reason": blocked}
        world = _WorldTask(
            Task(id=self.task.id, kind=self.task.kind, spec=self.task.spec), scenario
        )
        comp = jl.Compiled(self.algo, world, self.values, self.budget, [self.budget])
        r = comp.run([self.values], [seed])
        params = _index(r["params"], 0, 0)
        path = comp.paths(params)[0]
        cells = None if path is None else [tuple(c) for c in path]
        return {"path": cells, "total_steps": int(r["env_steps"][-1])}


class _WorldTask:
    """A task on another world (a re-plan round's): its start, target and obstacles."""

    def __init__(self, task: Any, scenario: Any) -> None:
        self.id, self.kind, self.spec = task.id, task.kind, task.spec
        self.scenario, self.is_goal = scenario, False
        self.eval_targets = [tuple(scenario.target)]
        self.optimal_lengths = [1]  # SPL is not read here, only the path


def _index(tree: Any, i: int, j: int) -> Any:
    import jax

    return jax.tree_util.tree_map(lambda x: x[i, j], tree)


def run_group(specs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Train the seeds of ``specs`` (same learner, task, budget, values; any seeds) in one
    vmapped call; one record per spec, in order, in ``runner.execute_run``'s schema."""
    from sixaxis_avoid.benchmark import jax_learners as jl
    from sixaxis_avoid.benchmark import runner
    from sixaxis_avoid.benchmark.algorithm2 import algorithm1_record, algorithm2_record

    if not specs:
        return []
    if len({group_key(s) for s in specs}) != 1:
        raise ValueError("run_group: the specs differ in more than their seed")
    spec0 = specs[0]
    if spec0["learner"] not in LEARNERS:
        raise ValueError(f"run_group: learner {spec0['learner']!r} is not {', '.join(LEARNERS)}")
    algo = LEARNERS[spec0["learner"]].algo
    t_start = time.perf_counter()
    task = runner.task_of(spec0)
    values = jl.check_values(algo, spec0["hyperparams"])
    budget = int(spec0["budget"])
    seeds = [int(s["seed"]) for s in specs]
    comp = jl.compiled_group(algo, task, values, budget, list(spec0["checkpoints"]) or [budget])
    r = comp.run([values], seeds)
    out, n = r["out"], len(seeds)
    wall, cpu = r["train_wall_s"] / n, r["train_cpu_s"] / n
    total = r["env_steps"][-1]
    optimal = task.optimal_lengths
    records = []
    for j, spec in enumerate(specs):
        t0 = time.perf_counter()
        params = _index(r["params"], 0, j)
        paths = comp.paths(params)
        spl, success = out["spl"][0, j], out["success"][0, j]
        curve = [
            {"env_steps": int(e), "score": float(s), "success": float(u)}
            for e, s, u in zip(r["env_steps"], spl, success)
        ]
        final = curve[-1]["score"]
        conv = None
        if final > 0:
            k = len(curve) - 1
            while k > 0 and curve[k - 1]["score"] == final:
                k -= 1
            conv = k
        fs = int(out["first_success_env_steps"][0, j])
        share = lambda steps: {  # noqa: E731
            "wall_time_s": wall * steps / total,
            "cpu_time_s": cpu * steps / total,
        }
        result: dict[str, Any] = {
            "score": final,
            "success": curve[-1]["success"],
            "paths": paths,
            "path_lengths": [None if p is None else len(p) - 1 for p in paths],
            "optimal_lengths": optimal,
            "env_steps": int(total),
            "episodes": int(out["episodes"][0, j]),
            "curve": curve,
            "first_success": None
            if fs < 0
            else {"env_steps": fs, "episode": int(out["first_success_episode"][0, j])},
            "convergence": None if conv is None else {"env_steps": curve[conv]["env_steps"]},
        }
        timing: dict[str, Any] = {
            "wall_time_s": wall,
            "cpu_time_s": cpu,
            "shared_by_seeds": n,
            "compile_s": r["compile_s"],
            "curve": [share(p["env_steps"]) for p in curve],
            "first_success": None if fs < 0 else share(fs),
            "convergence": None if conv is None else share(curve[conv]["env_steps"]),
        }
        if not task.is_goal:
            path = paths[0]
            cells = None if path is None else [tuple(c) for c in path]
            result["algorithm1"] = algorithm1_record(task.scenario, path)
            replan = _Replan(algo, task, values, budget, cells)
            replan.steps = total
            result["algorithm2"], timing["algorithm2"] = algorithm2_record(
                task.scenario, spec["seed"], replan, spec["max_replans"]
            )
        timing["run_wall_time_s"] = (t0 - t_start) / n + time.perf_counter() - t0
        records.append(runner.run_record(spec, result, timing, _jax_versions()))
    return records


def _jax_versions() -> dict[str, str]:
    import importlib.metadata as md

    out = {}
    for pkg in ("jax", "jaxlib", "rejax", "gymnax", "optax", "flax"):
        try:
            out[pkg] = md.version(pkg)
        except md.PackageNotFoundError:
            pass
    return out
