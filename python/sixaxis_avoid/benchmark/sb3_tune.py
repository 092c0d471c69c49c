"""SB3's PPO and DQN tuned by a search of their own at one budget of a suite's budget axis::

    python -m sixaxis_avoid.benchmark.sb3_tune --learner ppo --suite v2 --budget 300000 \\
        --trials 32 --seeds 3 --out docs/results/v2-tuning/ppo-300000.json

The study's SB3 rows take their JAX twin's tuned values (:mod:`~sixaxis_avoid.benchmark.
borrow`); this search gives SB3 the same tuning effort on its own:

- The candidates are ``--trials`` draws of the JAX search's space and sampler
  (:func:`jax_tune.draw`, SB3's names and ranges), each drawing its own static knobs (SB3
  compiles nothing, so nothing ties the trials to a few groups), with ``--implementation``
  fixed for every one (default ``"sb3"``: SB3's own algorithm), plus the twin's values as
  they are borrowed (``implementation: rejax``) as one more, labelled candidate when the
  hyperparameter file has them, so the search can only confirm or improve on them (a draw
  replaces them only if it scores strictly higher: :func:`best_trial`).
- Each candidate runs ``--seeds`` seeds (the suite's tuning seeds first, then consecutive
  ones, as ``jax_tune``) on every tuning task for the budget: ordinary benchmark runs
  (:func:`runner.plan_runs` at that budget, tagged by trial) without Algorithm 2's re-plans
  (``max_replans`` 0: the score is the learned path's, and a re-plan would train again).
  They run on Ray (one CPU each; ``--address`` joins a cluster, ``--no-ray`` runs them here)
  and each lands in ``--log-dir`` as it finishes, so a stopped search resumes on the same
  command (``touch LOG_DIR/STOP`` stops it once its running runs finish, exit status 75).
  ``LOG_DIR/study.json`` is its manifest (``kind: "sb3_tune"``, runs made, wall time over
  every call, ``finished``): a log directory under ``docs/results/v2-pending`` is named on
  the page as a set in progress.
- The objective is the reported metric: the mean final SPL over the tuning tasks and seeds.
  Every trial goes to ``--out`` in ``jax_tune``'s layout (values, per-task per-seed final
  scores and curves, objective); with ``--record``, the best one's values go into the
  hyperparameter file under ``learners[<learner>]["by_budget"][<budget>]``, replacing a
  borrowed entry, so the study's SB3 rows at that budget then run on SB3's own tuning.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import shlex
import sys
from pathlib import Path
from typing import Any

import numpy as np

from sixaxis_avoid.benchmark import runner
from sixaxis_avoid.benchmark._io import atomic_write_text
from sixaxis_avoid.benchmark.borrow import TWIN, borrowed_entry, sb3_values
from sixaxis_avoid.benchmark.implementation import IMPLEMENTATIONS
from sixaxis_avoid.benchmark.jax_tune import add_search_args, draw, record_best, tuning_seeds

#: What the twin's borrowed values are called among the candidates.
TWIN_CANDIDATE = "twin"


def candidates(
    learner: str,
    trials: int,
    seed: int,
    implementation: str,
    hp_data: dict[str, Any],
    budget: int,
) -> list[dict[str, Any]]:
    """The search's candidates: ``{"name", "values"}``, the draws first (``trial0`` ...),
    then the twin's borrowed values (``twin``) if the hyperparameter file has them."""
    out = []
    for k, v in enumerate(draw(learner, trials, trials, seed)):  # SB3's and rejax's names agree
        values, _ = sb3_values(learner, v, f"candidate trial{k}")
        out.append({"name": f"trial{k}", "values": {**values, "implementation": implementation}})
    twin = hp_data.get("learners", {}).get(TWIN[learner], {}).get("by_budget", {})
    if str(int(budget)) in twin:
        entry = borrowed_entry(hp_data, learner, budget)
        out.append({"name": TWIN_CANDIDATE, "values": entry["values"]})
    return out


def plan(
    suite: Any,
    learner: str,
    cands: list[dict[str, Any]],
    seeds: list[int],
    budget: int,
    hyperparams: Path,
) -> dict[str, list[dict[str, Any]]]:
    """Each candidate's runs (its name -> specs): tuning tasks x seeds at ``budget``, with
    exactly the candidate's values over the learner's defaults, and no re-plans."""
    from sixaxis_avoid.benchmark.learners import resolve

    defaults = dict(getattr(resolve(learner), "defaults", {}))
    out = {}
    for c in cands:
        specs = runner.plan_runs(
            suite, [learner], seeds=seeds, tasks=suite.tuning_tasks, hyperparams=hyperparams,
            overrides={learner: c["values"]}, tag=c["name"], budgets=[budget],
        )  # fmt: skip
        for s in specs:
            # The candidate alone, never a value left over from the file's entry at B.
            s["hyperparams"] = {**defaults, **suite.raw.get("overrides", {}).get(learner, {}),
                                **c["values"]}  # fmt: skip
            s["hyperparams_status"] = "tuning"
            s["max_replans"] = 0
        out[c["name"]] = specs
    return out


