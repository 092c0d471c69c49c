"""Tuning of the JAX learners at one budget: a seeded random search whose trials are all
trained at once, vmapped, on the suite's tuning tasks::

    python -m sixaxis_avoid.benchmark.jax_tune --algo ppo --suite v1 --budget 30000 \\
        --trials 32 --seeds 3 --out docs/results/v2-tuning/jax_ppo-30000.json

- The ``--trials`` candidates are drawn up front from :func:`space` with ``--sampler-seed``
  (a random search: every trial is known before any is scored, which is what lets one
  compiled call train them all; a sequential sampler such as TPE would need the scores of
  earlier trials first). Knobs that fix shapes (:data:`jax_learners.STATIC`) are drawn
  ``--groups`` times and each trial takes one of those draws in turn, so the search
  compiles ``groups x tasks`` programs; the traced knobs are drawn per trial.
- Each trial is trained on ``--seeds`` seeds (``tuning.seeds`` of the suite first, then
  consecutive ones) on every tuning task (``tuning.tasks``) for ``--budget`` env steps
  (on a goal task too: counted over all its targets).
- The objective is the reported metric: the mean final score (SPL over the evaluation
  targets, at the budget) over tasks and seeds.
- ``--set NAME=JSON`` fixes a value for every trial (after the draw, so the other draws
  stay the same), e.g. ``--set replay_sample='"with_replacement"'`` for DQN.
- ``--address`` trains the groups on a Ray cluster, each a Ray task of ``--group-cpus``
  CPUs (``tasks x groups`` of them, 10 for suite v2), so a search that takes hours here
  takes about one group's time on a cluster of that many nodes.
- The search resumes: each compiled group's outcome is saved in ``--parts`` (default
  ``OUT.parts``) as it finishes, and the same command run again reads those back and trains
  only the rest (a long search can span several sessions). The trials file's wall and CPU
  times add up the groups' own, wherever they ran; the parts go once it is written. The
  directory's ``study.json`` is the search's manifest (:func:`search_manifest`), so a
  search committed part way under ``docs/results/v2-pending`` is named on the page as a set
  in progress. With ``--save-state``, a group also saves its training state there
  (``*.state.npz``, not committed) at least every few minutes and goes on from it when
  run again, so a long group (hours at 3M env steps) stopped midway is not lost; see
  :meth:`jax_learners.Compiled.run`. That holds on a machine that keeps the file; on one
  that keeps nothing between sittings, ``--split-seeds`` trains each group not yet begun
  as one group per seed, each saved as it finishes (:func:`jax_groups.plan_groups`).
  ``--status`` with the search's own flags prints how far it got (each group done, saved
  part way or not started) and trains nothing.
- Every trial is written to ``--out`` (values, per-task per-seed final scores and curves,
  objective); the best goes into the hyperparameter file (``--hyperparams``, default
  ``hyperparams/v2.json``) under ``learners[<jax_ppo|jax_dqn>]["by_budget"][<budget>]``,
  merged into what the file holds.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import shlex
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import jax_learners as jl
from sixaxis_avoid.benchmark._io import atomic_write_text
from sixaxis_avoid.benchmark.hyperparams import HYPERPARAMS_DIR
from sixaxis_avoid.benchmark.jax_values import JAX_LEARNER

LEARNER = JAX_LEARNER


def space(algo: str, rng: np.random.Generator) -> tuple[dict[str, Any], dict[str, Any]]:
    """One draw of the search space: ``(static, traced)`` values (SB3's names). The ranges
    are the SB3 learners' (``hyperparams.suggest``), with the learning-rate schedule added."""
    c = lambda xs: xs[int(rng.integers(len(xs)))]  # noqa: E731
    logu = lambda lo, hi: float(np.exp(rng.uniform(np.log(lo), np.log(hi))))  # noqa: E731
    traced: dict[str, Any] = {
        "learning_rate": logu(1e-4, 3e-3),
        "lr_schedule": c(["constant", "linear"]),
        "gamma": c([0.9, 0.95, 0.98, 0.99, 0.995]),
        "max_episode_steps": c([100, 200, 500, 1000]),
    }
    if algo == "ppo":
        n_envs, n_steps = c([4, 8, 16]), c([32, 64, 128, 256])
        static = {
            "net_arch": c([[64, 64], [128, 128], [256, 256]]),
            "n_envs": n_envs,
            "n_steps": n_steps,
            "batch_size": min(c([32, 64, 128, 256]), n_envs * n_steps),
            "n_epochs": c([3, 5, 10]),
        }
        traced.update(
            gae_lambda=c([0.8, 0.9, 0.95, 0.98, 1.0]),
            ent_coef=logu(1e-4, 0.1),
            clip_range=c([0.1, 0.2, 0.3]),
        )
        return static, traced
    if algo == "dqn":
        gradient_steps = c([1, 2, 4])
        replay_ratio = c([0.0625, 0.125, 0.25, 0.5])
        static = {
            "net_arch": c([[64, 64], [128, 128], [256, 256]]),
            "batch_size": c([32, 64, 128, 256]),
            "buffer_size": c([10_000, 50_000, 100_000]),
            "train_freq": round(gradient_steps / replay_ratio),
            "gradient_steps": gradient_steps,
        }
        traced.update(
            learning_starts=c([0, 500, 1000, 5000]),
            target_update_interval=c([100, 500, 1000, 5000]),
            exploration_fraction=float(rng.uniform(0.05, 0.5)),
            exploration_final_eps=float(rng.uniform(0.01, 0.2)),
        )
        return static, traced
    raise jl.JaxLearnerError(f"algo: {algo!r} has no search space ({', '.join(jl.ALGOS)})")


def draw(algo: str, trials: int, groups: int, seed: int) -> list[dict[str, Any]]:
    """``trials`` candidates: ``groups`` static draws, each trial taking one in turn."""
    if trials < 1 or groups < 1:
        raise jl.JaxLearnerError(f"trials, groups: {trials!r}, {groups!r} must be positive")
    rng = np.random.default_rng(seed)
    statics = [space(algo, rng)[0] for _ in range(groups)]
    return [
        jl.check_values(algo, {**statics[i % groups], **space(algo, rng)[1]}) for i in range(trials)
    ]


def tuning_seeds(suite: Any, n: int) -> list[int]:
    """``n`` tuning seeds: the suite's ``tuning.seeds`` first, then consecutive ones (past
    100 when it lists none), disjoint from the reported seeds."""
    base = [int(s) for s in suite.tuning.get("seeds", [])]
    return (base + [max(base, default=99) + 1 + i for i in range(n)])[:n]


def tune(
    algo: str,
    suite: Any,
    budget: int,
    candidates: list[dict[str, Any]],
    seeds: list[int],
    tasks: list[Any] | None = None,
    log: Any = None,
    parts: Path | None = None,
    dispatch: Any = None,
    save_state: bool = False,
    split_seeds: bool = False,
) -> dict[str, Any]:
    """Train every candidate on every tuning task and seed; score and rank them.

    With ``parts`` (a directory), each compiled group's outcome is saved there as it
    finishes and read back on a rerun (:func:`jax_learners.train_candidates`): a search
    stopped midway resumes, and ``resumed_groups`` counts the groups read back. ``dispatch``
    trains the groups (default: here, one after another; :func:`ray_dispatch`: on a Ray
    cluster). Times (seconds): ``wall_time_s`` is this call's plus the resumed groups' own;
    ``cpu_time_s`` and each task's ``wall_s`` add up the groups' own (compiling and
    training), wherever they ran. ``part_files`` lists the saved outcomes (not part of the
    trials file: :func:`main` removes them once that file is written). ``split_seeds``:
    groups not saved whole train one seed at a time (:func:`jax_learners.train_candidates`);
    ``resumed_groups`` counts the groups read back whole, and the wall time adds the seeds
    read back."""
    tasks = suite.tuning_tasks if tasks is None else tasks
    if not tasks:
        raise jl.JaxLearnerError(f"suite {suite.name!r}: tuning.tasks is empty")
    t0 = time.perf_counter()
    per_task = jl.train_candidates(
        algo, tasks, candidates, seeds, budget, suite.checkpoints(budget),
        parts=parts, dispatch=dispatch, log=log, save_state=save_state, split_seeds=split_seeds,
    )  # fmt: skip
    timing: list[dict[str, Any]] = []
    groups_all: list[dict[str, Any]] = []
    for task in tasks:
        groups = list({r["group"]: r for r in per_task[task.id]}.values())
        groups_all += groups
        timing.append(
            {
                "task": task.id,
                "wall_s": sum(r["group_wall_s"] for r in groups),
                "compile_s": sum(r["compile_s"] for r in groups),
                "train_wall_s": sum(r["train_wall_s"] for r in groups),
                # calls that went on from a group's saved state (--save-state)
                "state_resumes": sum(r["state_resumes"] for r in groups),
            }
        )
    resumed = [r for r in groups_all if r["resumed"]]
    resumed_wall = sum(r["resumed_wall_s"] for r in groups_all)
    trials = []
    for i, values in enumerate(candidates):
        scores = {t: [row[-1] for row in per_task[t][i]["spl"]] for t in per_task}
        trials.append(
            {
                "number": i,
                "values": values,
                "group": per_task[tasks[0].id][i]["group"],
                "objective": float(np.mean([s for v in scores.values() for s in v])),
                "final_score": scores,
                "final_success": {
                    t: [row[-1] for row in per_task[t][i]["success"]] for t in per_task
                },
                "curves": {
                    t: {
                        "env_steps": per_task[t][i]["env_steps"],
                        "score": per_task[t][i]["spl"],
                        "success": per_task[t][i]["success"],
                    }
                    for t in per_task
                },
            }
        )
    best = max(trials, key=lambda tr: (tr["objective"], -tr["number"]))
    return {
        "trials": trials,
        "best_trial": best["number"],
        "best_value": best["objective"],
        "wall_time_s": time.perf_counter() - t0 + resumed_wall,
        "cpu_time_s": sum(r["group_cpu_s"] for r in groups_all),
        "resumed_groups": len(resumed),
        "per_task_timing": timing,
        "part_files": sorted({f for rows in per_task.values() for r in rows for f in r["parts"]}),
    }


def search_manifest(
    parts: Path,
    command: str,
    learner: str,
    budget: int,
    trials: int,
    seeds: list[int],
    tasks: list[Any],
    n_groups: int,
) -> tuple[Any, float]:
    """Write ``parts/study.json``, the search's manifest in `run`'s form (``kind:
    "jax_tune"``, ``command``, ``learners``, ``budget``, ``runs``: its compiled groups,
    ``wall_time_s_total``: every command's wall time so far, ``finished: false``), so that
    a search committed part way is named as a set in progress (:mod:`report_pending`) and
    resumed by its command on another day or machine. Returns the function that rewrites it
    (after each group) and the wall time (s) of the earlier commands on record there (0.0
    for a search's first command); :func:`main` removes it with the parts once the trials
    file is written."""
    from sixaxis_avoid.benchmark.runner import write_manifest

    state = parts / "study.json"
    before = 0.0
    if state.exists():  # an earlier command of the same search: its wall time counts too
        before = float(json.loads(state.read_text()).get("wall_time_s_total", 0.0))
    t0 = time.perf_counter()

    def write() -> None:
        parts.mkdir(parents=True, exist_ok=True)
        write_manifest(
            parts,
            {
                "kind": "jax_tune",
                "command": command,
                "learners": [learner],
                "budget": int(budget),
                "candidates": int(trials),
                "seeds": list(seeds),
                "tasks": [t.id for t in tasks],
                "runs": int(n_groups),
                "finished": False,
                "wall_time_s_total": before + time.perf_counter() - t0,
            },
        )

    write()
    return write, before


def search_status(
    algo: str,
    tasks: list[Any],
    candidates: list[dict[str, Any]],
    seeds: list[int],
    budget: int,
    checkpoints: list[int],
    parts: Path,
    save_state: bool = False,
    split_seeds: bool = False,
) -> dict[str, Any]:
    """How far the search of these arguments got in ``parts``, read from its files; nothing
    is trained or written. ``groups``: one entry per compiled group, task by task
    (:func:`jax_groups.plan_groups`; with ``split_seeds`` a group not saved whole has one
    entry per seed), with ``task``, ``group``, ``seed`` (None: the whole group),
    ``candidates`` and ``status``:

    - ``"done"``: its outcome is saved; ``cpu_s`` and ``wall_s`` are its own (seconds).
    - ``"saved part way"`` (a ``save_state`` search): its training state is saved, with
      ``checkpoints_done`` of ``checkpoints`` evaluated (the last at ``env_steps``, the
      requested env steps of that checkpoint), ``iterations_past`` training iterations
      since, ``resumes``, and its training's ``cpu_s`` and ``wall_s`` so far.
    - ``"not started"``: neither.

    ``other_files`` counts the outcome and state files in ``parts`` that belong to none of
    these groups (another search, or the other mode of ``save_state``); ``groups_done`` the
    groups done whole or in every seed."""
    from sixaxis_avoid.benchmark import jax_state

    checked = [jl.check_values(algo, c) for c in candidates]
    planned = jl.plan_groups(algo, tasks, checked, seeds, budget, checkpoints, parts,
                             save_state, split_seeds)  # fmt: skip
    rows = []
    for p in planned:
        row: dict[str, Any] = {"task": p.task.id, "group": p.group,
                               "seed": None if p.split is None else int(seeds[p.split]),
                               "candidates": len(p.members)}  # fmt: skip
        saved = jl.saved_group(p.part, p.ident)
        meta = None if saved or p.state is None else jax_state.state_meta(p.state)
        if saved is not None:
            row.update(status="done", cpu_s=saved["group_cpu_s"], wall_s=saved["group_wall_s"])
        elif meta is not None:
            k = int(meta["segment"])
            row.update(
                status="saved part way",
                checkpoints_done=k,
                checkpoints=len(checkpoints),
                env_steps=int(checkpoints[k - 1]) if k else 0,
                iterations_past=int(meta["done"]),
                resumes=int(meta["resumes"]),
                cpu_s=float(meta["cpu_s"]),
                wall_s=float(meta["wall_s"]),
            )
        else:
            row["status"] = "not started"
        rows.append(row)
    mine = {f.resolve() for p in planned for f in (p.part, p.state) if f is not None}
    files = [*parts.glob("*--*.json"), *parts.glob("*" + jax_state.STATE_SUFFIX)]
    other = [f for f in files if f.resolve() not in mine]
    status = [r["status"] for r in rows]
    units: dict[tuple[str, int], list[str]] = {}
    for r in rows:
        units.setdefault((r["task"], r["group"]), []).append(r["status"])
    return {
        "parts": str(parts),
        "groups": rows,
        "groups_done": sum(all(x == "done" for x in u) for u in units.values()),
        "groups_total": len(units),
        "done": status.count("done"),
        "saved_part_way": status.count("saved part way"),
        "not_started": status.count("not started"),
        "cpu_s": sum(r.get("cpu_s", 0.0) for r in rows),
        "other_files": len(other),
    }


def print_status(st: dict[str, Any], file: Any = None) -> None:
    """:func:`search_status` as a table (``jax_tune --status``)."""
    from sixaxis_avoid.benchmark.stats import fmt_steps

    out = file or sys.stdout
    n = len(st["groups"])
    split = sum(r["seed"] is not None for r in st["groups"])
    print(
        f"{n} compiled groups in {st['parts']}"
        + (f" ({split} of them one seed of a group split by seed)" if split else "")
        + f": {st['done']} done, {st['saved_part_way']} saved part way, {st['not_started']} "
        f"not started; {st['cpu_s'] / 3600:.2f} CPU-h in them so far; "
        f"{st['groups_done']} of {st['groups_total']} groups done",
        file=out,
    )
    table = [("task", "group", "seed", "candidates", "status", "progress", "CPU-h")]
    for r in st["groups"]:
        progress = ""
        if r["status"] == "saved part way":
            progress = f"{r['checkpoints_done']} of {r['checkpoints']} checkpoints"
            if r["checkpoints_done"]:
                progress += f" ({fmt_steps(r['env_steps'])} env steps)"
            progress += f" + {r['iterations_past']} iterations"
        cpu = f"{r['cpu_s'] / 3600:.2f}" if "cpu_s" in r else ""
        seed = "all" if r["seed"] is None else str(r["seed"])
        table.append((r["task"], str(r["group"]), seed, str(r["candidates"]), r["status"],
                      progress, cpu))  # fmt: skip
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    for row in table:
        print("  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip(), file=out)
    if st["other_files"]:
        print(
            f"{st['other_files']} other outcome or state files in {st['parts']} belong to none "
            "of these groups (another search, or the other --save-state mode)",
            file=out,
        )


def ray_dispatch(group_cpus: int) -> Any:
    """A :func:`jax_learners.train_candidates` dispatch over the connected Ray cluster: each
    group is a task reserving ``group_cpus`` CPUs (capped at the largest node's); outcomes
    come back as they finish."""

    def dispatch(jobs: list[Any]) -> Any:
        import ray

        from sixaxis_avoid.benchmark.runner import max_node_cpus

        if not jobs:
            return
        remote = ray.remote(num_cpus=min(group_cpus, max_node_cpus()), max_retries=0)(
            jl.train_group
        )
        pending = {remote.remote(*job): k for k, job in enumerate(jobs)}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            k = pending.pop(ready[0])
            yield k, ray.get(ready[0])

    return dispatch


def record_best(
    path: Path, learner: str, budget: int, values: dict[str, Any], entry: dict[str, Any]
) -> dict[str, Any]:
    """Merge ``learners[learner]["by_budget"][budget]`` into the hyperparameter file (other
    learners and budgets stay)."""
    data: dict[str, Any] = {"learners": {}}
    if path.exists():
        data = json.loads(path.read_text())
        if not isinstance(data.get("learners"), dict):
            raise jl.JaxLearnerError(f"{path}: field 'learners' must be an object")
    data.setdefault(
        "note",
        "Suite v2's hyperparameters, tuned per budget: learners[<name>].by_budget[<env "
        "steps>] holds the values a run at that budget uses, the command that chose them, "
        "its trials file and objective (mean final SPL over the tuning tasks and seeds).",
    )
    by_budget = data["learners"].setdefault(learner, {}).setdefault("by_budget", {})
    by_budget[str(int(budget))] = {"values": values, "status": "tuned", **entry}
    atomic_write_text(path, json.dumps(data, indent=1) + "\n")
    return data


def add_search_args(p: argparse.ArgumentParser, hyperparams_help: str) -> None:
    """The options every random search at one budget shares (this one and ``sb3_tune``):
    the budget, trials, seeds, sampler seed, hyperparameter file and trials file."""
    p.add_argument("--budget", type=int, required=True, help="env steps per run")
    p.add_argument("--trials", type=int, default=32, help="random draws")
    p.add_argument("--seeds", type=int, default=3, help="seeds per trial and task")
    p.add_argument("--sampler-seed", type=int, default=0)
    p.add_argument(
        "--hyperparams", type=Path, default=HYPERPARAMS_DIR / "v2.json", help=hyperparams_help
    )
    p.add_argument("--out", type=Path, required=True, help="trials file (JSON)")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--algo", choices=jl.ALGOS, default="ppo")
    p.add_argument("--suite", default="v1", help="suite whose tuning.tasks are scored")
    p.add_argument("--tasks", default=None, help="comma-separated subset of the tuning tasks")
    add_search_args(p, "hyperparameter file the best trial is merged into")
    p.add_argument("--groups", type=int, default=2, help="draws of the static knobs")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=JSON",
        help="a value fixed for every trial, over the drawn ones (jax_learners --set syntax)",
    )
    p.add_argument(
        "--parts",
        type=Path,
        default=None,
        help="directory where each compiled group's outcome is saved as it finishes, so a "
        "stopped search resumes on the same command (default: OUT.parts beside --out; "
        "removed once the trials file is written)",
    )
    p.add_argument(
        "--address",
        default=None,
        help="join this Ray cluster and train the groups there, each a Ray task (default: "
        "one after another in this process)",
    )
    p.add_argument(
        "--group-cpus",
        type=int,
        default=1,
        help="with --address: CPUs each group reserves (capped at the largest node's)",
    )
    p.add_argument(
        "--save-state",
        action="store_true",
        help="train each group in pieces and save its state in --parts as it goes, so a "
        "stop loses minutes of a group rather than all of it (float rounding differs from "
        "one-call training, so its groups' outcomes are saved apart from those)",
    )
    p.add_argument(
        "--split-seeds",
        action="store_true",
        help="train each group not yet begun (no outcome or state saved) as one group per "
        "seed, each saved as it finishes (for sittings on machines that keep no state between "
        "them); the groups saved whole are read back and those saved part way go on whole",
    )
    p.add_argument(
        "--status",
        action="store_true",
        help="print how far this search got in --parts (each compiled group done, saved part "
        "way or not started; give the search's own flags, --save-state included) and exit, "
        "training nothing",
    )
    a = p.parse_args(argv)
    if a.group_cpus < 1:
        p.error(f"--group-cpus: {a.group_cpus} must be >= 1")
    return a


def main(argv: list[str] | None = None) -> dict[str, Any]:
    from sixaxis_avoid.benchmark.runner import machine
    from sixaxis_avoid.benchmark.tasks import load_suite

    a = parse_args(argv if argv is not None else sys.argv[1:])
    suite = load_suite(a.suite)
    tasks = suite.tuning_tasks
    if a.tasks:
        want = a.tasks.split(",")
        known = {t.id: t for t in tasks}
        missing = [t for t in want if t not in known]
        if missing:
            raise jl.JaxLearnerError(
                f"--tasks: {missing[0]!r} is not a tuning task of suite {suite.name!r} "
                f"({', '.join(known)})"
            )
        tasks = [known[t] for t in want]
    seeds = tuning_seeds(suite, a.seeds)
    fixed = jl.parse_sets(a.set)
    candidates = [
        jl.check_values(a.algo, {**c, **fixed})
        for c in draw(a.algo, a.trials, a.groups, a.sampler_seed)
    ]
    parts = a.parts or a.out.with_name(a.out.name + ".parts")
    if a.status:
        st = search_status(a.algo, tasks, candidates, seeds, a.budget,
                           suite.checkpoints(a.budget), parts, a.save_state,
                           a.split_seeds)  # fmt: skip
        print_status(st)
        return st
    argv_s = argv if argv is not None else sys.argv[1:]
    command = "python -m sixaxis_avoid.benchmark.jax_tune " + shlex.join(argv_s)
    learner = LEARNER[a.algo]
    n_groups = len(tasks) * len(jl.candidate_groups(a.algo, candidates))
    t_command = time.perf_counter()
    progress, earlier_wall = search_manifest(parts, command, learner, a.budget, a.trials, seeds,
                                             tasks, n_groups)  # fmt: skip
    started = False
    if a.address:
        from sixaxis_avoid.benchmark.runner import init_ray

        started = init_ray(a.address, None)
    try:
        result = tune(
            a.algo, suite, a.budget, candidates, seeds, tasks,
            log=lambda m: (print(m, file=sys.stderr), progress()), parts=parts,
            dispatch=ray_dispatch(a.group_cpus) if a.address else None,
            save_state=a.save_state, split_seeds=a.split_seeds,
        )  # fmt: skip
    finally:
        if started:
            import ray

            ray.shutdown()
    part_files = [Path(f) for f in result.pop("part_files")]
    if earlier_wall > 0.0:
        # Earlier commands of this search are on record in its manifest: their wall time
        # is the search's, not the read-back groups' own times, which overlap when groups
        # train at once on a cluster (docs/PERFORMANCE.md, *JAX learners*).
        result["wall_time_s"] = earlier_wall + time.perf_counter() - t_command
        result["wall_time_basis"] = "commands"
    else:
        result["wall_time_basis"] = "this command and the read-back groups' own"
    out = {
        "learner": learner,
        "algo": a.algo,
        "suite": suite.name,
        "budget": a.budget,
        "command": command,
        "sampler": f"random search, numpy default_rng({a.sampler_seed}), {a.groups} static draws",
        "objective": "mean final SPL over the tuning tasks and seeds (the reported metric)",
        "tasks": [t.id for t in tasks],
        "seeds": seeds,
        "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": machine(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "ray": a.address or "in-process",
        **result,
    }
    a.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(a.out, json.dumps(out, indent=1) + "\n")
    best = out["trials"][out["best_trial"]]
    record_best(
        a.hyperparams,
        learner,
        a.budget,
        best["values"],
        {
            "command": command,
            "trials": str(a.out),
            "n_trials": a.trials,
            "seeds": seeds,
            "tasks": out["tasks"],
            "objective": out["best_value"],
            "best_trial": out["best_trial"],
            "date": out["date"],
        },
    )
    for f in part_files:  # the search is on record: its saved groups are not needed again
        f.unlink(missing_ok=True)
    (parts / "study.json").unlink(missing_ok=True)
    if parts.is_dir() and not any(parts.iterdir()):
        parts.rmdir()
    print(
        json.dumps({k: out[k] for k in ("best_trial", "best_value", "wall_time_s", "cpu_time_s")})
    )
    return out


if __name__ == "__main__":
    main()
