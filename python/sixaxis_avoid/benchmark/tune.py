"""``benchmark tune``: an Optuna study per deep learner, on the suite's tuning tasks.

Each trial draws hyperparameters (:func:`sixaxis_avoid.benchmark.hyperparams.suggest`), runs
the learner on every tuning task and tuning seed (Ray tasks, like ``run``), and scores the
draw by the mean area under the learning curve: the greedy path's score (SPL) averaged over
the budget's env steps, in [0, 1]. It is 1 only for a learner that is optimal from the first
step, so it rewards reaching the optimum and reaching it early. The tuning tasks must be
disjoint from the reported ones (checked). The best draw goes to the hyperparameter file with
the command, the trial count and the objective.
"""

from __future__ import annotations

import argparse
import datetime as dt
import sys
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import hyperparams as hpmod
from sixaxis_avoid.benchmark import runner
from sixaxis_avoid.benchmark.cli import command_line, parse_seeds, split
from sixaxis_avoid.benchmark.stats import curve_on
from sixaxis_avoid.benchmark.tasks import load_suite


def curve_area(record: dict[str, Any]) -> float:
    """Mean score over env steps 0..budget (a step function of the curve's points)."""
    budget = max(int(record["spec"]["budget"]), 1)
    grid = np.linspace(0, budget, 201)
    return float(np.mean(curve_on(grid, record["result"]["curve"])))