def tune(
    cands: list[dict[str, Any]],
    specs: dict[str, list[dict[str, Any]]],
    log_dir: Path,
    use_ray: bool = True,
    address: str | None = None,
    num_cpus: int | None = None,
    about: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Run the candidates' runs (``specs``, from :func:`plan`; those not in ``log_dir`` yet)
    and score the candidates.

    ``log_dir/study.json`` is the search's manifest in `run`'s form (``about``'s fields, such
    as ``command`` and ``learners``, plus ``kind: "sb3_tune"``, the run counts, the wall time
    over all the calls that ran it, ``finished``), rewritten after each run, so a search
    committed part way under a study's ``-pending`` directory is named on the page as a set
    in progress (:mod:`~sixaxis_avoid.benchmark.report_pending`)."""
    # The search's wall time over all the calls that ran it, each counted to its last
    # finished run (an interrupted call's unfinished runs are lost, and so is their time; a
    # call stopped on request, runner.STOP_FILE in log_dir, loses none).
    state = Path(log_dir) / "study.json"
    before = json.loads(state.read_text())["wall_time_s_total"] if state.exists() else 0.0

    def manifest(res: dict[str, Any], finished: bool) -> None:
        runner.write_manifest(
            log_dir,
            {
                **(about or {}),
                "kind": "sb3_tune",
                "candidates": len(cands),
                **runner.manifest_counts(res, before),
                "finished": finished,
            },
        )

    res = runner.run_study(
        [s for ss in specs.values() for s in ss], log_dir, address=address,
        num_cpus=num_cpus, use_ray=use_ray, progress=False,
        on_progress=lambda so_far: manifest(so_far, False),
    )  # fmt: skip
    manifest(res, not res["stopped"] and not res["failures"])
    wall = before + res["wall_time_s"]
    if res["failures"]:
        key, err = res["failures"][0]
        raise SystemExit(f"sb3_tune: {len(res['failures'])} runs failed, e.g. {key}: {err}")
    if res["stopped"]:
        left = runner.runs_left(res)
        print(f"sb3_tune: stopped on request, {left} runs left in {log_dir}; the same "
              "command runs them", file=sys.stderr)  # fmt: skip
        raise SystemExit(runner.EXIT_STOPPED)
    trials = []
    cpu = 0.0
    for number, c in enumerate(cands):
        recs = [runner.load_record(log_dir, s) for s in specs[c["name"]]]
        cpu += sum(float(r.get("timing", {}).get("cpu_time_s", 0.0)) for r in recs)
        by_task: dict[str, list[dict[str, Any]]] = {}
        for r in recs:
            by_task.setdefault(r["spec"]["task"]["id"], []).append(r)
        trials.append(
            {
                "number": number,
                "name": c["name"],
                "values": c["values"],
                "objective": float(np.mean([r["result"]["score"] for r in recs])),
                "final_score": {t: [r["result"]["score"] for r in rs] for t, rs in by_task.items()},
                "final_success": {
                    t: [r["result"]["success"] for r in rs] for t, rs in by_task.items()
                },
                "curves": {
                    t: {
                        "env_steps": [p["env_steps"] for p in rs[0]["result"]["curve"]],
                        "score": [[p["score"] for p in r["result"]["curve"]] for r in rs],
                        "success": [[p["success"] for p in r["result"]["curve"]] for r in rs],
                    }
                    for t, rs in by_task.items()
                },
            }
        )
    best = best_trial(trials)
    return {
        "trials": trials,
        "best_trial": best["number"],
        "best_value": best["objective"],
        "runs": res["runs"],
        "resumed_runs": res["skipped"],
        "wall_time_s": wall,
        "cpu_time_s": cpu,  # the runs' training CPU time (evaluation excluded)
    }


def best_trial(trials: list[dict[str, Any]]) -> dict[str, Any]:
    """The trial with the highest objective; on a tie the twin's (the values the study's
    SB3 runs already use: a draw replaces them only if it scores strictly higher), else the
    lowest-numbered one. Outcomes near 0 or 1 make ties at the top common."""
    top = max(tr["objective"] for tr in trials)
    tied = [tr for tr in trials if tr["objective"] == top]
    twin = [tr for tr in tied if tr["name"] == TWIN_CANDIDATE]
    return twin[0] if twin else min(tied, key=lambda tr: tr["number"])


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--learner", choices=sorted(TWIN), required=True)
    p.add_argument("--suite", default="v2", help="suite whose tuning.tasks are scored")
    add_search_args(p, "hyperparameter file: the twin's values are read from it")
    p.add_argument(
        "--implementation",
        default="sb3",
        help="the SB3 learner's implementation preset for every draw (sb3: SB3's own; rejax)",
    )
    p.add_argument("--record", action="store_true", help="write the best into --hyperparams")
    p.add_argument("--log-dir", type=Path, help="the runs (default: OUT.runs beside --out)")
    runner_args = p.add_argument_group("Ray")
    runner_args.add_argument("--address", help="join this Ray cluster")
    runner_args.add_argument("--num-cpus", type=int, help="local Ray: cores to use")
    runner_args.add_argument("--no-ray", action="store_true", help="run here, one at a time")
    a = p.parse_args(argv)
    for name in ("trials", "seeds"):
        if getattr(a, name) < 1:
            p.error(f"--{name}: {getattr(a, name)} must be >= 1")
    return a


def main(argv: list[str] | None = None) -> dict[str, Any]:
    from sixaxis_avoid.benchmark.tasks import load_suite

    a = parse_args(argv if argv is not None else sys.argv[1:])
    presets = IMPLEMENTATIONS[a.learner][1]
    if a.implementation not in presets:
        raise SystemExit(
            f"--implementation: {a.implementation!r} is not one of {', '.join(sorted(presets))}"
        )
    suite = load_suite(a.suite)
    suite.check_disjoint()
    axis = suite.budgets.get("axis") or []
    if a.budget not in axis:
        raise SystemExit(f"--budget: {a.budget} is not on suite {suite.name!r}'s axis {axis}")
    seeds = tuning_seeds(suite, a.seeds)
    hp_data = json.loads(a.hyperparams.read_text()) if a.hyperparams.exists() else {}
    cands = candidates(a.learner, a.trials, a.sampler_seed, a.implementation, hp_data, a.budget)
    log_dir = a.log_dir or a.out.with_name(a.out.name + ".runs")
    started = False if a.no_ray else runner.init_ray(a.address, a.num_cpus)
    if not suite.tuning_tasks:
        raise SystemExit(f"suite {suite.name!r}: tuning.tasks is empty")
    specs = plan(suite, a.learner, cands, seeds, a.budget, a.hyperparams)
    argv_s = argv if argv is not None else sys.argv[1:]
    command = "python -m sixaxis_avoid.benchmark.sb3_tune " + shlex.join(argv_s)
    about = {
        "command": command,
        "learners": [a.learner],
        "budget": a.budget,
        "suite": suite.name,
        "tasks": [t.id for t in suite.tuning_tasks],
        "seeds": seeds,
        "ray": "in-process" if a.no_ray else (a.address or "local"),
    }
    try:
        result = tune(
            cands,
            specs,
            log_dir,
            use_ray=not a.no_ray,
            address=a.address,
            num_cpus=a.num_cpus,
            about=about,
        )
    finally:
        if started:
            import ray

            ray.shutdown()
    out = {
        "learner": a.learner,
        "suite": suite.name,
        "budget": a.budget,
        "command": command,
        "sampler": f"random search, numpy default_rng({a.sampler_seed}) (jax_tune's space), "
        f"static knobs drawn per trial; implementation {a.implementation!r}; plus the "
        "twin's values (implementation 'rejax') when the file has them",
        "objective": "mean final SPL over the tuning tasks and seeds (the reported metric)",
        "tasks": [t.id for t in suite.tuning_tasks],
        "seeds": seeds,
        "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": runner.machine(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "ray": "in-process" if a.no_ray else (a.address or "local"),
        **result,
    }
    atomic_write_text(a.out, json.dumps(out, indent=1) + "\n")
    best = out["trials"][out["best_trial"]]
    if a.record:
        record_best(
            a.hyperparams,
            a.learner,
            a.budget,
            best["values"],
            {
                "command": command,
                "trials": str(a.out),
                "n_trials": len(cands),
                "seeds": seeds,
                "tasks": out["tasks"],
                "objective": out["best_value"],
                "best_trial": out["best_trial"],
                "best_candidate": best["name"],
                "date": out["date"],
            },
        )
    print(json.dumps({"best": best["name"], "best_value": out["best_value"]}))
    return out


if __name__ == "__main__":
    main()
