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