def cmd_tune(args: argparse.Namespace, argv: list[str]) -> int:
    import optuna

    suite = load_suite(args.suite)
    suite.check_disjoint()
    tasks = suite.tuning_tasks
    if not tasks:
        raise SystemExit(f"suite {suite.name}: no tuning tasks")
    seeds = parse_seeds(args.seeds) or [int(s) for s in suite.tuning.get("seeds", [0])]
    hp_file = args.out or hpmod.hyperparams_path(suite.raw.get("hyperparams", "v1"))
    log_dir = args.log_dir or Path("results") / "tune" / suite.name
    learners = split(args.learners)
    for lr in learners:
        if lr not in hpmod.TUNABLE:
            raise SystemExit(f"tune: {lr!r} has no search space ({', '.join(hpmod.TUNABLE)})")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    if args.storage and args.storage.startswith("sqlite:///"):
        Path(args.storage[len("sqlite:///") :]).parent.mkdir(parents=True, exist_ok=True)
    started = False if args.no_ray else runner.init_ray(args.address, args.num_cpus)
    try:
        for learner in learners:
            study = optuna.create_study(
                study_name=f"{suite.name}-{learner}",
                direction="maximize",
                sampler=optuna.samplers.TPESampler(seed=args.sampler_seed),
                storage=args.storage,
                load_if_exists=True,
            )
            done = len([t for t in study.trials if t.state.is_finished()])
            while done < args.trials:
                batch = [study.ask() for _ in range(min(args.parallel_trials, args.trials - done))]
                specs: dict[int, list[dict[str, Any]]] = {}
                for trial in batch:
                    hp = hpmod.suggest(trial, learner)
                    trial.set_user_attr("hyperparams", hp)
                    specs[trial.number] = runner.plan_runs(
                        suite,
                        [learner],
                        seeds=seeds,
                        tasks=tasks,
                        hyperparams=hp_file,
                        budget_scale=args.budget_scale,
                        overrides={learner: hp},
                        tag=f"trial{trial.number}",
                    )
                out = log_dir / learner
                res = runner.run_study(
                    [s for ss in specs.values() for s in ss],
                    out,
                    use_ray=not args.no_ray,
                    progress=not args.no_progress,
                )
                if res["stopped"]:
                    print(f"[tune] {learner}: stopped on request; the same command resumes "
                          "(the runs already in the log are kept)", file=sys.stderr)  # fmt: skip
                    raise SystemExit(runner.EXIT_STOPPED)
                failed = {k for k, _ in res["failures"]}
                for trial in batch:
                    ss = specs[trial.number]
                    if any(runner.run_key(s) in failed for s in ss):
                        study.tell(trial, state=optuna.trial.TrialState.FAIL)
                        continue
                    recs = [runner.load_record(out, s) for s in ss]
                    study.tell(trial, float(np.mean([curve_area(r) for r in recs])))
                done += len(batch)
                print(
                    f"[tune] {learner}: {done}/{args.trials} trials, best so far "
                    f"{study.best_value:.3f}",
                    file=sys.stderr,
                )
            best = study.best_trial
            hpmod.record_tuning(
                hp_file,
                learner,
                best.user_attrs["hyperparams"],
                {
                    "command": command_line(argv),
                    "trials": len([t for t in study.trials if t.state.is_finished()]),
                    "objective": "mean area under the SPL learning curve over the budget",
                    "best_value": float(best.value),
                    "best_trial": best.number,
                    "tasks": [t.id for t in tasks],
                    "seeds": seeds,
                    "budget_scale": args.budget_scale,
                    "sampler": f"TPESampler(seed={args.sampler_seed})",
                    "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                },
            )
            print(f"[tune] {learner}: best {best.value:.3f} -> {hp_file}", file=sys.stderr)
    finally:
        if started:
            import ray

            ray.shutdown()
    return 0


# ------------------------------------------------------------------------------------------
# ``benchmark tune-native``: the tabular learners at one budget in env steps

#: The tabular learners' search space: name -> (low, high, log scale). The paper's values
#: (alpha 0.05, gamma 0.9, epsilon_start 0.1, epsilon_decay_fraction 0.99) lie inside.
NATIVE_SPACE: dict[str, tuple[float, float, bool]] = {
    "alpha": (0.01, 1.0, True),
    "gamma": (0.5, 0.999, False),
    "epsilon_start": (0.01, 1.0, True),
    "epsilon_decay_fraction": (0.1, 1.0, False),
}
NATIVE_TUNABLE = ("q_assist", "q_plain")


def native_score(
    learner: str,
    task: Any,
    seed: int,
    budget: int,
    hp: dict[str, Any],
    checkpoints: list[int] | None = None,
) -> dict[str, Any]:
    """One tuning run of a tabular learner: ``budget`` env steps on ``task`` (the benchmark's
    own code path, :class:`~sixaxis_avoid.benchmark.learners.NativeQ` on a budget in env
    steps); its final score (mean SPL over the task's evaluation targets), success, and the
    area under its curve at ``checkpoints`` (env steps; default: the budget alone) as
    :func:`curve_area` reads a run."""
    from sixaxis_avoid.benchmark.learners import RunContext, resolve

    cls = resolve(learner)
    lr = cls({**hp, "max_env_steps": int(budget), "epsilon_schedule": "env_steps"})
    ctx = RunContext(task, seed, budget, lr.hyperparams, checkpoints or [budget], lr)
    lr.learn(ctx)
    ctx.finish()
    final = ctx.points[-1]
    curve = [{"env_steps": p["env_steps"], "score": p["score"]} for p in ctx.points]
    area = curve_area({"spec": {"budget": budget}, "result": {"curve": curve}})
    return {
        "score": final["score"],
        "success": final["success"],
        "area": area,
        "env_steps": ctx.env_steps,
    }


def best_trial(trials: list[dict[str, Any]]) -> dict[str, Any]:
    """The trial with the highest ``objective``; among tied ones the largest ``area`` (the
    mean area under the curves), then the lowest ``number``."""
    return max(trials, key=lambda t: (round(t["objective"], 12), t["area"], -t["number"]))


def tune_native(
    suite_name: str,
    learner: str,
    budget: int,
    trials: int,
    seeds: list[int],
    sampler_seed: int = 0,
    progress: bool = True,
) -> dict[str, Any]:
    """Random search (Optuna's ``RandomSampler(seed=sampler_seed)``) over
    :data:`NATIVE_SPACE` for a tabular learner at ``budget`` env steps: each trial is scored
    by the mean final SPL over the suite's tuning tasks x ``seeds``; returns every trial.

    The best trial has the highest objective; trials tied on it (at large budgets several
    reach 1.0 on every tuning task) are told apart by the mean area under their curves at
    the suite's checkpoints (the one that gets there sooner), then by trial number. The first
    v2 study took the earliest of six trials tied at 1.0 at 1M env steps, a near-greedy one
    that found no path on the study's 50 mm worlds (docs/BENCHMARKS.md, *Tuning record*)."""
    import time

    import optuna

    if learner not in NATIVE_TUNABLE:
        raise SystemExit(f"tune-native: {learner!r} is not one of {', '.join(NATIVE_TUNABLE)}")
    if budget < 1:
        raise SystemExit(f"tune-native: --budget {budget}: must be >= 1 env step")
    if trials < 1:
        raise SystemExit(f"tune-native: --trials {trials}: must be >= 1")
    suite = load_suite(suite_name)
    suite.check_disjoint()
    tasks = suite.tuning_tasks
    if not tasks:
        raise SystemExit(f"suite {suite.name}: no tuning tasks")
    checkpoints = suite.checkpoints(budget)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(
        direction="maximize", sampler=optuna.samplers.RandomSampler(seed=sampler_seed)
    )
    t0 = time.perf_counter()
    c0 = time.process_time()
    out: list[dict[str, Any]] = []
    for _ in range(trials):
        trial = study.ask()
        hp = {
            k: trial.suggest_float(k, lo, hi, log=log) for k, (lo, hi, log) in NATIVE_SPACE.items()
        }
        w0 = time.perf_counter()
        runs = [
            {"task": t.id, "seed": s, **native_score(learner, t, s, budget, hp, checkpoints)}
            for t in tasks
            for s in seeds
        ]
        value = float(np.mean([r["score"] for r in runs]))
        study.tell(trial, value)
        out.append(
            {
                "number": trial.number,
                "values": hp,
                "objective": value,
                "success": float(np.mean([r["success"] for r in runs])),
                "area": float(np.mean([r["area"] for r in runs])),
                "runs": runs,
                "wall_time_s": time.perf_counter() - w0,
            }
        )
        if progress:
            print(
                f"[tune-native] {learner} @ {budget}: trial {trial.number + 1}/{trials} "
                f"{value:.3f} (best {study.best_value:.3f})",
                file=sys.stderr,
            )
    best = best_trial(out)
    return {
        "learner": learner,
        "budget": int(budget),
        "suite": suite.name,
        "tasks": [t.id for t in tasks],
        "seeds": seeds,
        "objective": "mean final SPL (the reported score) over the tuning tasks x seeds",
        "tie_break": "mean area under the curve at the checkpoints, then the trial number",
        "checkpoints": checkpoints,
        "search": {
            "sampler": f"optuna RandomSampler(seed={sampler_seed})",
            "space": {
                k: {"low": lo, "high": hi, "log": log} for k, (lo, hi, log) in NATIVE_SPACE.items()
            },
            "fixed": {"epsilon_schedule": "env_steps", "max_env_steps": int(budget)},
        },
        "best": {k: best[k] for k in ("number", "values", "objective", "success", "area")},
        "trials": out,
        "wall_time_s": time.perf_counter() - t0,
        "cpu_time_s": time.process_time() - c0,
        "machine": runner.machine(),
        "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
    }


def record_by_budget(path: Path, export: dict[str, Any], trials_file: str, command: str) -> None:
    """Write the best values of a ``tune-native`` export into a hyperparameter file's
    ``learners.<learner>.by_budget.<budget>`` entry (docs: the v2 hyperparameter file);
    other entries stay."""
    import json

    from sixaxis_avoid.benchmark._io import atomic_write_text

    data = hpmod.load(path)
    data.pop("path", None)
    entry = data["learners"].setdefault(export["learner"], {})
    entry.setdefault("by_budget", {})[str(export["budget"])] = {
        "values": export["best"]["values"],
        "status": "tuned",
        "command": command,
        "trials": trials_file,
        # The best trial's objective, a number as jax_tune writes it (the report shows it).
        "objective": export["best"]["objective"],
        "objective_name": export["objective"],
    }
    atomic_write_text(Path(path), json.dumps(data, indent=1) + "\n")


def cmd_tune_native(args: argparse.Namespace, argv: list[str]) -> int:
    import json

    from sixaxis_avoid.benchmark._io import atomic_write_text

    suite = load_suite(args.suite)
    first = int(suite.tuning.get("seeds", [0])[0])
    # --seeds N: N seeds from the suite's first tuning seed (disjoint from the reported ones).
    if args.seeds and "," not in args.seeds:
        seeds = [first + k for k in range(int(args.seeds))]
    else:
        seeds = parse_seeds(args.seeds) or [first, first + 1, first + 2]
    if len(seeds) < 1:
        raise SystemExit(f"tune-native: --seeds {args.seeds!r}: need at least one seed")
    for learner in split(args.learners):
        export = tune_native(
            args.suite,
            learner,
            args.budget,
            args.trials,
            seeds,
            args.sampler_seed,
            not args.no_progress,
        )
        command = command_line(argv)
        export["command"] = command
        out = args.out or Path("docs/results/v2-tuning") / f"{learner}-{args.budget}.json"
        if len(split(args.learners)) > 1 and args.out:
            out = Path(args.out).with_name(f"{learner}-{args.budget}.json")
        atomic_write_text(Path(out), json.dumps(export, indent=1) + "\n")
        print(
            f"[tune-native] {learner} @ {args.budget}: best {export['best']['objective']:.3f} "
            f"of {args.trials} trials in {export['wall_time_s']:.0f} s -> {out}",
            file=sys.stderr,
        )
        if args.record:
            record_by_budget(args.record, export, str(out), command)
    return 0
